//! Test models with known answers, shared by the integration tests: the file the
//! unit tests use too (`src/test_models.rs`), so that there is one copy.

#[path = "../../src/test_models.rs"]
mod test_models;

pub use test_models::*;
