//! The trained decoder as a compact, versioned, little-endian integer table,
//! read zero-copy from `&[u8]` (a file's bytes or an `include_bytes!`
//! `const`). The host writes it (`protogist train-dem`); this is the one
//! parser, which the host uses too.
//!
//! | offset | type | field |
//! |---|---|---|
//! | 0 | `[u8; 4]` | magic `PGDM` |
//! | 4 | u16 | version, [`VERSION`] |
//! | 6 | u16 | header length, [`HEADER_LEN`] |
//! | 8 | u8 × 5 | max_disp, levels, carriers, shift_step, radius |
//! | 13 | u8 | fraction bits of the weights (`a, b, c` are Q`15−f`.`f` i16) |
//! | 14 | u8 | fraction bits of the bias |
//! | 15 | u8 | reserved, 0 |
//! | 16 | u16 | λ, Q8.8 |
//! | 18 | u16 | σ/λ, Q4.12 |
//! | 20 | u16 | groups `G` (level-major, carrier, shift) |
//! | 22 | u16 | disparities `N = max_disp + 1` |
//! | 24 | i16 × 3GN | `[group][d][a, b, c]` |
//! | | i16 × N | bias `ΣW(d)/mean ΣW` |
//! | | u32 | FNV-1a 32 of every byte before it |

use crate::checksum::Fnv1a;
use core::fmt;

/// The magic bytes.
pub const MAGIC: [u8; 4] = *b"PGDM";
/// The format version this code reads (and the host writes).
pub const VERSION: u16 = 1;
/// Bytes before the weights.
pub const HEADER_LEN: usize = 24;

/// Total bytes of a table with `cells` weight triples and `n` biases.
pub const fn table_len(cells: usize, n: usize) -> usize {
    HEADER_LEN + 6 * cells + 2 * n + 4
}

/// What a decoder was trained for: the parameters that shape the
/// population, with the real ones quantised as the table stores them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DemLayout {
    /// Largest disparity.
    pub max_disp: u8,
    /// Pyramid levels.
    pub levels: u8,
    /// Carriers.
    pub carriers: u8,
    /// Shift step, level px.
    pub shift_step: u8,
    /// Kernel radius.
    pub radius: u8,
    /// λ, unsigned Q8.8.
    pub wavelength_q8: u16,
    /// σ/λ, unsigned Q4.12.
    pub sigma_q12: u16,
}

impl DemLayout {
    /// Position shifts at `level`: `0, step, 2·step, ...` level px, enough
    /// to cover `0..=max_disp` full-resolution px.
    pub const fn shifts(&self, level: usize) -> usize {
        // A step that shifts out of range (never for a valid layout) is
        // taken as the widest, so that no division is by 0.
        let base = if self.shift_step == 0 {
            1
        } else {
            self.shift_step as usize
        };
        let step = match base.checked_shl(level as u32) {
            Some(s) if s > 0 && s >> level == base => s,
            _ => usize::MAX,
        };
        (self.max_disp as usize + 1).div_ceil(step)
    }

    /// Number of cell groups `(level, carrier, shift)`.
    pub const fn groups(&self) -> usize {
        let mut l = 0;
        let mut n = 0;
        while l < self.levels as usize {
            n += self.carriers as usize * self.shifts(l);
            l += 1;
        }
        n
    }

    /// Largest position shift, full-resolution px.
    pub const fn max_shift(&self) -> usize {
        let mut l = 0;
        let mut m = 0;
        while l < self.levels as usize {
            let s = ((self.shifts(l) - 1) * self.shift_step as usize) << l;
            if s > m {
                m = s;
            }
            l += 1;
        }
        m
    }
}

/// Why a table was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum TableError {
    /// Fewer bytes than the header or the dimensions require.
    Truncated {
        /// Bytes needed.
        needed: usize,
        /// Bytes present.
        got: usize,
    },
    /// More bytes than the dimensions require.
    TrailingBytes {
        /// Bytes expected.
        expected: usize,
        /// Bytes present.
        got: usize,
    },
    /// Not a decoder table.
    BadMagic,
    /// A version this code does not read.
    Version(u16),
    /// A header length this version does not use.
    HeaderLen(u16),
    /// The stored checksum differs from the bytes'.
    Checksum {
        /// Stored.
        stored: u32,
        /// Computed.
        computed: u32,
    },
    /// Header fields that contradict each other.
    Inconsistent(&'static str),
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Truncated { needed, got } => {
                write!(f, "decoder table truncated: {got} bytes, need {needed}")
            }
            Self::TrailingBytes { expected, got } => {
                write!(f, "decoder table has {got} bytes, expected {expected}")
            }
            Self::BadMagic => write!(f, "not a decoder table (bad magic)"),
            Self::Version(v) => write!(
                f,
                "decoder table version {v} is not supported (expected {VERSION})"
            ),
            Self::HeaderLen(h) => {
                write!(f, "decoder table header length {h} (expected {HEADER_LEN})")
            }
            Self::Checksum { stored, computed } => write!(
                f,
                "decoder table checksum {stored:#010x} does not match {computed:#010x}"
            ),
            Self::Inconsistent(what) => write!(f, "decoder table header is inconsistent: {what}"),
        }
    }
}

