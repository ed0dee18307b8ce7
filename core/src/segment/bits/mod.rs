//! Bit-packed binary maps and the word-parallel kernels [`segment`](super::segment)
//! runs on: dilation and erosion, non-maximum suppression, hole filling by
//! bit-parallel flood fill, and run-based connected components.
//!
//! A map is `words_per_row(width)` `u32` words per row, row after row; pixel
//! `x` of a row is bit `x % 32` of word `x / 32`. Bits past the width are
//! always 0. Each kernel gives exactly what the `bool` step of the same name
//! gives ([`dilate`](super::dilate), [`non_max_suppression`](super::non_max_suppression),
//! [`fill_holes`](super::fill_holes), [`Labeller`](super::Labeller)); the
//! `segment_bits` tests check that bit for bit on random maps.

use super::morph::{Disk, NMS_DIRECTIONS};
use super::SegmentError;
use crate::conspicuity::EdgeCell;
use crate::image::ImageView;

mod closing;
mod components;
mod square;

pub(super) use closing::close;
pub use closing::{closing_map_len, MAX_CLOSING_STEPS};
pub(super) use components::{components, Components};
pub(super) use square::{clear_square, square};
pub use square::{clear_square_bits, square_bits};

/// `u32` words per row of a bit map `width` pixels wide.
pub const fn words_per_row(width: usize) -> usize {
    width.div_ceil(32)
}

/// `u32` words of one bit map.
pub const fn bit_map_len(width: usize, height: usize) -> usize {
    words_per_row(width) * height
}

/// Most runs (maximal horizontal stretches of ON pixels) a row holds.
pub const fn row_runs(width: usize) -> usize {
    width.div_ceil(2)
}

/// Entries of the component table that labels any `width` x `height` map:
/// one per run, at most [`row_runs`] per row.
pub const fn run_capacity(width: usize, height: usize) -> usize {
    row_runs(width) * height
}

/// The shape of a bit map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Geom {
    pub width: usize,
    pub height: usize,
    pub stride: usize,
    /// Valid bits of the last word of a row.
    pub last: u32,
}

impl Geom {
    pub const fn new(width: usize, height: usize) -> Self {
        let r = width % 32;
        Self {
            width,
            height,
            stride: words_per_row(width),
            last: if r == 0 { u32::MAX } else { (1u32 << r) - 1 },
        }
    }

    pub const fn len(&self) -> usize {
        self.stride * self.height
    }

    /// Valid bits of word `i` of a row.
    fn valid(&self, i: usize) -> u32 {
        if i + 1 == self.stride {
            self.last
        } else {
            u32::MAX
        }
    }

    fn rows<'m>(&self, m: &'m [u32]) -> core::slice::ChunksExact<'m, u32> {
        m.chunks_exact(self.stride.max(1))
    }

    fn rows_mut<'m>(&self, m: &'m mut [u32]) -> core::slice::ChunksExactMut<'m, u32> {
        m.chunks_exact_mut(self.stride.max(1))
    }

    /// Row `y` of bit map `m`; `None` below the last row (a buffer may be
    /// longer than the map, as [`closing_map_len`]'s are) or past its end.
    pub(in crate::segment) fn row<'m>(&self, m: &'m [u32], y: usize) -> Option<&'m [u32]> {
        if y >= self.height {
            return None;
        }
        m.get(y * self.stride..(y + 1) * self.stride)
    }

    /// Sets pixel `(x, y)` of `m` to `on`; nothing past the map's end.
    pub(in crate::segment) fn set(&self, m: &mut [u32], x: usize, y: usize, on: bool) {
        if let Some(word) = m.get_mut(y * self.stride + x / 32) {
            let bit = 1u32 << (x % 32);
            if on {
                *word |= bit;
            } else {
                *word &= !bit;
            }
        }
    }

    /// Pixel `(x, y)`; false outside.
    pub fn bit(&self, m: &[u32], x: usize, y: usize) -> bool {
        x < self.width
            && y < self.height
            && m.get(y * self.stride + x / 32)
                .is_some_and(|w| w >> (x % 32) & 1 != 0)
    }
}

