//! Named settings of `protogist stereo` (`--preset`), and how the command's
//! options become [`DemParams`]: each option given explicitly wins, then the
//! preset's value, then the model's default. Without a preset and without
//! options the parameters are exactly `DemParams::default()` (the read-out
//! core reproduces bit for bit).

use super::{StereoOptions, SGM_P1, SGM_P2, SGM_PATHS};
use crate::error::{HostError, Result};
use crate::reference::stereo::{Aggregation, Colour, DemParams};

/// A named setting of the read-out (f32 reference only).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// Chosen on the held-out Middlebury Motorcycle pair for both 160 px
    /// D32 and 320 px D64 (docs/STEREO.md, "Settings chosen on a held-out
    /// pair"): [`HELD_OUT`].
    HeldOut,
}

impl Preset {
    /// The preset's settings.
    pub fn settings(self) -> Settings {
        match self {
            Self::HeldOut => HELD_OUT,
        }
    }

    /// The preset's options, as on the command line.
    pub fn options(self) -> &'static str {
        match self {
            Self::HeldOut => HELD_OUT_OPTIONS,
        }
    }
}

/// The options of `--preset held-out`, as on the command line: chosen on
/// Motorcycle in the third round (docs/STEREO.md, "Settings chosen on a
/// held-out pair"), coarse to fine with the speckle filter.
pub const HELD_OUT_OPTIONS: &str = "--levels 1 --sgm --colour luv --chroma-weight 2 --paths 8 \
     --pool 0 --min-margin 1 --c2f 2 --c2f-band 2 --speckle 100 --speckle-range 1";

/// `--preset held-out`, the same as [`HELD_OUT_OPTIONS`].
pub const HELD_OUT: Settings = Settings {
    levels: Some(1),
    pool: Some(0),
    colour: Some(Colour::Luv),
    chroma_weight: Some(2.0),
    sgm: true,
    p1: None,
    p2: None,
    paths: Some(8),
    p2_ref_width: None,
    min_margin: Some(1.0),
    lr: None,
    lr_from_left: false,
    complete: false,
    c2f: Some(2),
    c2f_radius: None,
    c2f_band: Some(2),
    c2f_finest: None,
    c2f_phase: false,
    speckle: Some(100),
    speckle_range: Some(1.0),
};

/// Read-out settings that may be left unset (`None`: not given).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Settings {
    /// Pyramid levels.
    pub levels: Option<u8>,
    /// Score pooling radius.
    pub pool: Option<u8>,
    /// Input channels.
    pub colour: Option<Colour>,
    /// Weight of u*, v* (luv).
    pub chroma_weight: Option<f32>,
    /// Semi-global aggregation on.
    pub sgm: bool,
    /// SGM P1.
    pub p1: Option<f32>,
    /// SGM P2 (at the reference width, if one is set).
    pub p2: Option<f32>,
    /// SGM path set.
    pub paths: Option<u8>,
    /// P2 scales with the working width: P2 · width / this.
    pub p2_ref_width: Option<u32>,
    /// Ambiguity threshold.
    pub min_margin: Option<f32>,
    /// Left-right tolerance.
    pub lr: Option<f32>,
    /// Left-right check against the right map derived from the left sums.
    pub lr_from_left: bool,
    /// Complete the map over the conspicuity regions.
    pub complete: bool,
    /// Coarse-to-fine levels (0: off).
    pub c2f: Option<u8>,
    /// Half width of the coarse-to-fine windows.
    pub c2f_radius: Option<u8>,
    /// Band of the coarse-to-fine decode.
    pub c2f_band: Option<u8>,
    /// `--c2f-finest`.
    pub c2f_finest: Option<u8>,
    /// `--c2f-phase`.
    pub c2f_phase: bool,
    /// Largest island the speckle filter removes, px (0: off).
    pub speckle: Option<u32>,
    /// Join tolerance of the speckle filter, px.
    pub speckle_range: Option<f32>,
}

/// A coarse-to-fine search ([`crate::reference::stereo::c2f`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Search {
    /// Coarse levels (at least 1).
    pub levels: usize,
    /// Half width of the fine windows.
    pub radius: usize,
    /// Band of the fine decode (`None`: every group).
    pub band: Option<usize>,
    /// The finest level run (0: the full size), at most `levels`.
    pub finest: usize,
    /// The phase refinement of the output (`--c2f-phase`).
    pub phase: bool,
}

