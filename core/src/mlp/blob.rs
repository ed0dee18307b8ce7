//! The model blob (`PGML` versions 1 and 2): a little-endian byte string
//! parsed zero-copy into a [`Model`] that borrows its sections. The layout
//! is documented field by field in `docs/MODEL_FORMAT.md`. Version 2 adds,
//! after the templates, one [`Symmetry`] byte per class: the mirrors under
//! which the class looks the same (for the mirror check,
//! [`super::mirror_check`]); a version-1 blob has no symmetry.
//!
//! Multi-byte fields are decoded with `from_le_bytes` on byte slices, so the
//! blob may sit at any address (flash or RAM) and no `unsafe` is needed.

pub use super::input_kind::InputKind;
pub use super::symmetry::Symmetry;

/// The first four bytes of every model.
pub const MAGIC: [u8; 4] = *b"PGML";
/// The newest version, the one with per-class [`Symmetry`] bytes.
pub const VERSION: u16 = 2;
/// The first version (no symmetry section), still read.
pub const VERSION_1: u16 = 1;
/// Bytes of the fixed header.
pub const HEADER_LEN: usize = 40;
/// Bytes of the CRC-32 trailer.
pub const CRC_LEN: usize = 4;
/// Input format 1: shape elements (`I4F12`, the core `shape` stage).
pub const INPUT_I4F12: u8 = 1;

/// Weight format 1: int8, symmetric, one scale per output channel, each
/// stored excess-128 (byte `w + 128`, so `w = −127..=127` is `1..=255`).
pub const WEIGHTS_I8_PER_CHANNEL: u8 = 1;
/// Hidden activation format 1: u8, scale 1/255 (log-sigmoid).
pub const HIDDEN_U8: u8 = 1;
/// Output format 2: u16, scale 1/65535 (log-sigmoid).
pub const OUTPUT_U16: u8 = 2;
/// Most classes a model may have (keeps the integer cosine in range).
pub const MAX_CLASSES: usize = 1024;
/// Longest class name in bytes.
pub const MAX_NAME_LEN: usize = 64;

/// Why a blob is not a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ModelError {
    /// Shorter than its header says (`needed` bytes, `got`).
    Truncated {
        /// Bytes the header asks for.
        needed: usize,
        /// Bytes given.
        got: usize,
    },
    /// Longer than its header says.
    TrailingBytes {
        /// Bytes the header asks for.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// Not `PGML`.
    BadMagic,
    /// A version this crate does not read.
    UnsupportedVersion(u16),
    /// An unknown format code (input, weights, hidden or output).
    UnsupportedFormat {
        /// Which field.
        field: &'static str,
        /// Its code.
        code: u8,
    },
    /// Zero or too large dimensions.
    BadDims,
    /// The CRC-32 of the content is not the stored one.
    BadCrc {
        /// Stored CRC.
        stored: u32,
        /// Computed CRC.
        computed: u32,
    },
    /// A requantisation multiplier below 0 or a shift outside `−31..=30`.
    BadRequant,
    /// Class `index` has an empty, too long or non-UTF-8 name, or the names
    /// do not fill their section exactly.
    BadClassName {
        /// The class.
        index: usize,
    },
    /// The metadata section is not UTF-8.
    BadMeta,
    /// Class `index`'s symmetry byte has bits other than 0 and 1 set, or
    /// a mirror is flagged on a model whose input is not a
    /// [`SHAPE_LEN`](crate::shape::SHAPE_LEN)-element shape vector.
    BadSymmetry {
        /// The class.
        index: usize,
    },
    /// An image input kind whose length `d` is not the kind's.
    InputLength {
        /// The input code.
        code: u8,
        /// The kind's length.
        expected: usize,
        /// `d` in the header.
        got: usize,
    },
}

impl core::error::Error for ModelError {}

impl core::fmt::Display for ModelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Truncated { needed, got } => {
                write!(f, "truncated: {got} bytes, the header needs {needed}")
            }
            Self::TrailingBytes { expected, got } => {
                write!(f, "{got} bytes, the header describes {expected}")
            }
            Self::BadMagic => write!(f, "not a protogist model (magic is not PGML)"),
            Self::UnsupportedVersion(v) => {
                write!(
                    f,
                    "model version {v}, this build reads versions {VERSION_1} to {VERSION}"
                )
            }
            Self::UnsupportedFormat { field, code } => {
                write!(f, "unsupported {field} format code {code}")
            }
            Self::BadDims => write!(f, "zero or too large dimensions"),
            Self::BadCrc { stored, computed } => write!(
                f,
                "corrupt: CRC-32 {computed:#010x}, the model stores {stored:#010x}"
            ),
            Self::BadRequant => write!(f, "a requantisation multiplier or shift is out of range"),
            Self::BadClassName { index } => write!(f, "class name {index} is bad"),
            Self::BadMeta => write!(f, "metadata is not UTF-8"),
            Self::BadSymmetry { index } => write!(f, "symmetry byte of class {index} is bad"),
            Self::InputLength {
                code,
                expected,
                got,
            } => write!(
                f,
                "input code {code} takes {expected} values, the header says {got}"
            ),
        }
    }
}

