//! Stereo (paper section 3.1): the disparity energy model (DEM) with a
//! trained decoding population, in fixed point, row-streamed, searched
//! coarse to fine with semi-global aggregation ([`c2f`], the one engine).
//!
//! ```text
//! left, right RGB ─► levels (2x2 means) ─► grey (U8F8) ─► complex Gabor
//!   bank (I10F6) ─► binocular cells A, X per (carrier, shift) in a window
//!   ─► votes with the integer decoder table ─► normalised costs ─► SGM
//!   ─► argmin + parabola ─► OFF tests (texture, ambiguity, left-right)
//!   ─► [phase refinement]
//! ```
//!
//! The f32 reference of every step is `protogist_host::reference::stereo`
//! (same names). Disparity is left-referenced, `d = x_L − x_R ≥ 0`. The
//! operating points a user chooses between are named constants of
//! [`c2f::C2fParams`] (`FULL`, `FAST`, `HALF`); docs/STEREO.md explains
//! the engine and the points.

pub mod c2f;
pub mod filters;
pub mod phase;
pub mod sgm;
pub mod table;

use crate::image::ImageError;
use core::fmt;
pub use filters::{Gabor, Z};
pub use table::{DemLayout, DemTable, TableError};

/// Largest number of carriers.
pub const MAX_CARRIERS: usize = 6;
/// Largest pooling radius.
pub const MAX_POOL_RADIUS: u8 = 7;
/// Largest number of pyramid levels.
pub const MAX_LEVELS: usize = 4;

/// Every parameter of the model, with the reference's defaults
/// (`protogist_host::reference::stereo::DemParams`; training parameters
/// live only on the host).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DemParams {
    /// Largest disparity searched, px; candidates are `0..=max_disp`.
    /// Default 15 (160x120 frames).
    pub max_disp: u8,
    /// Carrier orientations, evenly spread around horizontal: 3 gives
    /// −45°, 0°, 45°. Default 3; at most [`MAX_CARRIERS`].
    pub carriers: u8,
    /// Pyramid levels; level `l` has effective wavelength `λ·2^l`.
    /// Default 2 (λ 4 and 8); 1..=4.
    pub levels: u8,
    /// Wavelength on every level, px. Default 4 (setup only).
    pub wavelength: f32,
    /// Envelope σ / λ (isotropic). Default 0.56, one octave (setup only).
    pub sigma_per_wavelength: f32,
    /// Kernel radius, taps `−r..=r`. Default 7; at most
    /// [`filters::MAX_RADIUS`].
    pub radius: u8,
    /// Position-shift step in pixels of each level. Default 2 (λ/2).
    pub shift_step: u8,
    /// Score pooling box radius, px (0: none). Default 2 (5x5); at most
    /// [`MAX_POOL_RADIUS`].
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
}

impl DemParams {
    /// The defaults, as a `const`.
    pub const DEFAULT: Self = Self {
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
    };

    /// Smallest width and height the filters support: one kernel at the
    /// coarsest level.
    pub const fn min_size(&self) -> usize {
        let l = if self.levels == 0 {
            0
        } else {
            self.levels as usize - 1
        };
        (2 * self.radius as usize + 1) << l
    }

    /// The layout a decoder for these parameters has (λ and σ/λ quantised
    /// as the table stores them). Setup only.
    #[allow(
        clippy::float_arithmetic,
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss
    )]
    pub fn layout(&self) -> DemLayout {
        let q = |v: f32, one: f32| libm::roundf(v * one).clamp(0.0, 65535.0) as u16;
        DemLayout {
            max_disp: self.max_disp,
            levels: self.levels,
            carriers: self.carriers,
            shift_step: self.shift_step,
            radius: self.radius,
            wavelength_q8: q(self.wavelength, 256.0),
            sigma_q12: q(self.sigma_per_wavelength, 4096.0),
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`StereoError::BadParams`] naming the first bad one.
    pub fn check(&self) -> Result<(), StereoError> {
        param(
            (1..=MAX_CARRIERS).contains(&usize::from(self.carriers)),
            "carriers must be 1..=6",
        )?;
        param(
            (1..=MAX_LEVELS).contains(&usize::from(self.levels)),
            "levels must be 1..=4",
        )?;
        param(
            self.wavelength >= 2.0 && self.wavelength <= 64.0,
            "wavelength must be 2..=64",
        )?;
        param(
            self.sigma_per_wavelength > 0.1 && self.sigma_per_wavelength < 4.0,
            "sigma_per_wavelength must be in (0.1, 4)",
        )?;
        param(
            (1..=filters::MAX_RADIUS).contains(&usize::from(self.radius)),
            "radius must be 1..=15",
        )?;
        param(self.shift_step >= 1, "shift_step must be at least 1")?;
        param(
            self.pool_radius <= MAX_POOL_RADIUS,
            "pool_radius must be at most 7",
        )?;
        param(
            self.min_energy >= 0.0 && self.min_energy <= 1.0e6,
            "min_energy must be in 0..=1e6",
        )?;
        param(
            self.min_margin >= 0.0 && self.min_margin <= 1.0e4,
            "min_margin must be in 0..=1e4",
        )?;
        param(
            self.lr_tolerance <= 255.0 && !self.lr_tolerance.is_nan(),
            "lr_tolerance must be at most 255",
        )
    }
}