/// A read-only bit map (see the module docs for the layout).
#[derive(Clone, Copy, Debug)]
pub struct BitView<'a> {
    words: &'a [u32],
    g: Geom,
}

impl<'a> BitView<'a> {
    pub(super) fn with_geom(words: &'a [u32], g: Geom) -> Self {
        Self { words, g }
    }

    /// A view of `words` (the layout of the module docs) as a `width` x
    /// `height` map. Bits past the width must be 0.
    ///
    /// # Errors
    /// [`SegmentError::Image`] for a bad size or too few words.
    pub fn new(words: &'a [u32], width: usize, height: usize) -> Result<Self, SegmentError> {
        crate::image::buffer_len(width, height, width)?;
        let g = Geom::new(width, height);
        if words.len() < g.len() {
            return Err(crate::image::ImageError::BufferTooSmall {
                needed: g.len(),
                got: words.len(),
            }
            .into());
        }
        Ok(Self { words, g })
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.g.width, self.g.height)
    }

    /// The words, [`words_per_row`] per row; bit `x % 32` of word `x / 32`
    /// of a row is pixel `x`, bits past the width are 0.
    pub fn words(&self) -> &'a [u32] {
        self.words.get(..self.g.len()).unwrap_or(&[])
    }

    /// Pixel `(x, y)`; false outside the map.
    pub fn get(&self, x: usize, y: usize) -> bool {
        self.g.bit(self.words, x, y)
    }

    /// ON pixels.
    pub fn count(&self) -> u32 {
        self.words().iter().map(|w| w.count_ones()).sum()
    }

    /// The pixels in raster order.
    pub fn bools(&self) -> impl Iterator<Item = bool> + 'a {
        let g = self.g;
        self.words()
            .chunks_exact(g.stride.max(1))
            .flat_map(move |r| {
                (0..g.width).map(move |x| r.get(x / 32).is_some_and(|w| w >> (x % 32) & 1 != 0))
            })
    }

    /// `src` where the map is ON, `off` elsewhere, in raster order: the
    /// cell maps of the stage (D_fg, C_fg, ψ, ...) from their bit maps.
    pub fn masked<'s, T: Copy>(
        &'s self,
        src: &'s ImageView<'_, T>,
        off: T,
    ) -> impl Iterator<Item = T> + 's {
        src.pixels()
            .zip(self.bools())
            .map(move |(v, on)| if on { v } else { off })
    }
}

/// First and last rows holding an ON pixel.
pub(super) fn row_range(g: Geom, m: &[u32]) -> Option<(usize, usize)> {
    let mut r: Option<(usize, usize)> = None;
    for (y, row) in g.rows(m).take(g.height).enumerate() {
        if row.iter().any(|&w| w != 0) {
            r = Some(r.map_or((y, y), |(a, _)| (a, y)));
        }
    }
    r
}

/// First and last rows, and first and last words of a row, holding an ON
/// pixel.
fn extent(g: Geom, m: &[u32]) -> Option<(usize, usize, usize, usize)> {
    let mut r: Option<(usize, usize, usize, usize)> = None;
    for (y, row) in g.rows(m).take(g.height).enumerate() {
        for (i, &w) in row.iter().enumerate() {
            if w != 0 {
                r = Some(r.map_or((y, y, i, i), |(a, _, c, d)| (a, y, c.min(i), d.max(i))));
            }
        }
    }
    r
}

