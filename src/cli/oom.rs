//! The binary's allocator: the system's, except that an allocation the system refuses (a memory
//! limit such as `ulimit -v`, `prlimit --as` or a cgroup's) ends the run as an error instead of
//! Rust's abort (exit 134 with a backtrace): the message says what to do, the run's staging
//! directories and temporary files are removed, and the exit code is 1. What that takes is
//! served from a small reserve, since the system has no memory left to give.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::cell::UnsafeCell;
use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicUsize, Ordering};

/// Memory for the error path once the system refuses: the message, the cleanup's paths.
const RESERVE: usize = 256 << 10;

#[repr(align(4096))]
struct Reserve(UnsafeCell<[u8; RESERVE]>);

// SAFETY: handed out in disjoint pieces by an atomic bump pointer.
unsafe impl Sync for Reserve {}

static POOL: Reserve = Reserve(UnsafeCell::new([0; RESERVE]));
static USED: AtomicUsize = AtomicUsize::new(0);
static FAILED: AtomicBool = AtomicBool::new(false);

/// Address space set aside at start ([`set_aside`]) and given back when the system refuses: the
/// C library's own allocations on the error path (opening a directory to remove it) need it.
static BALLAST: AtomicPtr<u8> = AtomicPtr::new(std::ptr::null_mut());
const BALLAST_LAYOUT: Layout = match Layout::from_size_align(1 << 20, 4096) {
    Ok(l) => l,
    Err(_) => panic!("a valid layout"),
};

thread_local! {
    /// True on the thread that is ending the run.
    static ENDING: Cell<bool> = const { Cell::new(false) };
}

/// Set aside the address space the error path needs, and make a thread the system refuses
/// (no room for its stack) the same error (call first thing in `main`).
pub fn set_aside() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.starts_with("failed to spawn thread") {
            if FAILED.swap(true, Ordering::SeqCst) {
                loop {
                    std::thread::park();
                }
            }
            end_run("a thread's stack");
        }
        default(info)
    }));
    // SAFETY: a valid, non-zero layout; given back once in `refused`.
    let p = unsafe { System.alloc(BALLAST_LAYOUT) };
    BALLAST.store(p, Ordering::SeqCst);
}

/// The system allocator, ending the run cleanly when it refuses.
pub struct ExitOnOom;

fn in_pool(ptr: *mut u8) -> bool {
    let start = POOL.0.get() as usize;
    (start..start + RESERVE).contains(&(ptr as usize))
}

fn from_pool(layout: Layout) -> *mut u8 {
    let start = POOL.0.get() as usize;
    let mut used = USED.load(Ordering::Relaxed);
    loop {
        let at = (start + used).next_multiple_of(layout.align()) - start;
        let end = at + layout.size();
        if end > RESERVE {
            return std::ptr::null_mut();
        }
        match USED.compare_exchange(used, end, Ordering::SeqCst, Ordering::Relaxed) {
            Ok(_) => return (start + at) as *mut u8,
            Err(now) => used = now,
        }
    }
}

fn say(text: &str) {
    use std::io::Write;
    let _ = std::io::stderr().write_all(text.as_bytes());
}

/// The system refused `layout`: serve it from the reserve while the first thread to get here
/// reports the error, removes the run's partial outputs and exits 1.
fn refused(layout: Layout) -> *mut u8 {
    if FAILED.swap(true, Ordering::SeqCst) {
        let p = from_pool(layout);
        if !p.is_null() {
            return p;
        }
        if ENDING.with(Cell::get) {
            std::process::exit(1);
        }
        // Another thread is ending the run: wait for it to exit.
        loop {
            std::thread::park();
        }
    }
    end_run(&crate::error::readable_bytes(layout.size() as u64))
}

/// Report that the system refused `what`, remove the run's partial outputs and exit 1 (the
/// caller set [`FAILED`]).
fn end_run(what: &str) -> ! {
    ENDING.with(|e| e.set(true));
    let ballast = BALLAST.swap(std::ptr::null_mut(), Ordering::SeqCst);
    if !ballast.is_null() {
        // SAFETY: allocated in `set_aside` with this layout.
        unsafe { System.dealloc(ballast, BALLAST_LAYOUT) };
    }
    say(&format!(
        "hairfit: error: out of memory: the system refused {what} (a memory limit: ulimit -v, \
         prlimit --as or a cgroup's); nothing was published and what --out or --output held \
         is unchanged. Run with a higher limit, or on less data (fewer rows, fewer channels)\n",
    ));
    crate::atomic::stop_writing();
    crate::atomic::remove_in_flight();
    crate::outdir::remove_in_flight();
    // Runs no destructors (they would allocate); the reserve serves what exiting takes.
    std::process::exit(1)
}

// SAFETY: every pointer is the system's or a disjoint piece of the reserve, which is never
// freed (a dealloc of one is ignored) and never reallocated in place.
unsafe impl GlobalAlloc for ExitOnOom {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            return refused(layout);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            // The reserve is zeroed and never reused.
            return refused(layout);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if !in_pool(ptr) {
            unsafe { System.dealloc(ptr, layout) }
        }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let new_layout = unsafe { Layout::from_size_align_unchecked(new_size, layout.align()) };
        if in_pool(ptr) {
            let p = unsafe { self.alloc(new_layout) };
            if !p.is_null() {
                unsafe { std::ptr::copy_nonoverlapping(ptr, p, layout.size().min(new_size)) };
            }
            return p;
        }
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            let q = refused(new_layout);
            if !q.is_null() {
                unsafe { std::ptr::copy_nonoverlapping(ptr, q, layout.size().min(new_size)) };
            }
            return q;
        }
        p
    }
}
