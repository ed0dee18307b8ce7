//! Run-based connected components of a bit map: the runs of a row, the
//! union-find table over runs, and the selection of components by area.

use super::{row_range, Geom};
use crate::segment::label::Connectivity;
use crate::segment::SegmentError;

/// Marks a root entry of the component table; the low bits hold its area.
const ROOT: u32 = 1 << 31;

/// The runs of one row, `(first, last)` pixel, left to right.
struct Runs<'r> {
    words: core::slice::Iter<'r, u32>,
    word: u32,
    base: u32,
    pos: u32,
    open: Option<u32>,
}

impl<'r> Runs<'r> {
    fn new(row: &'r [u32]) -> Self {
        Self {
            words: row.iter(),
            word: 0,
            base: 0u32.wrapping_sub(32),
            pos: 32,
            open: None,
        }
    }
}

impl Iterator for Runs<'_> {
    type Item = (u32, u32);

    fn next(&mut self) -> Option<(u32, u32)> {
        loop {
            if self.pos >= 32 {
                let Some(&w) = self.words.next() else {
                    return self.open.take().map(|s| (s, self.base.wrapping_add(31)));
                };
                self.word = w;
                self.base = self.base.wrapping_add(32);
                self.pos = 0;
            }
            let rest = self.word >> self.pos;
            match self.open {
                None => {
                    if rest == 0 {
                        self.pos = 32;
                        continue;
                    }
                    let tz = rest.trailing_zeros();
                    self.open = Some(self.base + self.pos + tz);
                    self.pos += tz;
                }
                Some(s) => {
                    let tz = (!rest).trailing_zeros();
                    if tz >= 32 - self.pos {
                        self.pos = 32;
                        continue;
                    }
                    self.open = None;
                    self.pos += tz;
                    return Some((s, self.base + self.pos - 1));
                }
            }
        }
    }
}

fn entry(t: &[u32], i: u32) -> u32 {
    t.get(i as usize).copied().unwrap_or(ROOT)
}

fn set_entry(t: &mut [u32], i: u32, v: u32) {
    if let Some(e) = t.get_mut(i as usize) {
        *e = v;
    }
}

/// Root of run `a` (path halving; parents are below their children).
fn find(t: &mut [u32], mut a: u32) -> u32 {
    loop {
        let p = entry(t, a);
        if p & ROOT != 0 {
            return a;
        }
        let gp = entry(t, p);
        if gp & ROOT != 0 {
            return p;
        }
        set_entry(t, a, gp);
        a = gp;
    }
}

/// Joins the components of runs `a` and `b`: the lower root stays, with
/// the summed area.
fn union(t: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(t, a), find(t, b));
    if ra == rb {
        return;
    }
    let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
    let area = (entry(t, lo) & !ROOT).saturating_add(entry(t, hi) & !ROOT);
    set_entry(t, lo, ROOT | area.min(ROOT - 1));
    set_entry(t, hi, lo);
}

/// The connected components of a bit map, by runs: `table` has an entry per
/// run, a root's holding its component's area, every other run's its root.
pub(in crate::segment) struct Components {
    /// Runs labelled.
    runs: u32,
    /// Rows scanned.
    rows: Option<(usize, usize)>,
    /// Components.
    pub count: u32,
    /// The largest `(root run, area)`, the first in raster order on ties.
    pub largest: Option<(u32, u32)>,
}