/// `--c2f-radius` default.
pub const C2F_RADIUS: u8 = 2;

impl Settings {
    /// Each unset field of `self` taken from `fallback`; SGM on if either is.
    pub fn or(self, fallback: Self) -> Self {
        Self {
            levels: self.levels.or(fallback.levels),
            pool: self.pool.or(fallback.pool),
            colour: self.colour.or(fallback.colour),
            chroma_weight: self.chroma_weight.or(fallback.chroma_weight),
            sgm: self.sgm || fallback.sgm,
            p1: self.p1.or(fallback.p1),
            p2: self.p2.or(fallback.p2),
            paths: self.paths.or(fallback.paths),
            p2_ref_width: self.p2_ref_width.or(fallback.p2_ref_width),
            min_margin: self.min_margin.or(fallback.min_margin),
            lr: self.lr.or(fallback.lr),
            lr_from_left: self.lr_from_left || fallback.lr_from_left,
            complete: self.complete || fallback.complete,
            c2f: self.c2f.or(fallback.c2f),
            c2f_radius: self.c2f_radius.or(fallback.c2f_radius),
            c2f_band: self.c2f_band.or(fallback.c2f_band),
            c2f_finest: self.c2f_finest.or(fallback.c2f_finest),
            c2f_phase: self.c2f_phase || fallback.c2f_phase,
            speckle: self.speckle.or(fallback.speckle),
            speckle_range: self.speckle_range.or(fallback.speckle_range),
        }
    }
}

/// The settings given explicitly on the command line.
fn explicit(opts: &StereoOptions) -> Settings {
    let r = &opts.readout;
    Settings {
        levels: opts.levels,
        pool: opts.pool,
        colour: opts.colour,
        chroma_weight: opts.chroma_weight,
        sgm: r.sgm,
        p1: r.p1,
        p2: r.p2,
        paths: r.paths,
        p2_ref_width: r.p2_ref_width,
        min_margin: r.min_margin,
        lr: r.lr,
        lr_from_left: r.lr_from_left,
        complete: opts.complete,
        c2f: r.c2f,
        c2f_radius: r.c2f_radius,
        c2f_band: r.c2f_band,
        c2f_finest: r.c2f_finest,
        c2f_phase: r.c2f_phase,
        speckle: r.speckle,
        speckle_range: r.speckle_range,
    }
}

/// The settings in force: explicit options, then the preset's.
fn settings(opts: &StereoOptions) -> Settings {
    let preset = opts
        .readout
        .preset
        .map(Preset::settings)
        .unwrap_or_default();
    explicit(opts).or(preset)
}

/// Whether `protogist stereo` completes the map (`--complete` or the
/// preset's).
pub fn complete(opts: &StereoOptions) -> bool {
    settings(opts).complete
}

/// `--speckle-range` default, px.
pub const SPECKLE_RANGE: f32 = 1.0;

/// The speckle filter in force: the largest island removed, px, and the
/// join tolerance, px (`None`: off).
///
/// # Errors
/// [`HostError::InvalidArgument`] for `--speckle-range` given while the
/// filter is off, or a range that is negative or not finite.
pub fn speckle(opts: &StereoOptions) -> Result<Option<(usize, f32)>> {
    let s = settings(opts);
    let range = s.speckle_range.unwrap_or(SPECKLE_RANGE);
    if !(range.is_finite() && range >= 0.0) {
        return Err(HostError::InvalidArgument {
            name: "speckle-range",
            reason: "must be a finite number of px, at least 0".into(),
        });
    }
    match s.speckle.filter(|&n| n > 0) {
        Some(n) => Ok(Some((n as usize, range))),
        None if explicit(opts).speckle_range.is_some() => Err(HostError::InvalidArgument {
            name: "speckle-range",
            reason: "needs --speckle (or a preset with it)".into(),
        }),
        None => Ok(None),
    }
}

