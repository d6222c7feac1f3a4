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

/// The size of the last allocation the system refused (0: none), recorded
/// by [`Recording`] for [`report_out_of_memory_on_abort`].
static REFUSED_BYTES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// The system allocator, recording the size of any allocation it refuses.
/// The program's allocator (`main.rs`): an allocation that fails where no
/// code can take the failure ends the process in `abort`, and the record
/// lets [`report_out_of_memory_on_abort`] say why in words.
pub struct Recording;

// SAFETY: every method forwards to the system allocator with the same
// arguments; the only addition is an atomic store when it returns null.
unsafe impl std::alloc::GlobalAlloc for Recording {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: the caller's contract is System's.
        let p = unsafe { std::alloc::System.alloc(layout) };
        if p.is_null() {
            refused(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: as above.
        let p = unsafe { std::alloc::System.alloc_zeroed(layout) };
        if p.is_null() {
            refused(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: as above.
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as above.
        let p = unsafe { std::alloc::System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            refused(new_size);
        }
        p
    }
}

fn refused(bytes: usize) {
    REFUSED_BYTES.store(bytes.max(1), std::sync::atomic::Ordering::Relaxed);
}

/// The last line of defence against running out of memory: the estimates
/// ([`crate::memory`]) refuse what would not fit before it starts, and a
/// factorization's allocations are fallible, but an allocation can still
/// fail where the standard library can only abort ("memory allocation of
/// N bytes failed", SIGABRT, a core dump). After that message, this says
/// what happened in one line and ends the process with exit code 3
/// instead of the abort. An abort with no refused allocation (a bug) is
/// left as it is. Call once, first thing, in the binary.
pub fn report_out_of_memory_on_abort() {
    #[cfg(unix)]
    // SAFETY: the handler only calls async-signal-safe functions (write,
    // _exit, signal, raise) and reads an atomic.
    unsafe {
        libc::signal(
            libc::SIGABRT,
            on_abort as extern "C" fn(libc::c_int) as libc::sighandler_t,
        );
    }
}

#[cfg(unix)]
extern "C" fn on_abort(_: libc::c_int) {
    let bytes = REFUSED_BYTES.load(std::sync::atomic::Ordering::Relaxed);
    if bytes == 0 {
        // Not for want of memory: abort as the program asked.
        // SAFETY: async-signal-safe calls.
        unsafe {
            libc::signal(libc::SIGABRT, libc::SIG_DFL);
            libc::raise(libc::SIGABRT);
        }
        return;
    }
    let mut line = [0u8; 512];
    let mut len = 0;
    let mut put = |s: &[u8]| {
        let k = s.len().min(line.len() - len);
        line[len..len + k].copy_from_slice(&s[..k]);
        len += k;
    };
    put(b"error: out of memory: an allocation of ");
    let (amount, unit): (usize, &[u8]) = if bytes >= 1_000_000 {
        (bytes / 1_000_000, b" MB")
    } else {
        (bytes, b" bytes")
    };
    let mut digits = [0u8; 20];
    let mut k = digits.len();
    let mut rest = amount;
    loop {
        k -= 1;
        digits[k] = b'0' + (rest % 10) as u8;
        rest /= 10;
        if rest == 0 {
            break;
        }
    }
    put(&digits[k..]);
    put(unit);
    put(b" failed beyond what the estimates foresaw; use a coarser h or a leaner solver (`contactlab info` lists each solver's estimate), or free memory\n");
    // SAFETY: writing a stack buffer to stderr and leaving at once are
    // async-signal-safe.
    unsafe {
        libc::write(2, line.as_ptr().cast(), len);
        libc::_exit(3);
    }
}