/// CRC-32 (IEEE 802.3, reflected, polynomial `0xEDB88320`, initial and final
/// XOR `0xFFFFFFFF`), the checksum of zip and PNG. `crc32(b"123456789")` is
/// `0xCBF43926`.
pub fn crc32(bytes: &[u8]) -> u32 {
    !bytes.iter().fold(!0u32, |c, &b| {
        let i = ((c ^ u32::from(b)) & 0xff) as usize;
        CRC_TABLE.get(i).copied().unwrap_or(0) ^ (c >> 8)
    })
}

// Evaluated at compile time: an index out of bounds would fail the build.
#[allow(clippy::indexing_slicing)]
const CRC_TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// A parsed model: dimensions, the threshold and borrowed sections.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Model<'a> {
    inputs: usize,
    kind: InputKind,
    hidden: usize,
    classes: usize,
    input_multiplier: i32,
    input_shift: i32,
    delta_q16: u32,
    /// `(multiplier, shift)` pairs, 8 bytes per hidden unit.
    pub(crate) rq1: &'a [u8],
    /// `(multiplier, shift)` pairs, 8 bytes per class.
    pub(crate) rq2: &'a [u8],
    /// `i32` biases of the hidden layer.
    pub(crate) b1: &'a [u8],
    /// `i32` biases of the output layer.
    pub(crate) b2: &'a [u8],
    /// `hidden × inputs` int8 weights (excess-128 bytes), row-major.
    pub(crate) w1: &'a [u8],
    /// `classes × hidden` int8 weights (excess-128 bytes), row-major.
    pub(crate) w2: &'a [u8],
    /// `classes × classes` u16 templates.
    pub(crate) templates: &'a [u8],
    /// One [`Symmetry`] byte per class (empty in a version-1 blob).
    symmetry: &'a [u8],
    names: &'a [u8],
    meta: &'a str,
}

/// Little-endian reads that cannot panic.
pub(crate) fn le_u16(b: &[u8], at: usize) -> u16 {
    let mut a = [0u8; 2];
    if let Some(s) = b.get(at..at.wrapping_add(2)) {
        a.copy_from_slice(s);
    }
    u16::from_le_bytes(a)
}

pub(crate) fn le_u32(b: &[u8], at: usize) -> u32 {
    let mut a = [0u8; 4];
    if let Some(s) = b.get(at..at.wrapping_add(4)) {
        a.copy_from_slice(s);
    }
    u32::from_le_bytes(a)
}

pub(crate) fn le_i32(b: &[u8], at: usize) -> i32 {
    le_u32(b, at) as i32
}

/// Bytes of the symmetry section of a blob of `version` with `k` classes.
pub const fn symmetry_len(version: u16, k: usize) -> usize {
    if version >= VERSION {
        k
    } else {
        0
    }
}

/// Section lengths in blob order, from the header fields.
fn section_lengths(
    version: u16,
    d: usize,
    h: usize,
    k: usize,
    names: usize,
    meta: usize,
) -> Option<[usize; 10]> {
    Some([
        h.checked_mul(8)?,
        k.checked_mul(8)?,
        h.checked_mul(4)?,
        k.checked_mul(4)?,
        h.checked_mul(d)?,
        k.checked_mul(h)?,
        k.checked_mul(k)?.checked_mul(2)?,
        symmetry_len(version, k),
        names,
        meta,
    ])
}

/// The total length of a blob of `version` with these header fields
/// (`None` on overflow).
pub fn blob_len(
    version: u16,
    d: usize,
    h: usize,
    k: usize,
    names: usize,
    meta: usize,
) -> Option<usize> {
    section_lengths(version, d, h, k, names, meta)?
        .iter()
        .try_fold(HEADER_LEN + CRC_LEN, |a, &l| a.checked_add(l))
}

fn valid_rq(pairs: &[u8]) -> bool {
    pairs.chunks_exact(8).all(|p| {
        let (m, s) = (le_i32(p, 0), le_i32(p, 4));
        m >= 0 && (-31..=30).contains(&s)
    })
}

