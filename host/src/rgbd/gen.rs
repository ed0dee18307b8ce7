//! `protogist gen-rgbd`: a synthetic stand-in for the RGB-D Object Dataset,
//! in exactly its cropped layout ([`super::loader`]), so that the loader,
//! `protogist experiment` and the tests run where the real data cannot be
//! downloaded.
//!
//! **What it is.** Objects made of unions of solids (spheres, boxes,
//! cylinders, cones, tori, superquadrics), one category per arrangement
//! (a mug is a cylinder and a torus handle, a bottle a cylinder, a cone and
//! a cap, ...), ray-cast ([`super::render`]) on a turntable seen from about
//! 30°, 45° and 60° above the horizon (videos 1, 2 and 3), with Lambert and
//! specular shading, a cast shadow and textures. Instances of a category
//! differ in size, proportions, colour and texture. Each frame gives an RGB
//! crop around the object, its z-depth as a 16-bit PNG in mm with the
//! holes of a structured-light sensor (0 where depth jumps, on the
//! projector's shadow side of an edge, at grazing angles, and scattered
//! dropouts; noise growing with z²), the object mask and a `_loc.txt`.
//!
//! **What it is for.** Exercising the whole experiment of the paper end to
//! end — loader, sampling and split, pre-processing, the seven networks,
//! int8, the table and the figures — and checking that the conditions
//! behave sensibly (shape and range separate categories that differ in 3D
//! shape).
//!
//! **What it cannot show.** How the method does on real objects: the
//! categories are few and differ by construction, there is no clutter,
//! no real sensor noise, no specularities or translucency as in the real
//! data, no real textures or labels. Numbers measured on it cannot be
//! compared with the paper's Table 1.

use super::render::{render, rot_x, rot_z, Object, Part, Render, Solid, Texture, View, V3};
use crate::classify::mlp::{unit, SplitMix};
use crate::error::{HostError, Result};
use crate::output::ensure_dir;
use crate::summary::Summary;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// The categories, in order; `--categories N` takes the first `N`.
pub const CATEGORIES: [&str; 12] = [
    "ball",
    "can",
    "cereal_box",
    "funnel",
    "donut",
    "mug",
    "bottle",
    "mushroom",
    "pillow",
    "dumbbell",
    "stool",
    "snowman",
];

/// Camera elevations of videos 1, 2 and 3, degrees.
pub const ELEVATIONS: [f64; 3] = [30.0, 45.0, 60.0];

/// Options of `protogist gen-rgbd`.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct GenRgbdOptions {
    /// Output folder; the dataset goes to `<out>/rgbd-dataset`.
    #[arg(long)]
    pub out: PathBuf,
    /// Categories (at most 12).
    #[arg(long, default_value_t = 10)]
    pub categories: usize,
    /// Instances per category (the first is the test instance).
    #[arg(long, default_value_t = 4)]
    pub instances: usize,
    /// Frames per video (one turntable revolution); every 5th is sampled.
    #[arg(long, default_value_t = 30)]
    pub frames: u32,
    /// Seed of the instances and of the sensor noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

fn hsv(h: f64, s: f64, v: f64) -> V3 {
    let f = |n: f64| {
        let k = (n + h * 6.0) % 6.0;
        v - v * s * (k.min(4.0 - k).clamp(0.0, 1.0))
    };
    let c = [f(5.0), f(3.0), f(1.0)];
    // To linear light.
    c.map(|x| x.powf(2.2))
}

