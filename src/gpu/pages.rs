//! Arrays larger than one storage binding. An adapter limits how many bytes one storage binding
//! may cover (lavapipe: 128 MiB), and at 16M faces the packed topology (about 30 bytes a face)
//! and the smoothing neighbours (about 24 bytes a vertex) pass it, as do the exclusion rings of
//! a large brush's step (some 40 words a moving vertex). Such an array stays one buffer
//! (buffers may be larger: lavapipe allows 2 GiB) bound as [`PAGE_COUNT`] bindings of a bind
//! group of its own, page `k` covering words `k << PAGE_SHIFT ..`; the kernel declares it with
//! `#paged NAME GROUP` (`wgsl/shared/pages.wgsl`) and reads it as `NAME(i)`. A page is the
//! largest power of two of bytes one binding allows, so `PAGE_SHIFT` is a pipeline constant
//! set when the kernel is compiled.
//!
//! Only those arrays are paged: every per-vertex array is at most 12 bytes a vertex and fits
//! one 128 MiB binding up to 11M vertices (22M faces), and the per-entry arrays of a step (32
//! bytes a moving vertex at most) up to 4M moving vertices; past that the kernels report
//! `TooLarge` and the strokes run on the CPU.

use super::context::check_fits;
use super::limits::{WORD, page_bytes, page_shift};
use super::{GpuContext, GpuError};
use crate::abi::PAGE_COUNT;

impl GpuContext {
    /// Bytes in one page: the largest power of two one storage binding (and one buffer) may
    /// hold, and at least the offset alignment, so every page starts at a legal offset.
    pub fn page_bytes(&self) -> u64 {
        page_bytes(&self.limits)
    }

    /// log2 of the words in a page, as the kernels' `PAGE_SHIFT`.
    pub fn page_shift(&self) -> u32 {
        page_shift(&self.limits)
    }

    /// Pages `words` words span (at least one).
    pub fn pages_for(&self, words: usize) -> u64 {
        (words as u64 * WORD).div_ceil(self.page_bytes()).max(1)
    }

    /// Fails clearly when `words` words would not fit [`PAGE_COUNT`] pages or one buffer;
    /// checked before anything is allocated.
    pub fn check_paged(&self, what: &str, words: usize) -> Result<(), GpuError> {
        let bytes = words as u64 * WORD;
        let limit = (PAGE_COUNT * self.page_bytes()).min(self.limits.max_buffer_size);
        check_fits(what, bytes, limit)
    }
}
