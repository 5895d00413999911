//! The integration tests of the `lagrange` program, one test binary: each file
//! of this folder is a module of it. One binary links the dependency graph once
//! instead of once per file, which was most of what a test build cost.

mod bicycle;
mod bodies_top;
mod body_chains;
mod budgets;
mod common;
mod constraints;
mod default_method;
mod echoed_numbers;
mod export;
mod extremal;
mod gauss_substeps;
mod guide;
mod hostile;
mod hostile_zeros;
mod impacts;
mod inertia;
mod interrupt;
mod linearize;
mod mechanisms;
mod modes_orbit;
mod module_cycles;
mod noether;
mod notes_ch2;
mod outputs;
mod report;
mod roundoff;
mod section;
mod simulate_analytic;
mod simulate_plot;
mod snapshots;
mod start_causes;
mod sweep;
mod sweep_code;
mod taylor;
mod tidy;
mod urdf;
