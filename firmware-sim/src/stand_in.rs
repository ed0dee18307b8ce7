//! STAND-IN for the `protogist` core API (image, synth, conspicuity).
//!
//! This module exists only so firmware-sim compiles before the real core lands
//! on main. It mirrors the agreed signatures exactly; its numbers are NOT the
//! core's. When merging, delete this file and switch `pg` in lib.rs to
//! `protogist`. Nothing outside firmware-sim may depend on it.
#![allow(missing_docs)]

pub mod image {
    #[derive(Clone, Copy, PartialEq, Eq, Default, Debug)]
    #[repr(transparent)]
    pub struct Luma8(pub u8);

    #[derive(Clone, Copy, PartialEq, Eq, Default, Debug)]
    #[repr(C)]
    pub struct Rgb8 {
        pub r: u8,
        pub g: u8,
        pub b: u8,
    }

    #[derive(Clone, Copy, PartialEq, Eq, Debug)]
    pub enum ImageError {
        ZeroSize,
        StrideTooSmall,
        BufferTooSmall,
    }

    fn check(len: usize, width: usize, height: usize, stride: usize) -> Result<(), ImageError> {
        if width == 0 || height == 0 {
            return Err(ImageError::ZeroSize);
        }
        if stride < width {
            return Err(ImageError::StrideTooSmall);
        }
        let need = stride
            .checked_mul(height - 1)
            .and_then(|n| n.checked_add(width))
            .ok_or(ImageError::BufferTooSmall)?;
        if len < need {
            return Err(ImageError::BufferTooSmall);
        }
        Ok(())
    }

    pub struct ImageView<'a, P> {
        data: &'a [P],
        width: usize,
        height: usize,
        stride: usize,
    }

    impl<'a, P> ImageView<'a, P> {
        pub fn new(
            data: &'a [P],
            width: usize,
            height: usize,
            stride: usize,
        ) -> Result<Self, ImageError> {
            check(data.len(), width, height, stride)?;
            Ok(Self {
                data,
                width,
                height,
                stride,
            })
        }
        pub fn width(&self) -> usize {
            self.width
        }
        pub fn height(&self) -> usize {
            self.height
        }
        pub fn row(&self, y: usize) -> &[P] {
            &self.data[y * self.stride..y * self.stride + self.width]
        }
    }

    pub struct ImageViewMut<'a, P> {
        data: &'a mut [P],
        width: usize,
        height: usize,
        stride: usize,
    }

    impl<'a, P> ImageViewMut<'a, P> {
        pub fn new(
            data: &'a mut [P],
            width: usize,
            height: usize,
            stride: usize,
        ) -> Result<Self, ImageError> {
            check(data.len(), width, height, stride)?;
            Ok(Self {
                data,
                width,
                height,
                stride,
            })
        }
        pub fn as_view(&self) -> ImageView<'_, P> {
            ImageView {
                data: self.data,
                width: self.width,
                height: self.height,
                stride: self.stride,
            }
        }
        pub fn width(&self) -> usize {
            self.width
        }
        pub fn height(&self) -> usize {
            self.height
        }
        pub fn row_mut(&mut self, y: usize) -> &mut [P] {
            &mut self.data[y * self.stride..y * self.stride + self.width]
        }
    }
}

pub mod synth {
    use super::image::{ImageViewMut, Rgb8};

    #[derive(Clone, Copy, PartialEq, Eq, Debug)]
    pub enum SynthError {
        TooSmall,
    }

    #[derive(Clone, Debug)]
    pub struct SceneSpec {
        pub seed: u64,
        pub width: usize,
        pub height: usize,
    }

    impl SceneSpec {
        pub fn demo(width: usize, height: usize) -> SceneSpec {
            SceneSpec {
                seed: 0x5EED_0001,
                width,
                height,
            }
        }
    }