/// One dilation (`E == false`: any element pixel ON, outside OFF) or
/// erosion (`E == true`: every element pixel ON, outside ON). Only the rows
/// and words the result can reach are computed. `cw` and `vw` are row
/// scratch, `stride + 2` words each.
fn morph_step<const E: bool>(
    g: Geom,
    disk: Disk,
    src: &[u32],
    dst: &mut [u32],
    cw: &mut [u32],
    vw: &mut [u32],
) {
    let Some((a, b, ca, cb)) = extent(g, src) else {
        dst.fill(0);
        return;
    };
    let s = g.stride;
    // Dilation reaches one pixel further; erosion stays inside the set.
    let (y0, y1, c0, c1) = if E {
        (a, b, ca, cb)
    } else {
        (
            a.saturating_sub(1),
            (b + 1).min(g.height.saturating_sub(1)),
            ca.saturating_sub(1),
            (cb + 1).min(s.saturating_sub(1)),
        )
    };
    // Outside the image: ON for an erosion, OFF for a dilation.
    let pad = if E { u32::MAX } else { 0 };
    let op = |x: u32, y: u32| if E { x & y } else { x | y };
    // Words c0 − 1 ..= c1 + 1 of the centre row and of the vertical
    // combination, at index word + 1; indices 0 and s + 1 are outside.
    for k in [0, s + 1] {
        if let (Some(c), Some(v)) = (cw.get_mut(k), vw.get_mut(k)) {
            (*c, *v) = (pad, pad);
        }
    }
    let (wa, wb) = (c0.saturating_sub(1), (c1 + 1).min(s.saturating_sub(1)));
    let tail = pad & !g.last;
    let h = if disk == Disk::Square { 1 } else { 0 };
    for (y, out) in g.rows_mut(dst).take(g.height).enumerate() {
        if y < y0 || y > y1 {
            out.fill(0);
            continue;
        }
        let Some(cur) = g.row(src, y) else {
            continue;
        };
        // A missing row (mask all ones) reads as `pad`.
        let (up, um) = y
            .checked_sub(1)
            .and_then(|u| g.row(src, u))
            .map_or((cur, u32::MAX), |r| (r, 0));
        let (down, dm) = g.row(src, y + 1).map_or((cur, u32::MAX), |r| (r, 0));
        let loads = (
            cur.get(wa..=wb),
            up.get(wa..=wb),
            down.get(wa..=wb),
            cw.get_mut(wa + 1..=wb + 1),
            vw.get_mut(wa + 1..=wb + 1),
        );
        if let (Some(c), Some(u), Some(d), Some(co), Some(vo)) = loads {
            let words = c.iter().zip(u).zip(d).zip(co.iter_mut().zip(vo.iter_mut()));
            for (((&c, &u), &d), (co, vo)) in words {
                let (u, d) = if E {
                    (u | um, d | dm)
                } else {
                    (u & !um, d & !dm)
                };
                *co = c;
                *vo = op(c, op(u, d));
            }
        }
        // Bits past the width are outside.
        if wb + 1 == s {
            for m in [&mut *cw, &mut *vw] {
                if let Some(w) = m.get_mut(s) {
                    *w |= tail;
                }
            }
        }
        let hw: &[u32] = if h == 1 { vw } else { cw };
        let (Some(o), Some(hs), Some(vs)) = (
            out.get_mut(c0..=c1),
            hw.get(c0..=c1 + 2),
            vw.get(c0 + 1..=c1 + 1),
        ) else {
            continue;
        };
        for ((o, w3), &v) in o.iter_mut().zip(hs.windows(3)).zip(vs) {
            if let [hp, hc, hn] = *w3 {
                *o = op(v, op(hc << 1 | hp >> 31, hc >> 1 | hn << 31));
            }
        }
        if let Some(l) = out.get_mut(s.saturating_sub(1)) {
            *l &= g.last;
        }
        if let Some(lead) = out.get_mut(..c0) {
            lead.fill(0);
        }
        if let Some(rest) = out.get_mut(c1 + 1..) {
            rest.fill(0);
        }
    }
}

/// Row scratch words of the morphology: two rows and an outside word at
/// either end of each.
pub const fn morph_rows_len(width: usize) -> usize {
    2 * (words_per_row(width) + 2)
}

