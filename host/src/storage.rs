//! Owned, correctly sized storage for the core stages' caller-provided
//! buffers, for host code (the demo, the CLI, tests, benches).

/// Owned storage for [`protogist::conspicuity::EdgeBuffers`] at one size.
pub struct EdgeStorage {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// CIELUV map.
    pub luv: Vec<protogist::conspicuity::Luv>,
    /// Smoothed map.
    pub smoothed: Vec<protogist::conspicuity::Luv>,
    /// Row scratch.
    pub rows: Vec<protogist::conspicuity::Luv>,
    /// Conspicuity map.
    pub cmap: Vec<protogist::conspicuity::EdgeCell>,
}

impl EdgeStorage {
    /// Storage sized by the stage's `const fn`s.
    pub fn new(width: usize, height: usize) -> Self {
        use protogist::conspicuity::{luv_len, row_scratch_len, EdgeCell, Luv};
        Self {
            width,
            height,
            luv: vec![Luv::default(); luv_len(width, height)],
            smoothed: vec![Luv::default(); luv_len(width, height)],
            rows: vec![Luv::default(); row_scratch_len(width)],
            cmap: vec![EdgeCell::OFF; luv_len(width, height)],
        }
    }

    /// The stage's view of the storage.
    ///
    /// # Errors
    /// The stage's typed error for a zero or too-large size.
    pub fn buffers(
        &mut self,
    ) -> Result<protogist::conspicuity::EdgeBuffers<'_>, protogist::conspicuity::ConspicuityError>
    {
        protogist::conspicuity::EdgeBuffers::new(
            self.width,
            self.height,
            &mut self.luv,
            &mut self.smoothed,
            &mut self.rows,
            &mut self.cmap,
        )
    }
}

/// Owned storage for [`protogist::segment::SegmentBuffers`] at one size.
pub struct SegmentStorage {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// The bit maps and the run rows.
    pub maps: Vec<u32>,
    /// The component table (an entry per run: its root, or a root's area).
    pub area: Vec<u32>,
}

impl SegmentStorage {
    /// Storage sized by the stage's `const fn`s.
    pub fn new(width: usize, height: usize) -> Self {
        use protogist::segment as s;
        Self {
            width,
            height,
            maps: vec![0; s::maps_len(width, height)],
            area: vec![0; s::table_len(width, height)],
        }
    }

    /// The stage's view of the storage.
    ///
    /// # Errors
    /// The stage's typed error for a zero or too-large size.
    pub fn buffers(
        &mut self,
    ) -> Result<protogist::segment::SegmentBuffers<'_>, protogist::segment::SegmentError> {
        protogist::segment::SegmentBuffers::new(
            self.width,
            self.height,
            &mut self.maps,
            &mut self.area,
        )
    }
}
