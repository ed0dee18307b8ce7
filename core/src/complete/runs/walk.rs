//! The bit-map and run kernels of [`complete_runs`](super::complete_runs):
//! runs of a bit row, the run labelling with its bounded union-find
//! table, label rows, the trusted cells, and the walk over the trusted
//! cells of each region, run by run.

use crate::disparity::DisparityCell;
use crate::image::ImageView;

/// Calls `f(first, last)` for each run of set bits of a bit-map row, in
/// order (bits past the width are 0).
pub(super) fn for_each_run(row: &[u32], mut f: impl FnMut(u32, u32)) {
    let mut open: Option<u32> = None;
    let mut base = 0u32;
    for &w in row {
        let mut pos = 0u32;
        while pos < 32 {
            let rest = w >> pos;
            match open {
                None => {
                    if rest == 0 {
                        break;
                    }
                    let tz = rest.trailing_zeros();
                    open = Some(base + pos + tz);
                    pos += tz;
                }
                Some(s) => {
                    let ones = (!rest).trailing_zeros();
                    if ones >= 32 - pos {
                        break;
                    }
                    f(s, base + pos + ones - 1);
                    open = None;
                    pos += ones;
                }
            }
        }
        base = base.wrapping_add(32);
    }
    if let Some(s) = open {
        f(s, base.wrapping_sub(1));
    }
}

pub(super) fn get16(t: &[u16], i: usize) -> u16 {
    t.get(i).copied().unwrap_or(0)
}

pub(super) fn set16(t: &mut [u16], i: usize, v: u16) {
    if let Some(p) = t.get_mut(i) {
        *p = v;
    }
}

/// Root of run `a` (path halving; a parent is below its child).
pub(super) fn find(t: &mut [u16], mut a: usize) -> usize {
    loop {
        let p = usize::from(get16(t, a));
        if p == a {
            return a;
        }
        let gp = get16(t, p);
        set16(t, a, gp);
        a = usize::from(gp);
    }
}

pub(super) fn union(t: &mut [u16], a: usize, b: usize) {
    let (ra, rb) = (find(t, a), find(t, b));
    let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
    set16(t, hi, u16::try_from(lo).unwrap_or(0));
}

pub(super) fn bit(row: &[u32], x: usize) -> bool {
    row.get(x / 32).is_some_and(|w| w >> (x % 32) & 1 != 0)
}

/// Labels the runs of `open` (4-connected); returns `(regions, runs)`.
/// Each run below the table's capacity ends with its region, 1-based in
/// raster order of first cell; runs past it are counted, not labelled.
pub(super) fn label_runs(
    open: &[u32],
    stride: usize,
    height: usize,
    table: &mut [u16],
    rows: &mut [u32],
) -> (u16, usize) {
    let cap = table.len().min(u16::MAX as usize);
    let half = rows.len() / 2;
    let (mut prev, mut cur) = rows.split_at_mut(half);
    let (mut prev_base, mut pn) = (0usize, 0usize);
    let mut next = 0usize;
    for row in open.chunks_exact(stride.max(1)).take(height) {
        let mut cn = 0usize;
        let mut j = 0usize;
        let run = |buf: &[u32], k: usize| {
            (
                buf.get(2 * k).copied().unwrap_or(0),
                buf.get(2 * k + 1).copied().unwrap_or(0),
            )
        };
        for_each_run(row, |s, e| {
            let i = next;
            next += 1;
            if let Some(c) = cur.get_mut(2 * cn..2 * cn + 2) {
                c.copy_from_slice(&[s, e]);
            }
            cn += 1;
            if i >= cap {
                return;
            }
            set16(table, i, u16::try_from(i).unwrap_or(0));
            while j < pn && run(prev, j).1 < s {
                j += 1;
            }
            let mut k = j;
            while k < pn && run(prev, k).0 <= e {
                if prev_base + k < cap {
                    union(table, i, prev_base + k);
                }
                k += 1;
            }
        });
        core::mem::swap(&mut prev, &mut cur);
        prev_base = next - cn;
        pn = cn;
    }
    // Roots take 1..=n in order; every other run its root's final label
    // (a parent is below its child, so it is final first).
    let mut n = 0u16;
    for l in 0..next.min(cap) {
        let p = usize::from(get16(table, l));
        if p == l {
            n = n.saturating_add(1);
            set16(table, l, n);
        } else {
            let fp = get16(table, p);
            set16(table, l, fp);
        }
    }
    (n, next)
}

