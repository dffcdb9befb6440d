//! The memory a script may allocate.
//!
//! Rhai's size limits apply to single values, and not even to every way a value grows, so the
//! memory a recipe's script takes is bounded directly: [`CountingAllocator`] (the binary's
//! global allocator) counts what each thread allocates and frees, and while a thread evaluates
//! a script inside a [`Budget`], the engine stops the script with an error at the first
//! operation after it holds more than [`MAX_SCRIPT_BYTES`]. Files the recipe reads (meshes,
//! images) have their own bounds and are not counted ([`exempt`]). Without the counting
//! allocator (the library used on its own) nothing is counted and no budget applies.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// Memory one evaluation of a script (the recipe, or one sample's scene) may hold, bytes.
pub const MAX_SCRIPT_BYTES: i64 = 512 << 20;

thread_local! {
    /// Bytes allocated minus bytes freed by this thread.
    static HELD: Cell<i64> = const { Cell::new(0) };
    /// `HELD` when the innermost running budget started.
    static BASE: Cell<Option<i64>> = const { Cell::new(None) };
}

fn held() -> i64 {
    HELD.try_with(Cell::get).unwrap_or(0)
}

fn count(bytes: i64) {
    // `try_with`: allocations may happen while the thread's locals are torn down.
    let _ = HELD.try_with(|h| h.set(h.get().wrapping_add(bytes)));
}

/// The system allocator, counting bytes per thread.
pub struct CountingAllocator;

// SAFETY: every call is forwarded unchanged to `System`; counting touches only a const-initialised
// thread-local `Cell` that never allocates.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as i64);
        // SAFETY: the caller upholds `alloc`'s contract, which `System.alloc` shares.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as i64);
        // SAFETY: as for `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        count(-(layout.size() as i64));
        // SAFETY: `ptr` came from `System` with this layout, as every allocation here does.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size as i64 - layout.size() as i64);
        // SAFETY: as for `dealloc`; `new_size` is the caller's, unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[cfg(test)]
#[global_allocator]
static COUNTING: CountingAllocator = CountingAllocator;

/// Counts what the current thread allocates while it lives; budgets nest.
pub struct Budget {
    outer: Option<i64>,
}

impl Budget {
    pub fn start() -> Self {
        Budget {
            outer: BASE.with(|b| b.replace(Some(held()))),
        }
    }
}

impl Drop for Budget {
    fn drop(&mut self) {
        BASE.with(|b| b.set(self.outer));
    }
}

/// Whether the thread's running budget is spent.
pub fn over_budget() -> bool {
    BASE.with(Cell::get)
        .is_some_and(|base| held() - base > MAX_SCRIPT_BYTES)
}

/// Runs `f` without counting what it allocates against the running budget.
pub fn exempt<T>(f: impl FnOnce() -> T) -> T {
    let before = held();
    let result = f();
    let grown = held() - before;
    BASE.with(|b| b.set(b.get().map(|base| base + grown)));
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_count_what_the_thread_holds_except_exempt_work() {
        let _budget = Budget::start();
        assert!(!over_budget());
        let big = exempt(|| vec![0u8; (MAX_SCRIPT_BYTES + 1) as usize]);
        assert!(!over_budget());
        let more = vec![0u8; (MAX_SCRIPT_BYTES + 1) as usize];
        assert!(over_budget());
        drop(more);
        assert!(!over_budget());
        drop(big);
        {
            let _inner = Budget::start();
            assert!(!over_budget());
        }
        assert!(!over_budget());
    }
}