/// `n` dilations (`erode == false`) or erosions of `map` in place;
/// `scratch` is a map, `rows` [`morph_rows_len`] words.
pub(super) fn morph_n(
    g: Geom,
    disk: Disk,
    map: &mut [u32],
    scratch: &mut [u32],
    rows: &mut [u32],
    n: u8,
    erode: bool,
) {
    let (cw, vw) = rows.split_at_mut(rows.len() / 2);
    // Ping-pong between the two maps; one copy at the end when n is odd.
    let (mut a, mut b): (&mut [u32], &mut [u32]) = (&mut *map, &mut *scratch);
    for _ in 0..n {
        if erode {
            morph_step::<true>(g, disk, a, b, cw, vw);
        } else {
            morph_step::<false>(g, disk, a, b, cw, vw);
        }
        core::mem::swap(&mut a, &mut b);
    }
    if n % 2 == 1 {
        copy_map(map, scratch);
    }
}

/// Copies bit map `src` into `dst`: the words both hold (a map and the
/// longer buffer of [`close`] share their first [`Geom::len`] words; the
/// buffers are split from one slice at construction). `get` shows the
/// compiler that the lengths match, so `copy_from_slice` has no panic path.
pub(super) fn copy_map(dst: &mut [u32], src: &[u32]) {
    let n = dst.len().min(src.len());
    if let (Some(d), Some(s)) = (dst.get_mut(..n), src.get(..n)) {
        d.copy_from_slice(s);
    }
}

/// Calls `f(x, y)` for every ON pixel, raster order.
pub(super) fn for_each_on(g: Geom, m: &[u32], mut f: impl FnMut(usize, usize)) {
    for (y, row) in g.rows(m).take(g.height).enumerate() {
        for (i, &w) in row.iter().enumerate() {
            let mut v = w;
            while v != 0 {
                let b = v.trailing_zeros() as usize;
                f(i * 32 + b, y);
                v &= v - 1;
            }
        }
    }
}

/// C_Obj^M from C_Obj given as C and its ON bits `c_obj` (a set bit is an ON
/// C cell): the rule of [`non_max_suppression`](super::non_max_suppression).
/// Returns the survivors.
pub(super) fn nms(g: Geom, c: &ImageView<'_, EdgeCell>, c_obj: &[u32], dst: &mut [u32]) -> u32 {
    dst.fill(0);
    let val = |x: usize, y: usize, dx: isize, dy: isize| -> i32 {
        let (Some(x), Some(y)) = (x.checked_add_signed(dx), y.checked_add_signed(dy)) else {
            return -1;
        };
        if !g.bit(c_obj, x, y) {
            return -1;
        }
        c.get(x, y)
            .and_then(EdgeCell::get)
            .map_or(-1, |v| i32::from(v.to_bits()))
    };
    let mut n = 0;
    for_each_on(g, c_obj, |x, y| {
        let v = val(x, y, 0, 0);
        let keep = v >= 0
            && NMS_DIRECTIONS
                .iter()
                .any(|&(dx, dy)| v >= val(x, y, -dx, -dy) && v >= val(x, y, dx, dy));
        if keep {
            if let Some(w) = dst.get_mut(y * g.stride + x / 32) {
                *w |= 1 << (x % 32);
                n += 1;
            }
        }
    });
    n
}

/// Spreads `reach` along the runs of `allowed` of one row, both ways.
/// `reach` must lie inside `allowed`. Returns true if `reach` changed.
fn spread_row(reach: &mut [u32], allowed: &[u32]) -> bool {
    let mut changed = false;
    // Towards higher x: m + s carries from each seed through its run.
    let mut carry = false;
    for (r, &m) in reach.iter_mut().zip(allowed) {
        let (s1, c1) = m.overflowing_add(*r);
        let (s2, c2) = s1.overflowing_add(u32::from(carry));
        carry = c1 || c2;
        let v = *r | ((s2 ^ m) & m);
        changed |= v != *r;
        *r = v;
    }
    // Towards lower x: the same on bit-reversed words, last word first.
    let mut carry = false;
    for (r, &m) in reach.iter_mut().zip(allowed).rev() {
        let (rm, rr) = (m.reverse_bits(), r.reverse_bits());
        let (s1, c1) = rm.overflowing_add(rr);
        let (s2, c2) = s1.overflowing_add(u32::from(carry));
        carry = c1 || c2;
        let v = *r | ((s2 ^ rm) & rm).reverse_bits();
        changed |= v != *r;
        *r = v;
    }
    changed
}

