//! Windowed, row-streamed semi-global aggregation (SGM) in integers: the
//! building block of the coarse-to-fine engine (docs/STEREO.md, "Coarse-to-fine
//! with SGM"), bit-exact against the f32 reference
//! `protogist_host::reference::stereo::sgm::aggregate` with 5 paths.
//!
//! **Windows.** Pixel `x` of a row has `n` candidates `lo[x]..lo[x] + n`
//! (`lo` differs per pixel). A candidate outside a pixel's window is not
//! reachable: it behaves as the reference's `EXCLUDED` cost, i.e. as `+∞`
//! in every minimum, so a path entering a pixel from a neighbour whose
//! window does not contain `d` (nor `d ± 1`) takes the `min prev + P2`
//! branch, and `min prev` is taken over the neighbour's window.
//!
//! **Paths.** The 5 a row-streaming reader runs in one top-to-bottom pass
//! (`sgm::directions(5)` of the reference): left→right, right→left,
//! top→bottom and the two diagonals from above. Along each,
//! `L(p, d) = C(p, d) + min(L(p−r, d), L(p−r, d ± 1) + P1, min L(p−r) + P2)
//! − min L(p−r)`; a pixel with no predecessor along a path (image border,
//! first row) starts with `L = C`.
//!
//! **Formats and bounds.** Costs `C`, `P1` and `P2` are `u16` in the caller's
//! fixed-point units (`P1 <= P2`). Since every `L(p−r, ·) >= min L(p−r)`,
//! the bracket minus `min L(p−r)` lies in `0..=P2`, so every path value is
//! `C(p, d) <= L(p, d) <= C(p, d) + P2 <= C_max + P2`. Path values are kept
//! in `u16`, which holds them exactly when `C_max + P2 <= 65535`: a cost
//! above `65535 − P2` is rejected ([`SgmError::CostTooLarge`], checked
//! before any state changes). The output sums the 5 paths, at most
//! `5·(C_max + P2) <= 5·65535 < 2^19`, in `u32`. All arithmetic is integer
//! min/add/sub and exact; nothing rounds.
//!
//! **Streaming.** [`Sgm::push_row`] takes one row's costs (`[x][i]`,
//! `width·n`) and windows, and writes that row's summed costs. State kept
//! between rows ([`scratch_len`] `u16`s): the previous row's `L` of the
//! three paths from above (`3·width·n`) and its windows (`width`), plus two
//! pixels of working state (`2·n`); the right→left sweep reads the caller's
//! cost row, so no cost row is copied. At 160 px and `n = 5`:
//! `scratch_len(160, 5) = 2,570` elements, 5,140 bytes ([`scratch_bytes`]).

use core::fmt;

/// `u16` elements of scratch for rows of `width` pixels and `n` candidates:
/// `3·width·n` (previous row, three paths from above) + `width` (previous
/// row's windows) + `2·n` (horizontal path and one working pixel).
pub const fn scratch_len(width: usize, n: usize) -> usize {
    width
        .saturating_mul(n)
        .saturating_mul(3)
        .saturating_add(width)
        .saturating_add(n.saturating_mul(2))
}

/// Bytes of [`scratch_len`].
pub const fn scratch_bytes(width: usize, n: usize) -> usize {
    scratch_len(width, n).saturating_mul(2)
}

/// Why [`Sgm`] rejected its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SgmError {
    /// `n = 0`: a window needs at least one candidate.
    NoCandidates,
    /// `P2 < P1`.
    Penalties {
        /// The 1 px step penalty.
        p1: u16,
        /// The larger step penalty.
        p2: u16,
    },
    /// A buffer (scratch, costs, windows or output) of the wrong length.
    Buffer {
        /// Which buffer.
        what: &'static str,
        /// Elements needed.
        needed: usize,
        /// Elements given.
        got: usize,
    },
    /// A cost above `65535 − P2`: its path values would not fit in `u16`.
    CostTooLarge {
        /// Index of the cost in the row (`x·n + i`).
        index: usize,
        /// The cost.
        cost: u16,
        /// The largest cost allowed.
        max: u16,
    },
}

