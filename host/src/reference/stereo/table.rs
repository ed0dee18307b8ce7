//! The trained decoder as a compact, versioned, little-endian integer table
//! that core reads from `&[u8]`.
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

use super::{Decoder, DemLayout};
use protogist::checksum::Fnv1a;
// The parser is core's (`protogist::stereo::table`); this file keeps the
// owned form and the writer.
use protogist::stereo::table as core_table;
pub use protogist::stereo::table::{table_len, TableError, HEADER_LEN, MAGIC, VERSION};

/// The integer table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DemTable {
    /// The population it decodes.
    pub layout: DemLayout,
    /// Fraction bits of the weights.
    pub weight_frac: u8,
    /// Fraction bits of the bias.
    pub bias_frac: u8,
    /// `[group][d]` → `[a, b, c]`.
    pub weights: Vec<[i16; 3]>,
    /// Bias per disparity.
    pub bias: Vec<i16>,
}

/// Most fraction bits (≤ 14) that keep `max_abs` within i16.
fn frac_bits(max_abs: f32) -> u8 {
    (0..=14u8)
        .rev()
        .find(|&f| max_abs * f32::from(1u16 << f) <= 32767.0)
        .unwrap_or(0)
}

fn quantise(v: f32, frac: u8) -> i16 {
    (v * f32::from(1u16 << frac))
        .round()
        .clamp(-32767.0, 32767.0) as i16
}

impl DemTable {
    /// Quantises a decoder, choosing the fraction bits from its range.
    pub fn from_decoder(d: &Decoder) -> Self {
        let wmax = d
            .weights
            .iter()
            .flatten()
            .fold(0.0f32, |m, v| m.max(v.abs()));
        let bmax = d.bias.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        let (wf, bf) = (frac_bits(wmax), frac_bits(bmax));
        Self {
            layout: d.layout,
            weight_frac: wf,
            bias_frac: bf,
            weights: d
                .weights
                .iter()
                .map(|w| w.map(|v| quantise(v, wf)))
                .collect(),
            bias: d.bias.iter().map(|&v| quantise(v, bf)).collect(),
        }
    }

    /// The f32 decoder the table holds (exact values of the integers).
    pub fn to_decoder(&self) -> Decoder {
        let (ws, bs) = (
            f32::from(1u16 << self.weight_frac),
            f32::from(1u16 << self.bias_frac),
        );
        Decoder {
            layout: self.layout,
            weights: self
                .weights
                .iter()
                .map(|w| w.map(|v| f32::from(v) / ws))
                .collect(),
            bias: self.bias.iter().map(|&v| f32::from(v) / bs).collect(),
        }
    }

    /// The little-endian bytes, checksum last.
    pub fn to_bytes(&self) -> Vec<u8> {
        let l = &self.layout;
        let mut b = Vec::with_capacity(table_len(self.weights.len(), self.bias.len()));
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&(HEADER_LEN as u16).to_le_bytes());
        b.extend_from_slice(&[l.max_disp, l.levels, l.carriers, l.shift_step, l.radius]);
        b.extend_from_slice(&[self.weight_frac, self.bias_frac, 0]);
        b.extend_from_slice(&l.wavelength_q8.to_le_bytes());
        b.extend_from_slice(&l.sigma_q12.to_le_bytes());
        let groups = self.weights.len() / self.bias.len().max(1);
        b.extend_from_slice(&(groups as u16).to_le_bytes());
        b.extend_from_slice(&(self.bias.len() as u16).to_le_bytes());
        for v in self.weights.iter().flatten().chain(&self.bias) {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let mut h = Fnv1a::new();
        h.write(&b);
        b.extend_from_slice(&h.finish().to_le_bytes());
        b
    }

    /// Parses and checks a table (core's parser, then copied).
    ///
    /// # Errors
    /// [`TableError`] for anything but an intact table of this version.
    pub fn parse(bytes: &[u8]) -> Result<Self, TableError> {
        let t = core_table::DemTable::parse(bytes)?;
        Ok(Self {
            layout: t.layout,
            weight_frac: t.weight_frac,
            bias_frac: t.bias_frac,
            weights: t.weights().collect(),
            bias: t.bias().collect(),
        })
    }
}

