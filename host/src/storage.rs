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
    /// D_fg, D_ObjReg.
    pub disparity: Vec<protogist::disparity::DisparityCell>,
    /// C_fg, ψ, C_ObjReg, C_Obj.
    pub edges: Vec<protogist::conspicuity::EdgeCell>,
    /// Binary maps.
    pub binary: Vec<bool>,
    /// Label map and parent table.
    pub labels: Vec<u16>,
    /// Area table.
    pub area: Vec<u32>,
}

impl SegmentStorage {
    /// Storage sized by the stage's `const fn`s.
    pub fn new(width: usize, height: usize) -> Self {
        use protogist::segment as s;
        Self {
            width,
            height,
            disparity: vec![Default::default(); s::disparity_maps_len(width, height)],
            edges: vec![Default::default(); s::edge_maps_len(width, height)],
            binary: vec![false; s::binary_maps_len(width, height)],
            labels: vec![0; s::label_maps_len(width, height)],
            area: vec![0; s::label_capacity(width, height)],
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
            &mut self.disparity,
            &mut self.edges,
            &mut self.binary,
            &mut self.labels,
            &mut self.area,
        )
    }
}
