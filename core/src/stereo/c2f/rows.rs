//! Rows in and out of the engine: the levels' RGB rows from the frames,
//! and the sinks the finest level's cells go to.

use crate::disparity::DisparityCell;
use crate::image::{mean_2x2_row, ImageViewMut, Rgb8, RgbRows};
use crate::stereo::phase::{PhaseKernel, Refiner};

/// Where the finest level's cells go, in row-major order.
pub(super) trait Cells {
    /// Cell `(x, y)`.
    fn cell(&mut self, x: usize, y: usize, c: DisparityCell);
    /// A frame row to fill before [`Cells::row_done`], for a consumer that
    /// works on rows (the spread of a level `k > 0` then fills it instead
    /// of calling [`Cells::cell`]).
    fn row(&mut self) -> Option<&mut [DisparityCell]> {
        None
    }
    /// Frame row `y` of [`Cells::row`] is filled.
    fn row_done(&mut self, _y: usize) {}
}

/// A sink of cells.
pub(super) struct Plain<'f, F>(pub(super) &'f mut F);

impl<F: FnMut(usize, usize, DisparityCell)> Cells for Plain<'_, F> {
    #[inline(always)]
    fn cell(&mut self, x: usize, y: usize, c: DisparityCell) {
        (self.0)(x, y, c);
    }
}

/// A sink that is a map of the frame's size: a level `k > 0` fills its
/// rows whole.
pub(super) struct Map<'m, 'a> {
    pub(super) map: &'m mut ImageViewMut<'a, DisparityCell>,
    /// The frame row [`Cells::row`] hands out next.
    pub(super) next: usize,
}

impl Cells for Map<'_, '_> {
    #[inline(always)]
    fn cell(&mut self, x: usize, y: usize, c: DisparityCell) {
        self.map.set(x, y, c);
    }
    fn row(&mut self) -> Option<&mut [DisparityCell]> {
        self.map.row_mut(self.next)
    }
    fn row_done(&mut self, y: usize) {
        self.next = y + 1;
    }
}

/// A sink behind the phase refinement (phase step of kernel `K`): each
/// output row is refined, then passed on cell by cell.
pub(super) struct Refined<'r, 'p, 'b, S: RgbRows, F, K> {
    pub(super) refiner: &'r mut Refiner<'p, 'b, S, K>,
    pub(super) sink: &'r mut F,
}

impl<S: RgbRows, F: FnMut(usize, usize, DisparityCell), K: PhaseKernel> Cells
    for Refined<'_, '_, '_, S, F, K>
{
    #[inline(always)]
    fn cell(&mut self, x: usize, y: usize, c: DisparityCell) {
        self.refiner.push(x, y, c, self.sink);
    }
    fn row(&mut self) -> Option<&mut [DisparityCell]> {
        Some(self.refiner.row_mut())
    }
    fn row_done(&mut self, y: usize) {
        self.refiner.flush(y, self.sink);
    }
}

/// Level-`k` RGB row `j` of `src` (rounded 2x2 means, `k` times) into
/// `out` (`⌊w/2^k⌋` long), with `scratch` for the finer rows.
pub(super) fn level_row<S: RgbRows>(
    src: &S,
    k: usize,
    j: usize,
    out: &mut [Rgb8],
    scratch: &mut [Rgb8],
) {
    if k == 0 {
        src.rgb_row(j, out);
        return;
    }
    if k == 1 {
        src.half_row(j, out, scratch);
        return;
    }
    let fw = 2 * out.len();
    let (a, rest) = scratch.split_at_mut(fw.min(scratch.len()));
    let (b, rest) = rest.split_at_mut(fw.min(rest.len()));
    level_row(src, k - 1, 2 * j, a, rest);
    level_row(src, k - 1, 2 * j + 1, b, rest);
    mean_2x2_row(a, b, out);
}
