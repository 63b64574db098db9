//! The Marschner 2003 forward model (filled in by the model work).