impl fmt::Display for SgmError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NoCandidates => write!(f, "SGM needs at least one candidate per pixel"),
            Self::Penalties { p1, p2 } => write!(f, "SGM penalty P2 {p2} is below P1 {p1}"),
            Self::Buffer { what, needed, got } => {
                write!(f, "SGM buffer {what} holds {got}, needs {needed}")
            }
            Self::CostTooLarge { index, cost, max } => {
                write!(f, "SGM cost {cost} at {index} is above {max} (65535 − P2)")
            }
        }
    }
}

impl core::error::Error for SgmError {}

/// Moves the first `len` elements of `*s` out.
fn take<'a>(s: &mut &'a mut [u16], len: usize) -> Option<&'a mut [u16]> {
    let (head, tail) = core::mem::take(s).split_at_mut_checked(len)?;
    *s = tail;
    Some(head)
}

/// Row-streamed windowed SGM over 5 paths (module docs).
#[derive(Debug)]
pub struct Sgm<'a> {
    width: usize,
    n: usize,
    p1: u16,
    p2: u16,
    rows: usize,
    /// Top→bottom `L` of the previous row, `[x][i]`.
    up: &'a mut [u16],
    /// `L` of the diagonal from the upper left (`(x−1, y−1) → (x, y)`).
    from_left: &'a mut [u16],
    /// `L` of the diagonal from the upper right (`(x+1, y−1) → (x, y)`).
    from_right: &'a mut [u16],
    /// The previous row's windows.
    prev_lo: &'a mut [u16],
    /// Horizontal path state: `L` of the previous pixel along the sweep.
    h: &'a mut [u16],
    /// One working pixel.
    tmp: &'a mut [u16],
}

impl<'a> Sgm<'a> {
    /// Aggregation of rows of `width` pixels with `n` candidates each,
    /// penalties `p1 <= p2`, state in `scratch` ([`scratch_len`] long).
    ///
    /// # Errors
    /// [`SgmError::NoCandidates`], [`SgmError::Penalties`], or
    /// [`SgmError::Buffer`] for a scratch of another length.
    pub fn new(
        width: usize,
        n: usize,
        p1: u16,
        p2: u16,
        scratch: &'a mut [u16],
    ) -> Result<Self, SgmError> {
        if n == 0 {
            return Err(SgmError::NoCandidates);
        }
        if p2 < p1 {
            return Err(SgmError::Penalties { p1, p2 });
        }
        let needed = scratch_len(width, n);
        let got = scratch.len();
        let bad = SgmError::Buffer {
            what: "scratch",
            needed,
            got,
        };
        if got != needed {
            return Err(bad);
        }
        let mut s = scratch;
        let wn = width * n;
        let (Some(up), Some(from_left), Some(from_right), Some(prev_lo), Some(h), Some(tmp)) = (
            take(&mut s, wn),
            take(&mut s, wn),
            take(&mut s, wn),
            take(&mut s, width),
            take(&mut s, n),
            take(&mut s, n),
        ) else {
            return Err(bad);
        };
        Ok(Self {
            width,
            n,
            p1,
            p2,
            rows: 0,
            up,
            from_left,
            from_right,
            prev_lo,
            h,
            tmp,
        })
    }

    /// The largest cost [`Sgm::push_row`] accepts, `65535 − P2`.
    pub const fn max_cost(&self) -> u16 {
        u16::MAX - self.p2
    }

    /// Rows pushed since the start (or the last [`Sgm::reset`]).
    pub const fn rows(&self) -> usize {
        self.rows
    }

    /// Starts a new frame: the next row is a first row again.
    pub fn reset(&mut self) {
        self.rows = 0;
    }

