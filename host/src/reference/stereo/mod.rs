//! f32 reference of the stereo stage: the disparity energy model (DEM)
//! with a trained decoding population (`docs`: `dem-spec.md` §2–6).
//!
//! ```text
//! left, right ─► grey ─► ↓2 pyramid ─► complex Gabor bank (per eye, once)
//!   ─► binocular energies A, X per (level, carrier, shift) ─► Poisson
//!   log-likelihood per disparity (trained templates) ─► box pooling
//!   [─► semi-global aggregation, opt-in, `sgm`] ─► argmax + parabola
//!   ─► OFF tests (texture, ambiguity, left-right)
//! ```
//!
//! Names and argument order are what the fixed-point `protogist::stereo`
//! uses; core's engine is the coarse-to-fine search with SGM ([`c2f`],
//! `levels` 1, `pool_radius` 0). Disparity is left-referenced, `d = x_L − x_R ≥ 0`, in pixels.

pub mod c2f;
pub mod filters;
pub mod phase;
pub mod population;
pub mod readout;
pub mod sgm;
pub mod table;
pub mod train;

use protogist::disparity::{Disparity, DisparityCell};
use protogist::image::{ImageView, Rgb8};

pub use sgm::Aggregation;
pub use train::{train, Decoder};

/// Every parameter of the model, with the spec's defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DemParams {
    /// Largest disparity searched, px; candidates are `0..=max_disp`.
    /// Default 15 (160x120 frames).
    pub max_disp: u8,
    /// Carrier orientations, evenly spread around horizontal: 3 gives
    /// −45°, 0°, 45°. Default 3.
    pub carriers: u8,
    /// Pyramid levels; level `l` has effective wavelength `λ·2^l`.
    /// Default 2 (λ 4 and 8).
    pub levels: u8,
    /// Wavelength on every level, px. Default 4.
    pub wavelength: f32,
    /// Envelope σ / λ (isotropic). Default 0.56 (one octave).
    pub sigma_per_wavelength: f32,
    /// Kernel radius, taps `−r..=r`. Default 7 (⌈3σ⌉ at λ = 4).
    pub radius: u8,
    /// Position-shift step in pixels of each level. Default 2 (λ/2).
    pub shift_step: u8,
    /// Score pooling box radius, px (0: none). Default 2 (5x5).
    pub pool_radius: u8,
    /// OFF below this mean cell energy (grey levels², per cell and pooled
    /// pixel): no texture. Default 0.1.
    pub min_energy: f32,
    /// OFF when the best score beats the best score more than 1 px away by
    /// less than this (normalised score units). Default 0.
    pub min_margin: f32,
    /// Left-right check: OFF when `|d_L(x) − d_R(x − d_L)|` exceeds this,
    /// px; negative disables the check. Default 1.
    pub lr_tolerance: f32,
    /// Left-right check against the right map derived from the left map's
    /// SGM sums (SGBM's; core's `LeftRight::Derived`), not the
    /// right-referenced read-out (needs SGM). Default false.
    pub lr_from_left: bool,
    /// Spatial aggregation of the scores: box pooling only (default) or
    /// followed by semi-global aggregation (see `sgm`; core's engine).
    pub aggregation: Aggregation,
    /// Training: seed of the random-dot stereograms.
    pub train_seed: u64,
    /// Training: images per disparity. Default 4.
    pub train_images: u8,
    /// Training: interior width of each image, px. Default 64.
    pub train_width: u8,
    /// Training: interior height of each image, px. Default 48.
    pub train_height: u8,
}

impl Default for DemParams {
    fn default() -> Self {
        Self {
            max_disp: 15,
            carriers: 3,
            levels: 2,
            wavelength: 4.0,
            sigma_per_wavelength: 0.56,
            radius: 7,
            shift_step: 2,
            pool_radius: 2,
            min_energy: 0.1,
            min_margin: 0.0,
            lr_tolerance: 1.0,
            lr_from_left: false,
            aggregation: Aggregation::Box,
            train_seed: 0x0de1_5eed,
            train_images: 4,
            train_width: 64,
            train_height: 48,
        }
    }
}

