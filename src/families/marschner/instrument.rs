//! Per-thread counters of the expensive steps (root solves, caustics, eccentric index), so tests can
//! check that disabled lobes and effects are not computed at all (MODEL.md invariant 6).

use std::cell::Cell;

/// How often each expensive step ran on this thread since the last [`reset`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// TT root solves (one per evaluation of N_TT).
    pub tt_root_solves: u64,
    /// TRT root solves (one per evaluation of N_2).
    pub trt_root_solves: u64,
    /// Caustic / glint computations.
    pub caustics: u64,
    /// Evaluations of the eccentric index η*(φ_h).
    pub eccentricity: u64,
}

thread_local! {
    static COUNTS: Cell<Counts> = const { Cell::new(Counts {
        tt_root_solves: 0,
        trt_root_solves: 0,
        caustics: 0,
        eccentricity: 0,
    }) };
}

/// The counters of this thread.
pub fn counts() -> Counts {
    COUNTS.with(Cell::get)
}

/// Zero the counters of this thread.
pub fn reset() {
    COUNTS.with(|c| c.set(Counts::default()));
}

#[inline]
fn bump(f: impl FnOnce(&mut Counts)) {
    COUNTS.with(|c| {
        let mut v = c.get();
        f(&mut v);
        c.set(v);
    });
}

#[inline]
pub(crate) fn count_root_solve(p: usize) {
    bump(|c| {
        if p == 1 {
            c.tt_root_solves += 1
        } else {
            c.trt_root_solves += 1
        }
    });
}

#[inline]
pub(crate) fn count_caustic() {
    bump(|c| c.caustics += 1);
}

#[inline]
pub(crate) fn count_eccentricity() {
    bump(|c| c.eccentricity += 1);
}
