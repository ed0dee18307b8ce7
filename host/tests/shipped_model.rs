//! The shipped model (`host/data/shapes_model.bin`, issue 5 §9): it parses,
//! records how it was made, and the documented seeded commands regenerate
//! it bit for bit. It is trained on the masks core's pipeline segments
//! (issue 20 §3, `train --through-pipeline`), so a change to a stage before
//! the classifier (segmentation, stereo, completion) changes the masks and
//! the model: rerun the two commands of docs/CLASSIFY.md ("Shipped model")
//! and commit the new blob.
//!
//! The regeneration is exact on one machine: training is deterministic
//! whatever the thread count, but the float GEMM (`matrixmultiply`) picks
//! its SIMD kernel by CPU feature, so a CPU without the same features may
//! round some products differently and produce another model.

use protogist::mlp::Model;
use protogist_host::classify::model_cmd::{run_train_with, Features, TrainOptions};
use protogist_host::classify::pipeline_data::PipelineTraining;
use protogist_host::classify::shapes::{gen_shapes, GenShapesOptions};
use protogist_host::classify::shipped::SHIPPED_MODEL;

const META: &str = "protogist train --dataset shapes --features shape --hidden 256 --epochs 600 --test-fraction 0.1 --seed 1 --gamma 0.5 --through-pipeline --views 2 --with-clean --mirror-images";

#[test]
fn shipped_model_parses_and_records_its_parameters() {
    let m = Model::parse(SHIPPED_MODEL).unwrap();
    assert_eq!((m.inputs(), m.hidden(), m.classes()), (720, 256, 19));
    assert_eq!(m.meta(), META);
    assert_eq!(m.class_name(0), Some("00_square"));
    assert_eq!(m.class_name(18), Some("18_d-shape"));
    assert!(m.delta_q16() > 0 && m.delta_q16() < 65536);
}

/// `gen-shapes --out shapes --classes 19 --per-class 1000 --seed 1 --size 64`
/// then `train --dataset shapes --hidden 256 --epochs 600 --seed 1
/// --gamma 0.5 --test-fraction 0.1 --through-pipeline --views 2
/// --with-clean --mirror-images --out shapes_model.bin`.
#[test]
fn documented_commands_regenerate_the_shipped_model() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("shapes");
    gen_shapes(&GenShapesOptions {
        out: ds.clone(),
        classes: 19,
        per_class: 1000,
        seed: 1,
        size: 64,
    })
    .unwrap();
    let out = tmp.path().join("shapes_model.bin");
    run_train_with(
        &TrainOptions {
            dataset: ds,
            hidden: 256,
            epochs: 600,
            out: out.clone(),
            test_fraction: 0.1,
            seed: 1,
            gamma: 0.5,
            features: Features::Shape,
            mirror_images: true,
        },
        &PipelineTraining {
            through_pipeline: true,
            views: 2,
            with_clean: true,
        },
    )
    .unwrap();
    let fresh = std::fs::read(&out).unwrap();
    assert_eq!(fresh.len(), SHIPPED_MODEL.len());
    assert!(fresh == SHIPPED_MODEL, "the regenerated model differs");
}