impl<'a> Model<'a> {
    /// Parses and validates `blob` (see the module doc and
    /// `docs/MODEL_FORMAT.md`). Checks, in order: length of the header,
    /// magic, version, formats, dimensions, total length, CRC, requantisation
    /// parameters, class names, metadata, symmetry bytes (version 2).
    ///
    /// # Errors
    /// [`ModelError`] naming the first failed check.
    pub fn parse(blob: &'a [u8]) -> Result<Self, ModelError> {
        let got = blob.len();
        if got < MAGIC.len() {
            return Err(ModelError::Truncated {
                needed: HEADER_LEN + CRC_LEN,
                got,
            });
        }
        if blob.get(..4) != Some(&MAGIC[..]) {
            return Err(ModelError::BadMagic);
        }
        if got < HEADER_LEN + CRC_LEN {
            return Err(ModelError::Truncated {
                needed: HEADER_LEN + CRC_LEN,
                got,
            });
        }
        let version = le_u16(blob, 4);
        if version != VERSION && version != VERSION_1 {
            return Err(ModelError::UnsupportedVersion(version));
        }
        let byte = |at: usize| blob.get(at).copied().unwrap_or(0);
        let kind = InputKind::from_code(byte(6)).ok_or(ModelError::UnsupportedFormat {
            field: "input",
            code: byte(6),
        })?;
        for (field, at, want) in [
            ("weights", 7, WEIGHTS_I8_PER_CHANNEL),
            ("hidden", 8, HIDDEN_U8),
            ("output", 9, OUTPUT_U16),
        ] {
            if byte(at) != want {
                return Err(ModelError::UnsupportedFormat {
                    field,
                    code: byte(at),
                });
            }
        }
        let d = usize::from(le_u16(blob, 10));
        let h = usize::from(le_u16(blob, 12));
        let k = usize::from(le_u16(blob, 14));
        if d == 0 || h == 0 || k == 0 || k > MAX_CLASSES {
            return Err(ModelError::BadDims);
        }
        if kind != InputKind::Shape && d != kind.input_len() {
            return Err(ModelError::InputLength {
                code: kind.code(),
                expected: kind.input_len(),
                got: d,
            });
        }
        let names_len = le_u32(blob, 32) as usize;
        let meta_len = le_u32(blob, 36) as usize;
        let lens =
            section_lengths(version, d, h, k, names_len, meta_len).ok_or(ModelError::BadDims)?;
        let needed = blob_len(version, d, h, k, names_len, meta_len).ok_or(ModelError::BadDims)?;
        if got < needed {
            return Err(ModelError::Truncated { needed, got });
        }
        if got > needed {
            return Err(ModelError::TrailingBytes {
                expected: needed,
                got,
            });
        }
        let body = needed - CRC_LEN;
        let stored = le_u32(blob, body);
        let computed = crc32(blob.get(..body).unwrap_or(&[]));
        if stored != computed {
            return Err(ModelError::BadCrc { stored, computed });
        }
        let mut sections: [&[u8]; 10] = [&[]; 10];
        let mut at = HEADER_LEN;
        for (s, &l) in sections.iter_mut().zip(&lens) {
            *s = blob.get(at..at + l).ok_or(ModelError::BadDims)?;
            at += l;
        }
        let [rq1, rq2, b1, b2, w1, w2, templates, symmetry, names, meta] = sections;
        if !valid_rq(rq1) || !valid_rq(rq2) {
            return Err(ModelError::BadRequant);
        }
        let (input_multiplier, input_shift) = (le_i32(blob, 16), le_i32(blob, 20));
        if !valid_rq(blob.get(16..24).unwrap_or(&[])) {
            return Err(ModelError::BadRequant);
        }
        // Names: k entries of (length byte, UTF-8 bytes), filling the section.
        let mut rest = names;
        for index in 0..k {
            let bad = ModelError::BadClassName { index };
            let (&n, tail) = rest.split_first().ok_or(bad)?;
            let n = usize::from(n);
            if n == 0 || n > MAX_NAME_LEN {
                return Err(bad);
            }
            let name = tail.get(..n).ok_or(bad)?;
            core::str::from_utf8(name).map_err(|_| bad)?;
            rest = tail.get(n..).ok_or(bad)?;
        }
        if !rest.is_empty() {
            return Err(ModelError::BadClassName { index: k });
        }
        let meta = core::str::from_utf8(meta).map_err(|_| ModelError::BadMeta)?;
        // Mirrors permute a shape vector's bins: only such an input has them.
        let mirrors = kind == InputKind::Shape && d == crate::shape::SHAPE_LEN;
        for (index, &b) in symmetry.iter().enumerate() {
            match Symmetry::from_bits(b) {
                Some(s) if mirrors || s == Symmetry::NONE => {}
                _ => return Err(ModelError::BadSymmetry { index }),
            }
        }
        Ok(Self {
            inputs: d,
            kind,
            hidden: h,
            classes: k,
            input_multiplier,
            input_shift,
            delta_q16: le_u32(blob, 24),
            rq1,
            rq2,
            b1,
            b2,
            w1,
            w2,
            templates,
            symmetry,
            names,
            meta,
        })
    }

