//! The mirror check (`protogist::mlp::mirror`, docs/CLASSIFY.md "The
//! mirror check"): mirrors as permutations of the shape vector, per-class
//! averaging by the model's symmetry, the bar of the unsure objects and
//! the pipeline switch (the float reference and the error bound:
//! `mlp_mirror_reference.rs`; how the symmetry is derived:
//! `mlp_symmetry.rs`).

mod mirror_common;

use mirror_common::*;
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::mlp::{
    mirror_check, mirror_mean, mirror_top_k, scores, MirrorScratch, MlpError, Model, Ranked,
    Scratch, Symmetry, MIRROR_VIEWS, TOP_K,
};
use protogist::pipeline::{workspace_words, Pipeline, PipelineParams};
use protogist::shape::{Mirror, ShapeElem, BINS, SHAPE_LEN};
use protogist::synth::{render_left, render_right, SceneSpec};
use protogist_host::classify::mlp::Mlp;
use protogist_host::classify::quant::{quantize_net, write_blob, BlobExtras};

#[test]
fn mirrors_are_involutive_permutations() {
    for m in Mirror::ALL {
        let mut seen = [false; SHAPE_LEN];
        for i in 0..SHAPE_LEN {
            let s = m.source(i);
            assert!(s < SHAPE_LEN);
            // Within its half (max radii stay max radii).
            assert_eq!(s / BINS, i / BINS, "{m:?} {i}");
            assert_eq!(m.source(s), i, "{m:?} is its own inverse at {i}");
            seen[s] = true;
        }
        assert!(seen.iter().all(|&s| s), "{m:?} is a permutation");
    }
    // Bin 180 (0°, right) goes to bin 359 (179°, left) under V and stays
    // under H; bin 270 (90°, up) goes to 89 (−91°) under H, stays under V.
    assert_eq!(Mirror::Vertical.source(180), 359);
    assert_eq!(Mirror::Horizontal.source(180), 179);
    assert_eq!(Mirror::Vertical.source(269), 270);
    assert_eq!(Mirror::Horizontal.source(270), 89);
    // V then H is the half turn: bin b + 180.
    for i in 0..SHAPE_LEN {
        let vh = Mirror::Vertical.source(Mirror::Horizontal.source(i));
        assert_eq!(vh, i / BINS * BINS + (i % BINS + 180) % BINS);
    }
    let x = vector(blob);
    for m in Mirror::ALL {
        assert_eq!(
            mirrored(m, &mirrored(m, &x)),
            x,
            "{m:?} twice is the identity"
        );
        assert_ne!(mirrored(m, &x), x);
    }
}

#[test]
fn mirrors_agree_with_really_mirrored_masks() {
    let x = vector(blob);
    for (m, w) in [
        (Mirror::Vertical, vector(|x, y| blob(40 - x, y))),
        (Mirror::Horizontal, vector(|x, y| blob(x, 40 - y))),
    ] {
        let good = mean_abs(&mirrored(m, &x), &w);
        let other = Mirror::ALL.into_iter().find(|&o| o != m).unwrap();
        let wrong = mean_abs(&mirrored(other, &x), &w);
        let bad = mean_abs(&x, &w);
        eprintln!("{m:?}: mapped {good:.4}, other mirror {wrong:.4}, unmapped {bad:.4}");
        assert!(
            good < 0.05 && good * 5.0 < bad && good * 5.0 < wrong,
            "{m:?}"
        );
    }
}

/// The bar: an object whose plain best cosine reaches it keeps the plain
/// ranking, one under it gets the whole check; `u32::MAX` checks every
/// object and 0 none.
#[test]
fn the_bar_sends_only_the_unsure_objects_to_the_check() {
    let k = Model::parse(shipped_v1()).unwrap().classes();
    let blob = with_flags(&vec![3; k]);
    let m = Model::parse(&blob).unwrap();
    let mut b = Bufs::new(&m);
    let mut differ = 0;
    for x in probes() {
        let (_, plain) = b.plain(&m, &x);
        let check = b.check(&m, &x);
        differ += usize::from(plain != check);
        let best = plain[0].score;
        assert_eq!(b.gated(&m, &x, u32::MAX), check);
        assert_eq!(b.gated(&m, &x, 0), plain);
        assert_eq!(b.gated(&m, &x, best), plain);
        assert_eq!(b.gated(&m, &x, best + 1), check);
    }
    assert!(differ > 0, "the check changes some ranking here");
}

