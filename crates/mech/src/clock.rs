//! The clock that times derivations and runs: std's, or in the browser
//! (`wasm32-unknown-unknown`, where std's `Instant::now` panics) the page's
//! `performance.now()` through `web-time`, with the same interface.

#[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
pub(crate) use std::time::Instant;
#[cfg(all(target_arch = "wasm32", target_os = "unknown"))]
pub(crate) use web_time::Instant;
