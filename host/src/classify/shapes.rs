//! Development silhouettes (issue 5, section 8): seeded binary masks of
//! parametric shapes, object white (255) on black, in the image-folder
//! layout `OUT/{cc}_{name}/{name}_{iiii}.png`, one subfolder per class.
//!
//! Eleven families (ellipse, rounded rectangle, regular polygon, star,
//! cross, L, ring, crescent, heart, arrow, D-shape) give [`CLASSES`], in an
//! order that puts look-alike pairs first so that small class counts are
//! not trivial: square vs rounded square, 5- vs 6-pointed star, circle vs
//! hexagon (and, further on, ellipse vs rectangle, pentagon vs hexagon,
//! octagon vs circle).
//!
//! Each image draws, from its own seeded stream (SplitMix64 on the seed,
//! class and index, so an image does not depend on `--classes` or
//! `--per-class`): a rotation in ±15°, a scale of 55 to 75 % of the half
//! size, an aspect jitter of ±10 %, a shift of up to ±5 % of the size, and
//! boundary noise, three radial harmonics of order 3 to 9 with amplitudes
//! up to 3 %. Canonical shapes fit the unit disc, so objects stay inside
//! the frame. The stream is written here, not taken from `rand`, so a
//! seed gives the same images whatever crate versions are locked.

pub use super::families::{Family, ShapeClass, CLASSES, SIZE_RANGE};
use super::mlp::{unit, SplitMix};
use crate::error::{HostError, Result};
use crate::output::{ensure_dir, write_atomic};
use crate::summary::Summary;
use image::GrayImage;
use std::f64::consts::PI;
use std::path::PathBuf;

/// Renders image `index` of class `class` (into [`CLASSES`]) for `seed`
/// as a `size` x `size` mask, object 255 on 0.
///
/// # Errors
/// [`HostError::InvalidArgument`] for a class out of range or a size
/// outside [`SIZE_RANGE`].
pub fn render(class: usize, index: u64, seed: u64, size: u32) -> Result<GrayImage> {
    let spec = CLASSES
        .get(class)
        .ok_or_else(|| HostError::InvalidArgument {
            name: "classes",
            reason: format!("class {class} out of range, there are {}", CLASSES.len()),
        })?;
    check_size(size)?;
    // A sub-stream per image: the state after one draw, mixed with the
    // draw, the class and the index.
    let mut rng = SplitMix::new(seed);
    let first = rng.next_u64();
    let mut rng = SplitMix::new(rng.state() ^ first ^ ((class as u64) << 40) ^ index);
    let _ = rng.next_u64();
    let rot = range(&mut rng, -15.0, 15.0).to_radians();
    let half = f64::from(size) / 2.0;
    let scale = range(&mut rng, 0.55, 0.75) * half;
    let aspect = range(&mut rng, 0.9, 1.1);
    let (cx, cy) = (
        half + range(&mut rng, -0.05, 0.05) * f64::from(size),
        half + range(&mut rng, -0.05, 0.05) * f64::from(size),
    );
    let noise: Vec<(f64, f64, f64)> = (0..3)
        .map(|_| {
            let k = (rng.next_u64() % 7 + 3) as f64;
            (
                k,
                range(&mut rng, 0.0, 0.03),
                range(&mut rng, 0.0, 2.0 * PI),
            )
        })
        .collect();
    let (sin, cos) = rot.sin_cos();
    Ok(GrayImage::from_fn(size, size, |x, y| {
        let px = f64::from(x) + 0.5 - cx;
        let py = cy - (f64::from(y) + 0.5);
        let u = (cos * px + sin * py) / scale;
        let v = (cos * py - sin * px) / (scale * aspect);
        let phi = v.atan2(u);
        let f = 1.0
            + noise
                .iter()
                .map(|&(k, a, p)| a * (k * phi + p).sin())
                .sum::<f64>();
        image::Luma([if spec.family.contains(u / f, v / f) {
            255
        } else {
            0
        }])
    }))
}

fn check_size(size: u32) -> Result<()> {
    if (SIZE_RANGE.0..=SIZE_RANGE.1).contains(&size) {
        Ok(())
    } else {
        Err(HostError::InvalidArgument {
            name: "size",
            reason: format!("{size} px is outside {}..={}", SIZE_RANGE.0, SIZE_RANGE.1),
        })
    }
}

