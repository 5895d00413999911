//! The summary of a simulated run, for people ([`summary_text`]) and as the
//! `lagrange.simulate/1` JSON value ([`summary_json`], with [`section_json`]
//! for a run with a Poincaré section).
//!
//! The run is `mech::simulate`'s [`RunReport`]; what only the front end knows
//! comes as plain data: the signal that stopped the run ([`Interrupted`]), the
//! time spent before the integration ([`Timing`]), and how the user gives a
//! fixed step ([`Terms::step`]).

use crate::Terms;
use mech::{Derivation, RunReport, RunWarning};
use serde_json::{json, Value};

/// A run that a signal stopped: the signal's name (`SIGINT`), and the time of
/// the last row handed over (None when it came before the first).
#[derive(Clone, Debug, PartialEq)]
pub struct Interrupted {
    /// The signal's name, as the summary gives it.
    pub signal: String,
    /// The time of the last row handed over, None when none was.
    pub t: Option<f64>,
}

/// Where the time before the integration went, for the JSON summary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Reading, parsing and deriving the model.
    pub derive_seconds: f64,
    /// From reading the model to the first row (None when no row came).
    pub setup_seconds: Option<f64>,
}

/// The run's summary as a `lagrange.simulate/1` JSON value: the method and its
/// settings, the work done, where and why the run ended, the final state, the
/// audit of every invariant (and constraint), and `timing`. A front end may
/// add fields of its own before printing it.
pub fn summary_json(
    r: &RunReport,
    names: &[String],
    timing: &Timing,
    interrupted: Option<&Interrupted>,
    terms: &Terms,
) -> Value {
    let mut fin = serde_json::Map::new();
    for (i, name) in names.iter().enumerate() {
        fin.insert(name.clone(), json!(r.final_q[i]));
        fin.insert(format!("{name}'"), json!(r.final_qd[i]));
    }
    let mut inv = serde_json::Map::new();
    for a in &r.invariants {
        let mut entry = json!({
            "initial": a.initial,
            "final": a.final_value,
            "max_abs_drift": a.max_abs_drift,
            "max_rel_drift": a.max_rel_drift,
            "conserved": a.conserved,
        });
        if !r.impacts.is_empty() {
            entry["impact_change"] = json!(a.impact_change);
        }
        inv.insert(a.name.clone(), entry);
    }
    let v = json!({
        "format": "lagrange.simulate/1",
        "method": r.method.name(),
        "form": r.form.name(),
        "right_hand_side": r.right_hand_side,
        "dt": r.dt,
        "rtol": r.rtol,
        "atol": r.atol,
        "steps": r.steps,
        "rejected_steps": r.rejected,
        "rhs_evaluations": r.rhs_evaluations,
        "look_ahead_evaluations": r.look_ahead_evaluations,
        "t_final": r.t_final,
        "stopped_by": r.stopped_by,
        "failure": r.failure,
        "failure_reason": r.failure_reason,
        "pilot_rhs_evaluations": r.pilot_rhs_evaluations,
        "tolerance_controls": tolerance_controls(r, terms),
        "final": fin,
        "invariants": inv,
        "warnings": r.warnings.iter().map(|w| warning(w, terms)).collect::<Vec<_>>(),
        "wall_seconds": r.wall_seconds,
        "derive_seconds": timing.derive_seconds,
        "setup_seconds": timing.setup_seconds,
        "interrupted": interrupted.map(|i| json!({"signal": i.signal, "t": i.t})),
    });
    let mut v = v;
    if !r.constraints.is_empty() {
        let mut cs = serde_json::Map::new();
        for c in &r.constraints {
            cs.insert(
                c.name.clone(),
                json!({
                    "kind": c.kind.name(),
                    "max_abs_residual": c.max_abs_residual,
                    "max_abs_velocity_residual": c.max_abs_velocity_residual,
                    "final_lambda": c.final_lambda,
                    "max_force": c.max_force,
                }),
            );
        }
        v["constraints"] = Value::Object(cs);
        v["stabilization"] = json!("projection after every step (positions by Gauss-Newton, then velocities)");
    }
    if !r.impacts.is_empty() {
        v["impacts"] = impacts_json(&r.impacts);
        v["energy_lost_at_impacts"] = json!(r.impacts.iter().map(|i| i.energy_lost).sum::<f64>());
    }
    v
}

