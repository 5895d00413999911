//! The library's life cycle in one program: read a model file, derive its
//! equations of motion, simulate it and read the trajectory.
//!
//! ```sh
//! cargo run -p lagrange-mech --example pendulum -- examples/double_pendulum.toml 5
//! ```
//!
//! prints the Euler–Lagrange equations, then `t` and the coordinates every
//! tenth of the run, then the audit of the conserved quantities.

use std::error::Error;
use std::fmt::Write;
use std::ops::ControlFlow;

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "examples/pendulum.toml".into());
    let until: f64 = args.next().as_deref().unwrap_or("10").parse()?;
    let text = std::fs::read_to_string(&path)?;
    print!("{}", report(&text, until)?);
    Ok(())
}

/// The equations, the trajectory at 11 times and the audit, as text.
pub fn report(model_text: &str, until: f64) -> Result<String, Box<dyn Error>> {
    let model = mech::Model::parse(model_text, &[])?;
    let d = mech::Derivation::new(model)?;
    let mut out = String::new();
    let names = d.coordinate_names();
    for (name, &eq) in names.iter().zip(d.equations()) {
        writeln!(out, "{name}:  {} = 0", d.pool().display(eq))?;
    }

    let config = mech::RunConfig { until, output: mech::Output::Samples(11), ..mech::RunConfig::default() };
    writeln!(out, "\nt  {}", names.join("  "))?;
    let report = mech::simulate(&d, &config, |row| {
        let q: Vec<String> = row.q.iter().map(|v| format!("{v:.6}")).collect();
        let _ = writeln!(out, "{:.2}  {}", row.t, q.join("  "));
        ControlFlow::Continue(())
    })?;

    writeln!(out, "\n{} steps with {}", report.steps, report.method.name())?;
    for audit in &report.invariants {
        let conserved = if audit.conserved { "conserved" } else { "not conserved" };
        writeln!(out, "{} ({conserved}): drifted by {:.3e}", audit.name, audit.max_rel_drift)?;
    }
    Ok(out)
}