/// Writes the region labels of one row (0 on edges and on runs past the
/// table) from run `first` on; returns the row's run count.
pub(super) fn label_row(open_row: &[u32], table: &[u16], first: usize, out: &mut [u16]) -> usize {
    out.fill(0);
    let mut i = first;
    for_each_run(open_row, |s, e| {
        let l = get16(table, i);
        if let Some(r) = out.get_mut(s as usize..=e as usize) {
            r.fill(l);
        }
        i += 1;
    });
    i - first
}

/// The trusted cells of row `y`: ON, and no edge within `g` px.
pub(super) fn trusted_row(
    open: &[u32],
    stride: usize,
    (w, h): (usize, usize),
    y: usize,
    g: usize,
    disparity: &[DisparityCell],
    out: &mut [u32],
) {
    // Edges of rows y-g..=y+g, OR-ed.
    out.fill(0);
    for yy in y.saturating_sub(g)..=(y + g).min(h.saturating_sub(1)) {
        let Some(r) = open.get(yy * stride..(yy + 1) * stride) else {
            continue;
        };
        for (o, &v) in out.iter_mut().zip(r) {
            *o |= !v;
        }
    }
    // Bits past the width are 0 in `open`, so 1 here: clear them.
    let last = if w % 32 == 0 {
        u32::MAX
    } else {
        (1u32 << (w % 32)) - 1
    };
    if let Some(o) = out.last_mut() {
        *o &= last;
    }
    // Widen by g px each way, across words.
    for _ in 0..g {
        let mut carry_in = 0u32;
        for i in 0..out.len() {
            let cur = out.get(i).copied().unwrap_or(0);
            let next = out.get(i + 1).copied().unwrap_or(0);
            let widened = cur | cur << 1 | carry_in | cur >> 1 | next << 31;
            carry_in = cur >> 31;
            if let Some(o) = out.get_mut(i) {
                *o = widened;
            }
        }
    }
    // Trusted: ON and not near an edge.
    for (i, o) in out.iter_mut().enumerate() {
        let mut on = 0u32;
        let cells = disparity.get(i * 32..((i + 1) * 32).min(w)).unwrap_or(&[]);
        for (b, c) in cells.iter().enumerate() {
            on |= u32::from(c.is_on()) << b;
        }
        *o = on & !*o;
    }
}

/// The bit maps and the run table of a labelling, walked run by run.
pub(super) struct Walk<'a> {
    pub(super) open: &'a [u32],
    pub(super) trusted: &'a [u32],
    pub(super) table: &'a [u16],
    pub(super) stride: usize,
    pub(super) height: usize,
    /// Region-table capacity: regions at or past it are skipped.
    pub(super) cap: usize,
}

impl Walk<'_> {
    /// Calls `f(region, row y, disparity row, trusted row, (first, last))`
    /// for every run of a region within the tables, in raster order.
    pub(super) fn for_each_run<'d>(
        &self,
        disp: &ImageView<'d, DisparityCell>,
        mut f: impl FnMut(usize, usize, &'d [DisparityCell], &[u32], (usize, usize)),
    ) {
        let mut i = 0usize;
        let s = self.stride.max(1);
        let rows = self.open.chunks_exact(s).zip(self.trusted.chunks_exact(s));
        for (y, (orow, trow)) in rows.take(self.height).enumerate() {
            let drow = disp.row(y).unwrap_or(&[]);
            for_each_run(orow, |s, e| {
                let l = usize::from(get16(self.table, i));
                i += 1;
                if l != 0 && l < self.cap {
                    f(l, y, drow, trow, (s as usize, e as usize));
                }
            });
        }
    }

    /// Calls `f(region, row y, disparity row, trusted x)` for every run of
    /// a region within the tables, in raster order, with the trusted cells
    /// of the run.
    pub(super) fn for_each_trusted<'d>(
        &self,
        disp: &ImageView<'d, DisparityCell>,
        mut f: impl FnMut(usize, usize, &'d [DisparityCell], SetBits<'_>),
    ) {
        self.for_each_run(disp, |l, y, drow, trow, (s, e)| {
            f(l, y, drow, SetBits::new(trow, s, e));
        });
    }
}

