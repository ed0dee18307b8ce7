//! Why the smoothing cell runs once by default: edge precision on the
//! synthetic scene, whose object boundary is known, against passes K
//! (the end-to-end measure that decided it is in `docs/CONSPICUITY.md`).
//!
//! `cargo test -p protogist-tests --test smoothing_choice -- --nocapture`
//! prints the table quoted in `docs/CONSPICUITY.md`.

use protogist::conspicuity::*;
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::synth::{render_left, render_mask, SceneSpec};

struct Score {
    precision: f64,
    recall: f64,
}

fn score(k: u8) -> Score {
    let (w, h) = (160, 120);
    let spec = SceneSpec::demo(w, h);
    let mut px = vec![Rgb8::default(); w * h];
    render_left(&spec, &mut ImageViewMut::packed(&mut px, w, h).unwrap()).unwrap();
    let mut m = vec![0u8; w * h];
    render_mask(&spec, 0, &mut ImageViewMut::packed(&mut m, w, h).unwrap()).unwrap();
    let mask = ImageView::packed(&m, w, h).unwrap();
    // A pixel within 1 px of the object outline.
    let on_outline = |x: usize, y: usize| {
        let c = mask.get(x, y);
        (-1..=1).any(|dy: isize| {
            (-1..=1).any(|dx: isize| {
                let (xx, yy) = (x.checked_add_signed(dx), y.checked_add_signed(dy));
                matches!((xx, yy), (Some(a), Some(b)) if mask.get(a, b).is_some_and(|v| Some(v) != c))
            })
        })
    };
    let mut store = protogist_tests::EdgeStorage::new(w, h);
    let mut bufs = store.buffers().unwrap();
    let params = EdgeParams {
        smooth: SmoothParams { iterations: k },
        threshold_percent: 10,
    };
    let rgb = ImageView::packed(&px, w, h).unwrap();
    edge_conspicuity(&LuvTables::new(), &params, &rgb, &mut bufs).unwrap();
    let edges = bufs.conspicuity();
    let (mut tp, mut fp, mut outline) = (0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let on = edges.get(x, y).unwrap().is_on();
            let o = on_outline(x, y);
            outline += usize::from(o);
            tp += usize::from(on && o);
            fp += usize::from(on && !o);
        }
    }
    Score {
        precision: tp as f64 / (tp + fp).max(1) as f64,
        recall: tp as f64 / outline.max(1) as f64,
    }
}

#[test]
fn one_pass_takes_most_of_the_gain() {
    let s: Vec<Score> = (0..=4).map(score).collect();
    eprintln!("| passes K | edge precision | outline recall |\n|---|---|---|");
    for (k, sc) in s.iter().enumerate() {
        eprintln!("| {k} | {:.3} | {:.3} |", sc.precision, sc.recall);
    }
    let default = usize::from(SmoothParams::default().iterations);
    assert_eq!(default, 1);
    assert_eq!(EdgeParams::DEFAULT.smooth, SmoothParams::default());
    // Smoothing must remove texture edges without losing the outline...
    assert!(s[1].precision > s[0].precision + 0.05);
    assert!(s[1].recall >= 0.95);
    // ...and a second pass must buy little.
    assert!(s[2].precision - s[1].precision < 0.03);
}