    fn mix(mut z: u64) -> u64 {
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Gradient background, three seeded rectangles and a little hashed noise.
    pub fn render_left(
        spec: &SceneSpec,
        out: &mut ImageViewMut<'_, Rgb8>,
    ) -> Result<(), SynthError> {
        let (w, h) = (out.width(), out.height());
        if w < 4 || h < 4 {
            return Err(SynthError::TooSmall);
        }
        let mut rects = [(0usize, 0usize, 0usize, 0usize, Rgb8::default()); 3];
        for (i, r) in rects.iter_mut().enumerate() {
            let z = mix(spec.seed.wrapping_add(i as u64 + 1));
            // u64 arithmetic: usize is 32 bits on the MCU and 64 on the host.
            let pick = |shift: u32, n: usize| ((z >> shift) % n as u64) as usize;
            let (x0, y0) = (pick(0, w / 2), pick(16, h / 2));
            let (rw, rh) = (w / 4 + pick(32, w / 4), h / 4 + pick(40, h / 4));
            *r = (
                x0,
                y0,
                x0 + rw,
                y0 + rh,
                Rgb8 {
                    r: (z >> 8) as u8,
                    g: (z >> 24) as u8,
                    b: (z >> 48) as u8,
                },
            );
        }
        for y in 0..h {
            let row = out.row_mut(y);
            for (x, px) in row.iter_mut().enumerate() {
                let n = (mix(spec.seed ^ ((y * w + x) as u64)) & 15) as u8;
                *px = Rgb8 {
                    r: (x * 255 / w) as u8 / 2 + n,
                    g: (y * 255 / h) as u8 / 2 + n,
                    b: 64 + n,
                };
                for &(x0, y0, x1, y1, c) in &rects {
                    if (x0..x1).contains(&x) && (y0..y1).contains(&y) {
                        *px = c;
                    }
                }
            }
        }
        Ok(())
    }
}

pub mod conspicuity {
    use super::image::{ImageView, Rgb8};

    #[derive(Clone, Copy, PartialEq, Eq, Debug)]
    pub enum ConspicuityError {
        SizeMismatch,
        BufferTooSmall,
    }

    pub struct LuvTables {
        gamma: [u16; 256],
    }

    impl LuvTables {
        pub fn new() -> LuvTables {
            let mut gamma = [0u16; 256];
            for (i, g) in gamma.iter_mut().enumerate() {
                *g = ((i * i) >> 4) as u16; // crude square-law linearisation
            }
            LuvTables { gamma }
        }
    }

    impl Default for LuvTables {
        fn default() -> Self {
            Self::new()
        }
    }

    #[derive(Clone, Copy, PartialEq, Eq, Default, Debug)]
    pub struct Luv {
        l: u16,
        u: i16,
        v: i16,
    }

    #[derive(Clone, Copy, PartialEq, Eq, Default, Debug, PartialOrd, Ord)]
    pub struct Conspicuity(pub u16);

    /// One cell of a conspicuity map (the core's is `MaybeOff<Conspicuity>`).
    pub type EdgeCell = Conspicuity;

    #[derive(Clone, Copy, Debug)]
    pub struct EdgeParams {
        pub threshold: u16,
    }

    impl Default for EdgeParams {
        fn default() -> Self {
            EdgeParams { threshold: 256 }
        }
    }

    pub const fn luv_len(width: usize, height: usize) -> usize {
        width * height
    }
    pub const fn row_scratch_len(width: usize) -> usize {
        2 * width
    }
    pub const fn scratch_bytes(width: usize, height: usize) -> usize {
        (2 * luv_len(width, height) + row_scratch_len(width)) * 6 + luv_len(width, height) * 2
    }

    pub struct EdgeBuffers<'a> {
        width: usize,
        height: usize,
        luv: &'a mut [Luv],
        smoothed: &'a mut [Luv],
        rows: &'a mut [Luv],
        conspicuity: &'a mut [EdgeCell],
    }

    fn fnv(h: u32, bytes: &[u8]) -> u32 {
        bytes
            .iter()
            .fold(h, |h, &b| (h ^ b as u32).wrapping_mul(0x0100_0193))
    }

