//! How the process's heap keeps memory between views.
//!
//! Owns: glibc malloc's two thresholds, set once per run. Must not touch anything else: it
//! changes where buffers come from, never what they hold.
//!
//! Every view allocates a dozen buffers of a few megabytes (depth, triangle ids, colours,
//! masks, encoded files). By default glibc serves those from fresh `mmap`s and gives freed
//! memory back at once, so the kernel zeroes and maps every page again for the next view:
//! 3,800 page faults per 960×960 view, a sixth of a quickstart run spent in the kernel.
//! Serving them from the heap and keeping what was freed turns that into reuse; the peak
//! stays what one view per thread holds, so memory is still flat in the sample count.

/// Allocations below this come from the heap (glibc's largest allowed value, 32 MiB on
/// 64-bit); larger ones (the buffers of a 3840×3840 view) are still mapped and returned.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: i32 = 32 << 20;

/// Free memory at the top of a heap is returned to the kernel only beyond this.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const TRIM_THRESHOLD: i32 = 256 << 20;

/// Keeps per-view buffers in the process between views (glibc only; elsewhere nothing).
pub fn keep_view_buffers() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets two of malloc's tuning parameters; it is thread-safe and
    // takes no pointers.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD);
    }
}
