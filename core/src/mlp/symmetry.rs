//! The mirrors under which a class looks the same ([`Symmetry`]): the
//! model blob's per-class symmetry byte (version 2, docs/MODEL_FORMAT.md),
//! which the mirror check ([`super::mirror_check`]) reads.

use crate::shape::Mirror;

/// The mirrors ([`Mirror`]) under which a class looks the same, as the
/// blob stores them: bit 0 the mirror about the vertical axis, bit 1 about
/// the horizontal axis; the other bits are 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Symmetry(u8);

impl Symmetry {
    /// No mirror.
    pub const NONE: Self = Self(0);
    /// Bit of [`Mirror::Vertical`].
    pub const VERTICAL: u8 = 1;
    /// Bit of [`Mirror::Horizontal`].
    pub const HORIZONTAL: u8 = 2;

    /// The symmetry of a blob byte (`None` when another bit is set).
    pub const fn from_bits(bits: u8) -> Option<Self> {
        if bits & !(Self::VERTICAL | Self::HORIZONTAL) == 0 {
            Some(Self(bits))
        } else {
            None
        }
    }

    /// Its blob byte.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// The bit of `m`.
    pub const fn bit(m: Mirror) -> u8 {
        match m {
            Mirror::Vertical => Self::VERTICAL,
            Mirror::Horizontal => Self::HORIZONTAL,
        }
    }

    /// Whether the class looks the same under `m`.
    pub const fn has(self, m: Mirror) -> bool {
        self.0 & Self::bit(m) != 0
    }

    /// This symmetry and `m`.
    #[must_use]
    pub const fn with(self, m: Mirror) -> Self {
        Self(self.0 | Self::bit(m))
    }

    /// How many mirrors.
    pub const fn count(self) -> u32 {
        self.0.count_ones()
    }
}
