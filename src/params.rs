//! The parameter file with MODEL.md's names (filled in by the model work).