/// The table trained for `DemParams::default()`, by
/// `protogist train-dem --out host/data/dem_default.bin`.
pub const DEFAULT_TABLE: &[u8] = include_bytes!("../../../data/dem_default.bin");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::stereo::{train, DemParams};
    use proptest::prelude::*;

    fn small() -> DemTable {
        let p = DemParams {
            max_disp: 5,
            train_images: 1,
            train_width: 16,
            train_height: 8,
            ..DemParams::default()
        };
        DemTable::from_decoder(&train(&p))
    }

    #[test]
    fn round_trip_is_exact_and_dequantisation_is_close() {
        let t = small();
        let bytes = t.to_bytes();
        assert_eq!(bytes.len(), table_len(t.weights.len(), t.bias.len()));
        assert_eq!(DemTable::parse(&bytes).unwrap(), t);
        let d = t.to_decoder();
        assert_eq!(DemTable::from_decoder(&d), t);
    }

    #[test]
    fn the_default_table_is_what_train_dem_writes() {
        let t = DemTable::parse(DEFAULT_TABLE).unwrap();
        assert_eq!(
            t.layout,
            crate::reference::stereo::layout_of(&DemParams::default())
        );
        assert!(DEFAULT_TABLE.len() < 64 * 1024);
        assert_eq!(DemTable::from_decoder(&train(&DemParams::default())), t);
    }

    #[test]
    fn corrupt_tables_give_typed_errors() {
        let good = small().to_bytes();
        let mut b = good.clone();
        b[0] = b'X';
        assert_eq!(DemTable::parse(&b), Err(TableError::BadMagic));
        let mut b = good.clone();
        b[4] = 2;
        assert_eq!(DemTable::parse(&b), Err(TableError::Version(2)));
        let mut b = good.clone();
        b[HEADER_LEN + 3] ^= 1;
        assert!(matches!(
            DemTable::parse(&b),
            Err(TableError::Checksum { .. })
        ));
        assert!(matches!(
            DemTable::parse(&good[..good.len() - 1]),
            Err(TableError::Truncated { .. })
        ));
        assert!(matches!(
            DemTable::parse(&good[..10]),
            Err(TableError::Truncated { .. })
        ));
        let mut b = good.clone();
        b.push(0);
        assert!(matches!(
            DemTable::parse(&b),
            Err(TableError::TrailingBytes { .. })
        ));
        // A consistent checksum over an inconsistent header.
        let mut b = good[..good.len() - 4].to_vec();
        b[9] = 3;
        let mut h = Fnv1a::new();
        h.write(&b);
        b.extend_from_slice(&h.finish().to_le_bytes());
        assert!(matches!(
            DemTable::parse(&b),
            Err(TableError::Inconsistent(_))
        ));
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
            let _ = DemTable::parse(&bytes);
        }

        #[test]
        fn truncated_or_flipped_tables_are_rejected(cut in 0usize..1000, flip in 0usize..1000, bit in 0u8..8) {
            let good = DEFAULT_TABLE;
            let cut = cut % good.len();
            prop_assert!(DemTable::parse(&good[..cut]).is_err());
            let mut b = good.to_vec();
            let i = flip % b.len();
            b[i] ^= 1 << bit;
            prop_assert!(DemTable::parse(&b).is_err());
        }

        #[test]
        fn headers_with_any_dimensions_never_panic(h in proptest::collection::vec(any::<u8>(), HEADER_LEN..HEADER_LEN + 64)) {
            let mut b = h;
            b[..4].copy_from_slice(&MAGIC);
            b[4..6].copy_from_slice(&VERSION.to_le_bytes());
            b[6..8].copy_from_slice(&(HEADER_LEN as u16).to_le_bytes());
            let mut f = Fnv1a::new();
            f.write(&b);
            b.extend_from_slice(&f.finish().to_le_bytes());
            let _ = DemTable::parse(&b);
        }
    }
}
