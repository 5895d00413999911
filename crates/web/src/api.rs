//! The entry points the page calls, one per CLI command, each returning JSON
//! text (see the crate documentation). Each mirrors its CLI command's JSON
//! output: the same `mech` computation and the same `mech`/`view` value, with
//! the same defaults, so the browser and the terminal agree.

use crate::located::{error, model_error};
use crate::options::Options;
use mech::{Derivation, Model, RunConfig, RunError, RunSettings, SettingError};
use serde_json::{json, Value};
use std::ops::ControlFlow;
use wasm_bindgen::prelude::wasm_bindgen;
use web_time::Instant;

/// How the texts name the settings: the page's option names.
const TERMS: view::Terms = view::Terms {
    step: "dt",
    start_at: "at",
    full_output: "the JSON",
    animation: "the animation",
    until: "until",
    method: "method",
};

/// A failure of a call, as its `lagrange.error/1` value.
type Failure = Value;

/// The text of a result or of its failure.
fn answer(result: Result<Value, Failure>) -> String {
    match result {
        Ok(v) | Err(v) => v.to_string(),
    }
}

fn plain(message: impl std::fmt::Display) -> Failure {
    error(&message.to_string(), None, None)
}

fn options(text: &str) -> Result<Options, Failure> {
    Options::parse(text).map_err(plain)
}

/// Parses a model with the options' overrides and files.
fn parse(source: &str, o: &Options) -> Result<Model, Failure> {
    let files = |name: &str| -> Result<String, String> {
        o.file(name).cloned().ok_or_else(|| format!("{name}: no such file here (the page has only its examples)"))
    };
    Model::parse_with(source, &o.overrides(), &files).map_err(|e| model_error(source, &e))
}

/// The derivation `derive` shows: the model's inputs u(t) stay symbols.
fn derive_model(source: &str, o: &Options) -> Result<Derivation, Failure> {
    let model = parse(source, o)?;
    Derivation::new(model).map_err(|e| model_error(source, &e))
}

/// The derivation a run or an analysis needs, as the CLI's `derive_file` makes
/// it: every input replaced by its value, an expression of t.
fn derive_for_run(source: &str, o: &Options) -> Result<Derivation, Failure> {
    let model = parse(source, o)?.with_inputs_applied();
    Derivation::new(model).map_err(|e| model_error(source, &e))
}

fn to_json(value: &impl serde::Serialize) -> Result<Value, Failure> {
    serde_json::to_value(value).map_err(|e| plain(format!("cannot write JSON: {e}")))
}

/// The model as the editor needs it beside the text: its name, coordinates
/// and parameters (for the sliders), or where it is wrong. Parses only.
#[wasm_bindgen]
pub fn model(source: &str, options_json: &str) -> String {
    answer((|| {
        let o = options(options_json)?;
        let m = parse(source, &o)?;
        let parameters: Vec<Value> = m.parameters.iter().map(|p| json!({"name": p.name, "value": p.value})).collect();
        let coordinates: Vec<&str> = m.coordinates.iter().map(|c| c.name.as_str()).collect();
        Ok(json!({"format": "lagrange.model/1", "name": m.name, "coordinates": coordinates, "parameters": parameters}))
    })())
}

/// `lagrange derive --format json`: the `lagrange.derive/1` value, with the
/// derivation typeset as MathML (`mathml`, as the report shows it) beside it.
#[wasm_bindgen]
pub fn derive(source: &str, options_json: &str) -> String {
    answer((|| {
        let o = options(options_json)?;
        let start = Instant::now();
        let d = derive_model(source, &o)?;
        let derive_seconds = start.elapsed().as_secs_f64();
        let mut v = to_json(&mech::DeriveReport::new(&d))?;
        v["derive_seconds"] = json!(derive_seconds);
        v["mathml"] = json!(view::derive::mathml(&d));
        Ok(v)
    })())
}

/// The run configuration of the options, with the CLI's defaults and checks.
fn run_config(o: &Options) -> Result<RunConfig, Failure> {
    let settings = RunSettings {
        until: o.until,
        method: o.method.as_deref(),
        rtol: o.rtol,
        atol: o.atol,
        samples: o.samples,
        ..RunSettings::default()
    };
    RunConfig::from_settings(&settings).map_err(|e| match e {
        SettingError::UnknownMethod(message) => plain(message),
        SettingError::NotPositive { setting, value } => {
            plain(format!("{setting} must be a positive number, not {value}"))
        }
        SettingError::TooFewSamples { .. } => plain("samples: a run needs at least 2 rows (both ends)"),
    })
}

