//! Windowed, row-streamed semi-global aggregation (SGM) in integers: the
//! building block of the coarse-to-fine engine (docs/STEREO.md, "What the
//! engine computes"), bit-exact against the f32 reference
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
//! top→bottom and the two diagonals from above ([`Sgm::without_diagonals`]
//! runs the first 3 only, `directions(3)` of the reference). Along each,
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
//!
//! **Speed.** For `n <= 9` a pixel's candidates are fixed-size arrays: the
//! paths read each stored state once, fused per pixel (three in the forward
//! sweep, two in the backward one), the state is kept as `L − min L` (the
//! bracket only needs that; the minimum is taken once, when written), and
//! a predecessor whose window starts where the pixel's does (the common
//! case) is read without any gather. Other `n` run the plain per-path
//! recurrence; both give the same integers.

use crate::stereo::phase::{PhaseKernel, SafePhase};
use core::fmt;

mod kernels;

pub use kernels::sgm_step;
use kernels::{arr, kernel_step, step, step_self, INF};

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

/// Row-streamed windowed SGM over 5 paths, or 3 without the diagonals
/// (module docs).
#[derive(Debug)]
pub struct Sgm<'a> {
    width: usize,
    n: usize,
    p1: u16,
    p2: u16,
    /// Whether the two diagonal paths run (5 paths; else 3).
    diagonals: bool,
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
            diagonals: true,
            rows: 0,
            up,
            from_left,
            from_right,
            prev_lo,
            h,
            tmp,
        })
    }

    /// The same aggregation over the 3 paths left→right, right→left and
    /// top→bottom only (the reference's `directions(3)`): the diagonals'
    /// state in the scratch goes unused.
    #[must_use]
    pub fn without_diagonals(mut self) -> Self {
        self.diagonals = false;
        self
    }

    /// The number of paths summed: 5, or 3 [`Sgm::without_diagonals`].
    pub const fn paths(&self) -> u32 {
        if self.diagonals {
            5
        } else {
            3
        }
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
        self.push_row_with::<SafePhase>(costs, lo, out)
    }

    /// [`Sgm::push_row`] with the path step of kernel `K` for windows of 5
    /// ([`PhaseKernel::sgm_step5`]; the same integers with any kernel that
    /// honours its contract).
    ///
    /// # Errors
    /// As [`Sgm::push_row`].
    pub fn push_row_with<K: PhaseKernel>(
        &mut self,
        costs: &[u16],
        lo: &[u16],
        out: &mut [u32],
    ) -> Result<(), SgmError> {
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
        // `c + P2 < 2^17`, so bit 16 of the OR is set iff some `c > max`.
        let p2 = u32::from(self.p2);
        if costs.iter().fold(0, |a, &c| a | (u32::from(c) + p2)) > 0xffff {
            if let Some((index, &cost)) = costs.iter().enumerate().find(|&(_, &c)| c > max) {
                return Err(SgmError::CostTooLarge { index, cost, max });
            }
        }
        let p1 = u32::from(self.p1);
        let first = self.rows == 0;
        let diagonals = self.diagonals;
        let Self {
            up,
            from_left,
            from_right,
            prev_lo,
            h,
            tmp,
            ..
        } = self;
        let rows = Rows {
            costs,
            lo,
            prev_lo,
            pen: (p1, p2),
        };
        let state: [&mut [u16]; 3] = [up, from_left, from_right];
        macro_rules! fast {
            ($($k:literal)*; $($j:literal)*) => {
                match (n, diagonals) {
                    $(($k, true) => rows.fast::<K, $k, true>(first, state, out),)*
                    $(($j, false) => rows.fast::<K, $j, false>(first, state, out),)*
                    _ => rows.generic(first, state, h, tmp, out, diagonals),
                }
            };
        }
        // Without the diagonals, the windows the engine uses (5, 3 and the
        // coarsest level's 9) get the fixed-size path.
        fast!(1 2 3 4 5 6 7 8 9; 3 5 9);

        for (p, &l) in prev_lo.iter_mut().zip(lo) {
            *p = l;
        }
        self.rows = self.rows.saturating_add(1);
        Ok(())
    }
}

/// One row's inputs: costs (`[x][i]`), windows, the previous row's windows
/// and the penalties `(P1, P2)`.
struct Rows<'r> {
    costs: &'r [u16],
    lo: &'r [u16],
    prev_lo: &'r [u16],
    pen: (u32, u32),
}

