//! Typed buffers carved from the caller's one workspace.
//!
//! The workspace is a `&mut [u64]`, so it starts 8-byte aligned. Every
//! buffer taken from it is rounded up to a multiple of 8 bytes, so every
//! buffer starts 8-byte aligned too, whatever its element type; the
//! `const fn`s of [`super::layout`] count the same rounded sizes, so a
//! workspace of [`super::workspace_bytes`] always holds the buffers of a
//! run. The casts are `bytemuck`'s checked ones: a bad cast is an error,
//! never undefined behaviour (core forbids `unsafe`). Buffers are not
//! cleared: a buffer holds whatever the workspace held.

use super::PipelineError;

/// `n` elements of `size` bytes, rounded up to whole 8-byte words.
pub(super) const fn bytes(n: usize, size: usize) -> usize {
    (n * size).div_ceil(8) * 8
}

/// A cursor over the free bytes of a workspace region.
pub(super) struct Arena<'a> {
    rest: &'a mut [u8],
    /// Bytes the region held, for the error of a short one.
    total: usize,
    /// Bytes taken so far.
    used: usize,
}

impl<'a> Arena<'a> {
    /// An arena over `words`.
    pub(super) fn new(words: &'a mut [u64]) -> Self {
        let rest: &'a mut [u8] = bytemuck::cast_slice_mut(words);
        let total = rest.len();
        Self {
            rest,
            total,
            used: 0,
        }
    }

    fn take_bytes(&mut self, len: usize) -> Result<&'a mut [u8], PipelineError> {
        let padded = len.div_ceil(8) * 8;
        if padded > self.rest.len() {
            return Err(PipelineError::WorkspaceTooSmall {
                needed: self.used + padded,
                got: self.total,
            });
        }
        let r = core::mem::take(&mut self.rest);
        let (head, tail) = r.split_at_mut(padded);
        self.rest = tail;
        self.used += padded;
        Ok(head.get_mut(..len).unwrap_or(&mut []))
    }

    /// `n` elements of a plain-old-data type, as the workspace left them:
    /// not cleared (that cost about 0.24 M instructions a frame on the
    /// board). Every stage writes what it reads; `host/tests/
    /// stale_workspace.rs` runs frames in workspaces of random bytes, of
    /// ones and of an earlier frame's, against a zeroed one, to the bit.
    pub(super) fn take<T: bytemuck::Pod>(
        &mut self,
        n: usize,
    ) -> Result<&'a mut [T], PipelineError> {
        let b = self.take_bytes(n * core::mem::size_of::<T>())?;
        bytemuck::try_cast_slice_mut(b).map_err(|_| PipelineError::WorkspaceAlignment)
    }
}