    /// Input length (720 for shape vectors).
    pub const fn inputs(&self) -> usize {
        self.inputs
    }

    /// What the input is (the header's input code).
    pub const fn input_kind(&self) -> InputKind {
        self.kind
    }

    /// Checks that the model takes `kind`.
    ///
    /// # Errors
    /// [`super::MlpError::InputKind`] naming both kinds.
    pub const fn expect_input(&self, kind: InputKind) -> Result<(), super::MlpError> {
        if self.kind.code() == kind.code() {
            Ok(())
        } else {
            Err(super::MlpError::InputKind {
                model: self.kind,
                given: kind,
            })
        }
    }

    /// Hidden units.
    pub const fn hidden(&self) -> usize {
        self.hidden
    }

    /// Classes (outputs).
    pub const fn classes(&self) -> usize {
        self.classes
    }

    /// The input requantisation `(multiplier, shift)`: `I4F12` raw values to
    /// int8 (see [`super::quantize_input`]).
    pub const fn input_requant(&self) -> (i32, i32) {
        (self.input_multiplier, self.input_shift)
    }

    /// The verification and identification threshold `Δ` in Q16 (65536 is
    /// a cosine of 1).
    pub const fn delta_q16(&self) -> u32 {
        self.delta_q16
    }

    /// Free-form UTF-8 metadata (how the model was made).
    pub const fn meta(&self) -> &'a str {
        self.meta
    }

    /// Bytes of weights, biases, requantisation pairs and templates (the
    /// flash the network needs beside the names and metadata).
    pub const fn parameter_bytes(&self) -> usize {
        self.rq1.len()
            + self.rq2.len()
            + self.b1.len()
            + self.b2.len()
            + self.w1.len()
            + self.w2.len()
            + self.templates.len()
    }

    /// Name of class `c` (`None` out of range).
    pub fn class_name(&self, c: usize) -> Option<&'a str> {
        let mut rest = self.names;
        for i in 0..self.classes {
            let (&n, tail) = rest.split_first()?;
            let (name, tail) = tail.split_at_checked(usize::from(n))?;
            if i == c {
                return core::str::from_utf8(name).ok();
            }
            rest = tail;
        }
        None
    }

    /// The mirrors class `c` looks the same under ([`Symmetry::NONE`] in
    /// a version-1 blob and out of range).
    pub fn symmetry(&self, c: usize) -> Symmetry {
        self.symmetry
            .get(c)
            .and_then(|&b| Symmetry::from_bits(b))
            .unwrap_or(Symmetry::NONE)
    }

    /// The union of every class's symmetry: the mirrors the mirror check
    /// runs the network on ([`Symmetry::NONE`]: the check is the plain
    /// identification).
    pub fn any_symmetry(&self) -> Symmetry {
        let bits = self.symmetry.iter().fold(0u8, |a, &b| a | b);
        Symmetry::from_bits(bits).unwrap_or(Symmetry::NONE)
    }

    /// Whether the blob has a symmetry section (version 2).
    pub const fn has_symmetry_section(&self) -> bool {
        !self.symmetry.is_empty()
    }

    /// Template `v_c` (u16 per output), as its little-endian bytes.
    pub(crate) fn template(&self, c: usize) -> Option<&'a [u8]> {
        // `classes >= 1` (`parse`); `max` shows the compiler (no panic path).
        self.templates
            .chunks_exact((2 * self.classes).max(1))
            .nth(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn short_and_foreign_blobs() {
        assert_eq!(
            Model::parse(b"PG"),
            Err(ModelError::Truncated { needed: 44, got: 2 })
        );
        assert_eq!(Model::parse(b"GIF89a"), Err(ModelError::BadMagic));
        let mut b = [0u8; 44];
        b[..4].copy_from_slice(&MAGIC);
        b[4] = 3;
        assert_eq!(Model::parse(&b), Err(ModelError::UnsupportedVersion(3)));
        b[4] = 2;
        assert!(matches!(
            Model::parse(&b),
            Err(ModelError::UnsupportedFormat {
                field: "input",
                code: 0
            })
        ));
        b[4] = 1;
        assert!(matches!(
            Model::parse(&b),
            Err(ModelError::UnsupportedFormat {
                field: "input",
                code: 0
            })
        ));
    }
}