/// Each impact surface's count, the kinetic energy its impacts took and its
/// fastest impact's normal speed.
pub fn impacts_json(impacts: &[mech::ImpactTally]) -> Value {
    Value::Array(
        impacts
            .iter()
            .map(|i| json!({"name": i.name, "count": i.count, "energy_lost": i.energy_lost, "fastest_normal_speed": i.fastest}))
            .collect(),
    )
}

/// The `section` field of the JSON summary of a run with a Poincaré section:
/// its condition as written, the plane's two axes, and the number of points.
pub fn section_json(section: &mech::Section, points: usize) -> Value {
    json!({"condition": section.condition().text, "axes": section.axes(), "points": points})
}

/// A run's warning in words, with the settings a user can change spelled as
/// the front end spells them (`terms`).
pub fn warning(w: &RunWarning, terms: &Terms) -> String {
    match w {
        RunWarning::Drift { invariant, drift, explained } => format!(
            "{invariant} is conserved, but drifted by {drift:.3e} (relative), more than the tolerance explains ({explained:.1e})"
        ),
        RunWarning::PilotOutgrown { drift, bound } => format!(
            "H drifted by {drift:.3e} (relative), more than the {bound:.1e} the pilot runs chose the step for: the motion after them needed a shorter step (give a smaller {}, or a longer pilot with a shorter {})",
            terms.step, terms.until
        ),
        RunWarning::ConstraintViolated { constraint, residual } => {
            format!("the constraint {constraint} is violated by up to {residual:.3e} despite the projection")
        }
        RunWarning::TaylorAcrossKink => "the equations contain abs(), whose kink a Taylor series does not see: a step across it is not error-controlled (dop853 is the default for such models)".into(),
        RunWarning::Subdivided(s) => format!(
            "the stage equations of {} step{} of the fixed step did not converge, and {} taken as shorter sub-steps (down to {:.3e}), the first at t = {}: the motion there is faster than the step was chosen for, and H no longer keeps the bound the step promised; an adaptive method (the default, without {}) follows such motion",
            s.steps,
            if s.steps == 1 { "" } else { "s" },
            if s.steps == 1 { "was" } else { "were" },
            s.shortest,
            s.first_t,
            terms.method
        ),
    }
}

/// What the run's tolerance controlled: the method's sentence, or nothing
/// when the user gave the fixed step (spelled as `terms.step`).
pub fn tolerance_controls(r: &RunReport, terms: &Terms) -> String {
    if r.step_given {
        format!("nothing: the step was given ({})", terms.step)
    } else {
        r.method.tolerance_controls().to_string()
    }
}

