//! Connected components, hole filling and the area filter, allocation-free.
//!
//! Labels are `u16` in a caller-provided packed map; label 0 is "not in the
//! set". The two-pass labelling keeps its equivalences in a caller-provided
//! parent table (union-find; a parent is never above its child, so one
//! ascending sweep resolves every label) and counts areas in a
//! caller-provided `u32` table. Running out of provisional labels is
//! [`SegmentError::LabelCapacity`], never a panic.

use super::{check_size, Ratio, SegmentError};
use crate::image::{ImageError, ImageView, ImageViewMut};

/// Which neighbours touch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Connectivity {
    /// Left, right, up, down.
    Four,
    /// The four plus the diagonals.
    Eight,
}

/// Table entries that label any `width` x `height` binary map in either
/// connectivity: one per provisional label (at most a checkerboard's
/// `⌈w·h/2⌉`) plus label 0, capped at `u16::MAX + 1`.
pub const fn label_capacity(width: usize, height: usize) -> usize {
    let n = (width * height).div_ceil(2) + 1;
    if n > u16::MAX as usize + 1 {
        u16::MAX as usize + 1
    } else {
        n
    }
}

/// The label map and the two tables of the labelling, validated once.
#[derive(Debug)]
pub struct Labeller<'a> {
    width: usize,
    height: usize,
    labels: &'a mut [u16],
    parent: &'a mut [u16],
    area: &'a mut [u32],
    count: u16,
}

fn get16(t: &[u16], i: u16) -> u16 {
    t.get(usize::from(i)).copied().unwrap_or(0)
}

fn set16(t: &mut [u16], i: u16, v: u16) {
    if let Some(p) = t.get_mut(usize::from(i)) {
        *p = v;
    }
}

/// Root of `a`, halving the path on the way (parents only decrease).
fn find(parent: &mut [u16], mut a: u16) -> u16 {
    loop {
        let p = get16(parent, a);
        if p == a {
            return a;
        }
        let gp = get16(parent, p);
        set16(parent, a, gp);
        a = gp;
    }
}

/// Joins the sets of `a` and `b`; returns the root (the smaller one).
fn union(parent: &mut [u16], a: u16, b: u16) -> u16 {
    let (ra, rb) = (find(parent, a), find(parent, b));
    let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
    set16(parent, hi, lo);
    lo
}

impl<'a> Labeller<'a> {
    /// A labeller over a packed `width` x `height` label map; its capacity is
    /// the shorter table (at most `u16::MAX + 1` entries are used).
    ///
    /// # Errors
    /// [`SegmentError::Image`] for a bad geometry or a short label map.
    pub fn new(
        width: usize,
        height: usize,
        labels: &'a mut [u16],
        parent: &'a mut [u16],
        area: &'a mut [u32],
    ) -> Result<Self, SegmentError> {
        let needed = crate::image::buffer_len(width, height, width)?;
        if labels.len() < needed {
            return Err(ImageError::BufferTooSmall {
                needed,
                got: labels.len(),
            }
            .into());
        }
        Ok(Self {
            width,
            height,
            labels,
            parent,
            area,
            count: 0,
        })
    }

    /// Provisional labels the tables hold, label 0 included.
    pub fn capacity(&self) -> usize {
        self.parent
            .len()
            .min(self.area.len())
            .min(u16::MAX as usize + 1)
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The label map of the last labelling (always `Some`: the geometry was
    /// checked in [`Labeller::new`]).
    pub fn labels(&self) -> Option<ImageView<'_, u16>> {
        ImageView::packed(&*self.labels, self.width, self.height).ok()
    }

    /// Components found by the last labelling.
    pub fn count(&self) -> u16 {
        self.count
    }

    /// Area of final label `l` after [`Labeller::label`].
    pub fn area(&self, l: u16) -> u32 {
        self.area.get(usize::from(l)).copied().unwrap_or(0)
    }

    fn rows(&self) -> impl Iterator<Item = &[u16]> + '_ {
        self.labels.chunks_exact(self.width).take(self.height)
    }

    /// Labels the pixels of `src` equal to `value`, final labels `1..=n`
    /// in raster order of first appearance, and counts each one's area;
    /// returns `n`.
    ///
    /// # Errors
    /// [`SegmentError::SizeMismatch`], or [`SegmentError::LabelCapacity`] when
    /// the map needs more provisional labels than the tables hold.
    pub fn label(
        &mut self,
        src: &ImageView<'_, bool>,
        value: bool,
        conn: Connectivity,
    ) -> Result<u16, SegmentError> {
        check_size(self.size(), src.size())?;
        self.count = 0;
        let cap = self.capacity();
        let w = self.width;
        let eight = conn == Connectivity::Eight;
        let parent = &mut *self.parent;
        set16(parent, 0, 0);
        let mut next: usize = 1;
        for (y, s) in src.rows().enumerate() {
            // Rows `0..y` are done; the buffer holds every row (`new`).
            let Some((done, rest)) = self.labels.split_at_mut_checked(y * w) else {
                break;
            };
            let prev: &[u16] = match y.checked_sub(1) {
                Some(py) => done.get(py * w..).unwrap_or(&[]),
                None => &[],
            };
            let cur = rest.get_mut(..w).unwrap_or(&mut []);
            let mut west = 0u16;
            for (x, (out, &on)) in cur.iter_mut().zip(s).enumerate() {
                if on != value {
                    *out = 0;
                    west = 0;
                    continue;
                }
                let at = |i: Option<usize>| i.and_then(|i| prev.get(i)).copied().unwrap_or(0);
                let north = at(Some(x));
                let (nw, ne) = if eight {
                    (at(x.checked_sub(1)), at(Some(x + 1)))
                } else {
                    (0, 0)
                };
                let mut l = 0u16;
                for c in [west, north, nw, ne] {
                    if c != 0 {
                        l = if l == 0 { c } else { union(parent, l, c) };
                    }
                }
                if l == 0 {
                    if next >= cap {
                        return Err(SegmentError::LabelCapacity { capacity: cap });
                    }
                    l = next as u16;
                    set16(parent, l, l);
                    next += 1;
                }
                *out = l;
                west = l;
            }
        }
        // Resolve: roots get 1..=n in order, others their root's final label.
        let mut n = 0u16;
        for l in 1..next as u16 {
            let p = get16(parent, l);
            if p == l {
                n += 1;
                set16(parent, l, n);
            } else {
                let fp = get16(parent, p);
                set16(parent, l, fp);
            }
        }
        if let Some(a) = self.area.get_mut(..=usize::from(n)) {
            a.fill(0);
        }
        for l in self.labels.iter_mut().take(w * self.height) {
            if *l != 0 {
                *l = get16(parent, *l);
                if let Some(a) = self.area.get_mut(usize::from(*l)) {
                    *a += 1;
                }
            }
        }
        self.count = n;
        Ok(n)
    }

