//! Coarse-to-fine search: the f32 reference of core's engine
//! (`protogist::stereo::c2f`, docs/STEREO.md).
//!
//! The pair is halved `k` times (2x2 box means of the RGB pixels). The
//! coarsest level searches every candidate `0..=⌈D / 2^k⌉`; each finer level
//! searches only `2·d_c ± radius` around the coarser level's argmax `d_c`
//! at the parent pixel `(x/2, y/2)` (before its OFF tests), for the left-
//! and the right-referenced maps alike, in windows of fixed length
//! ([`windows_from`]). Every level runs the same read-out
//! ([`DemParams::aggregation`]: box or SGM) with its own decoder.
//!
//! What it answers: whether the read-out keeps its accuracy when the fine
//! level scores only `2·radius + 1` candidates, the saving that a fast
//! engine needs (the decode is `groups x candidates` per pixel). Here every
//! candidate is still scored (the window acts on the decision and the SGM
//! paths only, see [`super::stereo_planes_in`]), so it measures accuracy,
//! not speed.

use super::{
    check, filters, stereo_planes_in, Decoder, DemParams, DisparityMapsF, OffReason, StereoError,
    Windows,
};
use protogist::disparity::{DisparityCell, U8F8};
use protogist::image::{ImageView, Rgb8};

/// An owned RGB image.
#[derive(Clone, Debug)]
struct Rgb {
    width: usize,
    height: usize,
    data: Vec<Rgb8>,
}

impl Rgb {
    fn of(v: &ImageView<'_, Rgb8>) -> Self {
        Self {
            width: v.width(),
            height: v.height(),
            data: v.rows().flatten().copied().collect(),
        }
    }

    /// 2x2 box means (rounded), `⌊w/2⌋ x ⌊h/2⌋`. Not `io::area_downscale`:
    /// for an odd side that averages over a non-integer ratio, and the
    /// windows need coarse pixel `(x/2, y/2)` to be exactly the parent.
    fn half(&self) -> Self {
        let (w, h) = (self.width / 2, self.height / 2);
        let at = |x: usize, y: usize| self.data[y * self.width + x];
        let mut data = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let q = [
                    at(2 * x, 2 * y),
                    at(2 * x + 1, 2 * y),
                    at(2 * x, 2 * y + 1),
                    at(2 * x + 1, 2 * y + 1),
                ];
                let mean = |f: fn(&Rgb8) -> u8| {
                    let s: u16 = q.iter().map(|p| u16::from(f(p))).sum();
                    ((s + 2) / 4) as u8
                };
                data.push(Rgb8::new(mean(|p| p.r), mean(|p| p.g), mean(|p| p.b)));
            }
        }
        Self {
            width: w,
            height: h,
            data,
        }
    }

    fn view(&self) -> ImageView<'_, Rgb8> {
        ImageView::new(&self.data, self.width, self.height, self.width)
            .expect("an owned image is consistent")
    }
}

/// `max_disp` of level `k`: `⌈D / 2^k⌉`.
pub fn level_max_disp(max_disp: u8, k: usize) -> u8 {
    let m = u32::from(max_disp).div_ceil(1 << k);
    u8::try_from(m).unwrap_or(u8::MAX)
}

/// The parameters of level `k`: `params` with `max_disp` [`level_max_disp`].
pub fn level_params(params: &DemParams, k: usize) -> DemParams {
    DemParams {
        max_disp: level_max_disp(params.max_disp, k),
        ..*params
    }
}

/// The fine windows from a coarse level's raw argmax maps (`wc x hc`) for
/// a `w x h` level searching `0..=max_disp`: every window holds
/// `n = min(2·radius + 1, max_disp + 1)` consecutive candidates, the ones
/// around `c = 2·d_c` shifted to fit the range
/// (`lo = min(c − radius, max_disp + 1 − n)`, not below 0), and a pixel
/// whose parent has no estimate gets the lowest window `0..n`. A fixed
/// window length is what an engine that stores only the window holds
/// (`protogist::stereo::c2f`).
pub fn windows_from(
    coarse: &DisparityMapsF,
    w: usize,
    h: usize,
    radius: usize,
    band: Option<usize>,
    max_disp: usize,
) -> Windows {
    let (wc, hc) = (coarse.width, coarse.height);
    let n = (2 * radius + 1).min(max_disp + 1);
    let map = |raw: &[Option<f32>]| -> Vec<Option<(usize, usize)>> {
        (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                let q = (y / 2).min(hc.saturating_sub(1)) * wc + (x / 2).min(wc.saturating_sub(1));
                let lo = raw.get(q).copied().flatten().map_or(0, |d| {
                    let c = (2.0 * d).round().max(0.0) as usize;
                    c.saturating_sub(radius).min(max_disp + 1 - n)
                });
                Some((lo, lo + n - 1))
            })
            .collect()
    };
    Windows {
        left: map(&coarse.left_raw),
        right: map(&coarse.right_raw),
        band,
    }
}

