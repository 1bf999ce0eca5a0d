//! Heap accounting for the figures a user compares (bytes per face at a million faces and
//! beyond): [`Counting`] wraps the system allocator and keeps the bytes live and their peak.
//! A program opts in by installing it (`slayer` does):
//!
//! ```ignore
//! #[global_allocator]
//! static HEAP: slayer::memory::Counting = slayer::memory::Counting;
//! ```
//!
//! Without it, [`peak_bytes`] is `None`: the library never pretends to have measured.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::Relaxed};

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static INSTALLED: AtomicBool = AtomicBool::new(false);

/// The system allocator, counting.
pub struct Counting;

impl Counting {
    fn grew(by: usize) {
        let live = LIVE.fetch_add(by, Relaxed) + by;
        PEAK.fetch_max(live, Relaxed);
    }

    /// Counts a fresh block `p` of `size` bytes, if the allocation succeeded.
    fn allocated(p: *mut u8, size: usize) -> *mut u8 {
        if !p.is_null() {
            INSTALLED.store(true, Relaxed);
            Counting::grew(size);
        }
        p
    }
}

// SAFETY: every call is forwarded to `System` unchanged; the counters are plain atomics.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded with the caller's layout.
        Counting::allocated(unsafe { System.alloc(layout) }, layout.size())
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded with the caller's layout.
        Counting::allocated(unsafe { System.alloc_zeroed(layout) }, layout.size())
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from this allocator (hence `System`) with `layout`.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as the trait requires of the caller, forwarded unchanged.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            // Counted as the larger of the two sizes at once: a copying realloc holds both
            // for a moment, which the peak then slightly understates, never overstates.
            if new_size >= layout.size() {
                Counting::grew(new_size - layout.size());
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Relaxed);
            }
        }
        p
    }
}

/// Heap bytes live now, when [`Counting`] is installed.
pub fn live_bytes() -> Option<usize> {
    INSTALLED.load(Relaxed).then(|| LIVE.load(Relaxed))
}

/// The most heap bytes live at once since the program started or since [`reset_peak`], when
/// [`Counting`] is installed.
pub fn peak_bytes() -> Option<usize> {
    INSTALLED.load(Relaxed).then(|| PEAK.load(Relaxed))
}

/// Starts a new peak from what is live now (to measure one phase of a run).
pub fn reset_peak() {
    PEAK.store(LIVE.load(Relaxed), Relaxed);
}

/// The process's peak resident memory in bytes, as Linux reports it (`VmHWM`); `None`
/// elsewhere. Unlike [`peak_bytes`] it needs no allocator installed, and counts all memory.
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
