//! The allocators that turn an allocation the system refuses (a memory limit such as
//! `ulimit -v`, `prlimit --as` or a cgroup's) into an error instead of Rust's abort (exit 134
//! with a backtrace, or a dead Python interpreter):
//! - [`ExitOnOom`], the binary's: the message says what to do, the run's staging directories and
//!   temporary files are removed, and the exit code is 1;
//! - [`CancelOnOom`], the Python extension's: the address space set aside is given back so the
//!   work can wind down, every [`watch`]ed cancel flag is raised (a fit stops at its next
//!   iteration), and the caller, seeing [`refusals`] change, raises `MemoryError`.
//!
//! What the error path takes is served from a small reserve, since the system has no memory
//! left to give.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::cell::UnsafeCell;
use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// Memory for the error path once the system refuses: the message, the cleanup's paths.
const RESERVE: usize = 256 << 10;

#[repr(align(4096))]
struct Reserve(UnsafeCell<[u8; RESERVE]>);

// SAFETY: handed out in disjoint pieces by an atomic bump pointer.
unsafe impl Sync for Reserve {}

static POOL: Reserve = Reserve(UnsafeCell::new([0; RESERVE]));
static USED: AtomicUsize = AtomicUsize::new(0);
static FAILED: AtomicBool = AtomicBool::new(false);

/// Address space set aside at start ([`set_aside`], [`keep_ballast`]) and given back when the
/// system refuses: the C library's own allocations on the error path (opening a directory to
/// remove it) need it, and so does the work winding down after a cancel.
static BALLAST: AtomicPtr<u8> = AtomicPtr::new(std::ptr::null_mut());
static BALLAST_SIZE: AtomicUsize = AtomicUsize::new(0);

/// Refusals so far ([`CancelOnOom`]), and the largest refused size.
static REFUSALS: AtomicUsize = AtomicUsize::new(0);
static LARGEST_REFUSED: AtomicUsize = AtomicUsize::new(0);

/// The cancel flags [`CancelOnOom`] raises when the system refuses: a fixed table, so that
/// registering allocates nothing under the lock.
type Watched = [Option<Arc<AtomicBool>>; 32];
static WATCHED: Mutex<Watched> = Mutex::new([const { None }; 32]);

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
    keep_ballast(1 << 20);
}

fn ballast_layout(size: usize) -> Layout {
    Layout::from_size_align(size, 4096).expect("a valid layout")
}

/// Set `size` bytes of address space aside for the error path, unless some is already; false
/// when the system refuses them.
pub fn keep_ballast(size: usize) -> bool {
    if !BALLAST.load(Ordering::SeqCst).is_null() {
        return true;
    }
    // SAFETY: a valid, non-zero layout; given back once in `give_back_ballast`.
    let p = unsafe { System.alloc(ballast_layout(size)) };
    if p.is_null() {
        return false;
    }
    BALLAST_SIZE.store(size, Ordering::SeqCst);
    if BALLAST
        .compare_exchange(std::ptr::null_mut(), p, Ordering::SeqCst, Ordering::SeqCst)
        .is_err()
    {
        // SAFETY: allocated just above with this layout, and not published.
        unsafe { System.dealloc(p, ballast_layout(size)) };
    }
    true
}

fn give_back_ballast() {
    let ballast = BALLAST.swap(std::ptr::null_mut(), Ordering::SeqCst);
    if !ballast.is_null() {
        let size = BALLAST_SIZE.load(Ordering::SeqCst);
        // SAFETY: allocated in `keep_ballast` with this layout.
        unsafe { System.dealloc(ballast, ballast_layout(size)) };
    }
}

/// How many allocations the system has refused ([`CancelOnOom`]): a caller compares the count
/// before and after its work.
pub fn refusals() -> usize {
    REFUSALS.load(Ordering::SeqCst)
}

/// The largest allocation the system refused ([`CancelOnOom`]), for the message.
pub fn largest_refused() -> usize {
    LARGEST_REFUSED.load(Ordering::SeqCst)
}

