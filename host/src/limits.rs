//! Sizes, parameters and memory checked before any allocation or
//! training.
//!
//! A command that works on frames states the memory it will need, from the
//! working size (read from the input's header, not its pixels), the core's
//! `const fn`s and the model's shape, and refuses to start above a limit:
//! [`DEFAULT_MAX_MEMORY`], or `--max-memory MIB` (a flag of every command).
//! The same pass rejects parameters that can only fail later (a largest
//! disparity not below the working width, a frame over the core's
//! [`MAX_DIM`], more hidden units than the model blob can hold), so no
//! decoder is trained and no buffer allocated for a run that cannot finish.
//!
//! The f32 reference's estimate ([`dem_bytes`]) is an upper bound of its
//! planes: per pixel, the input planes and complex filter responses of
//! both eyes at every level and carrier, the read-out's scores of every
//! disparity for both eyes (four more copies with SGM), and the maps.

use crate::error::{HostError, Result};
use crate::reference::stereo::{Aggregation, DemParams, StereoError};
use protogist::image::MAX_DIM;
use std::path::Path;

/// Memory a command may plan to use unless `--max-memory` says otherwise:
/// 4 GiB.
pub const DEFAULT_MAX_MEMORY: u64 = 4 << 30;

/// Largest hidden layer a model blob can describe (its header holds a
/// `u16`).
pub const MAX_HIDDEN: usize = u16::MAX as usize;

/// The memory limit in bytes for `--max-memory` in MiB (`None`: the
/// default).
pub fn limit_bytes(max_memory_mib: Option<u64>) -> u64 {
    max_memory_mib.map_or(DEFAULT_MAX_MEMORY, |m| m.saturating_mul(1 << 20))
}

/// Refuses a plan of `need` bytes above `limit`.
///
/// # Errors
/// [`HostError::TooMuchMemory`], with both figures.
pub fn check_memory(what: &str, need: u64, limit: u64) -> Result<()> {
    if need > limit {
        return Err(HostError::TooMuchMemory {
            what: what.to_string(),
            need_mib: need.div_ceil(1 << 20),
            limit_mib: limit >> 20,
        });
    }
    Ok(())
}

/// Bytes the f32 disparity energy model plans for a `w x h` pair (upper
/// bound, see the module documentation).
pub fn dem_bytes(params: &DemParams, w: usize, h: usize) -> u64 {
    let levels = u64::from(params.levels);
    let carriers = u64::from(params.carriers);
    let disparities = u64::from(params.max_disp) + 1;
    let sgm = matches!(params.aggregation, Aggregation::Sgm { .. });
    // f32 planes per pixel.
    let responses = 2 * (levels * carriers * 2 + 2);
    let scores = 2 * disparities * if sgm { 4 } else { 1 };
    let maps = 16;
    (w as u64) * (h as u64) * 4 * (responses + scores + maps)
}

/// Bytes of core working memory for one `w x h` frame through
/// conspicuity, completion and segmentation (their `scratch_bytes`
/// `const fn`s) plus the frame itself and its disparity.
pub fn core_frame_bytes(w: usize, h: usize) -> u64 {
    let scratch = protogist::conspicuity::scratch_bytes(w, h)
        + protogist::complete::scratch_bytes(w, h, protogist::complete::DEFAULT_REGION_CAPACITY)
        + protogist::segment::scratch_bytes(w, h);
    scratch as u64 + (w as u64) * (h as u64) * 8
}

/// Refuses a frame over the core's [`MAX_DIM`] per side, before anything
/// of that size is allocated.
///
/// # Errors
/// [`HostError::InvalidArgument`] naming `width` or `height`.
pub fn check_frame(w: usize, h: usize) -> Result<()> {
    for (name, v) in [("width", w), ("height", h)] {
        if v == 0 {
            return Err(HostError::ZeroDimension { name });
        }
        if v > MAX_DIM {
            return Err(HostError::InvalidArgument {
                name,
                reason: format!("{v} px exceeds the {MAX_DIM} px limit of the core"),
            });
        }
    }
    Ok(())
}