/// The trusted cells of `s..=e` (bits of `trusted`) whose raw bits are
/// below `lim`, counted. The same count as a walk over the cells
/// [`SetBits`] gives, without finding each set bit: the cells of each word
/// are compared in a row and masked by their bit.
pub(super) fn count_below(
    trusted: &[u32],
    drow: &[DisparityCell],
    (s, e): (usize, usize),
    lim: u32,
) -> u32 {
    let mut n = 0u32;
    let mut x = s;
    while x <= e {
        let word = x / 32;
        let end = e.min(word * 32 + 31);
        let mut bits = trusted.get(word).copied().unwrap_or(0) >> (x % 32);
        if bits != 0 {
            for c in drow.get(x..=end).unwrap_or(&[]) {
                n += bits & u32::from(u32::from(c.raw().to_bits()) < lim);
                bits >>= 1;
            }
        }
        x = end + 1;
    }
    n
}

/// The set bits of a bit-map row within `s..=e`, as pixel indices.
pub(super) struct SetBits<'a> {
    row: &'a [u32],
    word: usize,
    last: usize,
    /// Bits of `last` at or below `e`.
    last_mask: u32,
    bits: u32,
}

impl<'a> SetBits<'a> {
    pub(super) fn new(row: &'a [u32], s: usize, e: usize) -> Self {
        let (word, last) = (s / 32, e / 32);
        let last_mask = u32::MAX >> (31 - e % 32);
        let mut bits = row.get(word).copied().unwrap_or(0) & (u32::MAX << (s % 32));
        if word == last {
            bits &= last_mask;
        }
        Self {
            row,
            word,
            last,
            last_mask,
            bits,
        }
    }
}

impl Iterator for SetBits<'_> {
    type Item = usize;

    #[inline]
    fn next(&mut self) -> Option<usize> {
        loop {
            if self.bits != 0 {
                let tz = self.bits.trailing_zeros() as usize;
                self.bits &= self.bits - 1;
                return Some(self.word * 32 + tz);
            }
            if self.word >= self.last {
                return None;
            }
            self.word += 1;
            self.bits = self.row.get(self.word).copied().unwrap_or(0);
            if self.word == self.last {
                self.bits &= self.last_mask;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::disparity::Disparity;

    /// `count_below` counts what a walk over `SetBits` counts, on every
    /// span of rows with words of all sorts and OFF cells.
    #[test]
    fn count_below_counts_the_trusted_cells_under_the_limit() {
        let w = 100;
        let mut seed = 0x1234_5678u32;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        for _ in 0..40 {
            let drow: [DisparityCell; 100] = core::array::from_fn(|_| match next() % 5 {
                0 => DisparityCell::OFF,
                _ => DisparityCell::on(Disparity::from_bits((next() % 8192) as u16))
                    .unwrap_or(DisparityCell::OFF),
            });
            let trusted = [next(), next() & next(), u32::MAX, next() | next()];
            let lim = next() % 8192;
            for s in (0..w).step_by(7) {
                for e in (s..w).step_by(5) {
                    let walk = SetBits::new(&trusted, s, e)
                        .filter(|&x| u32::from(drow[x].raw().to_bits()) < lim)
                        .count() as u32;
                    assert_eq!(count_below(&trusted, &drow, (s, e), lim), walk, "{s}..={e}");
                }
            }
        }
    }
}
