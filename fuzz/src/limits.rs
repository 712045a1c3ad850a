//! What makes a case a finding besides a panic: an allocation past the memory limit (the
//! global allocator counts live bytes and aborts) and a case that runs past the time limit (a
//! watchdog thread exits the process). Either kills the worker; the supervisor then files the
//! case the worker wrote to disk before running it.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The system allocator, counting live bytes and refusing to go past [`set_memory_limit`].
pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static LIMIT: AtomicUsize = AtomicUsize::new(usize::MAX);

/// Exit status of a worker whose case ran past the time limit.
pub const HANG_EXIT: i32 = 86;

/// Caps the live heap of this process at `bytes`.
pub fn set_memory_limit(bytes: usize) {
    LIMIT.store(bytes, Ordering::Relaxed);
}

fn over_limit() -> ! {
    // No allocation here: the allocator is what failed.
    let _ = std::io::stderr().write_all(b"rae-fuzz: allocation past the memory limit (unbounded allocation)\n");
    std::process::abort()
}

// SAFETY: every call forwards to `System` with the same layout; the counter only observes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size() > LIMIT.load(Ordering::Relaxed) {
            over_limit();
        }
        // SAFETY: as the caller's contract for `alloc`.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size() > LIMIT.load(Ordering::Relaxed) {
            over_limit();
        }
        // SAFETY: as the caller's contract for `alloc_zeroed`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: `ptr` came from this allocator with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() {
            let grow = new_size - layout.size();
            if LIVE.fetch_add(grow, Ordering::Relaxed) + grow > LIMIT.load(Ordering::Relaxed) {
                over_limit();
            }
        } else {
            LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
        }
        // SAFETY: as the caller's contract for `realloc`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Milliseconds since the watchdog started at which the running case began (0: none running).
static CASE_START: AtomicU64 = AtomicU64::new(0);

/// A thread that ends the process with [`HANG_EXIT`] when a case runs longer than `limit`.
pub struct Watchdog {
    epoch: Instant,
}

impl Watchdog {
    /// Starts the watchdog thread.
    pub fn start(limit: Duration) -> Watchdog {
        let epoch = Instant::now();
        std::thread::spawn(move || {
            loop {
                std::thread::sleep(Duration::from_millis(100));
                let start = CASE_START.load(Ordering::Relaxed);
                if start != 0 && epoch.elapsed().as_millis() as u64 > start + limit.as_millis() as u64 {
                    let _ = std::io::stderr().write_all(b"rae-fuzz: a case ran past the time limit (hang)\n");
                    std::process::exit(HANG_EXIT);
                }
            }
        });
        Watchdog { epoch }
    }

    /// Marks a case as started (`true`) or done.
    pub fn running(&self, on: bool) {
        let now = if on { self.epoch.elapsed().as_millis() as u64 + 1 } else { 0 };
        CASE_START.store(now, Ordering::Relaxed);
    }
}
