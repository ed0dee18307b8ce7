//! The parametric shape families and the class list of
//! [`super::shapes`]: each family is an inside test in canonical
//! coordinates (v up), every shape within the unit disc.

use std::f64::consts::{FRAC_PI_2, PI, SQRT_2};

/// A parametric shape family in canonical coordinates (v up, unit disc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Family {
    /// Ellipse with half-axes 1 and `aspect`.
    Ellipse {
        /// Minor / major half-axis.
        aspect: f64,
    },
    /// Rectangle of side ratio `aspect`, corners rounded by `radius` (of
    /// the half-width); circumradius 1.
    RoundedRect {
        /// Height / width.
        aspect: f64,
        /// Corner radius over the half-width (0 = sharp).
        radius: f64,
    },
    /// Regular polygon, one vertex up.
    Polygon {
        /// Number of sides.
        sides: u32,
    },
    /// Star with `points` tips at radius 1 and notches at `inner`.
    Star {
        /// Number of tips.
        points: u32,
        /// Notch radius.
        inner: f64,
    },
    /// Plus sign of arm half-width `arm`.
    Cross {
        /// Arm half-width.
        arm: f64,
    },
    /// L of arm width `arm` in the square [-0.7, 0.7]².
    LShape {
        /// Arm width.
        arm: f64,
    },
    /// Annulus of inner radius `inner`.
    Ring {
        /// Inner radius.
        inner: f64,
    },
    /// The unit disc less a disc of radius 0.8 shifted right by 0.45.
    Crescent,
    /// The heart curve `(x² + y² - 1)³ <= x² y³`.
    Heart,
    /// An arrow pointing right.
    Arrow,
    /// The unit disc cut by a horizontal chord at v = -0.35.
    DShape,
}

/// One class: its folder name and shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeClass {
    /// Name used for the folder and files.
    pub name: &'static str,
    /// The shape.
    pub family: Family,
}

const fn class(name: &'static str, family: Family) -> ShapeClass {
    ShapeClass { name, family }
}

/// Every class, look-alikes first; `--classes N` takes the first N.
pub const CLASSES: [ShapeClass; 19] = [
    class(
        "square",
        Family::RoundedRect {
            aspect: 1.0,
            radius: 0.0,
        },
    ),
    class(
        "rounded-square",
        Family::RoundedRect {
            aspect: 1.0,
            radius: 0.35,
        },
    ),
    class(
        "star5",
        Family::Star {
            points: 5,
            inner: 0.5,
        },
    ),
    class(
        "star6",
        Family::Star {
            points: 6,
            inner: 0.5,
        },
    ),
    class("circle", Family::Ellipse { aspect: 1.0 }),
    class("hexagon", Family::Polygon { sides: 6 }),
    class("triangle", Family::Polygon { sides: 3 }),
    class("cross", Family::Cross { arm: 0.3 }),
    class("l-shape", Family::LShape { arm: 0.5 }),
    class("ring", Family::Ring { inner: 0.55 }),
    class("crescent", Family::Crescent),
    class("heart", Family::Heart),
    class("arrow", Family::Arrow),
    class("ellipse", Family::Ellipse { aspect: 0.6 }),
    class(
        "rectangle",
        Family::RoundedRect {
            aspect: 0.55,
            radius: 0.0,
        },
    ),
    class("pentagon", Family::Polygon { sides: 5 }),
    class(
        "star8",
        Family::Star {
            points: 8,
            inner: 0.6,
        },
    ),
    class("octagon", Family::Polygon { sides: 8 }),
    class("d-shape", Family::DShape),
];

/// Smallest and largest image side accepted.
pub const SIZE_RANGE: (u32, u32) = (16, 1024);

/// Radius of the star boundary along the ray at angle `theta`.
fn star_radius(theta: f64, points: u32, inner: f64) -> f64 {
    let s = PI / f64::from(points);
    let mut t = (theta - FRAC_PI_2).rem_euclid(2.0 * s);
    if t > s {
        t = 2.0 * s - t;
    }
    // Edge from the tip (1, 0) to the notch inner·(cos s, sin s).
    let (ex, ey) = (inner * s.cos() - 1.0, inner * s.sin());
    ey / (t.cos() * ey - t.sin() * ex)
}

impl Family {
    /// Whether the canonical point `(u, v)` is inside the shape.
    pub fn contains(self, u: f64, v: f64) -> bool {
        let rho = u.hypot(v);
        match self {
            Self::Ellipse { aspect } => u * u + (v / aspect).powi(2) <= 1.0,
            Self::RoundedRect { aspect, radius } => {
                let hw = 1.0 / (1.0 + aspect * aspect).sqrt();
                let (hh, r) = (aspect * hw, radius * hw);
                let (qx, qy) = (u.abs() - (hw - r), v.abs() - (hh - r));
                qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0) <= r
            }
            Self::Polygon { sides } => {
                let s = PI / f64::from(sides);
                rho <= star_radius(v.atan2(u), sides, s.cos())
            }
            Self::Star { points, inner } => rho <= star_radius(v.atan2(u), points, inner),
            Self::Cross { arm } => {
                let w = 1.0 / SQRT_2.max((1.0 + arm * arm).sqrt());
                let (a, b) = (u.abs() / w, v.abs() / w);
                (a <= 1.0 && b <= arm) || (b <= 1.0 && a <= arm)
            }
            Self::LShape { arm } => {
                let (x, y) = ((u + 0.7) / 1.4, (v + 0.7) / 1.4);
                let unit = (0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y);
                unit && (x <= arm || y <= arm)
            }
            Self::Ring { inner } => (inner..=1.0).contains(&rho),
            Self::Crescent => rho <= 1.0 && (u - 0.45).hypot(v) > 0.8,
            Self::Heart => {
                let (x, y) = (u * 1.3, v * 1.3 + 0.15);
                (x * x + y * y - 1.0).powi(3) <= x * x * y.powi(3)
            }
            Self::Arrow => {
                let shaft = (-0.95..=0.2).contains(&u) && v.abs() <= 0.22;
                let head = (0.2..=0.95).contains(&u) && v.abs() <= 0.6 * (0.95 - u) / 0.75;
                shaft || head
            }
            Self::DShape => rho <= 1.0 && v >= -0.35,
        }
    }
}