/// The run's summary as a table for people: the model, the method and its
/// settings, the work done, where the run ended (or why it stopped), the final
/// state, and the audit of the invariants and constraints.
pub fn summary_text(
    r: &RunReport,
    names: &[String],
    d: &Derivation,
    interrupted: Option<&Interrupted>,
    terms: &Terms,
) -> String {
    let mut s = String::new();
    s.push_str(&format!("{}\n", d.model().name));
    let step = match r.dt {
        Some(h) => format!("fixed step {h:.3e}"),
        None => format!("rtol {:.0e}, atol {:.0e}", r.rtol, r.atol),
    };
    s.push_str(&format!(
        "method {} ({}, {}), state [q, {}]\n",
        r.method.name(),
        r.method.description(),
        step,
        if r.form.name() == "lagrange" { "q'" } else { "p" }
    ));
    s.push_str(&format!("tolerance controls {}\n", tolerance_controls(r, terms)));
    // The Taylor method's work unit is one expansion of the series per step.
    let evaluations = if r.method == num::Method::Taylor {
        format!("Taylor expansions of order {}", num::taylor_order(r.rtol))
    } else {
        "right-hand-side evaluations".to_string()
    };
    s.push_str(&format!(
        "{} steps ({} rejected), {} {evaluations}{}, {:.3} s\n",
        r.steps,
        r.rejected,
        r.rhs_evaluations,
        if r.pilot_rhs_evaluations > 0 {
            format!(" (+{} choosing the step)", r.pilot_rhs_evaluations)
        } else if r.look_ahead_evaluations > 0 {
            format!(" (+{} right-hand sides looking ahead)", r.look_ahead_evaluations)
        } else {
            String::new()
        },
        r.wall_seconds
    ));
    match (&r.failure, &r.stopped_by) {
        _ if interrupted.is_some() => {
            let Interrupted { signal, t } = interrupted.expect("matched");
            match t {
                Some(t) => s.push_str(&format!("interrupted at t = {} ({signal})\n", num::Shortest(*t))),
                None => s.push_str(&format!("interrupted before the first row ({signal})\n")),
            }
        }
        (Some(_), _) => s.push_str(&format!("FAILED after t = {} (see the error below)\n", num::Shortest(r.t_final))),
        (None, Some(why)) => s.push_str(&format!("stopped at t = {} ({why})\n", num::Shortest(r.t_final))),
        (None, None) => s.push_str(&format!("reached t = {}\n", num::Shortest(r.t_final))),
    }
    s.push_str("final state:");
    for (i, name) in names.iter().enumerate() {
        s.push_str(&format!("  {name} = {:.10}  {name}' = {:.10}", r.final_q[i], r.final_qd[i]));
    }
    s.push('\n');
    if !r.invariants.is_empty() {
        s.push_str("invariants          initial              final                max abs drift  max rel drift\n");
        for a in &r.invariants {
            s.push_str(&format!(
                "  {:<8}{} {:>20.12e} {:>20.12e} {:>14.3e} {:>14.3e}\n",
                a.name,
                if a.conserved { "*" } else { " " },
                a.initial,
                a.final_value,
                a.max_abs_drift,
                a.max_rel_drift
            ));
        }
        s.push_str("  (* conserved according to the derivation)\n");
        if !r.impacts.is_empty() {
            s.push_str("  (the drifts leave out the jumps at impacts)\n");
        }
    }
    if !r.impacts.is_empty() {
        s.push_str("impacts             count    energy lost    fastest |v_n|\n");
        for i in &r.impacts {
            s.push_str(&format!("  {:<16} {:>7} {:>14.6e} {:>16.6e}\n", i.name, i.count, i.energy_lost, i.fastest));
        }
    }
    if !r.constraints.is_empty() {
        s.push_str("constraints (the state is projected onto them after every step)\n");
        s.push_str("  name        kind        max |residual|  max |residual'|      max |Aᵀλ|        final λ\n");
        for c in &r.constraints {
            let vel = if c.kind == mech::ConstraintKind::Holonomic {
                format!("{:>15.3e}", c.max_abs_velocity_residual)
            } else {
                format!("{:>15}", "-")
            };
            s.push_str(&format!(
                "  {:<10}  {:<10} {:>15.3e}  {} {:>14.6e} {:>14.6e}\n",
                c.name,
                c.kind.name(),
                c.max_abs_residual,
                vel,
                c.max_force,
                c.final_lambda
            ));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ops::ControlFlow;

    /// A pendulum released at rest: the energy is its one invariant.
    const PENDULUM: &str = r#"
name = "pendulum"
coordinates = ["th"]
gravity = "g"
[parameters]
g = 9.81
[[particles]]
mass = "1"
position = ["sin(th)", "-cos(th)"]
[initial]
th = 0.5
"th'" = 0.0
"#;

    /// How a front end other than the CLI spells its settings.
    const PYTHON: Terms = Terms {
        step: "dt",
        start_at: "at",
        full_output: "the report's fields",
        animation: "animate()",
        until: "until",
        method: "method",
    };

    /// The pendulum run to t = 1 with `config`'s method and step.
    fn run(config: mech::RunConfig) -> (mech::Derivation, RunReport, Vec<String>) {
        let d = mech::Derivation::new(mech::Model::parse(PENDULUM, &[]).unwrap()).unwrap();
        let config = mech::RunConfig { until: 1.0, output: num::Output::Samples(11), ..config };
        let report = mech::simulate(&d, &config, |_| ControlFlow::Continue(())).unwrap();
        let names = d.coordinate_names().iter().map(|s| s.to_string()).collect();
        (d, report, names)
    }

    #[test]
    fn json_has_the_contract_fields() {
        let (_, r, names) = run(mech::RunConfig::default());
        let timing = Timing { derive_seconds: 0.25, setup_seconds: Some(0.5) };
        let v = summary_json(&r, &names, &timing, None, &PYTHON);
        assert_eq!(v["format"], "lagrange.simulate/1");
        assert_eq!(v["method"], r.method.name());
        assert_eq!(v["steps"], r.steps);
        assert_eq!(v["rhs_evaluations"], r.rhs_evaluations);
        assert_eq!(v["t_final"], 1.0);
        assert_eq!(v["final"]["th"], r.final_q[0]);
        assert_eq!(v["final"]["th'"], r.final_qd[0]);
        let energy = &v["invariants"][&r.invariants[0].name];
        for field in ["initial", "final", "max_abs_drift", "max_rel_drift"] {
            assert!(energy[field].is_f64(), "invariant field {field}: {energy}");
        }
        assert!(v["wall_seconds"].is_f64());
        assert_eq!((v["derive_seconds"].as_f64(), v["setup_seconds"].as_f64()), (Some(0.25), Some(0.5)));
        assert!(v["interrupted"].is_null() && v.get("constraints").is_none());
        assert_eq!(v["tolerance_controls"], r.method.tolerance_controls());

        let stopped = Interrupted { signal: "SIGINT".into(), t: Some(0.5) };
        let v = summary_json(&r, &names, &timing, Some(&stopped), &PYTHON);
        assert_eq!(v["interrupted"], json!({"signal": "SIGINT", "t": 0.5}));
    }

    #[test]
    fn a_given_step_is_named_as_the_front_end_names_it() {
        let config = mech::RunConfig { method: Some(num::Method::Verlet), dt: Some(0.01), ..Default::default() };
        let (_, r, names) = run(config);
        assert!(r.step_given);
        assert_eq!(tolerance_controls(&r, &PYTHON), "nothing: the step was given (dt)");
        let timing = Timing { derive_seconds: 0.0, setup_seconds: None };
        let v = summary_json(&r, &names, &timing, None, &PYTHON);
        assert_eq!(v["tolerance_controls"], "nothing: the step was given (dt)");
        assert_eq!(v["dt"], 0.01);
    }

    #[test]
    fn text_is_a_table_for_people() {
        let (d, r, names) = run(mech::RunConfig::default());
        let text = summary_text(&r, &names, &d, None, &PYTHON);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "pendulum");
        assert!(lines[1].starts_with(&format!("method {} (", r.method.name())), "{text}");
        assert_eq!(lines[2], format!("tolerance controls {}", r.method.tolerance_controls()));
        assert!(text.contains("reached t = 1\n"), "{text}");
        assert!(text.contains(&format!("final state:  th = {:.10}  th' = ", r.final_q[0])), "{text}");
        assert!(text.contains("(* conserved according to the derivation)"), "{text}");

        let before = Interrupted { signal: "SIGTERM".into(), t: None };
        let text = summary_text(&r, &names, &d, Some(&before), &PYTHON);
        assert!(text.contains("interrupted before the first row (SIGTERM)\n"), "{text}");
        assert!(!text.contains("reached t ="), "{text}");
    }

    #[test]
    fn warnings_name_the_settings_as_the_front_end_names_them() {
        let outgrown = RunWarning::PilotOutgrown { drift: 2e-6, bound: 1e-6 };
        let text = warning(&outgrown, &PYTHON);
        assert!(text.contains("give a smaller dt, or a longer pilot with a shorter until)"), "{text}");
        assert!(!text.contains("--"), "{text}");
        let sub = num::Subdivisions { steps: 2, first_t: 0.5, shortest: 1e-3 };
        let text = warning(&RunWarning::Subdivided(sub), &PYTHON);
        assert!(text.starts_with("the stage equations of 2 steps of the fixed step did not converge, and were taken"));
        assert!(text.ends_with("(the default, without method) follows such motion"), "{text}");
        let drift = RunWarning::Drift { invariant: "H".into(), drift: 3e-5, explained: 1e-6 };
        assert_eq!(
            warning(&drift, &PYTHON),
            "H is conserved, but drifted by 3.000e-5 (relative), more than the tolerance explains (1.0e-6)"
        );
    }
}
