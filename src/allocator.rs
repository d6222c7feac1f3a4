//! The program's allocator policy: memory that was freed is kept for the
//! next allocation instead of being returned to the kernel at once.
//!
//! glibc's malloc gives the free top of its heap back to the kernel once it
//! exceeds a threshold, which it raises only to the largest block it has
//! mapped so far, and serves every block above another threshold from a
//! mapping of its own. A study assembles and solves again and again, so
//! each time every page of the new matrices was faulted in afresh, at about
//! 2.5 µs a page on the 2-core machines this runs on: measured with `perf`,
//! 45 % of a repeated assembly at h = 1/64 was the kernel zeroing and
//! mapping pages that had just been freed. With this policy, repeats reuse
//! them. Blocks of 32 MiB and more (the factors and matrices of the finest
//! meshes) still get their own mapping and are returned when freed, so a
//! large solve does not stay resident; the process keeps at most 256 MiB of
//! free heap beyond that.
//!
//! Timings of repeated runs are therefore warm; a single run (the bench's
//! rows marked "once") still pays every first touch.

/// The largest block served from the heap; larger ones are mapped alone
/// (glibc's own ceiling for this threshold).
const MAPPED_FROM_BYTES: i32 = 32 << 20;
/// Free heap kept beyond what is in use.
const KEPT_FREE_BYTES: i32 = 256 << 20;

/// Sets the policy for this process; call it once, first thing. Elsewhere
/// than glibc, and if glibc refuses a setting, the allocator's defaults stay.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes two thresholds of the allocator; it is
    // called before any other thread exists.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MAPPED_FROM_BYTES);
        libc::mallopt(libc::M_TRIM_THRESHOLD, KEPT_FREE_BYTES);
    }
}

/// Returns the free memory kept by [`keep_freed_memory`] to the kernel, so
/// that the resident size measures what is in use (the memory table).
pub fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases free memory.
    unsafe {
        libc::malloc_trim(0);
    }
}
