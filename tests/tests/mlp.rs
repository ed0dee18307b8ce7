//! Issue 5, section 1: the float network trained on generated silhouettes
//! through `train` and `eval`, end to end.

use protogist_host::classify::model_cmd::{
    run_eval, run_train, EvalOptions, Features, TrainOptions,
};
use protogist_host::classify::shapes::{gen_shapes, GenShapesOptions};

/// 8 classes x 12 images at 64 px, half held out; H = 32, 200 epochs.
#[test]
fn float_network_on_generated_shapes() {
    const N: usize = 8;
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("shapes");
    gen_shapes(&GenShapesOptions {
        out: ds.clone(),
        classes: N,
        per_class: 12,
        seed: 2024,
        size: 64,
    })
    .unwrap();
    let model = tmp.path().join("model.bin");
    for gamma in [0.2, 0.9] {
        let t = run_train(&TrainOptions {
            dataset: ds.clone(),
            hidden: 32,
            epochs: 200,
            out: model.clone(),
            test_fraction: 0.5,
            seed: 7,
            gamma,
            features: Features::Shape,
            mirror_images: false,
        })
        .unwrap();
        print!("{t}");
        let s = run_eval(&EvalOptions {
            model: model.clone(),
            dataset: ds.clone(),
            out: tmp.path().join("eval"),
            json: false,
        })
        .unwrap();
        print!("{s}");
        let pc = |k: &str| -> f64 {
            // "float | int8": the float column.
            s.get(k)
                .unwrap()
                .split('|')
                .next()
                .unwrap()
                .trim()
                .trim_end_matches(" %")
                .parse::<f64>()
                .unwrap()
                / 100.0
        };
        let (ror, eer) = (pc("ROR"), pc("EER"));
        println!(
            "γ {gamma}: ROR {:.1} %, EER {:.1} %",
            100.0 * ror,
            100.0 * eer
        );
        // Chance is 1/8; what must hold: well above chance.
        assert!(ror >= 3.0 / N as f64, "γ {gamma}: ROR {ror}");
        assert!(eer < 0.5 && pc("HTER_min") <= eer + 1e-9);
    }
}
