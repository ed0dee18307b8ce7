//! Colour channels (dem-spec §6, an opt-in experiment of the f32
//! reference): each channel is filtered with the same Gabor bank and the
//! binocular energies `A` and `X` are summed over channels (see
//! [`super::population::energies_level`]) before the read-out, which is
//! unchanged: decode cost stays, monocular and cross costs scale with the
//! number of channels.
//!
//! Why the sum needs no rescaling for the decoder: the read-out score is
//! `Σ R ℓ(d) / Σ R − ΣW(d)/mean ΣW` (`readout`), a ratio of two sums linear
//! in the responses, so any common factor of the energies cancels. Only the
//! texture test (`min_energy`, mean cell energy in grey levels²) sees the
//! scale. Channel weights are therefore chosen so that a neutral (grey)
//! image gives the grey energies in every mode — *grey-equivalent
//! normalisation* — and `min_energy` keeps its meaning:
//!
//! - `Rgb`: R, G and B with weight 1/3 each (the mean of the three channel
//!   energies); an image with R = G = B = g gives exactly the grey energies
//!   in exact arithmetic.
//! - `Luv`: CIELUV from core's formulas (`reference::conspicuity::convert`),
//!   scaled by 2.55 so that L* spans 0..255 like grey (L* is close to the
//!   sRGB code value of a neutral grey, both being perceptual scales),
//!   with weights `1` for L* and `chroma_weight` for u* and v*. A neutral
//!   image has u* = v* = 0, so only L* counts there.
//!
//! A weight `w_c` is applied as `√w_c` on the input plane: the filters are
//! linear and `A`, `X` quadratic, so the channel's energies scale by `w_c`.

use super::filters::{grey, Plane};
use super::DemParams;
use crate::reference::conspicuity::convert;
use protogist::image::{ImageView, Rgb8};

/// Which channels the DEM filters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Colour {
    /// Rec. 601 luma only (the model, and what core runs).
    #[default]
    Grey,
    /// R, G and B, weight 1/3 each.
    Rgb,
    /// 2.55·L*, 2.55·u*, 2.55·v*, weights 1, `chroma_weight`, `chroma_weight`.
    Luv,
}

impl Colour {
    /// Planes filtered per eye by `params` (1 or 3).
    pub fn channels(self, params: &DemParams) -> usize {
        match self {
            Self::Grey => 1,
            Self::Rgb => 3,
            Self::Luv if params.chroma_weight > 0.0 => 3,
            Self::Luv => 1,
        }
    }
}

/// Scale of CIELUV to grey-like levels: L* 0..100 → 0..255.
pub const LUV_SCALE: f32 = 2.55;

/// The weighted input planes of `img` for `params.colour` (see the module
/// notes); u*, v* are dropped when `chroma_weight` is 0.
pub fn planes(params: &DemParams, img: &ImageView<'_, Rgb8>) -> Vec<Plane> {
    let (width, height) = img.size();
    let plane = |f: &dyn Fn(Rgb8) -> f32| Plane {
        width,
        height,
        data: img.pixels().map(f).collect(),
    };
    match params.colour {
        Colour::Grey => vec![grey(img)],
        Colour::Rgb => {
            let s = (1.0f32 / 3.0).sqrt();
            vec![
                plane(&|p| s * f32::from(p.r)),
                plane(&|p| s * f32::from(p.g)),
                plane(&|p| s * f32::from(p.b)),
            ]
        }
        Colour::Luv => {
            let luv: Vec<[f32; 3]> = img.pixels().map(convert).collect();
            let channel = |c: usize, s: f32| Plane {
                width,
                height,
                data: luv.iter().map(|v| s * v[c]).collect(),
            };
            let mut out = vec![channel(0, LUV_SCALE)];
            if params.chroma_weight > 0.0 {
                let s = LUV_SCALE * params.chroma_weight.sqrt();
                out.extend([channel(1, s), channel(2, s)]);
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neutral_pixels_give_grey_like_planes() {
        let px: Vec<Rgb8> = [0u8, 60, 128, 200, 255]
            .iter()
            .map(|&g| Rgb8::new(g, g, g))
            .collect();
        let img = ImageView::packed(&px, 5, 1).unwrap();
        for colour in [Colour::Rgb, Colour::Luv] {
            let p = DemParams {
                colour,
                ..DemParams::default()
            };
            let planes = planes(&p, &img);
            assert_eq!(planes.len(), colour.channels(&p));
            if colour == Colour::Rgb {
                // Σ (√(1/3)·g)² = g².
                for (i, &g) in [0.0f32, 60.0, 128.0, 200.0, 255.0].iter().enumerate() {
                    let e: f32 = planes.iter().map(|q| q.data[i] * q.data[i]).sum();
                    assert!((e - g * g).abs() <= 1e-5 * g * g, "{e} vs {}", g * g);
                }
            } else {
                // u*, v* vanish on neutral pixels up to the rounding of
                // core's white point to 5 digits against its 4-digit matrix
                // (|Δu′|, |Δv′| < 3e-5: 13·100·3e-5·2.55 ≈ 0.1 level);
                // 2.55·L* spans 0..255.
                assert!(planes[1..]
                    .iter()
                    .all(|q| q.data.iter().all(|v| v.abs() < 0.2)));
                assert!(planes[0].data[0].abs() < 1e-3);
                assert!((planes[0].data[4] - 255.0).abs() < 0.05);
            }
        }
    }
}
