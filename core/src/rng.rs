//! SplitMix64: the one seeded generator of the project (scene generation in
//! core; training data, weight initialisation and splits on the host).
//!
//! Integer only and `no_std`, so a seed means the same stream on the host
//! and on the board.
//!
//! ```
//! use protogist::rng::SplitMix64;
//! let mut a = SplitMix64::new(7);
//! let mut b = SplitMix64::new(7);
//! assert_eq!(a.next_u64(), b.next_u64());
//! assert!(a.below(10) < 10);
//! ```

/// A SplitMix64 stream (Steele, Lea and Flood 2014).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A stream from `seed`.
    pub const fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The internal state (to derive a sub-stream from this one).
    pub const fn state(&self) -> u64 {
        self.0
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// `next_u64() % n`, or 0 when `n` is 0 (consumes no draw then).
    pub fn below(&mut self, n: u64) -> u64 {
        match n {
            0 => 0,
            n => self.next_u64() % n,
        }
    }

    /// Uniform in `lo..=hi`; the midpoint, without a draw, when `hi < lo`.
    pub fn range(&mut self, lo: i32, hi: i32) -> i32 {
        if hi < lo {
            return lo + (hi - lo) / 2;
        }
        let span = (i64::from(hi) - i64::from(lo) + 1) as u64;
        lo + (self.next_u64() % span) as i32
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    #[test]
    fn matches_the_reference_stream() {
        // First outputs of SplitMix64 seeded with 0 (Vigna's splitmix64.c).
        let mut r = SplitMix64::new(0);
        assert_eq!(r.next_u64(), 0xe220_a839_7b1d_cdaf);
        assert_eq!(r.next_u64(), 0x6e78_9e6a_a1b9_65f4);
        assert_eq!(r.below(0), 0);
        assert_eq!(r.range(5, 3), 4);
        assert!((0..100).all(|_| (-3..=3).contains(&r.range(-3, 3))));
    }
}