/// One instance of category `c`, drawn from `rng`.
pub fn instance(c: usize, rng: &mut SplitMix) -> Object {
    let mut r = |a: f64, b: f64| a + (b - a) * unit(rng);
    let scale = r(0.7, 1.35);
    let hue = r(0.0, 1.0);
    let colour = hsv(hue, r(0.4, 0.9), r(0.5, 0.95));
    let colour2 = hsv((hue + r(0.2, 0.5)) % 1.0, r(0.3, 0.9), r(0.3, 0.9));
    let texture = [
        Texture::Plain,
        Texture::Stripes,
        Texture::Checker,
        Texture::Speckle,
    ][(r(0.0, 4.0) as usize).min(3)];
    let freq = r(25.0, 60.0);
    let p1 = r(0.75, 1.3);
    let p2 = r(0.75, 1.3);
    let s = |v: f64| v * scale;
    let part = |solid, at: V3| Part::new(solid, at.map(|v| v * scale), colour);
    let mut parts = match c % CATEGORIES.len() {
        0 => vec![part(Solid::Sphere(s(0.07 * p1)), [0.0, 0.07 * p1, 0.0])],
        1 => vec![part(
            Solid::Cylinder(s(0.035 * p1), s(0.06 * p2)),
            [0.0, 0.06 * p2, 0.0],
        )],
        2 => vec![part(
            Solid::Box([s(0.08 * p1), s(0.11 * p2), s(0.025)]),
            [0.0, 0.11 * p2, 0.0],
        )],
        3 => vec![
            part(
                Solid::Cone(s(0.07 * p1), s(0.012), s(0.05)),
                [0.0, 0.05, 0.0],
            ),
            part(
                Solid::Cylinder(s(0.012), s(0.03 * p2)),
                [0.0, 0.1 + 0.03 * p2, 0.0],
            ),
        ],
        4 => vec![part(
            Solid::Torus(s(0.06 * p1), s(0.025 * p2)),
            [0.0, 0.025 * p2, 0.0],
        )],
        5 => {
            let mut handle = part(
                Solid::Torus(s(0.03), s(0.008)),
                [0.045 * p1, 0.05 * p2, 0.0],
            );
            handle.rot = rot_x(PI / 2.0);
            vec![
                part(
                    Solid::Cylinder(s(0.045 * p1), s(0.05 * p2)),
                    [0.0, 0.05 * p2, 0.0],
                ),
                handle,
            ]
        }
        6 => vec![
            part(
                Solid::Cylinder(s(0.035 * p1), s(0.07 * p2)),
                [0.0, 0.07 * p2, 0.0],
            ),
            part(
                Solid::Cone(s(0.035 * p1), s(0.012), s(0.03)),
                [0.0, 0.14 * p2 + 0.03, 0.0],
            ),
            part(
                Solid::Cylinder(s(0.013), s(0.015)),
                [0.0, 0.14 * p2 + 0.075, 0.0],
            ),
        ],
        7 => vec![
            part(Solid::Cylinder(s(0.02 * p1), s(0.04)), [0.0, 0.04, 0.0]),
            part(
                Solid::Superquadric([s(0.07 * p2), s(0.035), s(0.07 * p2)], 0.8, 1.0),
                [0.0, 0.085, 0.0],
            ),
        ],
        8 => vec![part(
            Solid::Superquadric([s(0.09 * p1), s(0.035 * p2), s(0.07)], 0.35, 0.35),
            [0.0, 0.035 * p2, 0.0],
        )],
        9 => {
            let mut bar = part(Solid::Cylinder(s(0.012), s(0.06 * p1)), [0.0, 0.04, 0.0]);
            bar.rot = rot_z(PI / 2.0);
            vec![
                bar,
                part(Solid::Sphere(s(0.04 * p2)), [0.06 * p1, 0.04, 0.0]),
                part(Solid::Sphere(s(0.04 * p2)), [-0.06 * p1, 0.04, 0.0]),
            ]
        }
        10 => {
            let (w, h) = (0.06 * p1, 0.05 * p2);
            let mut v = vec![part(
                Solid::Box([s(w), s(0.01), s(w)]),
                [0.0, 2.0 * h + 0.01, 0.0],
            )];
            for (x, z) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
                v.push(part(
                    Solid::Cylinder(s(0.008), s(h)),
                    [0.8 * w * x, h, 0.8 * w * z],
                ));
            }
            v
        }
        _ => vec![
            part(Solid::Sphere(s(0.05 * p1)), [0.0, 0.05 * p1, 0.0]),
            part(
                Solid::Sphere(s(0.035 * p2)),
                [0.0, 0.1 * p1 + 0.03 * p2, 0.0],
            ),
            {
                let mut nose = part(
                    Solid::Cone(s(0.01), s(0.0), s(0.02)),
                    [0.0, 0.1 * p1 + 0.03 * p2, 0.045 * p2],
                );
                nose.rot = rot_x(-PI / 2.0);
                nose
            },
        ],
    };
    for p in &mut parts {
        p.colour2 = colour2;
        p.texture = texture;
        p.freq = freq;
    }
    // A bounding sphere from samples of the union's surface region.
    let top = parts
        .iter()
        .map(|p| p.at[1] + extent(&p.solid))
        .fold(0.0f64, f64::max);
    let centre_y = top / 2.0;
    let radius = parts
        .iter()
        .map(|p| {
            let d = [p.at[0], p.at[1] - centre_y, p.at[2]];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() + extent(&p.solid)
        })
        .fold(0.0f64, f64::max);
    Object {
        parts,
        radius,
        centre_y,
    }
}

