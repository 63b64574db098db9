//! Loading samples from measured or synthetic files (filled in by the data work).