/// The coarse-to-fine search in force (`None`: the full search).
///
/// # Errors
/// [`HostError::InvalidArgument`] for `--c2f-radius`, `--c2f-band` or
/// `--c2f-finest` without `--c2f` (or a preset with it), and for
/// `--c2f-finest` above `--c2f`.
pub fn search(opts: &StereoOptions) -> Result<Option<Search>> {
    let s = settings(opts);
    match s.c2f.filter(|&k| k > 0) {
        Some(k) if s.c2f_finest.is_some_and(|f| f > k) => Err(HostError::InvalidArgument {
            name: "c2f-finest",
            reason: format!("must be at most --c2f ({k})"),
        }),
        Some(k) => Ok(Some(Search {
            levels: usize::from(k),
            radius: usize::from(s.c2f_radius.unwrap_or(C2F_RADIUS)),
            band: s.c2f_band.map(usize::from),
            finest: usize::from(s.c2f_finest.unwrap_or(0)),
            phase: s.c2f_phase,
        })),
        None => {
            let c2f_only = [
                ("c2f-radius", s.c2f_radius.is_some()),
                ("c2f-band", s.c2f_band.is_some()),
                ("c2f-finest", s.c2f_finest.is_some()),
                ("c2f-phase", s.c2f_phase),
            ];
            match c2f_only.into_iter().find(|&(_, given)| given) {
                Some((name, _)) => Err(HostError::InvalidArgument {
                    name,
                    reason: "needs --c2f (or a preset with it)".into(),
                }),
                None => Ok(None),
            }
        }
    }
}

