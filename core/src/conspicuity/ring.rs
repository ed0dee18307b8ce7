//! A ring of three edge-padded rows: the 3x3 neighbourhood of a row sweep.
//!
//! Each source row is copied once into a buffer of `width + 2` pixels whose
//! first and last pixels replicate the row's ends. The sweep then reads
//! `prev`, `cur` and `next` with `windows(3)`, with no bounds checks and no
//! border cases; the top and bottom rows are replicated the same way.
//! Because the ring holds copies, a filter may write its output back into
//! the source image (in place) while it sweeps.

use super::{ConspicuityError, Luv};

/// Elements of row scratch a sweep over `width`-pixel rows needs.
pub const fn row_scratch_len(width: usize) -> usize {
    3 * (width + 2)
}

pub(crate) struct Ring<'r> {
    pub prev: &'r mut [Luv],
    pub cur: &'r mut [Luv],
    pub next: &'r mut [Luv],
}

impl<'r> Ring<'r> {
    pub fn new(rows: &'r mut [Luv], width: usize) -> Result<Self, ConspicuityError> {
        let needed = row_scratch_len(width);
        let pw = width + 2;
        let got = rows.len();
        let rows = rows
            .get_mut(..needed)
            .ok_or(ConspicuityError::ScratchTooSmall { needed, got })?;
        let too_small = ConspicuityError::ScratchTooSmall { needed, got };
        let (prev, rest) = rows.split_at_mut_checked(pw).ok_or(too_small)?;
        let (cur, next) = rest.split_at_mut_checked(pw).ok_or(too_small)?;
        Ok(Self { prev, cur, next })
    }

    /// Loads the first row into `cur`, and replicates it into `prev`.
    pub fn start(&mut self, first: &[Luv]) {
        load_padded(self.cur, first);
        self.prev.copy_from_slice(self.cur);
    }

    /// Loads the row below the current one into `next`.
    pub fn load_next(&mut self, row: &[Luv]) {
        load_padded(self.next, row);
    }

    /// Moves down one row.
    pub fn advance(&mut self) {
        core::mem::swap(&mut self.prev, &mut self.cur);
        core::mem::swap(&mut self.cur, &mut self.next);
    }
}

fn load_padded(dst: &mut [Luv], src: &[Luv]) {
    let (Some(&first), Some(&last)) = (src.first(), src.last()) else {
        return;
    };
    if let Some(body) = dst.get_mut(1..=src.len()) {
        body.copy_from_slice(src);
    }
    if let Some(d) = dst.first_mut() {
        *d = first;
    }
    if let Some(d) = dst.get_mut(src.len() + 1) {
        *d = last;
    }
}
