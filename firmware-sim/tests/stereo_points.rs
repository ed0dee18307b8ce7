//! The stereo stage's named operating points (`stereo_run::POINTS`: `fast`
//! and `half` after `full`): each runs in `full`'s buffers, gives its own
//! map, and reports itself.

use firmware_sim::bench::stereo_run::{self, len, StereoResult, POINTS};
use firmware_sim::pg::disparity::DisparityCell;
use firmware_sim::pg::image::Rgb8;
use firmware_sim::pg::stereo::c2f::C2fBuffers;
use firmware_sim::pg::stereo::phase::PhaseBuffers;
use firmware_sim::pg::stereo::phase::SafePhase;
use firmware_sim::NoTicks;

/// The phase refinement's buffers: RGB row, grey row, responses, map row.
type PhaseStorage = (Vec<Rgb8>, Vec<i32>, Vec<[i16; 2]>, Vec<DisparityCell>);

struct Storage {
    grey: Vec<u16>,
    rgb: Vec<Rgb8>,
    z: Vec<stereo_run::ZCell>,
    col: Vec<[i32; 3]>,
    scores: Vec<i64>,
    costs: Vec<u16>,
    sums: Vec<u32>,
    picks: Vec<i32>,
    maps: Vec<u8>,
    phase: PhaseStorage,
}

impl Storage {
    fn new() -> Self {
        Self {
            grey: vec![0; len::GREY],
            rgb: vec![Rgb8::new(0, 0, 0); len::RGB],
            z: vec![[0; 2]; len::Z],
            col: vec![[0; 3]; len::COL],
            scores: vec![0; len::SCORES],
            costs: vec![0; len::COSTS],
            sums: vec![0; len::SUMS],
            picks: vec![0; len::PICKS],
            maps: vec![0; len::MAPS],
            phase: (
                vec![Rgb8::new(0, 0, 0); len::P_RGB],
                vec![0; len::P_V],
                vec![[0; 2]; len::P_Z],
                vec![DisparityCell::OFF; len::P_ROW],
            ),
        }
    }

    fn bufs(&mut self) -> C2fBuffers<'_> {
        C2fBuffers {
            grey: &mut self.grey,
            rgb: &mut self.rgb,
            z: &mut self.z,
            col: &mut self.col,
            scores: &mut self.scores,
            costs: &mut self.costs,
            sums: &mut self.sums,
            picks: &mut self.picks,
            maps: &mut self.maps,
            phase: PhaseBuffers {
                rgb: &mut self.phase.0,
                v: &mut self.phase.1,
                z: &mut self.phase.2,
                row: &mut self.phase.3,
            },
        }
    }
}

#[test]
fn each_point_runs_its_own_window_and_band_in_the_default_buffers() {
    let mut storage = Storage::new();
    let default =
        stereo_run::run::<_, SafePhase>(&mut storage.bufs(), &mut NoTicks).expect("default runs");
    let runs: Vec<(&str, StereoResult)> = POINTS
        .iter()
        .map(|(name, p)| {
            let r = stereo_run::run_at::<_, SafePhase>(p, &mut storage.bufs(), &mut NoTicks)
                .unwrap_or_else(|e| panic!("{name}: {e:?}"));
            (*name, r)
        })
        .collect();
    // Another point is another map, and most of the scene stays
    // estimated.
    let pixels = (stereo_run::WIDTH * stereo_run::HEIGHT) as u64;
    for (name, r) in &runs {
        assert_ne!(r.checksum, default.checksum, "{name} ran `full`");
        assert!(
            r.report.on as u64 * 10 > pixels * 8,
            "{name}: {} on",
            r.report.on
        );
    }
    let get = |n: &str| {
        runs.iter()
            .find(|(name, _)| *name == n)
            .map(|(_, r)| *r)
            .expect("point")
    };
    let (fast, half) = (get("fast"), get("half"));
    // Band 1, no right eye and level 1 as the finest: well under half of
    // `full`'s cells (level 0 has about 4 times the pixels of level 1).
    assert!(half.report.cells * 2 < default.report.cells);
    // The phase refinement evaluates no cells and turns no pixel ON or
    // OFF, but changes the map.
    assert_eq!(fast.report.cells, half.report.cells);
    assert_eq!(fast.report.on, half.report.on);
    assert_ne!(fast.checksum, half.checksum);
    // The same point twice gives the same map (the buffers carry nothing
    // over between runs).
    let (name, p) = &POINTS[0];
    let again =
        stereo_run::run_at::<_, SafePhase>(p, &mut storage.bufs(), &mut NoTicks).expect("reruns");
    assert_eq!(again.checksum, runs[0].1.checksum, "{name}");
}

#[test]
fn a_point_line_names_its_window_band_and_figures() {
    let mut storage = Storage::new();
    let (name, p) = &POINTS[1];
    assert_eq!(*name, "half");
    let r = stereo_run::run_at::<_, SafePhase>(p, &mut storage.bufs(), &mut NoTicks).expect("runs");
    let mut out = String::new();
    stereo_run::write_point(&mut out, name, p, &r, |t| t).expect("writes");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 2, "{out}");
    assert!(lines[0].starts_with(&format!("checksum stereo@{name} 160x120 0x")));
    let band = p.band.map_or("-".to_string(), |b| b.to_string());
    assert!(
        lines[1].starts_with(&format!(
            "point stereo {name} 160x120 radius={} band={band} lr=derived paths=3 finest=1 phase=0 engine=",
            p.radius
        )),
        "{out}"
    );
    assert!(lines[1].contains(&format!("cells={}", r.report.cells)));
    for step in [
        "levels=",
        "filters=",
        "cells-votes=",
        "sgm=",
        "costs-picks=",
    ] {
        assert!(lines[1].contains(step), "{step} missing: {out}");
    }
}
