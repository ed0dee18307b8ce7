//! Unit tests of `image`.

use super::*;

#[test]
fn geometry_errors_are_typed() {
    let buf = [0u8; 10];
    assert_eq!(
        ImageView::new(&buf, 0, 1, 1).err(),
        Some(ImageError::ZeroSize)
    );
    assert_eq!(
        ImageView::new(&buf, 1, 0, 1).err(),
        Some(ImageError::ZeroSize)
    );
    assert_eq!(
        ImageView::new(&buf, 3, 2, 2).err(),
        Some(ImageError::StrideTooSmall {
            width: 3,
            stride: 2
        })
    );
    assert_eq!(
        ImageView::new(&buf, 3, 3, 4).err(),
        Some(ImageError::BufferTooSmall {
            needed: 11,
            got: 10
        })
    );
    assert!(matches!(
        ImageView::new(&buf, MAX_DIM + 1, 1, MAX_DIM + 1),
        Err(ImageError::TooLarge { .. })
    ));
    // The last row needs only `width` elements, not a whole stride.
    assert!(ImageView::new(&buf, 3, 3, 4).is_err());
    assert!(ImageView::new(&buf[..], 2, 3, 4).is_ok());
}

#[test]
fn rows_skip_padding_and_sub_views_clip() {
    let buf: [u8; 12] = core::array::from_fn(|i| i as u8);
    let img = ImageView::new(&buf, 3, 3, 4).unwrap();
    let mut rows = img.rows();
    assert_eq!(rows.next(), Some(&[0u8, 1, 2][..]));
    assert_eq!(rows.next(), Some(&[4u8, 5, 6][..]));
    assert_eq!(rows.next(), Some(&[8u8, 9, 10][..]));
    assert_eq!(rows.next(), None);
    let sub = img.sub_view(1, 1, 2, 2).unwrap();
    assert_eq!(sub.get(0, 0), Some(5));
    assert_eq!(sub.get(1, 1), Some(10));
    assert_eq!(sub.get(2, 0), None);
    assert!(img.sub_view(2, 0, 2, 1).is_none());
    assert!(img.sub_view(0, 0, 0, 1).is_none());
    assert!(img.sub_view(3, 0, 1, 1).is_none());
}

#[test]
fn rows_are_exact_with_a_short_last_row_and_in_sub_views() {
    // 3x3, stride 4, in the shortest buffer: the last row has no padding.
    let mut buf: [u8; 11] = core::array::from_fn(|i| i as u8);
    let img = ImageView::new(&buf, 3, 3, 4).unwrap();
    assert_eq!(img.rows().len(), 3);
    assert_eq!(img.rows().next_back(), Some(&[8u8, 9, 10][..]));
    let mut m = ImageViewMut::new(&mut buf, 3, 3, 4).unwrap();
    assert_eq!(m.rows_mut().len(), 3);
    for (y, row) in m.rows_mut().enumerate() {
        assert_eq!(row.len(), 3);
        row.fill(100 + y as u8);
    }
    // A sub-view's slice runs to the end of the buffer: still 2 rows.
    let mut sub = m.sub_view_mut(1, 1, 2, 2).unwrap();
    let mut rows = sub.rows_mut();
    assert_eq!(rows.len(), 2);
    rows.next().unwrap().fill(1);
    assert_eq!(rows.len(), 1);
    rows.next().unwrap().fill(2);
    assert!(rows.next().is_none());
    drop(rows);
    assert_eq!(buf, [100, 100, 100, 3, 101, 1, 1, 7, 102, 2, 2]);
}

#[test]
fn a_pair_of_different_sizes_is_a_typed_error() {
    let (l, r) = ([Rgb8::default(); 12], [Rgb8::default(); 12]);
    let left = ImageView::packed(&l, 4, 3).unwrap();
    let right = ImageView::packed(&r, 3, 4).unwrap();
    assert_eq!(check_same_size(&left, &left), Ok(()));
    assert_eq!(
        check_same_size(&left, &right),
        Err(ImageError::SizeMismatch {
            expected: (4, 3),
            got: (3, 4)
        })
    );
}

#[test]
fn mutable_views_write_only_inside() {
    let mut buf = [0u8; 8];
    let mut img = ImageViewMut::new(&mut buf, 3, 2, 4).unwrap();
    img.fill(7);
    assert!(img.set(2, 1, 9));
    assert!(!img.set(3, 1, 9));
    {
        let (row0, row1) = img.row_and_next_mut(0).unwrap();
        row0[0] = row1[2];
    }
    assert!(img.row_and_next_mut(1).is_none());
    assert_eq!(buf, [9, 7, 7, 0, 7, 7, 9, 0]);
}