    impl<'a> EdgeBuffers<'a> {
        pub fn new(
            width: usize,
            height: usize,
            luv: &'a mut [Luv],
            smoothed: &'a mut [Luv],
            rows: &'a mut [Luv],
            conspicuity: &'a mut [EdgeCell],
        ) -> Result<Self, ConspicuityError> {
            let n = luv_len(width, height);
            if luv.len() < n
                || smoothed.len() < n
                || conspicuity.len() < n
                || rows.len() < row_scratch_len(width)
            {
                return Err(ConspicuityError::BufferTooSmall);
            }
            Ok(Self {
                width,
                height,
                luv,
                smoothed,
                rows,
                conspicuity,
            })
        }

        pub fn checksum(&self) -> u32 {
            let n = luv_len(self.width, self.height);
            let mut h = 0x811c_9dc5;
            for p in self.luv[..n].iter().chain(&self.smoothed[..n]) {
                h = fnv(h, &p.l.to_le_bytes());
                h = fnv(h, &p.u.to_le_bytes());
                h = fnv(h, &p.v.to_le_bytes());
            }
            for c in &self.conspicuity[..n] {
                h = fnv(h, &c.0.to_le_bytes());
            }
            h
        }
    }

    pub struct EdgeReport {
        pub max: Conspicuity,
        pub on_count: u32,
    }

    pub fn edge_conspicuity(
        tables: &LuvTables,
        params: &EdgeParams,
        rgb: &ImageView<'_, Rgb8>,
        bufs: &mut EdgeBuffers<'_>,
    ) -> Result<EdgeReport, ConspicuityError> {
        let (w, h) = (bufs.width, bufs.height);
        if rgb.width() != w || rgb.height() != h {
            return Err(ConspicuityError::SizeMismatch);
        }
        for y in 0..h {
            for (x, p) in rgb.row(y).iter().enumerate() {
                let (r, g, b) = (
                    tables.gamma[p.r as usize],
                    tables.gamma[p.g as usize],
                    tables.gamma[p.b as usize],
                );
                let l = ((r as u32 * 77 + g as u32 * 150 + b as u32 * 29) >> 8) as u16;
                let u = ((r as i32 - g as i32) >> 1) as i16;
                let v = ((g as i32 + r as i32 - 2 * b as i32) >> 2) as i16;
                bufs.luv[y * w + x] = Luv { l, u, v };
            }
        }
        // Horizontal [1 2 1] through the row scratch (the real core also smooths vertically).
        for y in 0..h {
            let (cur, _) = bufs.rows.split_at_mut(w);
            for (x, c) in cur.iter_mut().enumerate() {
                let (a, b, d) = (
                    bufs.luv[y * w + x.saturating_sub(1)],
                    bufs.luv[y * w + x],
                    bufs.luv[y * w + (x + 1).min(w - 1)],
                );
                *c = Luv {
                    l: ((a.l as u32 + 2 * b.l as u32 + d.l as u32) >> 2) as u16,
                    u: ((a.u as i32 + 2 * b.u as i32 + d.u as i32) >> 2) as i16,
                    v: ((a.v as i32 + 2 * b.v as i32 + d.v as i32) >> 2) as i16,
                };
            }
            bufs.smoothed[y * w..(y + 1) * w].copy_from_slice(cur);
        }
        let mut report = EdgeReport {
            max: Conspicuity(0),
            on_count: 0,
        };
        for y in 0..h {
            for x in 0..w {
                let at = |xx: usize, yy: usize| bufs.smoothed[yy * w + xx];
                let (l, r) = (at(x.saturating_sub(1), y), at((x + 1).min(w - 1), y));
                let (t, b) = (at(x, y.saturating_sub(1)), at(x, (y + 1).min(h - 1)));
                let d = l.l.abs_diff(r.l) as u32
                    + t.l.abs_diff(b.l) as u32
                    + l.u.abs_diff(r.u) as u32
                    + t.v.abs_diff(b.v) as u32;
                let c = Conspicuity(d.min(u16::MAX as u32) as u16);
                bufs.conspicuity[y * w + x] = c;
                report.max = report.max.max(c);
                report.on_count += (c.0 >= params.threshold) as u32;
            }
        }
        Ok(report)
    }
}