#[test]
fn without_symmetry_the_check_is_plain_identification() {
    let v1 = Model::parse(shipped_v1()).unwrap();
    assert!(!v1.has_symmetry_section());
    let zeros = with_flags(&vec![0; v1.classes()]);
    let v2 = Model::parse(&zeros).unwrap();
    assert!(v2.has_symmetry_section());
    let mut b = Bufs::new(&v1);
    for x in probes() {
        let (_, plain) = b.plain(&v1, &x);
        assert_eq!(b.check(&v1, &x), plain);
        assert_eq!(b.check(&v2, &x), plain);
        assert_eq!(b.plain(&v2, &x).1, plain);
    }
}

/// The check against its definition: the network on x, V(x), H(x), per
/// class the rounded mean over x and the class's mirrors, its cosine with
/// the class's template.
#[test]
fn the_check_scores_each_class_on_its_own_mirrors() {
    let k = Model::parse(shipped_v1()).unwrap().classes();
    // Every combination of flags over the classes.
    let flags: Vec<u8> = (0..k).map(|c| (c % 4) as u8).collect();
    let blob = with_flags(&flags);
    let m = Model::parse(&blob).unwrap();
    let mut b = Bufs::new(&m);
    let mut changed = 0;
    for x in probes() {
        let views: Vec<Vec<u16>> = [
            x,
            mirrored(Mirror::Vertical, &x),
            mirrored(Mirror::Horizontal, &x),
        ]
        .iter()
        .map(|v| b.plain(&m, v).0)
        .collect();
        let mut want: Vec<(u32, u16)> = (0..k)
            .map(|c| {
                let s = Symmetry::from_bits(flags[c]).unwrap();
                let mut rows = vec![&views[0]];
                if s.has(Mirror::Vertical) {
                    rows.push(&views[1]);
                }
                if s.has(Mirror::Horizontal) {
                    rows.push(&views[2]);
                }
                let n = rows.len() as u32;
                let mean: Vec<u16> = (0..k)
                    .map(|j| {
                        ((rows.iter().map(|r| u32::from(r[j])).sum::<u32>() + n / 2) / n) as u16
                    })
                    .collect();
                let mut sc = vec![0u32; k];
                scores(&m, &mean, &mut sc).unwrap();
                (sc[c], c as u16)
            })
            .collect();
        want.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
        let got = b.check(&m, &x);
        let want: Vec<Ranked> = want[..TOP_K]
            .iter()
            .map(|&(score, class)| Ranked { class, score })
            .collect();
        assert_eq!(got, want);
        changed += usize::from(got != b.plain(&m, &x).1);
    }
    assert!(changed > 0, "the flags change some ranking");
}

/// A 720-4-2 model whose templates are (60000, 10000) and (10000, 60000),
/// with symmetry `flags`.
fn two_class_blob(flags: Option<[u8; 2]>) -> Vec<u8> {
    let net = Mlp::new(SHAPE_LEN, 4, 2, 3);
    let calib: Vec<Vec<i16>> = vec![(0..SHAPE_LEN).map(|j| (j as i16 % 200) - 100).collect()];
    let q = quantize_net(&net, &calib).unwrap();
    let names: Vec<String> = ["left", "right"].map(String::from).to_vec();
    write_blob(
        &q,
        &BlobExtras {
            templates: &[60000, 10000, 10000, 60000],
            delta_q16: 0,
            names: &names,
            meta: "",
            symmetry: flags.as_ref().map(|f| &f[..]),
        },
    )
    .unwrap()
}

