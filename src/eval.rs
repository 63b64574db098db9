//! `hairfit eval`: stream an angles file through the model (filled in by the eval work).
