//! Levenberg–Marquardt as an argmin `Solver` (filled in by the solver work).
