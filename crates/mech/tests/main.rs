//! The integration tests of `mech`'s public API, one test binary: each file of
//! this folder is a module of it (one link of the dependency graph, not one per file).

mod body_inertia;
mod body_tree;
mod budget;
mod common;
mod derive;
mod error_kinds;
mod gravity;
mod layers;
mod run;