impl DemParams {
    /// Smallest width and height the filters support: one kernel at the
    /// coarsest level.
    pub fn min_size(&self) -> usize {
        (2 * usize::from(self.radius) + 1) << usize::from(self.levels.max(1) - 1)
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`StereoError::BadParams`] naming the first bad one.
    pub fn check(&self) -> Result<(), StereoError> {
        let bad = |ok: bool, what| {
            if ok {
                Ok(())
            } else {
                Err(StereoError::BadParams(what))
            }
        };
        bad(self.carriers >= 1, "carriers must be at least 1")?;
        bad((1..=4).contains(&self.levels), "levels must be 1..=4")?;
        bad(
            self.wavelength >= 2.0 && self.wavelength <= 64.0,
            "wavelength must be 2..=64",
        )?;
        bad(
            self.sigma_per_wavelength > 0.1 && self.sigma_per_wavelength < 4.0,
            "sigma_per_wavelength must be in (0.1, 4)",
        )?;
        bad(self.radius >= 1, "radius must be at least 1")?;
        bad(self.shift_step >= 1, "shift_step must be at least 1")?;
        bad(self.min_energy >= 0.0, "min_energy must be >= 0")?;
        bad(self.train_images >= 1, "train_images must be at least 1")?;
        if let Aggregation::Sgm { p1, p2, paths } = self.aggregation {
            bad(
                p1 >= 0.0 && p2 >= p1 && p2.is_finite(),
                "SGM penalties must satisfy 0 <= p1 <= p2 < inf",
            )?;
            bad(sgm::directions(paths).is_some(), "SGM paths must be 3 or 5")?;
        } else {
            bad(!self.lr_from_left, "lr_from_left needs SGM aggregation")?;
        }
        bad(
            self.train_width >= 1 && self.train_height >= 1,
            "training size must be at least 1x1",
        )
    }
}

/// What a decoder was trained for: core's layout type, one definition for
/// the table format of both crates.
pub use protogist::stereo::table::DemLayout;

/// The layout of `params`: the parameters that shape the population, with
/// the real ones quantised as the table stores them.
pub fn layout_of(params: &DemParams) -> DemLayout {
    let q = |v: f32, bits: i32| (v * 2f32.powi(bits)).round().clamp(0.0, 65535.0) as u16;
    DemLayout {
        max_disp: params.max_disp,
        levels: params.levels,
        carriers: params.carriers,
        shift_step: params.shift_step,
        radius: params.radius,
        wavelength_q8: q(params.wavelength, 8),
        sigma_q12: q(params.sigma_per_wavelength, 12),
    }
}

/// Why the stereo stage rejected its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum StereoError {
    /// Left and right differ in size.
    #[error("left is {}x{} but right is {}x{}", left.0, left.1, right.0, right.1)]
    SizeMismatch {
        /// Left size.
        left: (usize, usize),
        /// Right size.
        right: (usize, usize),
    },
    /// An image smaller than one filter at the coarsest level.
    #[error("{}x{} is smaller than the filter support ({min}x{min})", got.0, got.1)]
    TooSmall {
        /// The smallest width and height.
        min: usize,
        /// The image size.
        got: (usize, usize),
    },
    /// `max_disp` not below the width.
    #[error("max disparity {max_disp} must be below the image width {width}")]
    MaxDispTooLarge {
        /// The maximum disparity.
        max_disp: u8,
        /// The width.
        width: usize,
    },
    /// The decoder was trained for other parameters.
    #[error("the decoder was trained for other parameters (max_disp {got}, expected {expected})")]
    DecoderMismatch {
        /// The decoder's max_disp.
        got: u8,
        /// The parameters' max_disp.
        expected: u8,
    },
    /// A parameter out of range.
    #[error("bad stereo parameters: {0}")]
    BadParams(&'static str),
}

/// The outputs of the stage.
#[derive(Clone, Debug, PartialEq)]
pub struct DisparityMapsF {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// The result, left-referenced, U8F8 px or OFF.
    pub disparity: Vec<DisparityCell>,
    /// The same in f32 (`None`: OFF).
    pub disparity_f32: Vec<Option<f32>>,
    /// Left-referenced argmax before the OFF tests (`None`: no energy).
    pub left_raw: Vec<Option<f32>>,
    /// Right-referenced argmax (`None`: no energy).
    pub right_raw: Vec<Option<f32>>,
    /// Pixels OFF for lack of texture.
    pub off_texture: usize,
    /// Pixels OFF as ambiguous.
    pub off_ambiguous: usize,
    /// Pixels OFF by the left-right check.
    pub off_inconsistent: usize,
    /// Which of the read-out's OFF tests each pixel failed (`None`: it
    /// passed them all; like the counts, not changed by later steps such as
    /// the phase refinement).
    pub why_off: Vec<Option<OffReason>>,
}

/// Which of the read-out's OFF tests a pixel failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OffReason {
    /// Too little evidence (the texture test).
    Texture,
    /// The margin test.
    Ambiguous,
    /// The left-right check.
    Inconsistent,
}

