//! Where figure-ground writes its object masks.

use super::bits::Geom;

/// Where [`segment_into`](super::segment_into) writes the object masks:
/// one chunk per object.
#[derive(Debug)]
pub enum Masks<'m> {
    /// `width · height` `bool`s per object (as [`segment`](super::segment)).
    Bools(&'m mut [bool]),
    /// One bit map per object, [`bit_map_len`](super::bit_map_len) words
    /// each, read with [`BitView::new`](super::BitView::new).
    Bits(&'m mut [u32]),
}

impl Masks<'_> {
    /// Length of one object's slot: a frame of `bool`s or a bit map.
    pub(super) fn chunk(&self, g: Geom) -> usize {
        match self {
            Masks::Bools(_) => (g.width * g.height).max(1),
            Masks::Bits(_) => g.len().max(1),
        }
    }

    /// ORs slot `i` into the bit map `dst`.
    pub(super) fn or_into(&self, i: usize, chunk: usize, g: Geom, dst: &mut [u32]) {
        match self {
            Masks::Bits(m) => {
                if let Some(m) = m.get(i * chunk..(i + 1) * chunk) {
                    for (d, s) in dst.iter_mut().zip(m) {
                        *d |= *s;
                    }
                }
            }
            Masks::Bools(m) => {
                let Some(m) = m.get(i * chunk..(i + 1) * chunk) else {
                    return;
                };
                for (k, _) in m.iter().enumerate().filter(|(_, &on)| on) {
                    let (x, y) = (k % g.width.max(1), k / g.width.max(1));
                    if let Some(word) = dst.get_mut(y * g.stride + x / 32) {
                        *word |= 1 << (x % 32);
                    }
                }
            }
        }
    }

    /// Writes the bit map `src` into slot `i`.
    pub(super) fn write(&mut self, i: usize, chunk: usize, g: Geom, src: &[u32]) {
        let span = i * chunk..(i + 1) * chunk;
        match self {
            Masks::Bits(m) => {
                if let Some(m) = m.get_mut(span) {
                    super::bits::copy_map(m, src);
                }
            }
            Masks::Bools(m) => {
                let Some(mask) = m.get_mut(span) else {
                    return;
                };
                let w = g.width;
                // Rows by index: a zip of two `chunks_exact` is not always
                // inlined, and its size hint links a division panic.
                for y in 0..g.height {
                    let (Some(out), Some(words)) = (
                        mask.get_mut(y * w..(y + 1) * w),
                        src.get(y * g.stride..(y + 1) * g.stride),
                    ) else {
                        break;
                    };
                    for (o, b) in out.chunks_mut(32).zip(words) {
                        for (i, o) in o.iter_mut().enumerate() {
                            *o = b >> i & 1 != 0;
                        }
                    }
                }
            }
        }
    }

    /// The same masks, borrowed again for a shorter time.
    pub fn reborrow(&mut self) -> Masks<'_> {
        match self {
            Masks::Bools(m) => Masks::Bools(m),
            Masks::Bits(m) => Masks::Bits(m),
        }
    }

    pub(super) fn len(&self) -> usize {
        match self {
            Self::Bools(m) => m.len(),
            Self::Bits(m) => m.len(),
        }
    }
}