/// The parameters of `protogist stereo` at working width `width`: explicit
/// options, then the preset's, then `DemParams::default()`.
///
/// # Errors
/// [`HostError::InvalidArgument`] for SGM options without SGM, or a zero
/// reference width.
pub fn params_for(opts: &StereoOptions, width: usize) -> Result<DemParams> {
    let s = settings(opts);
    let mut params = DemParams {
        max_disp: opts.max_disp,
        ..DemParams::default()
    };
    if let Some(r) = s.pool {
        params.pool_radius = r;
    }
    if let Some(l) = s.levels {
        params.levels = l;
    }
    if let Some(r) = opts.refine {
        params.refine_radius = r;
    }
    if let Some(m) = s.min_margin {
        params.min_margin = m;
    }
    if let Some(t) = s.lr {
        params.lr_tolerance = t;
    }
    params.lr_from_left = s.lr_from_left;
    if let Some(c) = s.colour {
        params.colour = c;
    }
    if let Some(c) = s.chroma_weight {
        params.chroma_weight = c;
    }
    if s.sgm {
        let mut p2 = s.p2.unwrap_or(SGM_P2);
        if let Some(w0) = s.p2_ref_width {
            if w0 == 0 {
                return Err(HostError::InvalidArgument {
                    name: "p2-ref-width",
                    reason: "must be at least 1".into(),
                });
            }
            // An image-size ratio: exact enough in f32 for any width.
            #[allow(clippy::cast_precision_loss)]
            let ratio = width as f32 / w0 as f32;
            p2 *= ratio;
        }
        params.aggregation = Aggregation::Sgm {
            p1: s.p1.unwrap_or(SGM_P1),
            p2,
            paths: s.paths.unwrap_or(SGM_PATHS),
        };
    } else {
        let sgm_only = [
            ("p1", s.p1.is_some()),
            ("p2", s.p2.is_some()),
            ("paths", s.paths.is_some()),
            ("p2-ref-width", s.p2_ref_width.is_some()),
            ("lr-from-left", s.lr_from_left),
        ];
        if let Some((name, _)) = sgm_only.into_iter().find(|&(_, given)| given) {
            return Err(HostError::InvalidArgument {
                name,
                reason: "needs --sgm (or a preset with SGM)".into(),
            });
        }
    }
    Ok(params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command};
    use clap::Parser;

    fn parse(extra: &str) -> StereoOptions {
        let base = "protogist stereo --left l.png --right r.png --out o --max-disp 32";
        let args: Vec<&str> = base
            .split_whitespace()
            .chain(extra.split_whitespace())
            .collect();
        match Cli::try_parse_from(args).unwrap().command {
            Some(Command::Stereo(o)) => o,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn no_options_give_the_default_parameters() {
        let o = parse("");
        let expected = DemParams {
            max_disp: 32,
            ..DemParams::default()
        };
        for w in [160, 320] {
            assert_eq!(params_for(&o, w).unwrap(), expected);
        }
        assert!(!complete(&o));
    }

    #[test]
    fn the_preset_is_its_options_and_explicit_options_override_it() {
        let (preset, spelled) = (parse("--preset held-out"), parse(HELD_OUT_OPTIONS));
        for w in [160, 320] {
            assert_eq!(
                params_for(&preset, w).unwrap(),
                params_for(&spelled, w).unwrap()
            );
        }
        assert!(!complete(&preset));
        let p = params_for(&preset, 320).unwrap();
        assert_eq!((p.levels, p.pool_radius, p.colour), (1, 0, Colour::Luv));
        assert_eq!(p.min_margin, 1.0);
        assert_eq!(
            p.aggregation,
            Aggregation::Sgm {
                p1: SGM_P1,
                p2: SGM_P2,
                paths: 8
            }
        );
        let c2f = Search {
            levels: 2,
            radius: 2,
            band: Some(2),
            finest: 0,
            phase: false,
        };
        assert_eq!(speckle(&preset).unwrap(), Some((100, 1.0)));
        assert_eq!(speckle(&spelled).unwrap(), Some((100, 1.0)));
        assert_eq!(
            speckle(&parse("--preset held-out --speckle 0")).unwrap(),
            None
        );
        assert_eq!(search(&preset).unwrap(), Some(c2f));
        assert_eq!(search(&spelled).unwrap(), Some(c2f));
        assert_eq!(
            search(&parse("--preset held-out --c2f-radius 3")).unwrap(),
            Some(Search { radius: 3, ..c2f })
        );
        let o = parse("--preset held-out --pool 1 --colour grey --p2 16 --paths 5");
        let q = params_for(&o, 160).unwrap();
        assert_eq!((q.levels, q.pool_radius, q.colour), (1, 1, Colour::Grey));
        assert_eq!(
            q.aggregation,
            Aggregation::Sgm {
                p1: SGM_P1,
                p2: 16.0,
                paths: 5
            }
        );
    }

    #[test]
    fn sgm_options_without_sgm_are_typed_errors() {
        for extra in [
            "--p1 1",
            "--p2 4",
            "--paths 8",
            "--p2-ref-width 160",
            "--lr-from-left",
        ] {
            let e = params_for(&parse(extra), 160).unwrap_err();
            assert!(
                matches!(e, HostError::InvalidArgument { .. }),
                "{extra}: {e}"
            );
        }
        let e = params_for(&parse("--sgm --p2-ref-width 0"), 160).unwrap_err();
        assert!(matches!(e, HostError::InvalidArgument { .. }), "{e}");
        // Without a reference width P2 is as given at every width.
        let p = params_for(&parse("--sgm --p2 4"), 320).unwrap();
        assert!(matches!(p.aggregation, Aggregation::Sgm { p2, .. } if p2 == 4.0));
    }

    #[test]
    fn coarse_to_fine_options_without_c2f_are_typed_errors() {
        assert_eq!(search(&parse("")).unwrap(), None);
        assert_eq!(search(&parse("--c2f 0")).unwrap(), None);
        for extra in [
            "--c2f-radius 1",
            "--c2f-band 2",
            "--c2f 0 --c2f-band 2",
            "--c2f-finest 1",
            "--c2f 2 --c2f-finest 3",
        ] {
            let e = search(&parse(extra)).unwrap_err();
            assert!(
                matches!(e, HostError::InvalidArgument { .. }),
                "{extra}: {e}"
            );
        }
        let s = search(&parse("--c2f 1")).unwrap();
        assert_eq!(
            s,
            Some(Search {
                levels: 1,
                radius: usize::from(C2F_RADIUS),
                band: None,
                finest: 0,
                phase: false,
            })
        );
        let s = search(&parse("--c2f 2 --c2f-finest 2")).unwrap();
        assert_eq!(s.map(|s| s.finest), Some(2));
    }

    #[test]
    fn speckle_options_are_checked() {
        assert_eq!(speckle(&parse("")).unwrap(), None);
        assert_eq!(
            speckle(&parse("--speckle 20")).unwrap(),
            Some((20, SPECKLE_RANGE))
        );
        assert_eq!(
            speckle(&parse("--speckle 20 --speckle-range 2.5")).unwrap(),
            Some((20, 2.5))
        );
        for extra in [
            "--speckle-range 2",
            "--speckle 0 --speckle-range 2",
            "--speckle 20 --speckle-range -1",
            "--speckle 20 --speckle-range NaN",
            "--speckle 20 --speckle-range inf",
        ] {
            let e = speckle(&parse(extra)).unwrap_err();
            assert!(
                matches!(
                    e,
                    HostError::InvalidArgument {
                        name: "speckle-range",
                        ..
                    }
                ),
                "{extra}: {e}"
            );
        }
    }
}