/// Checks the inputs of [`stereo`].
fn check(
    params: &DemParams,
    decoder: &Decoder,
    l: (usize, usize),
    r: (usize, usize),
) -> Result<(), StereoError> {
    params.check()?;
    if l != r {
        return Err(StereoError::SizeMismatch { left: l, right: r });
    }
    if decoder.layout != layout_of(params)
        || decoder.weights.len() != decoder.layout.groups() * decoder.disparities()
    {
        return Err(StereoError::DecoderMismatch {
            got: decoder.layout.max_disp,
            expected: params.max_disp,
        });
    }
    let min = params.min_size();
    if l.0 < min || l.1 < min {
        return Err(StereoError::TooSmall { min, got: l });
    }
    if usize::from(params.max_disp) >= l.0 {
        return Err(StereoError::MaxDispTooLarge {
            max_disp: params.max_disp,
            width: l.0,
        });
    }
    Ok(())
}

/// Runs the stage on an RGB pair (converted to grey).
///
/// # Errors
/// [`StereoError`] for mismatched sizes, too small images, `max_disp` not
/// below the width, a decoder of other parameters, or bad parameters.
pub fn stereo(
    params: &DemParams,
    decoder: &Decoder,
    left: &ImageView<'_, Rgb8>,
    right: &ImageView<'_, Rgb8>,
) -> Result<DisparityMapsF, StereoError> {
    check(params, decoder, left.size(), right.size())?;
    Ok(stereo_grey(
        params,
        decoder,
        filters::grey(left),
        filters::grey(right),
    ))
}

/// Runs the stage on grey planes of equal size (sizes checked by the
/// caller, see [`stereo`]).
pub fn stereo_grey(
    params: &DemParams,
    decoder: &Decoder,
    left: filters::Plane,
    right: filters::Plane,
) -> DisparityMapsF {
    stereo_planes(params, decoder, vec![left], vec![right])
}

/// Runs the stage on one or more channel planes per eye, all of one size
/// (checked by the caller), energies summed over channels.
pub fn stereo_planes(
    params: &DemParams,
    decoder: &Decoder,
    left: Vec<filters::Plane>,
    right: Vec<filters::Plane>,
) -> DisparityMapsF {
    stereo_planes_in(params, decoder, left, right, None)
}

/// A search window of candidates `lo..=hi` per pixel (`None`: the whole
/// range), for the left- and the right-referenced maps ([`c2f`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Windows {
    /// Left-referenced windows, row-major.
    pub left: Vec<Option<(usize, usize)>>,
    /// Right-referenced windows, row-major.
    pub right: Vec<Option<(usize, usize)>>,
    /// Decode a pixel with a window only from the groups whose shift is
    /// within this many px of the window's centre
    /// ([`readout::scores_banded`]; `None`: every group).
    pub band: Option<usize>,
}