    /// Aggregates the next row: `costs` (`width·n`, `[x][i]`, candidate
    /// `lo[x] + i`), the windows `lo` (`width`), into `out` (`width·n`): the
    /// sum of the 5 paths' `L` at each window candidate.
    ///
    /// # Errors
    /// [`SgmError::Buffer`] for a buffer of the wrong length,
    /// [`SgmError::CostTooLarge`]; on error nothing changes (state or `out`).
    pub fn push_row(&mut self, costs: &[u16], lo: &[u16], out: &mut [u32]) -> Result<(), SgmError> {
        let (width, n) = (self.width, self.n);
        let wn = width * n;
        for (what, got, needed) in [
            ("costs", costs.len(), wn),
            ("lo", lo.len(), width),
            ("out", out.len(), wn),
        ] {
            if got != needed {
                return Err(SgmError::Buffer { what, needed, got });
            }
        }
        let max = self.max_cost();
        if let Some((index, &cost)) = costs.iter().enumerate().find(|&(_, &c)| c > max) {
            return Err(SgmError::CostTooLarge { index, cost, max });
        }
        let (p1, p2) = (u32::from(self.p1), u32::from(self.p2));
        let first = self.rows == 0;
        let Self {
            up,
            from_left,
            from_right,
            prev_lo,
            h,
            tmp,
            ..
        } = self;

        // Forward sweep: left→right, top→bottom, and the diagonal from the
        // upper right, which reads slot x + 1 before it is overwritten.
        let mut diag = from_right.chunks_exact_mut(n).peekable();
        let mut before: Option<u16> = None;
        for (x, (((c, &l), o), v)) in costs
            .chunks_exact(n)
            .zip(lo)
            .zip(out.chunks_exact_mut(n))
            .zip(up.chunks_exact_mut(n))
            .enumerate()
        {
            // Left→right from x − 1 (the first path: sets `o`).
            step_self(c, l, h, before, (p1, p2), tmp, o, true);
            before = Some(l);
            // Top→bottom from (x, y − 1).
            let above = prev_lo.get(x).copied().filter(|_| !first);
            step_self(c, l, v, above, (p1, p2), tmp, o, false);
            // From (x + 1, y − 1).
            let Some(slot) = diag.next() else { break };
            let right = prev_lo.get(x + 1).copied().filter(|_| !first);
            let prev = right.zip(diag.peek()).map(|(a, s)| (&**s, a));
            step_from(c, l, prev, (p1, p2), slot, o);
        }

        // Backward sweep: right→left, and the diagonal from the upper left,
        // which reads slot x − 1 before it is overwritten.
        let mut diag = from_left.chunks_exact_mut(n).rev().peekable();
        let mut before: Option<u16> = None;
        for (x, ((c, &l), o)) in costs
            .chunks_exact(n)
            .zip(lo)
            .zip(out.chunks_exact_mut(n))
            .enumerate()
            .rev()
        {
            step_self(c, l, h, before, (p1, p2), tmp, o, false);
            before = Some(l);
            let Some(slot) = diag.next() else { break };
            let left = x
                .checked_sub(1)
                .and_then(|xl| prev_lo.get(xl))
                .copied()
                .filter(|_| !first);
            let prev = left.zip(diag.peek()).map(|(a, s)| (&**s, a));
            step_from(c, l, prev, (p1, p2), slot, o);
        }

        for (p, &l) in prev_lo.iter_mut().zip(lo) {
            *p = l;
        }
        self.rows = self.rows.saturating_add(1);
        Ok(())
    }
}

/// A step whose predecessor is `state` itself, at window `plo` (the
/// horizontal and vertical paths; `None`: no predecessor): `state` becomes
/// the pixel's `L`, added to `out` (or stored, with `set`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn step_self(
    c: &[u16],
    lo: u16,
    state: &mut [u16],
    plo: Option<u16>,
    pen: (u32, u32),
    tmp: &mut [u16],
    out: &mut [u32],
    set: bool,
) {
    if let (Ok(c5), Ok(s5)) = (
        <&[u16; 5]>::try_from(c),
        <&mut [u16; 5]>::try_from(&mut *state),
    ) {
        let ext = plo.map(|p| gather(&s5[..], p, lo));
        apply(c5, ext, pen, s5, out, set);
        return;
    }
    for (t, &v) in tmp.iter_mut().zip(state.iter()) {
        *t = v;
    }
    step(c, lo, plo.map(|p| (&*tmp, p)), pen, state, out, set);
}