    /// The largest component of the last labelling as `(label, area)`; the
    /// first in raster order on ties; `None` when there is none.
    pub fn largest(&self) -> Option<(u16, u32)> {
        (1..=self.count)
            .map(|l| (l, self.area(l)))
            .fold(None, |best, (l, a)| match best {
                Some((_, ba)) if ba >= a => best,
                _ => Some((l, a)),
            })
    }

    /// Writes `dst = (label == l)` for the last labelling.
    ///
    /// # Errors
    /// [`SegmentError::SizeMismatch`].
    pub fn select(&self, l: u16, dst: &mut ImageViewMut<'_, bool>) -> Result<u32, SegmentError> {
        check_size(self.size(), dst.size())?;
        let mut n = 0;
        for (d, s) in dst.rows_mut().zip(self.rows()) {
            for (o, &v) in d.iter_mut().zip(s) {
                *o = l != 0 && v == l;
                n += u32::from(*o);
            }
        }
        Ok(n)
    }
}

/// Fills every closed contour: `filled = closed ∪` the background pixels
/// (not in `closed`) that are not 4-connected to the image border. Returns
/// the number of filled hole pixels. Foreground is thus 8-connected and
/// background 4-connected, the consistent pair.
///
/// # Errors
/// [`SegmentError::SizeMismatch`] or [`SegmentError::LabelCapacity`].
pub fn fill_holes(
    closed: &ImageView<'_, bool>,
    filled: &mut ImageViewMut<'_, bool>,
    lab: &mut Labeller<'_>,
) -> Result<u32, SegmentError> {
    check_size(closed.size(), filled.size())?;
    lab.label(closed, false, Connectivity::Four)?;
    let (w, h) = lab.size();
    // Components touching the border are outside: zero their area.
    for (y, row) in lab.labels.chunks_exact(w).take(h).enumerate() {
        let edge_row = y == 0 || y + 1 == h;
        let border = row
            .iter()
            .enumerate()
            .filter(|&(x, _)| edge_row || x == 0 || x + 1 == w);
        for (_, &l) in border {
            if let Some(a) = lab.area.get_mut(usize::from(l)) {
                *a = 0;
            }
        }
    }
    let mut holes = 0;
    for ((d, c), l) in filled.rows_mut().zip(closed.rows()).zip(lab.rows()) {
        for ((o, &on), &l) in d.iter_mut().zip(c).zip(l) {
            let hole = !on && l != 0 && lab.area(l) != 0;
            holes += u32::from(hole);
            *o = on || hole;
        }
    }
    Ok(holes)
}

/// What [`area_filter`] kept.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AreaReport {
    /// Filled regions found (8-connected components of the filled map).
    pub regions: u16,
    /// Regions kept.
    pub kept: u16,
    /// Area of the largest region.
    pub largest: u32,
    /// Pixels of the mask.
    pub area: u32,
}

/// The paper's area filter: keeps the 8-connected components of `filled`
/// whose area is at least `keep` times the largest one's (the paper drops
/// regions below 1/5 of the largest). A contour that never closed stays as
/// its own (thin) pixels, the paper's "partial fill", and usually falls to
/// this filter when a filled region exists.
///
/// # Errors
/// [`SegmentError::SizeMismatch`] or [`SegmentError::LabelCapacity`].
pub fn area_filter(
    filled: &ImageView<'_, bool>,
    mask: &mut ImageViewMut<'_, bool>,
    lab: &mut Labeller<'_>,
    keep: Ratio,
) -> Result<AreaReport, SegmentError> {
    check_size(filled.size(), mask.size())?;
    let n = lab.label(filled, true, Connectivity::Eight)?;
    let mut rep = AreaReport {
        regions: n,
        largest: lab.largest().map_or(0, |(_, a)| a),
        ..AreaReport::default()
    };
    let kept = |l: u16| {
        l != 0
            && u64::from(lab.area(l)) * u64::from(keep.den)
                >= u64::from(rep.largest) * u64::from(keep.num)
    };
    rep.kept = (1..=n).map(|l| u16::from(kept(l))).sum();
    for (d, l) in mask.rows_mut().zip(lab.rows()) {
        for (o, &l) in d.iter_mut().zip(l) {
            *o = kept(l);
            rep.area += u32::from(*o);
        }
    }
    Ok(rep)
}
