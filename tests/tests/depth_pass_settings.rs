//! The depth pass's settings (`DepthPass`, `Refine`, `Holes`): each out
//! of range is a typed error, and the least area in pixels.

use protogist::segment::{DepthPass, Holes, Ratio, Refine, SegmentError, MAX_GROUND_BAND};

#[test]
fn the_settings_are_checked() {
    assert!(DepthPass::DEFAULT.validate().is_ok());
    let bad = [
        DepthPass {
            rise: 0,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            rise: MAX_GROUND_BAND + 1,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            radius: MAX_GROUND_BAND + 1,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            closing: 9,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            searches: 0,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            searches: 17,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            clearance: 17,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            min_area: Ratio::new(1, 0),
            ..DepthPass::DEFAULT
        },
        DepthPass {
            min_area: Ratio::new(2, 1),
            ..DepthPass::DEFAULT
        },
        DepthPass {
            refine: Some(Refine {
                core: 9,
                ..Refine::DEFAULT
            }),
            ..DepthPass::DEFAULT
        },
        DepthPass {
            refine: Some(Refine {
                reach: 9,
                ..Refine::DEFAULT
            }),
            ..DepthPass::DEFAULT
        },
        DepthPass {
            refine: Some(Refine {
                ring: 0,
                ..Refine::DEFAULT
            }),
            ..DepthPass::DEFAULT
        },
    ];
    let holes = [
        Holes {
            band: 0,
            ..Holes::DEFAULT
        },
        Holes {
            band: 9,
            ..Holes::DEFAULT
        },
        Holes {
            gap: 9,
            ..Holes::DEFAULT
        },
        Holes {
            ring: 0,
            ..Holes::DEFAULT
        },
        Holes {
            ring: 9,
            ..Holes::DEFAULT
        },
        Holes {
            opening: 5,
            ..Holes::DEFAULT
        },
        Holes {
            min_area: Ratio::new(1, 0),
            ..Holes::DEFAULT
        },
        Holes {
            min_area: Ratio::new(2, 1),
            ..Holes::DEFAULT
        },
    ];
    let bad = bad.into_iter().chain(holes.map(|h| DepthPass {
        holes: Some(h),
        ..DepthPass::DEFAULT
    }));
    for b in bad {
        assert!(
            matches!(b.validate(), Err(SegmentError::BadParams(_))),
            "{b:?}"
        );
    }
    // 1/64 of 160x120 is 300 px; of 7x7, 49/64 rounded up.
    assert_eq!(DepthPass::DEFAULT.least_area(160, 120), 300);
    assert_eq!(DepthPass::DEFAULT.least_area(7, 7), 1);
}