/// Raise `flag` when the system refuses an allocation, until the returned guard is dropped.
pub fn watch(flag: &Arc<AtomicBool>) -> Watch {
    let mut table = WATCHED.lock().unwrap_or_else(|e| e.into_inner());
    let slot = table.iter().position(Option::is_none);
    if let Some(i) = slot {
        table[i] = Some(flag.clone());
    }
    Watch { slot }
}

/// A cancel flag [`CancelOnOom`] raises; unregistered on drop.
pub struct Watch {
    slot: Option<usize>,
}

impl Drop for Watch {
    fn drop(&mut self) {
        if let Some(i) = self.slot {
            let flag = WATCHED.lock().unwrap_or_else(|e| e.into_inner())[i].take();
            drop(flag);
        }
    }
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
    give_back_ballast();
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

/// The system refused `layout` ([`CancelOnOom`]): count it, raise the watched cancel flags, give
/// back the ballast and `retry`; the reserve serves what is still refused.
fn refused_cancel(layout: Layout, retry: impl Fn() -> *mut u8) -> *mut u8 {
    REFUSALS.fetch_add(1, Ordering::SeqCst);
    LARGEST_REFUSED.fetch_max(layout.size(), Ordering::SeqCst);
    // `try_lock`: the lock is never held across an allocation, but a thread may be registering.
    let table = match WATCHED.try_lock() {
        Ok(t) => Some(t),
        Err(std::sync::TryLockError::Poisoned(p)) => Some(p.into_inner()),
        Err(std::sync::TryLockError::WouldBlock) => None,
    };
    for flag in table.iter().flat_map(|t| t.iter().flatten()) {
        flag.store(true, Ordering::SeqCst);
    }
    drop(table);
    give_back_ballast();
    let p = retry();
    if !p.is_null() {
        return p;
    }
    let p = from_pool(layout);
    if !p.is_null() {
        return p;
    }
    // Last resort before Rust's abort: other threads, cancelled, free what they hold as they
    // wind down; ask again for up to two seconds.
    for _ in 0..200 {
        std::thread::sleep(std::time::Duration::from_millis(10));
        let p = retry();
        if !p.is_null() {
            return p;
        }
    }
    std::ptr::null_mut()
}

/// The system allocator, raising the watched cancel flags when it refuses (see the module).
pub struct CancelOnOom;

/// `GlobalAlloc` over the system allocator for `$name`, calling `$refused(layout, retry)` when
/// the system refuses (`retry` asks it again).
macro_rules! guarded_allocator {
    ($name:ident, $refused:expr) => {
        // SAFETY: every pointer is the system's or a disjoint piece of the reserve, which is
        // never freed (a dealloc of one is ignored) and never reallocated in place.
        unsafe impl GlobalAlloc for $name {
            unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
                let p = unsafe { System.alloc(layout) };
                if p.is_null() {
                    return $refused(layout, || unsafe { System.alloc(layout) });
                }
                p
            }

            unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
                let p = unsafe { System.alloc_zeroed(layout) };
                if p.is_null() {
                    // The reserve is zeroed and never reused.
                    return $refused(layout, || unsafe { System.alloc_zeroed(layout) });
                }
                p
            }

            unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
                if !in_pool(ptr) {
                    unsafe { System.dealloc(ptr, layout) }
                }
            }

            unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
                let new_layout =
                    unsafe { Layout::from_size_align_unchecked(new_size, layout.align()) };
                if in_pool(ptr) {
                    let p = unsafe { self.alloc(new_layout) };
                    if !p.is_null() {
                        let n = layout.size().min(new_size);
                        unsafe { std::ptr::copy_nonoverlapping(ptr, p, n) };
                    }
                    return p;
                }
                let p = unsafe { System.realloc(ptr, layout, new_size) };
                if p.is_null() {
                    let q = $refused(new_layout, || unsafe { System.alloc(new_layout) });
                    if !q.is_null() {
                        let n = layout.size().min(new_size);
                        unsafe { std::ptr::copy_nonoverlapping(ptr, q, n) };
                        // The caller owns the old block only when realloc fails.
                        unsafe { System.dealloc(ptr, layout) };
                    }
                    return q;
                }
                p
            }
        }
    };
}

guarded_allocator!(ExitOnOom, |layout, _retry| refused(layout));
guarded_allocator!(CancelOnOom, refused_cancel);