impl core::error::Error for TableError {}

/// A checked table, borrowing its bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DemTable<'a> {
    /// The population it decodes.
    pub layout: DemLayout,
    /// Fraction bits of the weights.
    pub weight_frac: u8,
    /// Fraction bits of the bias.
    pub bias_frac: u8,
    /// `[group][d][a, b, c]`, little-endian i16.
    weights: &'a [u8],
    /// `[d]`, little-endian i16.
    bias: &'a [u8],
}

fn u16_at(b: &[u8], o: usize) -> u16 {
    match b.get(o..o + 2) {
        Some(&[lo, hi]) => u16::from_le_bytes([lo, hi]),
        _ => 0,
    }
}

fn i16_of(c: &[u8]) -> i16 {
    match *c {
        [lo, hi] => i16::from_le_bytes([lo, hi]),
        _ => 0,
    }
}

impl<'a> DemTable<'a> {
    /// Parses and checks a table without copying it.
    ///
    /// # Errors
    /// [`TableError`] for anything but an intact table of this version.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, TableError> {
        let got = bytes.len();
        let header = bytes.get(..HEADER_LEN).filter(|_| got >= HEADER_LEN + 4);
        let Some(h) = header else {
            return Err(TableError::Truncated {
                needed: HEADER_LEN + 4,
                got,
            });
        };
        if h.get(..4) != Some(&MAGIC[..]) {
            return Err(TableError::BadMagic);
        }
        if u16_at(h, 4) != VERSION {
            return Err(TableError::Version(u16_at(h, 4)));
        }
        if usize::from(u16_at(h, 6)) != HEADER_LEN {
            return Err(TableError::HeaderLen(u16_at(h, 6)));
        }
        let (groups, n) = (usize::from(u16_at(h, 20)), usize::from(u16_at(h, 22)));
        let expected = table_len(groups * n, n);
        if got < expected {
            return Err(TableError::Truncated {
                needed: expected,
                got,
            });
        }
        if got > expected {
            return Err(TableError::TrailingBytes { expected, got });
        }
        let body_len = expected - 4;
        let Some((body, sum)) = bytes.split_at_checked(body_len) else {
            return Err(TableError::Truncated {
                needed: expected,
                got,
            });
        };
        let stored = match *sum {
            [a, b, c, d] => u32::from_le_bytes([a, b, c, d]),
            _ => 0,
        };
        let mut f = Fnv1a::new();
        f.write(body);
        let computed = f.finish();
        if computed != stored {
            return Err(TableError::Checksum { stored, computed });
        }
        let byte = |o: usize| h.get(o).copied().unwrap_or(0);
        let layout = DemLayout {
            max_disp: byte(8),
            levels: byte(9),
            carriers: byte(10),
            shift_step: byte(11),
            radius: byte(12),
            wavelength_q8: u16_at(h, 16),
            sigma_q12: u16_at(h, 18),
        };
        let (weight_frac, bias_frac) = (byte(13), byte(14));
        let bad = |ok: bool, what| {
            if ok {
                Ok(())
            } else {
                Err(TableError::Inconsistent(what))
            }
        };
        bad(byte(15) == 0, "reserved byte is not 0")?;
        bad(
            weight_frac <= 15 && bias_frac <= 15,
            "more than 15 fraction bits",
        )?;
        bad((1..=4).contains(&layout.levels), "levels must be 1..=4")?;
        bad(
            layout.carriers >= 1 && layout.shift_step >= 1 && layout.radius >= 1,
            "zero carriers, step or radius",
        )?;
        bad(
            n == usize::from(layout.max_disp) + 1,
            "disparities != max_disp + 1",
        )?;
        bad(
            groups == layout.groups(),
            "group count does not match the layout",
        )?;
        let rest = body.get(HEADER_LEN..).unwrap_or(&[]);
        let (weights, bias) = rest.split_at((6 * groups * n).min(rest.len()));
        Ok(Self {
            layout,
            weight_frac,
            bias_frac,
            weights,
            bias,
        })
    }

    /// Number of disparities, `max_disp + 1`.
    pub const fn disparities(&self) -> usize {
        self.layout.max_disp as usize + 1
    }

    /// The raw little-endian weight bytes of group `g`: `N` triples
    /// `[a, b, c]` of 6 bytes (empty if `g` is out of range).
    pub fn group_bytes(&self, g: usize) -> &'a [u8] {
        let n6 = 6 * self.disparities();
        self.weights.get(g * n6..(g + 1) * n6).unwrap_or(&[])
    }

    /// Every group's raw weight bytes: group `g`'s triple of disparity `d`
    /// at `6·(g·N + d)` ([`DemTable::group_bytes`]).
    pub const fn weight_bytes(&self) -> &'a [u8] {
        self.weights
    }

    /// The weights `[a, b, c]` of group `g`, one per disparity.
    pub fn group(&self, g: usize) -> impl ExactSizeIterator<Item = [i16; 3]> + 'a {
        self.group_bytes(g).chunks_exact(6).map(|c| {
            [
                i16_of(c.get(0..2).unwrap_or(&[])),
                i16_of(c.get(2..4).unwrap_or(&[])),
                i16_of(c.get(4..6).unwrap_or(&[])),
            ]
        })
    }

    /// Every weight triple, group-major.
    pub fn weights(&self) -> impl ExactSizeIterator<Item = [i16; 3]> + 'a {
        self.weights.chunks_exact(6).map(|c| {
            [
                i16_of(c.get(0..2).unwrap_or(&[])),
                i16_of(c.get(2..4).unwrap_or(&[])),
                i16_of(c.get(4..6).unwrap_or(&[])),
            ]
        })
    }

    /// The raw little-endian bias bytes: disparity `d`'s at `2d`.
    pub const fn bias_bytes(&self) -> &'a [u8] {
        self.bias
    }

    /// The bias per disparity.
    pub fn bias(&self) -> impl ExactSizeIterator<Item = i16> + 'a {
        self.bias.chunks_exact(2).map(i16_of)
    }

    /// The bias of disparity `d` (0 if out of range).
    pub fn bias_at(&self, d: usize) -> i16 {
        self.bias.get(2 * d..2 * d + 2).map_or(0, i16_of)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> [u8; 56] {
        // max_disp 1, levels 1, carriers 1, step 1 -> 2 groups, N = 2.
        let mut b = [0u8; 56];
        b[..4].copy_from_slice(&MAGIC);
        b[4..6].copy_from_slice(&VERSION.to_le_bytes());
        b[6..8].copy_from_slice(&(HEADER_LEN as u16).to_le_bytes());
        b[8..13].copy_from_slice(&[1, 1, 1, 1, 7]);
        b[13] = 10;
        b[14] = 12;
        b[16..18].copy_from_slice(&1024u16.to_le_bytes());
        b[20..22].copy_from_slice(&2u16.to_le_bytes());
        b[22..24].copy_from_slice(&2u16.to_le_bytes());
        for (i, c) in b[24..24 + 28].chunks_exact_mut(2).enumerate() {
            c.copy_from_slice(&(i as i16 - 7).to_le_bytes());
        }
        let end = b.len() - 4;
        let mut f = Fnv1a::new();
        f.write(&b[..end]);
        let h = f.finish();
        b[end..].copy_from_slice(&h.to_le_bytes());
        b
    }

    #[test]
    fn any_layout_bytes_give_counts_without_a_panic() {
        // A corrupt header can hold any bytes: 255 levels shift the step
        // past the word, which is taken as the widest step (one shift).
        let l = DemLayout {
            max_disp: 255,
            levels: 255,
            carriers: 255,
            shift_step: 255,
            radius: 255,
            wavelength_q8: u16::MAX,
            sigma_q12: u16::MAX,
        };
        assert_eq!(l.shifts(0), 2);
        assert_eq!(l.shifts(200), 1);
        // 255 at levels 0 and 1 (2 and 1 shifts), then 1 shift per level.
        assert_eq!(l.groups(), 255 * (2 + 1 + 253));
        let z = DemLayout { shift_step: 0, ..l };
        assert_eq!(z.shifts(0), 256);
    }

    #[test]
    fn parses_and_reads_weights() {
        let b = tiny();
        let t = DemTable::parse(&b).unwrap();
        assert_eq!(t.layout.groups(), 2);
        assert_eq!(t.group(1).next(), Some([-1, 0, 1]));
        assert_eq!(t.bias().collect::<heapless::Vec<i16, 4>>(), [5, 6]);
        let mut c = b;
        c[30] ^= 4;
        assert!(matches!(
            DemTable::parse(&c),
            Err(TableError::Checksum { .. })
        ));
        assert!(matches!(
            DemTable::parse(&b[..20]),
            Err(TableError::Truncated { .. })
        ));
    }
}