/// Derives and runs the model, handing each row to `on_row`; the summary
/// (`lagrange.simulate/1`) and the derivation.
fn run(
    source: &str,
    o: &Options,
    mut on_row: impl FnMut(&mech::Row<'_>),
) -> Result<(Derivation, RunConfig, Value), Failure> {
    let started = Instant::now();
    let d = derive_for_run(source, o)?;
    let derived = started.elapsed().as_secs_f64();
    let config = run_config(o)?;
    let mut first_row = None;
    let result = mech::simulate(&d, &config, |row| {
        first_row.get_or_insert_with(|| started.elapsed().as_secs_f64());
        on_row(row);
        ControlFlow::Continue(())
    });
    let report = match result {
        Ok(r) => r,
        // The summary says where and why it failed, as the CLI's does.
        Err(RunError::Failed { report, .. }) => *report,
        Err(RunError::Input(e)) => return Err(model_error(source, &e)),
        Err(e) => return Err(plain(e)),
    };
    let names: Vec<String> = d.coordinate_names().iter().map(|s| s.to_string()).collect();
    let timing = view::simulate::Timing { derive_seconds: derived, setup_seconds: first_row };
    let summary = view::simulate::summary_json(&report, &names, &timing, None, &TERMS);
    Ok((d, config, summary))
}

/// `lagrange simulate --summary json`: the `lagrange.simulate/1` summary of
/// the run (the final state in `final`).
#[wasm_bindgen]
pub fn simulate(source: &str, options_json: &str) -> String {
    answer((|| {
        let o = options(options_json)?;
        run(source, &o, |_| ()).map(|(_, _, summary)| summary)
    })())
}

/// `lagrange report`: the `lagrange.report/1` data of a run, with the page
/// that shows it (`page`: the same HTML file the CLI writes, made by
/// `view::report::page`, for an `iframe`).
#[wasm_bindgen]
pub fn report(source: &str, options_json: &str) -> String {
    answer((|| {
        let o = options(options_json)?;
        let mut rows = view::report::Recorder::new();
        let (d, config, summary) = run(source, &o, |row| rows.push(row))?;
        let mut data = rows.data(&d, config.until, summary);
        data["page"] = json!(view::report::page(&data));
        Ok(data)
    })())
}

/// `lagrange modes --format json --allow-unstable`: the `lagrange.modes/1`
/// value (an unstable equilibrium is reported, with its `stable` false).
#[wasm_bindgen]
pub fn modes(source: &str, options_json: &str) -> String {
    answer((|| {
        let o = options(options_json)?;
        let d = derive_for_run(source, &o)?;
        d.reject_constraints("modes").map_err(|e| model_error(source, &e))?;
        // As `--allow-unstable`: the equilibrium Newton reaches from the start is kept.
        let config = mech::ModesConfig { keep_unstable: true, ..mech::ModesConfig::default() };
        let m = mech::normal_modes(&d, &config).map_err(|e| match e {
            mech::ModesError::Model(m) => model_error(source, &m),
            other => plain(other),
        })?;
        to_json(&mech::ModesReport::new(&d, &m))
    })())
}

/// `lagrange orbit --format json`: the `lagrange.orbit/1` value.
#[wasm_bindgen]
pub fn orbit(source: &str, options_json: &str) -> String {
    answer((|| {
        let o = options(options_json)?;
        let d = derive_for_run(source, &o)?;
        d.reject_constraints("orbit").map_err(|e| model_error(source, &e))?;
        let orbit = mech::Orbit::new(&d).map_err(|e| match e {
            mech::OrbitError::Model(m) => model_error(source, &m),
            other => error(&other.to_string(), other.help().as_deref(), None),
        })?;
        to_json(&orbit.report(&d))
    })())
}

/// `lagrange top --format json`: the `lagrange.top/1` value.
#[wasm_bindgen]
pub fn top(source: &str, options_json: &str) -> String {
    answer((|| {
        let o = options(options_json)?;
        let d = derive_for_run(source, &o)?;
        let top = mech::Top::new(&d).map_err(|e| match e {
            mech::TopError::Model(m) => model_error(source, &m),
        })?;
        to_json(&top.report())
    })())
}

/// `lagrange extremal --format json`: the `lagrange.extremal/1` value of a
/// problem file (`examples/extremal/`).
#[wasm_bindgen]
pub fn extremal(source: &str, options_json: &str) -> String {
    answer((|| {
        let o = options(options_json)?;
        let problem = mech::Problem::parse(source, &o.overrides()).map_err(|e| model_error(source, &e))?;
        let config = mech::ExtremalConfig { check_minimum: o.check_minimum, points: o.points.unwrap_or(201) };
        let report = mech::extremal(&problem, &config).map_err(|e| match e {
            mech::ExtremalError::Model(m) => model_error(source, &m),
            mech::ExtremalError::NoExtremal { message, help } => error(&message, help.as_deref(), None),
        })?;
        to_json(&report)
    })())
}
