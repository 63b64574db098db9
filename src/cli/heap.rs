//! How the command-line process's heap treats freed memory. glibc's malloc maps every large block
//! (the fit's per-pass buffers: a few MB per 100k samples) afresh and unmaps it when freed, or
//! trims the heap top, so each LM iteration's buffers fault their pages in again (about a third
//! of the 100k fit's page faults). Kept in the heap instead, a freed buffer's pages serve the
//! next pass. Only the binary asks for this: the Python extension leaves its host's heap alone.

/// Blocks up to this size come from the heap (glibc's largest accepted threshold: half a heap).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MAP_ABOVE: libc::c_int = 32 << 20;

/// Freed memory at the heap's top is given back to the system only beyond this.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const TRIM_ABOVE: libc::c_int = 256 << 20;

/// Keep freed large blocks in the heap for reuse (glibc; elsewhere nothing changes). Call before
/// any thread starts.
pub fn keep_freed_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets two of malloc's tuning values; it is called before any other
    // thread exists and a refusal (returned 0) leaves malloc's defaults, which are correct too.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MAP_ABOVE);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_ABOVE);
    }
}