/// A step from another slot `prev` (the diagonals) into `state`, added to
/// `out`.
#[inline(always)]
fn step_from(
    c: &[u16],
    lo: u16,
    prev: Option<(&[u16], u16)>,
    pen: (u32, u32),
    state: &mut [u16],
    out: &mut [u32],
) {
    if let (Ok(c5), Ok(s5)) = (
        <&[u16; 5]>::try_from(c),
        <&mut [u16; 5]>::try_from(&mut *state),
    ) {
        let ext = prev.map(|(p, plo)| gather(p, plo, lo));
        apply(c5, ext, pen, s5, out, false);
        return;
    }
    step(c, lo, prev, pen, state, out, false);
}

/// Larger than any `L − min + P1` (both below 2^17), and no overflow.
const INF: u32 = 1 << 30;

/// The predecessor's `L − min` (window from `plo`) at candidates `lo − 1 ..
/// lo + 6` (`INF` outside its window): a window of up to 6 from `lo`
/// with both neighbours.
#[inline(always)]
fn gather(prev: &[u16], plo: u16, lo: u16) -> [u32; 8] {
    let min = prev.iter().copied().min().map_or(0, u32::from);
    let off = i32::from(lo) - i32::from(plo);
    let mut ext = [INF; 8];
    for (j, e) in (off - 1..).zip(ext.iter_mut()) {
        if let Some(&v) = usize::try_from(j).ok().and_then(|j| prev.get(j)) {
            *e = u32::from(v).saturating_sub(min);
        }
    }
    ext
}

/// The recurrence for a window of `N <= 6` from the gathered predecessor
/// (`None`: `L = C`), the same integers as [`step`].
#[inline(always)]
fn apply<const N: usize>(
    c: &[u16; N],
    ext: Option<[u32; 8]>,
    (p1, p2): (u32, u32),
    new: &mut [u16; N],
    out: &mut [u32],
    set: bool,
) {
    let Some(ext) = ext else {
        for ((o, s), &cd) in new.iter_mut().zip(out.iter_mut()).zip(c) {
            *o = cd;
            *s = if set {
                u32::from(cd)
            } else {
                *s + u32::from(cd)
            };
        }
        return;
    };
    for (((o, s), &cd), w) in new
        .iter_mut()
        .zip(out.iter_mut())
        .zip(c)
        .zip(ext.windows(3))
    {
        if let [below, here, above] = *w {
            let v = u32::from(cd) + p2.min(here).min(below.min(above) + p1);
            *o = u16::try_from(v).unwrap_or(u16::MAX);
            *s = if set { v } else { *s + v };
        }
    }
}

/// One step of a path into `new`: the pixel's costs `c` over its window
/// `lo..lo + n`, and the predecessor's `L` over its window (`None`: no
/// predecessor, `L = C`). Candidates outside the predecessor's window are
/// `+∞`. Needs `c + P2 <= 65535` (checked by the caller). Each new value
/// is also added to `out` (or stored, with `set`).
fn step(
    c: &[u16],
    lo: u16,
    prev: Option<(&[u16], u16)>,
    (p1, p2): (u32, u32),
    new: &mut [u16],
    out: &mut [u32],
    set: bool,
) {
    let Some((prev, plo)) = prev else {
        for ((o, s), &cd) in new.iter_mut().zip(out).zip(c) {
            *o = cd;
            *s = if set {
                u32::from(cd)
            } else {
                *s + u32::from(cd)
            };
        }
        return;
    };
    let min = prev.iter().copied().min().map_or(0, u32::from);
    // `L − min` of the predecessor at candidates `lo − 1, lo, ..` (`INF`
    // outside its window), read once each.
    let off = i32::from(lo) - i32::from(plo);
    let at = |j: i32| {
        usize::try_from(j)
            .ok()
            .and_then(|j| prev.get(j))
            .map_or(INF, |&v| u32::from(v).saturating_sub(min))
    };
    let (mut below, mut here) = (at(off - 1), at(off));
    for (j, ((o, s), &cd)) in (off + 1..).zip(new.iter_mut().zip(out).zip(c)) {
        let above = at(j);
        let m = p2.min(here).min(below.min(above) + p1);
        let v = u32::from(cd) + m;
        *o = u16::try_from(v).unwrap_or(u16::MAX);
        *s = if set { v } else { *s + v };
        (below, here) = (here, above);
    }
}
