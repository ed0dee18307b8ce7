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
}

/// The options of `--preset held-out`, as on the command line.
pub const HELD_OUT_OPTIONS: &str =
    "--levels 1 --sgm --paths 8 --colour luv --chroma-weight 2 --pool 1 --p2 16";

/// `--preset held-out`, the same as [`HELD_OUT_OPTIONS`].
pub const HELD_OUT: Settings = Settings {
    levels: Some(1),
    pool: Some(1),
    colour: Some(Colour::Luv),
    chroma_weight: Some(2.0),
    sgm: true,
    p1: None,
    p2: Some(16.0),
    paths: Some(8),
    p2_ref_width: None,
    min_margin: None,
    lr: None,
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
}

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
    }
}

/// The parameters of `protogist stereo` at working width `width`: explicit
/// options, then the preset's, then `DemParams::default()`.
///
/// # Errors
/// [`HostError::InvalidArgument`] for SGM options without SGM, or a zero
/// reference width.
pub fn params_for(opts: &StereoOptions, width: usize) -> Result<DemParams> {
    let preset = opts.readout.preset.map(Preset::settings).unwrap_or_default();
    let s = explicit(opts).or(preset);
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