/// A radius that holds the solid.
fn extent(s: &Solid) -> f64 {
    match *s {
        Solid::Sphere(r) => r,
        Solid::Box(b) => (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt(),
        Solid::Cylinder(r, h) => r.hypot(h),
        Solid::Cone(r1, r2, h) => r1.max(r2).hypot(h),
        Solid::Torus(a, b) => a + b,
        Solid::Superquadric(a, _, _) => (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt(),
    }
}

/// A sensor's depth in mm from a render: 0 beyond range, at depth jumps, on
/// the shadow side of edges, at grazing angles and at random dropouts;
/// Gaussian-ish noise of `1.5 mm · (z / 1 m)²`.
pub fn sensor_depth(r: &Render, rng: &mut SplitMix) -> Vec<u16> {
    let n = r.size;
    let z = |x: usize, y: usize| r.depth[y * n + x];
    let mut out = vec![0u16; n * n];
    for y in 0..n {
        for x in 0..n {
            let d = z(x, y);
            let i = y * n + x;
            let noise = (unit(rng) + unit(rng) + unit(rng) - 1.5) * 2.0;
            if d <= 0.0 || d > 3.5 || r.facing[i] < 0.15 || unit(rng) < 0.004 {
                continue;
            }
            // A jump to a nearer surface within 3 px to the right shadows
            // this pixel from the projector (offset to the right); a jump
            // to either neighbour leaves no estimate.
            let jump = (1..=3)
                .filter(|&k| x + k < n)
                .any(|k| z(x + k, y) > 0.0 && d - z(x + k, y) > 0.02)
                || [
                    (x.wrapping_sub(1), y),
                    (x + 1, y),
                    (x, y.wrapping_sub(1)),
                    (x, y + 1),
                ]
                .iter()
                .any(|&(a, b)| a < n && b < n && (z(a, b) - d).abs() > 0.02);
            if jump {
                continue;
            }
            let mm = d * 1000.0 + noise * 1.5 * d * d;
            out[i] = mm.round().clamp(1.0, 65535.0) as u16;
        }
    }
    out
}

fn srgb(v: f64) -> u8 {
    let c = v.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// Writes one frame's four files.
fn write_frame(dir: &Path, stem: &str, r: &Render, depth: &[u16]) -> Result<()> {
    let n = r.size;
    // The crop: the mask's bounding box with a 10 % margin.
    let (mut x0, mut y0, mut x1, mut y1) = (n, n, 0, 0);
    for (i, _) in r.mask.iter().enumerate().filter(|(_, &m)| m) {
        let (x, y) = (i % n, i / n);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    if x0 > x1 {
        (x0, y0, x1, y1) = (0, 0, n - 1, n - 1);
    }
    let m = ((x1 - x0).max(y1 - y0) / 10).max(2);
    let (x0, y0) = (x0.saturating_sub(m), y0.saturating_sub(m));
    let (x1, y1) = ((x1 + m).min(n - 1), (y1 + m).min(n - 1));
    let (w, h) = ((x1 - x0 + 1) as u32, (y1 - y0 + 1) as u32);
    let at = |x: u32, y: u32| (y as usize + y0) * n + x as usize + x0;
    let rgb = image::RgbImage::from_fn(w, h, |x, y| image::Rgb(r.rgb[at(x, y)].map(srgb)));
    let dep = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(w, h, |x, y| {
        image::Luma([depth[at(x, y)]])
    });
    let mask =
        image::GrayImage::from_fn(w, h, |x, y| image::Luma([255 * u8::from(r.mask[at(x, y)])]));
    let save = |p: PathBuf, res: image::ImageResult<()>| {
        res.map_err(|e| HostError::Encode {
            name: p.display().to_string(),
            source: e,
        })
    };
    let p = dir.join(format!("{stem}_crop.png"));
    save(p.clone(), rgb.save(&p))?;
    let p = dir.join(format!("{stem}_depthcrop.png"));
    save(p.clone(), dep.save(&p))?;
    let p = dir.join(format!("{stem}_maskcrop.png"));
    save(p.clone(), mask.save(&p))?;
    let p = dir.join(format!("{stem}_loc.txt"));
    let loc = format!("{},{}\n", r.origin.0 + x0 as i64, r.origin.1 + y0 as i64);
    std::fs::write(&p, loc).map_err(|e| HostError::io(&p, e))
}

/// `protogist gen-rgbd`.
///
/// # Errors
/// Bad counts ([`HostError::InvalidArgument`]), I/O and encoding errors.
pub fn gen_rgbd(opts: &GenRgbdOptions) -> Result<Summary> {
    let arg = |name, reason: String| HostError::InvalidArgument { name, reason };
    if opts.categories == 0 || opts.categories > CATEGORIES.len() {
        return Err(arg(
            "categories",
            format!("{} is not in 1..=12", opts.categories),
        ));
    }
    if opts.instances < 2 {
        return Err(arg(
            "instances",
            format!(
                "{}: one test and at least one training instance are needed",
                opts.instances
            ),
        ));
    }
    if opts.frames == 0 {
        return Err(HostError::ZeroDimension { name: "frames" });
    }
    let start = std::time::Instant::now();
    let root = opts.out.join("rgbd-dataset");
    let mut jobs = vec![];
    for (c, cat) in CATEGORIES.iter().enumerate().take(opts.categories) {
        for k in 1..=opts.instances {
            let mut rng =
                SplitMix::new(opts.seed ^ ((c as u64) << 32 | k as u64).wrapping_mul(0x9E37_79B9));
            let obj = instance(c, &mut rng);
            let distance = 0.8 + 0.3 * unit(&mut rng);
            let name = format!("{cat}_{k}");
            let dir = root.join(cat).join(&name);
            ensure_dir(&dir)?;
            for (v, &elev) in ELEVATIONS.iter().enumerate() {
                for f in 1..=opts.frames {
                    jobs.push((
                        obj.clone(),
                        dir.clone(),
                        name.clone(),
                        v + 1,
                        f,
                        elev,
                        distance,
                    ));
                }
            }
        }
    }
    let bar = indicatif::ProgressBar::new(jobs.len() as u64);
    jobs.par_iter()
        .map(|(obj, dir, name, v, f, elev, distance)| {
            let view = View {
                azimuth: 2.0 * PI * f64::from(f - 1) / f64::from(opts.frames),
                elevation: elev.to_radians(),
                distance: *distance,
                focal: 300.0,
            };
            let r = render(obj, &view, [0.55, 0.52, 0.48]);
            let mut rng = SplitMix::new(opts.seed.wrapping_add((*v as u64) << 20 | u64::from(*f)));
            let depth = sensor_depth(&r, &mut rng);
            write_frame(dir, &format!("{name}_{v}_{f}"), &r, &depth)?;
            bar.inc(1);
            Ok(())
        })
        .collect::<Result<Vec<()>>>()?;
    bar.finish_and_clear();
    let mut s = Summary::new(format!("protogist gen-rgbd: {}", root.display()));
    s.push("categories", CATEGORIES[..opts.categories].join(", "));
    s.push("instances", format!("{} per category", opts.instances));
    s.push(
        "frames",
        format!(
            "{} ({} videos of {} frames per instance)",
            jobs.len(),
            ELEVATIONS.len(),
            opts.frames
        ),
    );
    s.push(
        "note",
        "synthetic: for exercising the experiment, not for comparing with the paper",
    );
    s.push("time", format!("{:.1} s", start.elapsed().as_secs_f64()));
    Ok(s)
}
