//! The native tests of the playground's bindings, one test binary: each file of
//! this folder is a module of it (one link, not one per file).

mod api;
mod bindgen_pin;