impl Rows<'_> {
    /// The rows of `N` candidates. State (`up`, `from_left`, `from_right`):
    /// each pixel's `L − min L`, in `u16` (`L <= 65535`, checked by the
    /// caller). A missing predecessor (first row, image border) is read as
    /// zeros with zero pads, which gives `L = C` (every bracket is 0).
    /// `DIAG`: the two diagonal paths run too (else their state is left
    /// alone).
    #[inline(always)]
    fn fast<K: PhaseKernel, const N: usize, const DIAG: bool>(
        self,
        first: bool,
        state: [&mut [u16]; 3],
        out: &mut [u32],
    ) {
        let Self {
            costs,
            lo,
            prev_lo,
            pen,
        } = self;
        let [up, from_left, from_right] = state;
        let pad = if first {
            up.fill(0);
            from_left.fill(0);
            from_right.fill(0);
            0
        } else {
            INF
        };
        let zero = [0u16; N];

        // Forward sweep: left→right, top→bottom, and the diagonal from the
        // upper right, which reads slot x + 1 before slot x is overwritten.
        let mut slots = from_right.chunks_exact_mut(N);
        let mut slot = slots.next();
        let mut right_lo = prev_lo.iter().skip(1);
        let (mut hs, mut hlo, mut hpad) = ([0u16; N], lo.first().copied().unwrap_or(0), 0);
        for ((((c, &l), o), v), &vlo) in costs
            .chunks_exact(N)
            .zip(lo)
            .zip(out.chunks_exact_mut(N))
            .zip(up.chunks_exact_mut(N))
            .zip(prev_lo)
        {
            let next = slots.next();
            let (Some(c), Ok(o), Ok(v), Some(s)) = (
                arr(c),
                <&mut [u32; N]>::try_from(o),
                <&mut [u16; N]>::try_from(v),
                slot.and_then(|s| <&mut [u16; N]>::try_from(s).ok()),
            ) else {
                return;
            };
            let mut acc = [0u32; N];
            hs = kernel_step::<K, N>(c, &hs, (l, hlo), hpad, pen, &mut acc);
            (hlo, hpad) = (l, INF);
            *v = kernel_step::<K, N>(c, v, (l, vlo), pad, pen, &mut acc);
            if DIAG {
                let from = next.as_deref().and_then(arr).zip(right_lo.next());
                let (p, plo, pd) = from.map_or((&zero, l, 0), |(p, &plo)| (p, plo, pad));
                *s = kernel_step::<K, N>(c, p, (l, plo), pd, pen, &mut acc);
            }
            *o = acc;
            slot = next;
        }
        if !DIAG {
            // Right→left alone: the backward sweep adds one path. (The
            // backward sweep below with its diagonal under `if DIAG` gives
            // the same sums but walks the diagonal's slots for nothing: 30
            // instructions per pixel more on the M4.)
            let (mut hs, mut hlo, mut hpad) = ([0u16; N], lo.last().copied().unwrap_or(0), 0);
            for ((c, &l), o) in costs
                .chunks_exact(N)
                .zip(lo)
                .zip(out.chunks_exact_mut(N))
                .rev()
            {
                let (Some(c), Ok(o)) = (arr(c), <&mut [u32; N]>::try_from(o)) else {
                    return;
                };
                hs = kernel_step::<K, N>(c, &hs, (l, hlo), hpad, pen, o);
                (hlo, hpad) = (l, INF);
            }
            return;
        }

        // Backward sweep: right→left, and the diagonal from the upper left,
        // which reads slot x − 1 before slot x is overwritten.
        let mut slots = from_left.chunks_exact_mut(N).rev();
        let mut slot = slots.next();
        let mut left_lo = prev_lo.iter().rev().skip(1);
        let (mut hs, mut hlo, mut hpad) = ([0u16; N], lo.last().copied().unwrap_or(0), 0);
        for ((c, &l), o) in costs
            .chunks_exact(N)
            .zip(lo)
            .zip(out.chunks_exact_mut(N))
            .rev()
        {
            let next = slots.next();
            let (Some(c), Ok(o), Some(s)) = (
                arr(c),
                <&mut [u32; N]>::try_from(o),
                slot.and_then(|s| <&mut [u16; N]>::try_from(s).ok()),
            ) else {
                return;
            };
            let mut acc = *o;
            hs = kernel_step::<K, N>(c, &hs, (l, hlo), hpad, pen, &mut acc);
            (hlo, hpad) = (l, INF);
            let from = next.as_deref().and_then(arr).zip(left_lo.next());
            let (p, plo, pd) = from.map_or((&zero, l, 0), |(p, &plo)| (p, plo, pad));
            *s = kernel_step::<K, N>(c, p, (l, plo), pd, pen, &mut acc);
            *o = acc;
            slot = next;
        }
    }

    /// The rows of any `n` (plain [`step`]s), the diagonals only with
    /// `diagonals`. State: each pixel's `L`.
    fn generic(
        self,
        first: bool,
        [up, from_left, from_right]: [&mut [u16]; 3],
        h: &mut [u16],
        tmp: &mut [u16],
        out: &mut [u32],
        diagonals: bool,
    ) {
        let Self {
            costs,
            lo,
            prev_lo,
            pen,
        } = self;
        // At least 1 (`Sgm::new`); `max` shows the compiler, so that the
        // chunk loops have no panic path.
        let n = h.len().max(1);
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
            step_self(c, l, h, before, pen, tmp, o, true);
            before = Some(l);
            // Top→bottom from (x, y − 1).
            let above = prev_lo.get(x).copied().filter(|_| !first);
            step_self(c, l, v, above, pen, tmp, o, false);
            // From (x + 1, y − 1).
            let Some(slot) = diag.next() else { break };
            if diagonals {
                let right = prev_lo.get(x + 1).copied().filter(|_| !first);
                let prev = right.zip(diag.peek()).map(|(a, s)| (&**s, a));
                step(c, l, prev, pen, slot, o, false);
            }
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
            step_self(c, l, h, before, pen, tmp, o, false);
            before = Some(l);
            let Some(slot) = diag.next() else { break };
            if !diagonals {
                continue;
            }
            let left = x
                .checked_sub(1)
                .and_then(|xl| prev_lo.get(xl))
                .copied()
                .filter(|_| !first);
            let prev = left.zip(diag.peek()).map(|(a, s)| (&**s, a));
            step(c, l, prev, pen, slot, o, false);
        }
    }
}

#[cfg(test)]
mod tests;
