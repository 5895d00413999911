//! The entry points as the page calls them, run natively in the build the
//! browser gets (sym without `jit`, mech without `parallel`: run alone,
//! `cargo test -p lagrange-web` builds them so), so that this path is tested
//! on every build. The browser test (tests/browser/playground.test.mjs)
//! compares the same functions in WebAssembly with the CLI.

use serde_json::Value;

const PENDULUM: &str = include_str!("../../../examples/pendulum.toml");

fn call(f: fn(&str, &str) -> String, source: &str, options: &str) -> Value {
    serde_json::from_str(&f(source, options)).expect("every answer is JSON")
}

#[test]
fn the_pendulum_derives_and_runs_with_its_contracts() {
    let d = call(lagrange_web::derive, PENDULUM, "");
    assert_eq!(d["format"], "lagrange.derive/1");
    assert!(d["mathml"].as_str().unwrap().contains("<math"), "{d}");
    let s = call(lagrange_web::simulate, PENDULUM, r#"{"until": 2, "rtol": 1e-10}"#);
    assert_eq!(s["format"], "lagrange.simulate/1");
    assert_eq!(s["t_final"], 2.0);
    // The energy of the swing from ph = 1 at rest: conserved to the tolerance.
    let invariants = s["invariants"].as_object().unwrap();
    assert!(!invariants.is_empty(), "{s}");
    for (name, e) in invariants {
        assert!(e["max_rel_drift"].as_f64().unwrap() < 1e-8, "{name}: {s}");
    }
    let m = call(lagrange_web::model, PENDULUM, r#"{"set": {"g": 1.62}}"#);
    assert_eq!(m["parameters"][2], serde_json::json!({"name": "g", "value": 1.62}));
    let r = call(lagrange_web::report, PENDULUM, r#"{"until": 1, "samples": 11}"#);
    assert_eq!(r["format"], "lagrange.report/1");
    assert!(r["page"].as_str().unwrap().starts_with("<!DOCTYPE html>"));
}

#[test]
fn an_error_is_located_at_its_line_and_column() {
    let bad = PENDULUM.replace("\"-l*cos(ph)\"", "\"-l*cos(ph) +\"");
    let e = call(lagrange_web::derive, &bad, "");
    assert_eq!(e["format"], "lagrange.error/1", "{e}");
    let line = bad.lines().position(|l| l.contains("cos(ph) +")).unwrap() + 1;
    assert_eq!(e["line"], line);
    // Within the string that holds the expression, at or after its start.
    let quote = bad.lines().nth(line - 1).unwrap().find("\"-l").unwrap() + 1;
    assert!(e["column"].as_u64().unwrap() as usize >= quote, "{e}");
    let e = call(lagrange_web::simulate, PENDULUM, r#"{"rtol": -1}"#);
    assert_eq!(e["format"], "lagrange.error/1");
    let e = call(lagrange_web::derive, PENDULUM, "{");
    assert_eq!(e["format"], "lagrange.error/1");
}

#[test]
fn inputs_are_symbols_in_derive_and_their_values_in_a_run() {
    // As the CLI: `derive` keeps F and tau as symbols (M q'' = f0 + B u), a run
    // and the analyses put in their values of t.
    let cart = include_str!("../../../examples/cart_pendulum.toml");
    let d = call(lagrange_web::derive, cart, "");
    assert_eq!(d["format"], "lagrange.derive/1", "{d}");
    let inputs: Vec<&str> = d["inputs"].as_array().unwrap().iter().map(|u| u["name"].as_str().unwrap()).collect();
    assert_eq!(inputs, ["F", "tau"]);
    let s = call(lagrange_web::simulate, cart, r#"{"until": 1}"#);
    assert_eq!(s["format"], "lagrange.simulate/1", "{s}");
    assert_eq!(s["t_final"], 1.0);
    let r = call(lagrange_web::report, cart, r#"{"until": 1, "samples": 11}"#);
    assert_eq!(r["format"], "lagrange.report/1", "{r}");
}