/// Options of `protogist gen-shapes`.
#[derive(Clone, Debug, PartialEq, Eq, clap::Args)]
pub struct GenShapesOptions {
    /// Output directory (created if missing); one subfolder per class.
    #[arg(long)]
    pub out: PathBuf,
    /// Number of classes (the first N of the built-in list of 19).
    #[arg(long, default_value_t = 12)]
    pub classes: usize,
    /// Images per class.
    #[arg(long, default_value_t = 20)]
    pub per_class: u64,
    /// Seed of the whole set.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Image side, px.
    #[arg(long, default_value_t = 64)]
    pub size: u32,
}

/// The folder of class `c`: `{cc}_{name}`.
pub fn class_dir(c: usize) -> Option<String> {
    CLASSES.get(c).map(|k| format!("{c:02}_{}", k.name))
}

/// Writes the set; every PNG atomically (temporary name, then rename).
///
/// # Errors
/// [`HostError::ZeroDimension`] for 0 classes or images per class,
/// [`HostError::InvalidArgument`] for too many classes or a bad size, and
/// I/O or encoding errors. Arguments are checked before anything is
/// written.
pub fn gen_shapes(opts: &GenShapesOptions) -> Result<Summary> {
    if opts.classes == 0 {
        return Err(HostError::ZeroDimension { name: "classes" });
    }
    if opts.per_class == 0 {
        return Err(HostError::ZeroDimension { name: "per-class" });
    }
    if opts.classes > CLASSES.len() {
        return Err(HostError::InvalidArgument {
            name: "classes",
            reason: format!("{} asked, {} available", opts.classes, CLASSES.len()),
        });
    }
    check_size(opts.size)?;
    ensure_dir(&opts.out)?;
    for (c, spec) in CLASSES.iter().enumerate().take(opts.classes) {
        let dir = opts.out.join(format!("{c:02}_{}", spec.name));
        ensure_dir(&dir)?;
        for i in 0..opts.per_class {
            let img = render(c, i, opts.seed, opts.size)?;
            let name = format!("{}_{i:04}.png", spec.name);
            let mut png = std::io::Cursor::new(Vec::new());
            img.write_to(&mut png, image::ImageFormat::Png)
                .map_err(|source| HostError::Encode {
                    name: name.clone(),
                    source,
                })?;
            write_atomic(&dir.join(&name), png.get_ref())?;
        }
    }
    let mut s = Summary::new(format!(
        "protogist gen-shapes: {} classes x {} images, {}x{} px, seed {}",
        opts.classes, opts.per_class, opts.size, opts.size, opts.seed
    ));
    s.push("output", opts.out.display());
    s.push(
        "classes",
        CLASSES[..opts.classes]
            .iter()
            .map(|k| k.name)
            .collect::<Vec<_>>()
            .join(" "),
    );
    Ok(s)
}

/// Uniform in `[lo, hi)`.
fn range(rng: &mut SplitMix, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * unit(rng)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_class_renders_inside_the_frame_and_reproducibly() {
        for (c, spec) in CLASSES.iter().enumerate() {
            let img = render(c, 3, 7, 48).unwrap();
            let on = img.pixels().filter(|p| p.0[0] == 255).count();
            assert!(on > 48 * 48 / 20, "{}: {on} px", spec.name);
            let w = img.width() - 1;
            let border = img
                .enumerate_pixels()
                .filter(|(x, y, p)| (*x == 0 || *y == 0 || *x == w || *y == w) && p.0[0] > 0)
                .count();
            assert_eq!(border, 0, "{} touches the border", spec.name);
            assert_eq!(img, render(c, 3, 7, 48).unwrap());
            assert_ne!(img, render(c, 4, 7, 48).unwrap());
        }
    }

    #[test]
    fn bad_arguments_are_typed_errors() {
        let opts = |classes, per_class, size| GenShapesOptions {
            out: PathBuf::from("/nonexistent/never-written"),
            classes,
            per_class,
            seed: 0,
            size,
        };
        assert!(matches!(
            gen_shapes(&opts(0, 1, 64)),
            Err(HostError::ZeroDimension { name: "classes" })
        ));
        assert!(matches!(
            gen_shapes(&opts(2, 0, 64)),
            Err(HostError::ZeroDimension { name: "per-class" })
        ));
        assert!(matches!(
            gen_shapes(&opts(99, 1, 64)),
            Err(HostError::InvalidArgument {
                name: "classes",
                ..
            })
        ));
        assert!(matches!(
            gen_shapes(&opts(2, 1, 4)),
            Err(HostError::InvalidArgument { name: "size", .. })
        ));
        assert!(render(CLASSES.len(), 0, 0, 64).is_err());
    }
}
