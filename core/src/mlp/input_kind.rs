//! What a model's input is ([`InputKind`]): the model blob's input code
//! (docs/MODEL_FORMAT.md).

use super::blob::INPUT_I4F12;

/// What a model's input is: the blob's input code. Every kind is read as
/// `I4F12` (`raw / 4096`). Code 1 (shape) is the original format and takes
/// any length (720 in practice); codes 2 to 8 are the image conditions of
/// the paper's section 4.4 and fix the length.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum InputKind {
    /// Shape vector `s^N` (code 1, 720 values).
    Shape,
    /// Luminance `I_L^N`, 60×60 (code 2).
    Luminance,
    /// Colour `I_C^N` as an indexed image, 60×60 (code 3).
    Colour,
    /// Colour as three 60×60 planes, R, G, B (code 4).
    Colour3,
    /// Conspicuity `C^N`, 60×60 (code 5).
    Conspicuity,
    /// Range `R^N`, 60×60 (code 6).
    Range,
    /// `(s^N, R^N)`, 720 + 3600 (code 7).
    ShapeRange,
    /// `(s^N, R^N, C^N, I_L^N)`, 720 + 3·3600 (code 8).
    ShapeRangeConspicuityLuminance,
}

impl InputKind {
    /// Every kind, by code.
    pub const ALL: [Self; 8] = [
        Self::Shape,
        Self::Luminance,
        Self::Colour,
        Self::Colour3,
        Self::Conspicuity,
        Self::Range,
        Self::ShapeRange,
        Self::ShapeRangeConspicuityLuminance,
    ];

    /// Its code in the blob header.
    pub const fn code(self) -> u8 {
        match self {
            Self::Shape => INPUT_I4F12,
            Self::Luminance => 2,
            Self::Colour => 3,
            Self::Colour3 => 4,
            Self::Conspicuity => 5,
            Self::Range => 6,
            Self::ShapeRange => 7,
            Self::ShapeRangeConspicuityLuminance => 8,
        }
    }

    /// The kind of a code (`None` for an unknown one).
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(Self::Shape),
            2 => Some(Self::Luminance),
            3 => Some(Self::Colour),
            4 => Some(Self::Colour3),
            5 => Some(Self::Conspicuity),
            6 => Some(Self::Range),
            7 => Some(Self::ShapeRange),
            8 => Some(Self::ShapeRangeConspicuityLuminance),
            _ => None,
        }
    }

    /// Input length (`SHAPE_LEN` for shape).
    pub const fn input_len(self) -> usize {
        const IMG: usize = 3600;
        match self {
            Self::Shape => crate::shape::SHAPE_LEN,
            Self::Colour3 => 3 * IMG,
            Self::ShapeRange => crate::shape::SHAPE_LEN + IMG,
            Self::ShapeRangeConspicuityLuminance => crate::shape::SHAPE_LEN + 3 * IMG,
            _ => IMG,
        }
    }

    /// The name `protogist train --features` and `experiment` use.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Shape => "shape",
            Self::Luminance => "luminance",
            Self::Colour => "colour",
            Self::Colour3 => "colour3",
            Self::Conspicuity => "conspicuity",
            Self::Range => "range",
            Self::ShapeRange => "shape-range",
            Self::ShapeRangeConspicuityLuminance => "all",
        }
    }
}