/// Fills every closed contour of `closed` into `filled`: the pixels not
/// 4-connected through background to the image border, the rule of
/// [`fill_holes`](super::fill_holes). `allowed` is scratch.
pub(super) fn fill_holes(g: Geom, closed: &[u32], filled: &mut [u32], allowed: &mut [u32]) {
    // allowed = background; filled holds the background reached so far.
    for (a, (i, &c)) in allowed.iter_mut().zip(
        closed
            .iter()
            .enumerate()
            .map(|(i, c)| (i % g.stride.max(1), c)),
    ) {
        *a = !c & g.valid(i);
    }
    let Some((y0, y1)) = row_range(g, closed) else {
        filled.fill(0);
        return;
    };
    // Rows without a closed pixel are background from border to border:
    // all reached. In the others, the border columns seed the fill.
    let h = g.height;
    for (y, (r, a)) in g.rows_mut(filled).zip(g.rows(allowed)).take(h).enumerate() {
        if y < y0 || y > y1 || y == 0 || y + 1 == h {
            r.copy_from_slice(a);
        } else {
            r.fill(0);
            let last = g.stride.saturating_sub(1);
            let right = (g.width - 1) % 32;
            if let (Some(f), Some(&m)) = (r.first_mut(), a.first()) {
                *f |= m & 1;
            }
            if let (Some(l), Some(&m)) = (r.get_mut(last), a.get(last)) {
                *l |= m & (1 << right);
            }
        }
    }
    // Bit-parallel flood fill: sweep down and up until nothing changes.
    let stride = g.stride;
    let mut changed = true;
    while changed {
        changed = false;
        for down in [true, false] {
            let mut y = if down { y0 } else { y1 };
            loop {
                let from = if down { y.checked_sub(1) } else { Some(y + 1) };
                let from = from.filter(|&f| f < h);
                let Some((head, tail)) = filled.split_at_mut_checked(y * stride) else {
                    return;
                };
                let Some((row, rest)) = tail.split_at_mut_checked(stride) else {
                    return;
                };
                let neighbour = match from {
                    Some(f) if f < y => head.get(f * stride..(f + 1) * stride),
                    Some(_) => rest.get(..stride),
                    None => None,
                };
                let a = g.row(allowed, y).unwrap_or(&[]);
                if let Some(nb) = neighbour {
                    for ((r, &m), &n) in row.iter_mut().zip(a).zip(nb) {
                        let v = *r | (n & m);
                        changed |= v != *r;
                        *r = v;
                    }
                }
                changed |= spread_row(row, a);
                if down {
                    if y == y1 {
                        break;
                    }
                    y += 1;
                } else {
                    if y == y0 {
                        break;
                    }
                    y -= 1;
                }
            }
        }
    }
    // filled = not reached.
    for (i, f) in filled.iter_mut().enumerate() {
        *f = !*f & g.valid(i % stride.max(1));
    }
}

/// Bounding box `(x0, y0, x1, y1)` (inclusive) of the ON pixels.
pub(super) fn bbox(g: Geom, m: &[u32]) -> Option<(usize, usize, usize, usize)> {
    let mut b: Option<(usize, usize, usize, usize)> = None;
    for (y, row) in g.rows(m).take(g.height).enumerate() {
        let first = row
            .iter()
            .enumerate()
            .find(|(_, &w)| w != 0)
            .map(|(i, w)| i * 32 + w.trailing_zeros() as usize);
        let last = row
            .iter()
            .enumerate()
            .rev()
            .find(|(_, &w)| w != 0)
            .map(|(i, w)| i * 32 + 31 - w.leading_zeros() as usize);
        if let (Some(x0), Some(x1)) = (first, last) {
            b = Some(b.map_or((x0, y, x1, y), |(a, b0, c, _)| {
                (a.min(x0), b0, c.max(x1), y)
            }));
        }
    }
    b
}