impl Default for DemParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why the stereo stage rejected its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum StereoError {
    /// Left and right differ in size.
    SizeMismatch {
        /// Left size.
        left: (usize, usize),
        /// Right size.
        right: (usize, usize),
    },
    /// An image smaller than one filter at the coarsest level.
    TooSmall {
        /// The smallest width and height.
        min: usize,
        /// The image size.
        got: (usize, usize),
    },
    /// `max_disp` not below the width.
    MaxDispTooLarge {
        /// The maximum disparity.
        max_disp: u8,
        /// The width.
        width: usize,
    },
    /// The decoder table is corrupt.
    Table(TableError),
    /// The decoder table was trained for other parameters.
    DecoderMismatch {
        /// The table's layout.
        got: DemLayout,
        /// The parameters' layout.
        expected: DemLayout,
    },
    /// A parameter out of range.
    BadParams(&'static str),
    /// A scratch buffer or the output is not of the working size.
    Buffer {
        /// Which buffer.
        what: &'static str,
        /// Elements needed.
        needed: usize,
        /// Elements given.
        got: usize,
    },
    /// The output map cannot be viewed.
    Image(ImageError),
}

/// `Ok` if `ok`, else [`StereoError::BadParams`]`(what)`: the parameter
/// checks of the stage's set-ups.
pub(crate) fn param(ok: bool, what: &'static str) -> Result<(), StereoError> {
    if ok {
        Ok(())
    } else {
        Err(StereoError::BadParams(what))
    }
}

impl fmt::Display for StereoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::SizeMismatch { left, right } => write!(
                f,
                "left is {}x{} but right is {}x{}",
                left.0, left.1, right.0, right.1
            ),
            Self::TooSmall { min, got } => write!(
                f,
                "{}x{} is smaller than the filter support ({min}x{min})",
                got.0, got.1
            ),
            Self::MaxDispTooLarge { max_disp, width } => write!(
                f,
                "max disparity {max_disp} must be below the image width {width}"
            ),
            Self::Table(e) => write!(f, "{e}"),
            Self::DecoderMismatch { got, expected } => write!(
                f,
                "the decoder was trained for other parameters ({got:?}, expected {expected:?})"
            ),
            Self::BadParams(what) => write!(f, "bad stereo parameters: {what}"),
            Self::Buffer { what, needed, got } => {
                write!(f, "stereo buffer {what} holds {got}, needs {needed}")
            }
            Self::Image(e) => write!(f, "stereo output: {e}"),
        }
    }
}

impl core::error::Error for StereoError {}

impl From<TableError> for StereoError {
    fn from(e: TableError) -> Self {
        Self::Table(e)
    }
}

/// The set-up stage: checked parameters, kernels and integer thresholds.
#[derive(Clone, Debug, PartialEq)]
pub struct Dem {
    /// The parameters.
    pub params: DemParams,
    /// Their layout.
    pub layout: DemLayout,
    /// One kernel per carrier (the same on every level).
    pub kernels: [Gabor; MAX_CARRIERS],
    /// `min_energy` in `Q8` grey².
    pub min_energy_q8: u64,
    /// `min_margin` in `Q16`.
    pub min_margin_q16: i64,
    /// `lr_tolerance` in `U8F8` (`None`: no check).
    pub lr_tolerance_q8: Option<i32>,
}

impl Dem {
    /// Checks `params` and builds the kernels. One-time setup (floats, via
    /// `libm`).
    ///
    /// # Errors
    /// [`StereoError::BadParams`].
    #[allow(
        clippy::float_arithmetic,
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss
    )]
    pub fn new(params: &DemParams) -> Result<Self, StereoError> {
        params.check()?;
        let n = usize::from(params.carriers);
        let kernels = core::array::from_fn(|k| {
            Gabor::new(
                params.wavelength,
                params.sigma_per_wavelength,
                params.radius,
                filters::carrier_deg(k.min(n - 1), n),
            )
        });
        let lr = (params.lr_tolerance >= 0.0)
            .then(|| libm::round(f64::from(params.lr_tolerance) * 256.0) as i32);
        Ok(Self {
            params: *params,
            layout: params.layout(),
            kernels,
            min_energy_q8: libm::ceil(f64::from(params.min_energy) * 256.0) as u64,
            min_margin_q16: libm::round(f64::from(params.min_margin) * 65536.0) as i64,
            lr_tolerance_q8: lr,
        })
    }

    /// The kernel of carrier `c`.
    pub fn kernel(&self, c: usize) -> Option<&Gabor> {
        self.kernels
            .get(c)
            .filter(|_| c < usize::from(self.params.carriers))
    }
}

/// What a run found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StereoReport {
    /// Pixels with a disparity.
    pub on: usize,
    /// Pixels OFF for lack of texture.
    pub off_texture: usize,
    /// Pixels OFF as ambiguous.
    pub off_ambiguous: usize,
    /// Pixels OFF by the left-right check.
    pub off_inconsistent: usize,
    /// Binocular complex cells evaluated (one per carrier and cell
    /// position; every level and eye): the engine's measure of its
    /// decoding work ([`c2f`]).
    pub cells: usize,
}

/// The steps a [`Probe`] is told about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Grey rows and pyramid planes.
    Pyramid,
    /// Gabor responses.
    Filters,
    /// Binocular energies (vertically pooled).
    Energies,
    /// Votes, pooling, argmax, OFF tests.
    Readout,
    /// Semi-global aggregation (the coarse-to-fine engine).
    Sgm,
}

/// Told when the stage enters a step (for per-step timing); `()` ignores it.
pub trait Probe {
    /// The stage enters `step`.
    fn enter(&mut self, step: Step);
}

impl Probe for () {
    fn enter(&mut self, _: Step) {}
}