/// Runs the stage coarse to fine: `decoders[k]` is level `k`'s decoder
/// (`decoders[0]` for `params`, then `⌈D / 2^k⌉`), so `decoders.len() − 1`
/// coarse levels; `radius` is the fine window's half width, and `band`
/// (optional) limits a windowed pixel's decode to the groups whose shift is
/// within `band` px of its window's centre.
///
/// # Errors
/// [`StereoError`] as [`super::stereo`], for the full-size pair and for
/// every coarse level (too small, or a decoder of other parameters).
pub fn stereo_c2f(
    params: &DemParams,
    decoders: &[Decoder],
    left: &ImageView<'_, Rgb8>,
    right: &ImageView<'_, Rgb8>,
    radius: usize,
    band: Option<usize>,
) -> Result<DisparityMapsF, StereoError> {
    stereo_c2f_from(params, decoders, left, right, radius, band, 0)
}

/// [`stereo_c2f`] run down to level `finest` only (core's
/// `C2fParams::finest`): the levels below it are not run, and level
/// `finest`'s maps are spread over the frame by [`spread`] (each cell over
/// its `2^finest` block, disparities times `2^finest`).
///
/// # Errors
/// As [`stereo_c2f`], and [`StereoError::BadParams`] for `finest` above the
/// coarse levels.
pub fn stereo_c2f_from(
    params: &DemParams,
    decoders: &[Decoder],
    left: &ImageView<'_, Rgb8>,
    right: &ImageView<'_, Rgb8>,
    radius: usize,
    band: Option<usize>,
    finest: usize,
) -> Result<DisparityMapsF, StereoError> {
    if finest >= decoders.len().max(1) {
        return Err(StereoError::BadParams(
            "the finest level must be at most the coarse levels",
        ));
    }
    let Some(fine) = decoders.first() else {
        return Err(StereoError::BadParams("no decoder"));
    };
    check(params, fine, left.size(), right.size())?;
    let mut pyramid = vec![(Rgb::of(left), Rgb::of(right))];
    for (k, decoder) in decoders.iter().enumerate().skip(1) {
        let (l, r) = &pyramid[k - 1];
        let next = (l.half(), r.half());
        let size = (next.0.width, next.0.height);
        check(&level_params(params, k), decoder, size, size)?;
        pyramid.push(next);
    }
    let mut prior: Option<DisparityMapsF> = None;
    for (k, ((l, r), decoder)) in pyramid.iter().zip(decoders).enumerate().rev() {
        if k < finest {
            break;
        }
        let p = level_params(params, k);
        let windows = prior
            .as_ref()
            .map(|c| windows_from(c, l.width, l.height, radius, band, usize::from(p.max_disp)));
        let (lv, rv) = (l.view(), r.view());
        let maps = stereo_planes_in(
            &p,
            decoder,
            vec![filters::grey(&lv)],
            vec![filters::grey(&rv)],
            windows.as_ref(),
        );
        prior = Some(maps);
    }
    let mut maps = prior.ok_or(StereoError::BadParams("no level"))?;
    if finest > 0 {
        maps = spread(&maps, finest, left.size());
    }
    Ok(maps)
}

/// Level-`k` maps over the `w x h` frame: frame pixel `(x, y)` takes level
/// pixel `(min(x >> k, wk − 1), min(y >> k, hk − 1))`, its disparities
/// times `2^k`; the OFF counts are those of the frame's pixels (a level
/// vector shorter than `wk·hk` reads as OFF, `None`, for its missing
/// pixels).
pub fn spread(maps: &DisparityMapsF, k: usize, (w, h): (usize, usize)) -> DisparityMapsF {
    let (wk, hk) = (maps.width, maps.height);
    let scale = (1u32 << k) as f32;
    let src = |x: usize, y: usize| {
        (y >> k).min(hk.saturating_sub(1)) * wk + (x >> k).min(wk.saturating_sub(1))
    };
    let index: Vec<usize> = (0..w * h).map(|p| src(p % w, p / w)).collect();
    let times = |v: &[Option<f32>]| -> Vec<Option<f32>> {
        index
            .iter()
            .map(|&q| v.get(q).copied().flatten().map(|d| d * scale))
            .collect()
    };
    let mut out = DisparityMapsF {
        width: w,
        height: h,
        disparity: index
            .iter()
            .map(|&q| match maps.disparity.get(q).and_then(|c| c.get()) {
                Some(d) => DisparityCell::from_raw(U8F8::from_bits(
                    (u32::from(d.to_bits()) << k).min(u32::from(u16::MAX - 1)) as u16,
                )),
                None => DisparityCell::OFF,
            })
            .collect(),
        disparity_f32: times(&maps.disparity_f32),
        left_raw: times(&maps.left_raw),
        right_raw: times(&maps.right_raw),
        off_texture: 0,
        off_ambiguous: 0,
        off_inconsistent: 0,
        why_off: index
            .iter()
            .map(|&q| maps.why_off.get(q).copied().flatten())
            .collect(),
    };
    for why in out.why_off.iter().flatten() {
        match why {
            OffReason::Texture => out.off_texture += 1,
            OffReason::Ambiguous => out.off_ambiguous += 1,
            OffReason::Inconsistent => out.off_inconsistent += 1,
        }
    }
    out
}
