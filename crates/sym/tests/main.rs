//! The integration tests of `sym`, one test binary: each file of this folder is a
//! module of it (one link, not one per file).

mod common;
mod jit;
mod properties;