/// A near tie on the object itself, decided by its vertical mirror for the
/// class that looks the same mirrored, and only for that class.
#[test]
fn averaging_follows_the_flags() {
    // Rows: x (a near tie leaning to class 1), V(x) (clearly class 0),
    // H(x) (clearly class 1).
    let outputs = [30000u16, 31000, 60000, 5000, 8000, 62000];
    let rank = |flags: Option<[u8; 2]>| {
        let b = two_class_blob(flags);
        let m = Model::parse(&b).unwrap();
        let mut mean = [0u16; 2];
        let mut r = [Ranked::default(); 2];
        assert_eq!(mirror_top_k(&m, &outputs, &mut mean, &mut r).unwrap(), 2);
        r
    };
    let plain = rank(None);
    assert_eq!(plain[0].class, 1);
    // Class 0 has V: its mean (45000, 18000) wins.
    let v0 = rank(Some([1, 0]));
    assert_eq!(v0[0].class, 0);
    assert!(v0[0].score > plain[0].score);
    // Class 1's score is the plain one: it has no mirror.
    assert_eq!(
        v0.iter().find(|r| r.class == 1),
        plain.iter().find(|r| r.class == 1)
    );
    // Class 0 with H instead: its mean (19000, 46500) only loses more.
    let h0 = rank(Some([2, 0]));
    assert_eq!(h0[0].class, 1);
    // Class 1 with V: x and V(x) for class 1 only; class 0 plain.
    let v1 = rank(Some([0, 1]));
    assert_eq!(
        v1.iter().find(|r| r.class == 0),
        plain.iter().find(|r| r.class == 0)
    );
    assert!(v1.iter().find(|r| r.class == 1).unwrap().score < plain[0].score);
    // The means, rounded half up.
    let mut mean = [0u16; 2];
    mirror_mean(
        Symmetry::from_bits(3).unwrap(),
        &[1, 2, 2, 2, 2, 3],
        &mut mean,
    );
    assert_eq!(mean, [2, 2]);
    mirror_mean(
        Symmetry::from_bits(1).unwrap(),
        &[1, 2, 2, 2, 0, 0],
        &mut mean,
    );
    assert_eq!(mean, [2, 2]);
    mirror_mean(Symmetry::NONE, &[1, 2, 9, 9, 9, 9], &mut mean);
    assert_eq!(mean, [1, 2]);
}

#[test]
fn short_buffers_are_typed_errors() {
    let flagged = two_class_blob(Some([1, 0]));
    let plain = two_class_blob(Some([0, 0]));
    for (blob, vector_needed) in [(&flagged, true), (&plain, false)] {
        let m = Model::parse(blob).unwrap();
        let mut b = Bufs::new(&m);
        let x = vector(blob_fn);
        let mut s = Scratch {
            input: &mut b.xi,
            hidden: &mut b.hi,
            output: &mut b.yo,
        };
        let mut r = [Ranked::default(); 2];
        let mut short = [ShapeElem::ZERO; 10];
        let mut ms = MirrorScratch {
            vector: &mut short,
            outputs: &mut b.o,
            mean: &mut b.mean,
        };
        let got = mirror_check(&m, &x, &mut s, &mut ms, &mut r);
        if vector_needed {
            assert!(
                matches!(got, Err(MlpError::ScratchTooSmall { .. })),
                "{got:?}"
            );
        } else {
            assert_eq!(got, Ok(2));
        }
        let mut few = [0u16; MIRROR_VIEWS * 2 - 1];
        let mut ms = MirrorScratch {
            vector: &mut b.v,
            outputs: &mut few,
            mean: &mut b.mean,
        };
        assert!(matches!(
            mirror_check(&m, &x, &mut s, &mut ms, &mut r),
            Err(MlpError::ScratchTooSmall {
                buffer: "outputs",
                ..
            })
        ));
    }
}

fn blob_fn(x: i32, y: i32) -> bool {
    blob(x, y)
}

