//! shadowvol CLI library.
