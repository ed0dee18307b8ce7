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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::HostError;
    use crate::ground_truth::load_gt;
    use npyz::{AutoSerialize, WriteOptions, WriterBuilder};
    use std::io::Write;
    use std::path::Path;

    /// A `.npy` of `data` (in file order) with `shape` and `order`.
    fn npy<T: AutoSerialize + Clone>(shape: &[u64], order: Order, data: &[T]) -> Vec<u8> {
        let mut buf = Vec::new();
        let mut w = WriteOptions::new()
            .default_dtype()
            .shape(shape)
            .order(order)
            .writer(&mut buf)
            .begin_nd()
            .unwrap();
        w.extend(data.iter().cloned()).unwrap();
        w.finish().unwrap();
        buf
    }

    /// A deflated `.npz` of `(member name, npy bytes)`.
    fn npz(members: &[(&str, Vec<u8>)]) -> Vec<u8> {
        let mut z = zip::ZipWriter::new(Cursor::new(Vec::new()));
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        for (name, bytes) in members {
            z.start_file(*name, opts).unwrap();
            z.write_all(bytes).unwrap();
        }
        z.finish().unwrap().into_inner()
    }

    fn load(dir: &Path, name: &str, bytes: &[u8]) -> crate::error::Result<GtMap> {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        load_gt(&p, 1.0)
    }

    fn reason(r: crate::error::Result<GtMap>) -> String {
        match r {
            Err(HostError::BadGroundTruth { reason, .. }) => reason,
            other => panic!("expected BadGroundTruth, got {other:?}"),
        }
    }

    /// 2 rows x 3 columns with every kind of unknown.
    const VALUES: [f32; 6] = [1.5, f32::INFINITY, 0.0, -2.0, f32::NAN, 1.25];
    const EXPECTED: [Option<f32>; 6] = [Some(1.5), None, None, None, None, Some(1.25)];

    #[test]
    fn npy_and_npz_round_trip_with_unknowns() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let f32_c = npy(&[2, 3], Order::C, &VALUES);
        let f64_c = npy(&[2, 3], Order::C, &VALUES.map(f64::from));
        // Column-major file order of the same 2x3 array.
        let fortran: Vec<f32> = [0, 3, 1, 4, 2, 5].iter().map(|&k| VALUES[k]).collect();
        let f32_f = npy(&[2, 3], Order::Fortran, &fortran);
        let other = npy(&[1, 1], Order::C, &[99.0f32]);
        let cases = [
            ("a.npy", f32_c.clone()),
            ("b.npy", f64_c.clone()),
            ("c.npy", f32_f),
            ("d.npz", npz(&[("arr_0.npy", f32_c.clone())])),
            // arr_0 wins over an earlier member; else the first array.
            (
                "e.npz",
                npz(&[("x.npy", other), ("arr_0.npy", f64_c.clone())]),
            ),
            (
                "f.npz",
                npz(&[("readme.txt", b"hi".to_vec()), ("disp.npy", f32_c)]),
            ),
        ];
        for (name, bytes) in cases {
            let g = load(d, name, &bytes).unwrap();
            assert_eq!((g.width, g.height), (3, 2), "{name}");
            assert_eq!(g.data, EXPECTED, "{name}");
        }
    }

    #[test]
    fn truncated_or_corrupt_files_are_typed_errors() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let good = npy(&[2, 3], Order::C, &VALUES);
        let archive = npz(&[("arr_0.npy", npy(&[40, 50], Order::C, &[3.0f32; 2000]))]);
        let mut flipped = archive.clone();
        // A byte in the deflated data: the CRC (or the inflater) catches it.
        flipped[60] ^= 0x55;
        for (name, bytes) in [
            ("short.npy", good[..good.len() - 1].to_vec()),
            ("header.npy", good[..12].to_vec()),
            ("magic.npy", NPY_MAGIC.to_vec()),
            ("short.npz", archive[..archive.len() / 2].to_vec()),
            ("flipped.npz", flipped),
            ("empty.npz", npz(&[])),
            ("text.npz", npz(&[("a.txt", b"x".to_vec())])),
        ] {
            let r = reason(load(d, name, &bytes));
            eprintln!("{name}: {r}");
            assert!(!r.contains('\n'), "{name}: {r}");
        }
    }

    #[test]
    fn wrong_dtype_or_rank_is_a_typed_error() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let ints = reason(load(d, "i.npy", &npy(&[2, 3], Order::C, &[1i32; 6])));
        assert!(ints.contains("not float32"), "{ints}");
        let half = reason(load(
            d,
            "u.npz",
            &npz(&[("arr_0.npy", npy(&[2], Order::C, &[1u16; 2]))]),
        ));
        assert!(half.contains("not float32"), "{half}");
        for shape in [&[6u64][..], &[1, 2, 3], &[0, 3]] {
            let n = shape.iter().product::<u64>() as usize;
            let r = reason(load(d, "s.npy", &npy(shape, Order::C, &vec![1.0f32; n])));
            assert!(r.contains("2-D") || r.contains("size"), "{shape:?}: {r}");
        }
    }

    #[test]
    fn gt_of_another_size_than_the_left_image_is_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let img = d.join("l.png");
        image::RgbImage::new(3, 2).save(&img).unwrap();
        let ok = d.join("ok.npy");
        std::fs::write(&ok, npy(&[2, 3], Order::C, &VALUES)).unwrap();
        let pair = crate::pair::load_pair(&img, &img, Some(&ok), 1.0, 3).unwrap();
        assert_eq!(pair.gt.unwrap().data, EXPECTED);
        // 3 rows x 2 columns: the transposed size.
        let bad = d.join("bad.npz");
        std::fs::write(&bad, npz(&[("arr_0.npy", npy(&[3, 2], Order::C, &VALUES))])).unwrap();
        let err = crate::pair::load_pair(&img, &img, Some(&bad), 1.0, 3).unwrap_err();
        assert!(
            matches!(
                err,
                HostError::GroundTruthSize {
                    got: (2, 3),
                    expected: (3, 2),
                    ..
                }
            ),
            "{err:?}"
        );
    }
}
