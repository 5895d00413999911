//! The integration tests of `num`, one test binary: each file of this folder is a
//! module of it (one link, not one per file).

mod behaviour;
mod common;
mod order;
