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

/// Owned storage for [`protogist::stereo::c2f::C2fBuffers`] at one size.
pub struct C2fStorage {
    /// Grey rings.
    pub grey: Vec<u16>,
    /// RGB rows.
    pub rgb: Vec<protogist::image::Rgb8>,
    /// Response rows.
    pub z: Vec<protogist::stereo::filters::Z>,
    /// Grey row.
    pub col: Vec<[i32; 3]>,
    /// Score rows.
    pub scores: Vec<i64>,
    /// Costs, windows, voters, SGM states.
    pub costs: Vec<u16>,
    /// SGM sums.
    pub sums: Vec<u32>,
    /// Row picks.
    pub picks: Vec<i32>,
    /// Window maps.
    pub maps: Vec<u8>,
    /// The phase refinement's.
    pub phase: PhaseStorage,
}

/// Owned storage for [`protogist::stereo::phase::PhaseBuffers`] at one
/// width (empty without parameters).
pub struct PhaseStorage {
    /// One RGB row.
    pub rgb: Vec<protogist::image::Rgb8>,
    /// Grey row.
    pub v: Vec<i32>,
    /// Response rows.
    pub z: Vec<[i16; 2]>,
    /// One map row.
    pub row: Vec<protogist::disparity::DisparityCell>,
}

impl PhaseStorage {
    /// Storage for width `width`, sized by the refinement's `const fn`s.
    pub fn new(
        width: usize,
        p: Option<&protogist::stereo::phase::PhaseParams>,
        max_disp: u8,
    ) -> Self {
        use protogist::stereo::phase as ph;
        let Some(p) = p else {
            return Self {
                rgb: Vec::new(),
                v: Vec::new(),
                z: Vec::new(),
                row: Vec::new(),
            };
        };
        Self {
            rgb: vec![protogist::image::Rgb8::new(0, 0, 0); width],
            v: vec![0; ph::v_len(width, p)],
            z: vec![[0; 2]; ph::z_len(width, p, max_disp)],
            row: vec![protogist::disparity::DisparityCell::OFF; width],
        }
    }

    /// The refinement's view of the storage.
    pub fn buffers(&mut self) -> protogist::stereo::phase::PhaseBuffers<'_> {
        protogist::stereo::phase::PhaseBuffers {
            rgb: &mut self.rgb,
            v: &mut self.v,
            z: &mut self.z,
            row: &mut self.row,
        }
    }
}

impl C2fStorage {
    /// Storage for a `width x height` pair, sized by the engine's
    /// `const fn`s.
    pub fn new(width: usize, height: usize, p: &protogist::stereo::c2f::C2fParams) -> Self {
        use protogist::stereo::c2f as c;
        Self {
            grey: vec![0; c::grey_len(width, p)],
            rgb: vec![protogist::image::Rgb8::new(0, 0, 0); c::rgb_len(width, p)],
            z: vec![[0; 2]; c::z_len(width, p)],
            col: vec![[0; 3]; width],
            scores: vec![0; c::score_len(width, p)],
            costs: vec![0; c::cost_len(width, p)],
            sums: vec![0; c::sum_len(width, p)],
            picks: vec![0; c::pick_len(width)],
            maps: vec![0; c::map_len(width, height, p)],
            phase: PhaseStorage::new(width, p.phase.as_ref(), p.dem.max_disp),
        }
    }

    /// The engine's view of the storage.
    pub fn buffers(&mut self) -> protogist::stereo::c2f::C2fBuffers<'_> {
        protogist::stereo::c2f::C2fBuffers {
            grey: &mut self.grey,
            rgb: &mut self.rgb,
            z: &mut self.z,
            col: &mut self.col,
            scores: &mut self.scores,
            costs: &mut self.costs,
            sums: &mut self.sums,
            picks: &mut self.picks,
            maps: &mut self.maps,
            phase: self.phase.buffers(),
        }
    }
}
