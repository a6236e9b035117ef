//! A counting global allocator: forwards every call to [`System`] and counts, per thread, the
//! calls that obtain memory (`alloc`, `alloc_zeroed`, `realloc`).
//!
//! Tests run in parallel threads of one process, so the count is thread-local: a test sees only
//! its own allocations. The `#[global_allocator]` attribute must stand in the test binary
//! itself:
//!
//! ```
//! use flexprr_testkit::alloc::{CountingAllocator, count_allocations};
//!
//! #[global_allocator]
//! static GLOBAL: CountingAllocator = CountingAllocator;
//!
//! let mut buffer = vec![0.0_f64; 8];
//! let (_, none) = count_allocations(|| buffer.iter_mut().for_each(|x| *x += 1.0));
//! assert_eq!(none, 0);
//! let (_, one) = count_allocations(|| std::hint::black_box(vec![1.0_f64; 8]));
//! assert_eq!(one, 1);
//! ```

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    /// Allocations made by this thread since it started (constant initialiser, no destructor:
    /// reading it never allocates).
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// Counts one allocation on the current thread. `try_with`: while a thread shuts down its
/// thread-locals may already be gone, and the allocator must not panic then.
fn note_allocation() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

/// A global allocator that forwards to [`System`] and counts allocations per thread.
///
/// Install it in a test binary with
/// `#[global_allocator] static GLOBAL: CountingAllocator = CountingAllocator;` and read the
/// count with [`allocations`] or [`count_allocations`].
#[derive(Debug, Clone, Copy, Default)]
pub struct CountingAllocator;

// SAFETY: every call is forwarded unchanged to the system allocator, whose contract is the
// caller's; the only addition is a thread-local counter that never allocates.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note_allocation();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note_allocation();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note_allocation();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Allocations made so far by the current thread (zero forever if [`CountingAllocator`] is
/// not the global allocator of the binary). Differences of two readings count what happened
/// in between.
pub fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Runs `f` and returns its result with the number of allocations the current thread made
/// during it (the result is returned, not dropped, so its own deallocation is not counted).
pub fn count_allocations<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = allocations();
    let result = f();
    (result, allocations() - before)
}
