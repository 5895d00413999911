//! `lagrange report`: every example model gives a page; the data it holds is
//! the run's (rows as `simulate` writes them, positions as the model places
//! its particles); long runs stay small; bad input is refused. The page's
//! script is tested in a browser by `tests/browser/` (see `.ci/run`).

use crate::common;

use crate::common::{ok, repo_root, run, scratch, Csv};
use serde_json::Value;

/// The `lagrange.report/1` data inlined in a page.
fn data(page: &std::path::Path) -> Value {
    let html = std::fs::read_to_string(page).expect("the page was written");
    let start = html.find(r#"<script type="application/json" id="lagrange-data">"#).expect("the data element");
    let rest = &html[start..];
    let body = &rest[rest.find('>').unwrap() + 1..rest.find("</script>").unwrap()];
    serde_json::from_str(&body.replace("<\\/", "</")).expect("the data is JSON")
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array().expect("an array").iter().map(|x| x.as_f64().expect("a number")).collect()
}

/// Every model file among the examples (not body or problem files).
fn example_models() -> Vec<String> {
    let root = repo_root();
    let mut found = Vec::new();
    for dir in ["examples", "examples/constraints", "examples/tops"] {
        for entry in std::fs::read_dir(root.join(dir)).unwrap() {
            let path = entry.unwrap().path();
            let is_model = path.extension().is_some_and(|e| e == "toml")
                && std::fs::read_to_string(&path).unwrap().lines().any(|l| l.starts_with("coordinates"));
            if is_model {
                found.push(format!("{dir}/{}", path.file_name().unwrap().to_str().unwrap()));
            }
        }
    }
    found.sort();
    found
}

#[test]
fn every_example_gives_a_page_with_its_run() {
    let models = example_models();
    assert!(models.len() >= 25, "{models:?}");
    for model in models {
        let page = scratch("report", &format!("{}.html", model.replace('/', "_")));
        let r = ok(&["report", &model, "--until", "2", "--samples", "101", "-o", page.to_str().unwrap()]);
        assert!(r.stdout.contains("101 of 101 rows shown"), "{}", r.describe());
        let d = data(&page);
        assert_eq!(d["format"], "lagrange.report/1", "{model}");
        assert_eq!(numbers(&d["time"]).len(), 101, "{model}");
        assert!(!d["points"].as_array().unwrap().is_empty(), "{model}: nothing to draw");
        assert_eq!(d["summary"]["format"], "lagrange.simulate/1", "{model}");
        assert!(d["derivation"].as_str().unwrap().contains("<math"), "{model}: no typeset derivation");
    }
}

#[test]
fn the_rows_are_the_runs_and_the_points_are_where_the_model_puts_them() {
    let page = scratch("report", "double.html");
    let csv = scratch("report", "double.csv");
    let (page_s, csv_s) = (page.to_str().unwrap(), csv.to_str().unwrap());
    ok(&["report", "examples/double_pendulum.toml", "--until", "3", "--samples", "301", "-o", page_s]);
    ok(&["simulate", "examples/double_pendulum.toml", "--until", "3", "--samples", "301", "--out", csv_s]);
    let d = data(&page);
    let table = Csv::read(csv_s);
    let (t, a, b) = (table.column("t"), table.column("a"), table.column("b"));
    assert_eq!(numbers(&d["time"]), t);
    assert_eq!(numbers(&d["coordinates"][0]["q"]), a);
    assert_eq!(d["rods"], serde_json::json!([[-1, 0], [0, 1]]));
    // lA = lB = 1: the bobs at (sin a, −cos a) and (sin a + sin b, −cos a − cos b),
    // drawn to a millionth of the mechanism's size (up to 2 here): 10⁻⁶ at most.
    let (x2, y2) = (numbers(&d["points"][1]["x"]), numbers(&d["points"][1]["y"]));
    for k in 0..t.len() {
        assert!((x2[k] - (a[k].sin() + b[k].sin())).abs() <= 5e-7 + 1e-15, "row {k}");
        assert!((y2[k] + a[k].cos() + b[k].cos()).abs() <= 5e-7 + 1e-15, "row {k}");
    }
    let invariants = d["invariants"].as_array().unwrap();
    assert_eq!(invariants[0]["name"], "H");
    assert_eq!(invariants[0]["conserved"], true);
}

#[test]
fn a_long_run_stays_under_two_megabytes_and_keeps_its_turning_points() {
    let page = scratch("report", "long.html");
    let r = ok(&[
        "report",
        "examples/pendulum.toml",
        "--until",
        "1000",
        "--samples",
        "100000",
        "-o",
        page.to_str().unwrap(),
    ]);
    let size = std::fs::metadata(&page).unwrap().len();
    assert!(size < 2_000_000, "{size} bytes: {}", r.stdout);
    let d = data(&page);
    let qd = numbers(&d["coordinates"][0]["qd"]);
    let turns = qd.windows(2).filter(|w| w[0].signum() != w[1].signum()).count();
    // Period 2.0 s at ph = 1 rad with l = 1: a turning point a second, about 1000 in all.
    assert!(turns > 900, "{turns} turning points shown");
    // Fifty masses and their fifty modes, 10⁵ rows.
    let page = scratch("report", "long_chain.html");
    let r =
        ok(&["report", "examples/chain50.toml", "--until", "100", "--samples", "100000", "-o", page.to_str().unwrap()]);
    let size = std::fs::metadata(&page).unwrap().len();
    assert!(size < 2_000_000, "{size} bytes: {}", r.stdout);
}

#[test]
fn a_large_mechanism_s_page_stays_under_two_megabytes_with_its_derivation_in_outline() {
    // 32 rods: typeset whole, the derivation alone would take some 7 MB.
    let page = scratch("report", "rod_chain.html");
    let r = ok(&["report", "examples/large/rod_chain.toml", "--until", "1", "-o", page.to_str().unwrap()]);
    let size = std::fs::metadata(&page).unwrap().len();
    assert!(size < 2_000_000, "{size} bytes: {}", r.stdout);
    let d = data(&page);
    let derivation = d["derivation"].as_str().unwrap();
    assert!(derivation.contains("<code>lagrange derive</code> prints them all"), "{derivation}");
    assert!(!derivation.contains("<math display=\"block\">"), "{derivation}");
    for verdict in ["Cyclic coordinates", "H is the energy:", "H is conserved:"] {
        assert!(derivation.contains(verdict), "{verdict}: {derivation}");
    }
    // Each rod drawn by its pivot's and its point mass's places.
    assert_eq!(d["points"].as_array().unwrap().len(), 64);
}

#[test]
fn a_top_has_its_body_axes_and_its_figure_axis_on_the_sphere() {
    let page = scratch("report", "top.html");
    ok(&["report", "examples/tops/heavy_top.toml", "--until", "2", "-o", page.to_str().unwrap()]);
    let d = data(&page);
    assert_eq!(d["dimension"], 3);
    let axes = &d["bodies"][0]["axes"];
    assert_eq!(axes.as_array().unwrap().len(), 3);
    let top = &d["analyses"]["top"];
    let (lo, hi) = (top["beta_min"].as_f64().unwrap(), top["beta_max"].as_f64().unwrap());
    for z in numbers(&top["axis"]["z"]) {
        let beta = z.clamp(-1.0, 1.0).acos();
        assert!(beta >= lo - 1e-6 && beta <= hi + 1e-6, "β = {beta} outside [{lo}, {hi}]");
    }
}

#[test]
fn bad_input_is_refused_and_a_failed_run_still_writes_its_page() {
    let page = scratch("report", "bad.html");
    let p = page.to_str().unwrap();
    let r = run(&["report", "crates/cli/tests/bad/unknown_name.toml", "-o", p]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("unknown_name.toml:4:28"), "{}", r.describe());
    let r = run(&["report", "examples/pendulum.toml", "--until", "-1", "-o", p]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    let r = run(&["report", "crates/cli/tests/bad_simulate/blow_up.toml", "--until", "5", "-o", p]);
    assert_eq!(r.code, Some(1), "{}", r.describe());
    assert!(data(&page)["time"].as_array().unwrap().len() > 1);
}

/// Names that break a page whose data is inlined naively: each ends the data
/// element, or puts the tokenizer in a state where its end tag does not.
const HOSTILE_NAMES: [&str; 8] = [
    "<!--<script>x",
    "</script><script>alert(1)</script>",
    "<!--",
    "a --> b <script ",
    "</SCRIPT/>",
    "line\u{2028}break\u{2029}",
    "\\\" {{data}} ]]> &amp; <b>",
    "<script><!--</script>",
];

/// The page's scripts as a browser's tokenizer splits them: the data element,
/// holding the JSON with the model's name as written, then the page's script.
#[track_caller]
fn assert_scripts_intact(page: &std::path::Path, name: &str) {
    let html = std::fs::read_to_string(page).expect("the page was written");
    let scripts = common::html::scripts(&html).unwrap_or_else(|| panic!("{name:?}: a script element never closes"));
    assert_eq!(scripts.len(), 2, "{name:?}: {} script elements", scripts.len());
    let data: Value = serde_json::from_str(&scripts[0]).expect("the data element holds JSON");
    assert_eq!(data["name"], name);
    assert!(scripts[1].trim_start().starts_with("// The script of a `lagrange report` page."), "{name:?}");
    // The two ways out of script data: an end tag and a comment.
    assert!(!scripts[0].contains("</") && !scripts[0].contains("<!"), "{name:?}: a '</' or '<!' in the data");
}

#[test]
fn the_tokenizer_model_finds_what_a_browser_finds() {
    use common::html::scripts;
    assert_eq!(scripts("<p>a</p><script>x = 1;</script><script>y</script>").unwrap(), ["x = 1;", "y"]);
    // `<!--<script>`: the element's `</script>` only leaves the double-escaped
    // state, and what follows is script text to the end of the page.
    assert_eq!(scripts(r#"<script>{"name":"<!--<script>x"}</script><script>y</script>"#), None);
    assert_eq!(scripts("<script>a<!--b--></script><script>y</SCRIPT >").unwrap(), ["a<!--b-->", "y"]);
}

#[test]
fn hostile_names_leave_every_examples_page_whole() {
    let models = example_models();
    for (k, model) in models.iter().enumerate() {
        let text = std::fs::read_to_string(repo_root().join(model)).unwrap();
        if text.contains(".toml\"") {
            continue; // refers to a body file beside it
        }
        let name = HOSTILE_NAMES[k % HOSTILE_NAMES.len()];
        // The model's own name: the first `name = ` line, before any table.
        let at = text.find("\nname = ").expect("the model has a name") + 1;
        let end = at + text[at..].find('\n').unwrap();
        assert!(!text[..at].contains("\n["), "{model}: the name is inside a table");
        let hostile = format!("{}name = {}{}", &text[..at], toml_string(name), &text[end..]);
        let file = scratch("hostile-report", &model.replace('/', "_"));
        std::fs::write(&file, hostile).unwrap();
        let page = file.with_extension("html");
        ok(&["report", file.to_str().unwrap(), "--until", "0.2", "--samples", "11", "-o", page.to_str().unwrap()]);
        assert_scripts_intact(&page, name);
    }
    // Every hostile name on one model.
    let text = std::fs::read_to_string(repo_root().join("examples/pendulum.toml")).unwrap();
    for (k, name) in HOSTILE_NAMES.iter().enumerate() {
        let file = scratch("hostile-report", &format!("pendulum-{k}.toml"));
        std::fs::write(&file, text.replace("name = \"planar pendulum\"", &format!("name = {}", toml_string(name))))
            .unwrap();
        let page = file.with_extension("html");
        ok(&["report", file.to_str().unwrap(), "--until", "0.2", "--samples", "11", "-o", page.to_str().unwrap()]);
        assert_scripts_intact(&page, name);
    }
}

/// `s` as a TOML basic string.
fn toml_string(s: &str) -> String {
    let mut out = String::from('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 || c == '\u{2028}' || c == '\u{2029}' => {
                out.push_str(&format!("\\u{:04X}", c as u32))
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

#[test]
fn a_section_in_the_report_is_simulate_sections_points() {
    let page = scratch("report-section", "hh.html");
    let csv = scratch("report-section", "hh.csv");
    // The same rows on both sides (the samples are states the steps land on).
    let common =
        ["examples/henon_heiles.toml", "--until", "300", "--samples", "2001", "--set", "E=0.125", "--section", "x = 0"];
    let mut args = vec!["report"];
    args.extend(common);
    args.extend(["-o", page.to_str().unwrap()]);
    ok(&args);
    let mut args = vec!["simulate"];
    args.extend(common);
    args.extend(["--out", csv.to_str().unwrap()]);
    ok(&args);
    let data = data(&page);
    let section = &data["analyses"]["section"];
    assert_eq!(section["condition"], "x = 0");
    assert_eq!(section["axes"], serde_json::json!(["y", "p_y"]));
    let csv = Csv::read(csv.to_str().unwrap());
    assert_eq!(section["points"].as_u64(), Some(csv.rows.len() as u64));
    assert_eq!(numbers(&section["t"]), csv.column("t"));
    assert_eq!(numbers(&section["x"]), csv.column("y"));
    assert_eq!(numbers(&section["y"]), csv.column("p_y"));
    // The section's points are not the run's events.
    assert!(data["events"].as_array().is_none_or(|e| e.is_empty()), "{}", data["events"]);
}