/// Labels `src` in `conn` connectivity. `rows` holds two rows of runs
/// (`4 · row_runs(width)` words). Components are in raster order of their
/// first pixel, as [`Labeller`](crate::segment::Labeller) numbers them.
///
/// # Errors
/// [`SegmentError::LabelCapacity`] when `src` has more runs than `table`
/// has entries.
pub(in crate::segment) fn components(
    g: Geom,
    src: &[u32],
    conn: Connectivity,
    rows: &mut [u32],
    table: &mut [u32],
) -> Result<Components, SegmentError> {
    let range = row_range(g, src);
    let mut out = Components {
        runs: 0,
        rows: range,
        count: 0,
        largest: None,
    };
    let Some((y0, y1)) = range else {
        return Ok(out);
    };
    let d = u32::from(conn == Connectivity::Eight);
    let cap = table.len().min(ROOT as usize);
    let half = rows.len() / 2;
    let (mut prev, mut cur) = rows.split_at_mut(half);
    let (mut prev_base, mut pn) = (0u32, 0usize);
    let mut next = 0u32;
    for y in y0..=y1 {
        let row = g.row(src, y).unwrap_or(&[]);
        let mut cn = 0usize;
        let mut j = 0usize;
        let run = |buf: &[u32], k: usize| {
            (
                buf.get(2 * k).copied().unwrap_or(0),
                buf.get(2 * k + 1).copied().unwrap_or(0),
            )
        };
        for (s, e) in Runs::new(row) {
            if next as usize >= cap || 2 * cn + 1 >= cur.len() {
                return Err(SegmentError::LabelCapacity { capacity: cap });
            }
            set_entry(table, next, ROOT | (e - s + 1));
            if let Some(c) = cur.get_mut(2 * cn..2 * cn + 2) {
                c.copy_from_slice(&[s, e]);
            }
            cn += 1;
            while j < pn && run(prev, j).1 + d < s {
                j += 1;
            }
            let mut k = j;
            while k < pn && run(prev, k).0 <= e + d {
                union(table, next, prev_base + k as u32);
                k += 1;
            }
            next += 1;
        }
        core::mem::swap(&mut prev, &mut cur);
        prev_base = next - cn as u32;
        pn = cn;
    }
    // Point every run straight at its root (a parent is below its child,
    // so it is resolved first), and find the largest component.
    for i in 0..next {
        let p = entry(table, i);
        if p & ROOT == 0 {
            let pp = entry(table, p);
            if pp & ROOT == 0 {
                set_entry(table, i, pp);
            }
        } else {
            out.count += 1;
            let area = p & !ROOT;
            if out.largest.is_none_or(|(_, a)| area > a) {
                out.largest = Some((i, area));
            }
        }
    }
    out.runs = next;
    Ok(out)
}

/// Sets pixels `s..=e` of a row.
fn set_run(row: &mut [u32], s: u32, e: u32) {
    let (ws, we) = ((s / 32) as usize, (e / 32) as usize);
    for (i, w) in row.iter_mut().enumerate().take(we + 1).skip(ws) {
        let lo = if i == ws { s % 32 } else { 0 };
        let hi = if i == we { e % 32 } else { 31 };
        let m = (u32::MAX >> (31 - hi)) & (u32::MAX << lo);
        *w |= m;
    }
}

impl Components {
    /// Writes into `dst` the components whose `(root, area)` `keep` accepts;
    /// `src` and `table` must be those of the labelling. Returns the pixels
    /// written.
    pub fn select(
        &self,
        g: Geom,
        src: &[u32],
        table: &[u32],
        dst: &mut [u32],
        mut keep: impl FnMut(u32, u32) -> bool,
    ) -> u32 {
        dst.fill(0);
        let Some((y0, y1)) = self.rows else {
            return 0;
        };
        let mut i = 0u32;
        let mut n = 0;
        for y in y0..=y1 {
            let row = g.row(src, y).unwrap_or(&[]);
            let Some(out) = dst.get_mut(y * g.stride..(y + 1) * g.stride) else {
                continue;
            };
            for (s, e) in Runs::new(row) {
                if i >= self.runs {
                    return n;
                }
                let p = entry(table, i);
                let root = if p & ROOT != 0 { i } else { p };
                if keep(root, entry(table, root) & !ROOT) {
                    set_run(out, s, e);
                    n += e - s + 1;
                }
                i += 1;
            }
        }
        n
    }

    /// Writes into `out` the `(root, area)` of the largest components that
    /// `keep(area)` accepts, largest first (the first in raster order on
    /// ties), as many as `out` holds; returns how many it wrote.
    pub fn largest_roots(
        &self,
        table: &[u32],
        keep: impl Fn(u32) -> bool,
        out: &mut [(u32, u32)],
    ) -> usize {
        let mut n = 0;
        for i in 0..self.runs {
            let e = entry(table, i);
            let area = e & !ROOT;
            if e & ROOT == 0 || !keep(area) {
                continue;
            }
            // Insertion: after every entry at least as large.
            let at = out.iter().take(n).position(|&(_, a)| a < area).unwrap_or(n);
            if at >= out.len() {
                continue;
            }
            n = (n + 1).min(out.len());
            let mut carry = (i, area);
            for slot in out.iter_mut().take(n).skip(at) {
                core::mem::swap(slot, &mut carry);
            }
        }
        n
    }

    /// Calls `f(area)` for every component, in order.
    pub fn for_each_root(&self, table: &[u32], mut f: impl FnMut(u32)) {
        for i in 0..self.runs {
            let e = entry(table, i);
            if e & ROOT != 0 {
                f(e & !ROOT);
            }
        }
    }
}
