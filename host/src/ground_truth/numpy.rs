//! NumPy ground truth: a 2-D float32 or float64 array of disparities in px
//! (rows first, as `np.save` writes an `(height, width)` array), in a `.npy`
//! file or as a member of a `.npz` archive (`arr_0`, else the first array).
//! Non-finite and non-positive values are unknown. Parsing is `npyz`'s, the
//! archive `zip`'s (npyz's documented "npz without the feature" route: zip
//! with only its pure-Rust deflate, no C codecs).

use super::GtMap;
use npyz::{DType, NpyFile, Order, TypeChar};
use std::io::{Cursor, Read};

/// Magic of a `.npy` file.
pub const NPY_MAGIC: &[u8] = b"\x93NUMPY";
/// Magic of a zip archive (`.npz`): a local file header, or the end record
/// of an empty archive.
pub const ZIP_MAGICS: [&[u8]; 2] = [b"PK\x03\x04", b"PK\x05\x06"];

/// Largest accepted side, px (as for PFM).
const MAX_SIDE: u64 = 1 << 16;

/// Parses a `.npy` file.
///
/// # Errors
/// A one-line reason: truncated or corrupt, not a float array, not 2-D.
pub fn parse_npy(bytes: &[u8]) -> Result<GtMap, String> {
    read_array(Cursor::new(bytes), bytes.len() as u64)
}

/// Parses a `.npz` archive: its `arr_0` member, else its first `.npy`
/// member in archive order.
///
/// # Errors
/// A one-line reason: not a readable archive, no array in it, or the
/// array's own errors of [`parse_npy`].
pub fn parse_npz(bytes: &[u8]) -> Result<GtMap, String> {
    let mut zip =
        zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| format!("corrupt npz: {e}"))?;
    let index = zip
        .index_for_name("arr_0.npy")
        .or_else(|| {
            (0..zip.len()).find(|&k| zip.name_for_index(k).is_some_and(|n| n.ends_with(".npy")))
        })
        .ok_or("npz holds no .npy array")?;
    let member = zip
        .by_index(index)
        .map_err(|e| format!("corrupt npz: {e}"))?;
    let name = member.name().to_string();
    let size = member.size();
    read_array(member, size).map_err(|e| format!("{name}: {e}"))
}

/// Reads one array from `reader`, which holds `available` bytes from the
/// start of the `.npy` header.
fn read_array(reader: impl Read, available: u64) -> Result<GtMap, String> {
    let npy = NpyFile::new(reader).map_err(|e| format!("corrupt or truncated npy header: {e}"))?;
    let dtype = npy.dtype();
    let item = match &dtype {
        DType::Plain(t) if t.type_char() == TypeChar::Float && matches!(t.size_field(), 4 | 8) => {
            t.size_field()
        }
        other => return Err(format!("dtype {} is not float32 or float64", other.descr())),
    };
    let (h, w) = match *npy.shape() {
        [h, w] if (1..=MAX_SIDE).contains(&h) && (1..=MAX_SIDE).contains(&w) => (h, w),
        [_, _] => return Err(format!("bad array size {:?}", npy.shape())),
        ref s => return Err(format!("array of shape {s:?} is not 2-D")),
    };
    // The data must be all there before anything is allocated for it.
    let need = h * w * item;
    if available < need {
        return Err(format!(
            "truncated npy: {available} bytes with the header, the data alone needs {need}"
        ));
    }
    let order = npy.order();
    let truncated = |e: std::io::Error| format!("truncated or corrupt npy data: {e}");
    let values: Vec<f32> = if item == 4 {
        npy.into_vec::<f32>().map_err(truncated)?
    } else {
        // f64 → f32: disparities are far inside f32's range and precision.
        #[allow(clippy::cast_possible_truncation)]
        npy.into_vec::<f64>()
            .map_err(truncated)?
            .into_iter()
            .map(|v| v as f32)
            .collect()
    };
    let (w, h) = (w as usize, h as usize);
    let known = |v: f32| (v.is_finite() && v > 0.0).then_some(v);
    let data = match order {
        Order::C => values.into_iter().map(known).collect(),
        // Column-major: element (y, x) is at x * h + y.
        Order::Fortran => (0..h)
            .flat_map(|y| (0..w).map(move |x| x * h + y))
            .map(|k| values.get(k).copied().and_then(known))
            .collect(),
    };
    Ok(GtMap {
        width: w,
        height: h,
        data,
    })
}
