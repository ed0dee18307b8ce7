//! FNV-1a 32-bit: the checksum that host and firmware compare bit for bit.

/// An FNV-1a 32-bit hasher.
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a(u32);

impl Default for Fnv1a {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv1a {
    /// The FNV offset basis.
    pub const fn new() -> Self {
        Self(0x811c_9dc5)
    }

    /// Feeds bytes.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u32::from(b)).wrapping_mul(0x0100_0193);
        }
    }

    /// The hash so far.
    pub const fn finish(&self) -> u32 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn known_vectors() {
        let h = |s: &[u8]| {
            let mut f = super::Fnv1a::new();
            f.write(s);
            f.finish()
        };
        assert_eq!(h(b""), 0x811c_9dc5);
        assert_eq!(h(b"a"), 0xe40c_292c);
        assert_eq!(h(b"foobar"), 0xbf9c_f968);
    }
}