/// The working size of an input for `--width` (from its header only).
///
/// # Errors
/// [`HostError::Io`] or [`HostError::Decode`] for an unreadable header,
/// [`HostError::ZeroDimension`] for a zero width.
pub fn working_size_of(path: &Path, max_width: u32) -> Result<(usize, usize)> {
    let (w, h) = image::ImageReader::open(path)
        .map_err(|e| HostError::io(path, e))?
        .with_guessed_format()
        .map_err(|e| HostError::io(path, e))?
        .into_dimensions()
        .map_err(|source| HostError::Decode {
            path: path.to_path_buf(),
            source,
        })?;
    let (w, h) = crate::io::working_size(w, h, max_width)?;
    Ok((w as usize, h as usize))
}

/// The checks of a stereo run (`stereo` with the f32 reference, `run`):
/// the working size within the core's limit, `max_disp` below the working
/// width, and the memory of [`dem_bytes`] plus [`core_frame_bytes`] within
/// `limit`.
///
/// # Errors
/// As [`check_frame`], [`StereoError::MaxDispTooLarge`],
/// [`HostError::TooMuchMemory`].
pub fn check_stereo(params: &DemParams, w: usize, h: usize, limit: u64) -> Result<()> {
    check_frame(w, h)?;
    if usize::from(params.max_disp) >= w {
        return Err(StereoError::MaxDispTooLarge {
            max_disp: params.max_disp,
            width: w,
        }
        .into());
    }
    let need = dem_bytes(params, w, h) + core_frame_bytes(w, h);
    check_memory(
        &format!("the disparity energy model at {w}x{h}"),
        need,
        limit,
    )
}

/// Bytes `train` plans for a `inputs`-`hidden`-`classes` network on
/// `samples` training images: the weights and Rprop's three copies of
/// them (gradient, previous gradient, steps), in `f64`, and the forward
/// and backward activations of every sample.
pub fn train_bytes(inputs: usize, hidden: usize, classes: usize, samples: usize) -> u64 {
    let (d, h, k, n) = (inputs as u64, hidden as u64, classes as u64, samples as u64);
    let weights = h * (d + 1) + k * (h + 1);
    let activations = n * (d + 2 * h + 2 * k);
    8 * (4 * weights + activations)
}

/// The checks of `train` that need no dataset: `hidden` within what a
/// blob holds.
///
/// # Errors
/// [`HostError::InvalidArgument`] for `--hidden`.
pub fn check_hidden(hidden: usize) -> Result<()> {
    if hidden > MAX_HIDDEN {
        return Err(HostError::InvalidArgument {
            name: "hidden",
            reason: format!("{hidden} is over the model blob's limit of {MAX_HIDDEN}"),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dem_estimate_grows_with_the_frame_and_the_search() {
        let p = DemParams::default();
        let small = dem_bytes(&p, 160, 120);
        assert_eq!(dem_bytes(&p, 320, 240), 4 * small);
        let wide = DemParams {
            max_disp: 63,
            ..DemParams::default()
        };
        assert!(dem_bytes(&wide, 160, 120) > small);
        // The case: 8000x6000 is refused at the default limit,
        // with the figure, and allowed by a higher one.
        let err = check_stereo(&p, 8000, 6000, DEFAULT_MAX_MEMORY).unwrap_err();
        let need = (dem_bytes(&p, 8000, 6000) + core_frame_bytes(8000, 6000)).div_ceil(1 << 20);
        assert!(matches!(err, HostError::TooMuchMemory { need_mib, .. } if need_mib == need));
        assert!(err.to_string().contains("4096 MiB"), "{err}");
        assert!(check_stereo(&p, 8000, 6000, 1 << 40).is_ok());
        assert!(check_stereo(&p, 160, 120, DEFAULT_MAX_MEMORY).is_ok());
    }

    #[test]
    fn max_disp_must_be_below_the_width() {
        let p = DemParams {
            max_disp: 160,
            ..DemParams::default()
        };
        let err = check_stereo(&p, 160, 120, DEFAULT_MAX_MEMORY).unwrap_err();
        assert!(matches!(
            err,
            HostError::Stereo(StereoError::MaxDispTooLarge { .. })
        ));
    }

    #[test]
    fn frames_and_hidden_layers_over_the_limits() {
        assert!(check_frame(50_000, 50_000).is_err());
        assert!(check_frame(MAX_DIM, 1).is_ok());
        assert!(check_hidden(70_000).is_err());
        assert!(check_hidden(MAX_HIDDEN).is_ok());
        assert!(train_bytes(720, 70_000, 19, 400) > DEFAULT_MAX_MEMORY / 4);
        assert!(check_memory("x", 5 << 20, 4 << 20)
            .unwrap_err()
            .to_string()
            .contains("5 MiB"));
    }
}