/// [`stereo_planes`] with the candidates of each pixel restricted to its
/// window (`windows`, sized `width x height`; `None` or a missing entry:
/// every candidate). Scores are still computed for every candidate; only
/// the decision and the SGM paths see the window.
pub fn stereo_planes_in(
    params: &DemParams,
    decoder: &Decoder,
    left: Vec<filters::Plane>,
    right: Vec<filters::Plane>,
    windows: Option<&Windows>,
) -> DisparityMapsF {
    let (w, h) = left.first().map_or((0, 0), |p| (p.width, p.height));
    let (ml, mr) = (
        filters::monocular_planes(params, left),
        filters::monocular_planes(params, right),
    );
    let r = usize::from(params.pool_radius);
    // Scores, box counts, and (banded) the groups voting per pixel of each
    // map; without a band every group votes everywhere.
    let (sl, sr, count, voters) = match windows.and_then(|ws| ws.band.map(|b| (ws, b))) {
        Some((ws, band)) => {
            let (sl, sr, voters) =
                readout::scores_banded(params, decoder, &ml, &mr, w, h, ws, band);
            let mut count = vec![1.0f32; w * h];
            readout::box_sum(&mut count, w, h, 1, r);
            (sl, sr, count, Some(voters))
        }
        None => {
            let (mut sl, mut sr) = readout::scores(params, decoder, &ml, &mr, w, h);
            let count = readout::pool(&mut sl, r);
            readout::pool(&mut sr, r);
            (sl, sr, count, None)
        }
    };
    let all_groups = decoder.layout.groups() as f32;
    let groups_at = |eye: usize, p: usize| {
        voters
            .as_ref()
            .and_then(|v| v.get(eye)?.get(p).copied())
            .unwrap_or(all_groups)
    };
    let n = decoder.disparities();
    // Margins with SGM are per path, in units of a pixel's mean cost gap.
    let per_path = match params.aggregation {
        Aggregation::Sgm { paths, .. } => sgm::directions(paths).map_or(1, <[_]>::len) as f32,
        Aggregation::Box => 1.0,
    };
    // With `lr_from_left`, the right-referenced map of the check comes from
    // the left map's SGM sums (SGBM's `disp2`): for each right pixel, the
    // candidate of least sum over the left pixels that map onto it.
    let derived = std::cell::RefCell::new(None::<Vec<Option<f32>>>);
    let picks = |s: &readout::Scores,
                 top: &dyn Fn(usize) -> usize,
                 win: &[Option<(usize, usize)>],
                 eye: usize|
     -> Vec<Option<readout::Pick>> {
        let window = |p: usize| win.get(p).copied().flatten();
        // The decision window: `lo..=hi` within `0..=top` (`None`: the
        // window lies wholly beyond `top`, no estimate).
        let range = |p: usize| {
            let t = top(p).min(n - 1);
            window(p).map_or(Some((0, t)), |(lo, hi)| {
                (lo <= t).then_some((lo, hi.min(t)))
            })
        };
        match params.aggregation {
            Aggregation::Box => (0..w * h)
                .map(|p| {
                    let (raw, total) = (&s.raw[p * n..(p + 1) * n], s.total[p]);
                    let (lo, hi) = range(p).filter(|_| total > 0.0)?;
                    Some(readout::pick_in(lo, hi, |d| {
                        raw[d] / total - decoder.bias[d]
                    }))
                })
                .collect(),
            Aggregation::Sgm { p1, p2, paths } => {
                let evidence =
                    |p: usize| s.total[p] >= params.min_energy * 4.0 * groups_at(eye, p) * count[p];
                let cost = sgm::costs_in(s, &decoder.bias, evidence, top, window);
                let sum = sgm::aggregate(&cost, w, h, n, paths, p1, p2);
                if eye == 0 && params.lr_from_left {
                    let mut best = vec![None::<(f32, usize)>; w * h];
                    for p in 0..w * h {
                        let Some((lo, hi)) = range(p).filter(|_| s.total[p] > 0.0) else {
                            continue;
                        };
                        for d in lo..=hi.min(p % w) {
                            let (q, c) = (p - d, sum[p * n + d]);
                            if best[q].is_none_or(|(b, _)| c < b) {
                                best[q] = Some((c, d));
                            }
                        }
                    }
                    *derived.borrow_mut() =
                        Some(best.iter().map(|o| o.map(|(_, d)| d as f32)).collect());
                }
                (0..w * h)
                    .map(|p| {
                        let (lo, hi) = range(p).filter(|_| s.total[p] > 0.0)?;
                        let k = readout::pick_in(lo, hi, |d| -sum[p * n + d]);
                        Some(readout::Pick {
                            margin: k.margin / per_path,
                            ..k
                        })
                    })
                    .collect()
            }
        }
    };
    let none = Vec::new();
    let (wl, wr) = windows.map_or((&none, &none), |ws| (&ws.left, &ws.right));
    let (left_picks, right_picks) = (
        picks(&sl, &|p| p % w, wl, 0),
        picks(&sr, &|p| w - 1 - p % w, wr, 1),
    );
    let right_raw: Vec<Option<f32>> = derived
        .into_inner()
        .unwrap_or_else(|| right_picks.iter().map(|k| k.map(|k| k.disparity)).collect());
    let mut out = DisparityMapsF {
        width: w,
        height: h,
        disparity: vec![DisparityCell::OFF; w * h],
        disparity_f32: vec![None; w * h],
        left_raw: left_picks.iter().map(|k| k.map(|k| k.disparity)).collect(),
        right_raw,
        off_texture: 0,
        off_ambiguous: 0,
        off_inconsistent: 0,
        why_off: vec![None; w * h],
    };
    for (p, pick) in left_picks.iter().enumerate() {
        let energy = sl.total[p] / (4.0 * groups_at(0, p) * count[p]);
        let Some(pick) = pick.filter(|_| energy >= params.min_energy && energy > 0.0) else {
            out.off_texture += 1;
            out.why_off[p] = Some(OffReason::Texture);
            continue;
        };
        if pick.margin < params.min_margin {
            out.off_ambiguous += 1;
            out.why_off[p] = Some(OffReason::Ambiguous);
            continue;
        }
        let d = pick.disparity;
        if params.lr_tolerance >= 0.0 {
            let xr = (p % w) as isize - d.round() as isize;
            let back = (xr >= 0)
                .then(|| out.right_raw[p - (p % w) + xr as usize])
                .flatten();
            if back.is_none_or(|b| (b - d).abs() > params.lr_tolerance) {
                out.off_inconsistent += 1;
                out.why_off[p] = Some(OffReason::Inconsistent);
                continue;
            }
        }
        out.disparity_f32[p] = Some(d);
        out.disparity[p] = DisparityCell::on(
            Disparity::saturating_from_num(d).min(Disparity::from_bits(u16::MAX - 1)),
        )
        .unwrap_or(DisparityCell::OFF);
    }
    out
}