fn demo_pair() -> (Vec<Rgb8>, Vec<Rgb8>) {
    let (w, h) = (160, 120);
    let spec = SceneSpec::demo(w, h);
    let mut l = vec![Rgb8::default(); w * h];
    let mut r = l.clone();
    render_left(&spec, &mut ImageViewMut::packed(&mut l, w, h).unwrap()).unwrap();
    render_right(&spec, &mut ImageViewMut::packed(&mut r, w, h).unwrap()).unwrap();
    (l, r)
}

/// The frame's objects: box, centroid, ranking and identity.
fn run(params: &PipelineParams, model: &[u8]) -> Vec<String> {
    run_with_check(params, model).0
}

/// [`run`], and each object's ranking by `mirror_check` on its shape
/// vector beside the pipeline's own ranking.
fn run_with_check(params: &PipelineParams, model: &[u8]) -> (Vec<String>, Vec<(String, String)>) {
    let (l, r) = demo_pair();
    let p = Pipeline::new(params, &protogist_host::product::DEFAULT_TABLES, model).unwrap();
    let mut ws = vec![0u64; workspace_words(160, 120, params)];
    let f = p
        .run(
            &ImageView::packed(&l, 160, 120).unwrap(),
            &ImageView::packed(&r, 160, 120).unwrap(),
            &mut ws,
        )
        .unwrap();
    let m = Model::parse(model).unwrap();
    let mut b = Bufs::new(&m);
    let objects = f
        .objects()
        .iter()
        .map(|o| {
            format!(
                "{:?} {:?} {:?} {:?}",
                o.bbox,
                o.centroid,
                o.top(),
                o.identity
            )
        })
        .collect();
    let checked = f
        .objects()
        .iter()
        .map(|o| {
            (
                format!("{:?}", o.top()),
                format!("{:?}", b.check(&m, f.shape(o).unwrap())),
            )
        })
        .collect();
    (objects, checked)
}

#[test]
fn the_switch_off_is_todays_pipeline() {
    let k = Model::parse(shipped_v1()).unwrap().classes();
    let off = PipelineParams::DEFAULT
        .with_objects(4)
        .with_mirror_check(false);
    // On for every object, as the accurate preset runs it.
    let on = PipelineParams {
        mirror_below_q16: u32::MAX,
        ..off.with_mirror_check(true)
    };
    const {
        assert!(PipelineParams::DEFAULT.mirror_check && PipelineParams::ACCURATE.mirror_check);
        assert!(PipelineParams::ACCURATE.mirror_below_q16 == u32::MAX);
        assert!(PipelineParams::DEFAULT.mirror_below_q16 == 62_259);
    };
    // The switch's buffers only when it is on.
    use protogist::pipeline::layout::{classify_bytes, mirror_bytes, object_bytes, segment_bytes};
    assert_eq!(mirror_bytes(&off), 0);
    assert!(mirror_bytes(&on) >= protogist::mlp::mirror_scratch_bytes(64));
    assert_eq!(
        classify_bytes(&on),
        classify_bytes(&off) + mirror_bytes(&on)
    );
    // They take segmentation's maps' place: the object phase is the maps'.
    assert_eq!(object_bytes(160, 120, &on), segment_bytes(160, 120));
    assert_eq!(object_bytes(160, 120, &off), segment_bytes(160, 120));
    let today = run(&off, shipped_v1());
    assert!(!today.is_empty());
    // A v1 model with the check on, a v2 model with the check off.
    assert_eq!(run(&on, shipped_v1()), today);
    let all = with_flags(&vec![3; k]);
    assert_eq!(run(&off, &all), today);
    // On with flags: each object ranked as `mirror_check` ranks its
    // vector, which is not the plain ranking here.
    let (objects, checked) = run_with_check(&on, &all);
    assert_eq!(objects.len(), today.len());
    for (got, want) in &checked {
        assert_eq!(got, want);
    }
    let (_, plain) = run_with_check(&off, &all);
    assert_ne!(checked, plain);
}
