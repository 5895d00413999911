//! `lagrange report`: one self-contained HTML page that typesets the
//! derivation, animates the mechanism, plots the run and shows its audit and
//! the analyses that apply.
//!
//! The page is a template (`report/page.html`) with its style
//! (`report/report.css`), its script (`report/report.js`) and the data inlined:
//! one `lagrange.report/1` JSON value that [`Recorder`] builds from the rows of
//! a run. Long runs are decimated for display ([`Recorder::data`]): a budget of
//! numbers keeps the file small, and the rows that matter are kept whatever
//! the budget (the ends, events, and every turning point of a coordinate).
//! The numbers are printed exactly, so a row shown is the row computed.

use mech::mechanism::{self, Mechanism};
use mech::{Derivation, ModeKind, Modes, Orbit, Top};
use serde_json::{json, Map, Value};

/// The numbers the data may hold for the rows: about 1 MB of JSON, and at
/// most twice that with the rows that matter.
const NUMBER_BUDGET: usize = 40_000;
/// Rows kept at least and at most, before the rows that matter are added.
const MIN_ROWS: usize = 120;
const MAX_ROWS: usize = 4000;
/// Frames of one period of a mode's animation, at most and at least: fewer
/// where the modes are many and the points too (the numbers of all frames of
/// all modes stay within `MODE_NUMBERS`).
const MODE_FRAMES: usize = 64;
const MIN_MODE_FRAMES: usize = 16;
const MODE_NUMBERS: usize = 24_000;
/// The most modes animated (the lowest frequencies; the data lists them all).
const MAX_ANIMATED_MODES: usize = 12;

/// The template and what goes into it.
const PAGE: &str = include_str!("report/page.html");
const STYLE: &str = include_str!("report/report.css");
const SCRIPT: &str = include_str!("report/report.js");

/// One row of a run, as the report keeps it.
#[derive(Debug, Clone)]
struct Row {
    t: f64,
    q: Vec<f64>,
    qd: Vec<f64>,
    invariants: Vec<f64>,
    constraints: Vec<f64>,
    event: Option<String>,
}

/// The rows of a run, kept for the page (see the module documentation).
#[derive(Debug)]
pub struct Recorder {
    rows: Vec<Row>,
}

impl Default for Recorder {
    fn default() -> Self {
        Recorder::new()
    }
}

impl Recorder {
    /// An empty recorder.
    pub fn new() -> Recorder {
        Recorder { rows: Vec::new() }
    }

    /// Keeps one row of the run (`mech::Row`'s fields).
    pub fn push(&mut self, row: &mech::Row<'_>) {
        self.rows.push(Row {
            t: row.t,
            q: row.q.to_vec(),
            qd: row.qd.to_vec(),
            invariants: row.invariants.to_vec(),
            constraints: row.constraints.to_vec(),
            event: row.event.map(str::to_string),
        });
    }

    /// The number of rows kept.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether no row was kept.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The `lagrange.report/1` data of the run: `summary` is the run's
    /// `lagrange.simulate/1` summary, `derivation` the derivation's HTML.
    pub fn data(&self, d: &Derivation, until: f64, summary: Value, derivation: String) -> Value {
        let mut mech = Mechanism::new(d);
        let names = d.coordinate_names();
        let inv = mech::invariants_of(d);
        let constraint_columns = mech::constraint_columns(d);
        let dim = mech.dimension();
        let points = mech.points().len();
        // A body's axes, and a top's figure axis once more.
        let per_row =
            1 + 2 * names.len() + inv.len() + constraint_columns.len() + points * dim + 12 * mech.bodies().len();
        let keep = self.decimate(per_row);
        let rows: Vec<&Row> = keep.iter().map(|&i| &self.rows[i]).collect();

        let column = |f: &dyn Fn(&Row) -> f64| -> Vec<f64> { rows.iter().map(|r| f(r)).collect() };
        let angles = crate::angles::angles(d);
        let coordinates: Vec<Value> = names
            .iter()
            .enumerate()
            .map(|(i, n)| json!({"name": n, "angle": angles[i], "q": column(&|r| r.q[i]), "qd": column(&|r| r.qd[i])}))
            .collect();
        let invariants: Vec<Value> = inv
            .iter()
            .enumerate()
            .map(|(k, a)| {
                // Whether the derivation says it is conserved: the audit's flag.
                let conserved = summary["invariants"][&a.name]["conserved"].as_bool().unwrap_or(false);
                json!({"name": a.name, "conserved": conserved, "values": column(&|r| r.invariants[k])})
            })
            .collect();
        let forces: Vec<Value> = constraint_columns
            .iter()
            .enumerate()
            .filter_map(|(k, c)| c.strip_prefix("force_").map(|name| (k, name)))
            .map(|(k, name)| json!({"name": name, "values": column(&|r| r.constraints[k])}))
            .collect();

        // Positions of every point at every kept row.
        let mut frames: Vec<Vec<f64>> = Vec::with_capacity(rows.len());
        for r in &rows {
            let mut out = vec![0.0; points * dim];
            mech.place(r.t, &r.q, &r.qd, &mut out);
            frames.push(out);
        }
        let axis = |p: usize, k: usize| -> Vec<f64> { frames.iter().map(|f| f[p * dim + k]).collect() };
        let point_values: Vec<Value> = mech
            .points()
            .iter()
            .enumerate()
            .map(|(p, pt)| {
                json!({
                    "name": pt.name,
                    "kind": pt.kind.name(),
                    "mass": pt.mass,
                    "x": axis(p, 0),
                    "y": axis(p, 1),
                    "z": if dim == 3 { json!(axis(p, 2)) } else { Value::Null },
                })
            })
            .collect();
        // The mechanism's size; a body turning about a fixed point alone has
        // none, and its axes are drawn a unit long.
        let extent = match extent(&frames, dim) {
            e if e > 1e-9 => e,
            _ => 1.0 / 0.3,
        };
        let bodies: Vec<Value> = (0..mech.bodies().len())
            .map(|b| {
                let axes: Vec<[[f64; 3]; 3]> = rows.iter().map(|r| mech.axes(b, r.t, &r.q, &r.qd)).collect();
                let per_axis: Vec<Vec<[f64; 3]>> = (0..3).map(|k| axes.iter().map(|a| a[k]).collect()).collect();
                json!({
                    "name": mech.bodies()[b].name,
                    "point": mech.bodies()[b].point,
                    "axes": per_axis,
                    "length": 0.3 * extent,
                })
            })
            .collect();
        // Rods join particles and bodies; the points of a model given by T and U
        // alone stand for coordinates, which nothing joins.
        let drawn_from_positions = mech.points().iter().all(|p| p.kind != mech::PointKind::Coordinate);
        let rods: Vec<[isize; 2]> = if drawn_from_positions {
            mechanism::rods(&frames, points, dim).into_iter().map(|(a, b)| [a, b]).collect()
        } else {
            Vec::new()
        };
        let springs: Vec<[usize; 2]> = mech.springs().iter().map(|&(a, b)| [a, b]).collect();
        let events: Vec<Value> =
            self.rows.iter().filter_map(|r| r.event.as_ref().map(|e| json!({"t": r.t, "label": e}))).collect();

        let mut analyses = Map::new();
        if let Some(m) = modes(d, &mut mech, extent) {
            analyses.insert("modes".into(), m);
        }
        if let Some(o) = orbit(d) {
            analyses.insert("orbit".into(), o);
        }
        if let Some(t) = top(d, &mut mech, &rows) {
            analyses.insert("top".into(), t);
        }
        json!({
            "format": "lagrange.report/1",
            "name": d.model().name,
            "dimension": dim,
            "derivation": derivation,
            "until": until,
            "time": column(&|r| r.t),
            "coordinates": coordinates,
            "invariants": invariants,
            "constraint_forces": forces,
            "points": point_values,
            "bodies": bodies,
            "rods": rods,
            "springs": springs,
            "summary": summary,
            "events": events,
            "analyses": analyses,
        })
    }

    /// The indices of the rows shown: evenly spaced rows up to the budget of
    /// `per_row` numbers each, the ends, the events, and the turning points of
    /// the coordinates (where a velocity changes sign: the rows on both sides),
    /// as many of those as the budget again holds (evenly chosen among them
    /// when there are more: a chain of fifty masses turns all the time).
    fn decimate(&self, per_row: usize) -> Vec<usize> {
        let n = self.rows.len();
        let budget = (NUMBER_BUDGET / per_row.max(1)).clamp(MIN_ROWS, MAX_ROWS);
        if n <= budget {
            return (0..n).collect();
        }
        let mut keep = vec![false; n];
        keep[0] = true;
        keep[n - 1] = true;
        let stride = n.div_ceil(budget);
        for i in (0..n).step_by(stride) {
            keep[i] = true;
        }
        let mut turning = Vec::new();
        for i in 1..n {
            let (a, b) = (&self.rows[i - 1], &self.rows[i]);
            if b.event.is_some() {
                keep[i] = true;
            } else if a.qd.iter().zip(&b.qd).any(|(x, y)| x.signum() != y.signum()) {
                turning.push(i);
            }
        }
        let every = turning.len().div_ceil(budget / 2).max(1);
        for &i in turning.iter().step_by(every) {
            keep[i - 1] = true;
            keep[i] = true;
        }
        (0..n).filter(|&i| keep[i]).collect()
    }
}

/// The page: the template with the style, the script and the data inlined.
pub fn page(data: &Value) -> String {
    let title = escape(data["name"].as_str().unwrap_or("lagrange report"));
    // `</` inside a script element would end it: JSON allows `<\/`.
    let data = data.to_string().replace("</", "<\\/");
    fill(&strip_comments(PAGE), &[("title", &title), ("style", STYLE), ("script", SCRIPT), ("data", &data)])
}

/// The template without its HTML comments (notes for the people who edit it,
/// which name the placeholders).
fn strip_comments(html: &str) -> String {
    let mut out = String::with_capacity(html.len());
    let mut rest = html;
    while let Some(start) = rest.find("<!--") {
        out.push_str(&rest[..start]);
        rest = rest[start..].find("-->").map_or("", |end| &rest[start + end + 3..]);
    }
    out.push_str(rest);
    out
}

/// Replaces each `{{key}}` of the template, in one pass: what is put in is not
/// looked at again (a model named `{{data}}` stays so named).
fn fill(template: &str, values: &[(&str, &str)]) -> String {
    let mut out = String::with_capacity(template.len() + values.iter().map(|(_, v)| v.len()).sum::<usize>());
    let mut rest = template;
    while let Some(start) = rest.find("{{") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 2..];
        match after.find("}}").and_then(|end| values.iter().find(|(k, _)| *k == &after[..end]).map(|(_, v)| (end, v))) {
            Some((end, value)) => {
                out.push_str(value);
                rest = &after[end + 2..];
            }
            None => {
                out.push_str("{{");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// Text for HTML.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// The largest distance of a drawn point from the origin over the run.
fn extent(frames: &[Vec<f64>], dim: usize) -> f64 {
    frames.iter().flat_map(|f| f.chunks(dim).map(|p| p.iter().map(|x| x * x).sum::<f64>().sqrt())).fold(0.0, f64::max)
}

/// Each normal mode animated: the points' positions over one period (a mode
/// of frequency zero: a drift along it and back), with an amplitude that
/// moves the points by a tenth of the mechanism's size.
fn modes(d: &Derivation, mech: &mut Mechanism, extent: f64) -> Option<Value> {
    if !d.constraints().is_empty() {
        return None;
    }
    let modes: Modes = mech::normal_modes(d, &mech::ModesConfig::default()).ok()?;
    if !modes.stable {
        return None;
    }
    let dim = mech.dimension();
    let n_points = mech.points().len();
    let zeros = vec![0.0; modes.equilibrium.len()];
    let place = |mech: &mut Mechanism, q: &[f64]| {
        let mut out = vec![0.0; n_points * dim];
        mech.place(0.0, q, &zeros, &mut out);
        out
    };
    let rest = place(mech, &modes.equilibrium);
    let animated = modes.modes.len().min(MAX_ANIMATED_MODES);
    let frames_per_mode = (MODE_NUMBERS / (animated * n_points * dim).max(1)).clamp(MIN_MODE_FRAMES, MODE_FRAMES);
    let mut animations = Vec::new();
    for m in &modes.modes[..animated] {
        // How far the points move per unit amplitude along the shape.
        let eps = 1e-6;
        let nudged: Vec<f64> = modes.equilibrium.iter().zip(&m.shape).map(|(q, s)| q + eps * s).collect();
        let moved = place(mech, &nudged);
        let per_unit = rest.iter().zip(&moved).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / eps;
        let amplitude = if per_unit > 0.0 { 0.1 * extent / per_unit } else { 0.1 };
        let drift = m.kind == ModeKind::Free;
        let mut frames: Vec<Vec<f64>> = Vec::with_capacity(frames_per_mode);
        for k in 0..frames_per_mode {
            let phase = k as f64 / frames_per_mode as f64;
            let s = if drift {
                // Out and back along the mode, at constant speed.
                1.0 - 4.0 * (phase - 0.5).abs()
            } else {
                (2.0 * std::f64::consts::PI * phase).cos()
            };
            let q: Vec<f64> = modes.equilibrium.iter().zip(&m.shape).map(|(q0, a)| q0 + amplitude * s * a).collect();
            frames.push(place(mech, &q));
        }
        let coord = |p: usize, k: usize| -> Vec<f64> { frames.iter().map(|f| f[p * dim + k]).collect() };
        let points: Vec<Value> = (0..n_points)
            .map(|p| json!({"x": coord(p, 0), "y": coord(p, 1), "z": if dim == 3 { json!(coord(p, 2)) } else { Value::Null }}))
            .collect();
        animations.push(Value::Array(points));
    }
    // As `lagrange.modes/1` has them (frequencies, shapes), and the frames of
    // the animated modes: `points[mode][point]`.
    Some(json!({
        "coordinates": modes.coordinates,
        "equilibrium": modes.equilibrium,
        "frequencies": modes.modes.iter().map(|m| m.frequency.unwrap_or(0.0)).collect::<Vec<_>>(),
        "modes": modes.modes.iter().map(|m| m.shape.clone()).collect::<Vec<_>>(),
        "points": animations,
    }))
}

/// The orbit's kind, turning radii and energy, and U_eff(r) over the radii it spans.
fn orbit(d: &Derivation) -> Option<Value> {
    if !d.constraints().is_empty() {
        return None;
    }
    let mut orbit = Orbit::new(d).ok()?;
    let report = serde_json::to_value(orbit.report(d)).ok()?;
    let periapsis = report["periapsis"].as_f64()?;
    let outer = report["apoapsis"].as_f64().unwrap_or(3.0 * periapsis);
    let (lo, hi) = (0.5 * periapsis, 1.5 * outer);
    let r: Vec<f64> = (0..=200).map(|k| lo + (hi - lo) * k as f64 / 200.0).collect();
    let u: Vec<f64> = r.iter().map(|&r| orbit.u_eff(r)).collect();
    let mut value = report;
    value["u_eff"] = json!({"r": r, "u": u});
    Some(value)
}

/// The top's nutation bounds and its figure axis (e3 of its body) along the run.
fn top(d: &Derivation, mech: &mut Mechanism, rows: &[&Row]) -> Option<Value> {
    let top = Top::new(d).ok()?;
    let report = serde_json::to_value(top.report()).ok()?;
    if mech.bodies().is_empty() {
        return None;
    }
    let e3: Vec<[f64; 3]> = rows.iter().map(|r| mech.axes(0, r.t, &r.q, &r.qd)[2]).collect();
    let mut value = report;
    value["axis"] = json!({
        "x": e3.iter().map(|e| e[0]).collect::<Vec<_>>(),
        "y": e3.iter().map(|e| e[1]).collect::<Vec<_>>(),
        "z": e3.iter().map(|e| e[2]).collect::<Vec<_>>(),
    });
    if let Some(n) = value.get("nutation").cloned() {
        value["beta_min"] = n["beta_min"].clone();
        value["beta_max"] = n["beta_max"].clone();
    }
    Some(value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ops::ControlFlow;

    const PENDULUM: &str = r#"
name = "pendulum"
coordinates = ["th"]
gravity = "g"
[parameters]
m = 1.0
l = 2.0
g = 9.81
[[particles]]
mass = "m"
position = ["l*sin(th)", "-l*cos(th)"]
[initial]
th = 0.5
"th'" = 0.0
"#;

    fn run(samples: usize) -> (Derivation, Recorder) {
        let d = Derivation::new(mech::Model::parse(PENDULUM, &[]).unwrap()).unwrap();
        let config = mech::RunConfig { until: 20.0, output: num::Output::Samples(samples), ..Default::default() };
        let mut rec = Recorder::new();
        mech::simulate(&d, &config, |row| {
            rec.push(row);
            ControlFlow::Continue(())
        })
        .unwrap();
        (d, rec)
    }

    #[test]
    fn a_long_run_keeps_every_turning_point_and_both_ends() {
        let (d, rec) = run(100_000);
        let data = rec.data(&d, 20.0, json!({}), String::new());
        let time: Vec<f64> = data["time"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert!(time.len() < 5000, "{} rows shown", time.len());
        assert_eq!((time[0], time[time.len() - 1]), (0.0, 20.0));
        // Period of a 0.5 rad swing with l = 2: about 2.87; a turning point every half period.
        let qd: Vec<f64> =
            data["coordinates"][0]["qd"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        let shown = qd.windows(2).filter(|w| w[0].signum() != w[1].signum()).count();
        let all = rec.rows.windows(2).filter(|w| w[0].qd[0].signum() != w[1].qd[0].signum()).count();
        assert_eq!(shown, all);
        assert!(all >= 13, "{all} turning points");
    }

    #[test]
    fn the_pendulum_hangs_on_a_rod_from_the_origin_and_its_angle_wraps() {
        let (d, rec) = run(201);
        let data = rec.data(&d, 20.0, json!({}), String::new());
        assert_eq!(data["rods"], json!([[-1, 0]]));
        assert_eq!(data["coordinates"][0]["angle"], json!(true));
        assert_eq!(data["dimension"], json!(2));
        let x0 = data["points"][0]["x"][0].as_f64().unwrap();
        assert_eq!(x0, 2.0 * 0.5f64.sin());
        // ω = √(g/l) = 2.2147; the frames of mode 0, point 0, as the page reads them.
        let modes = &data["analyses"]["modes"];
        assert!((modes["frequencies"][0].as_f64().unwrap() - (9.81f64 / 2.0).sqrt()).abs() < 1e-9);
        let x = modes["points"][0][0]["x"].as_array().unwrap();
        assert!(x.len() >= MIN_MODE_FRAMES, "{} frames", x.len());
        assert_eq!(modes["modes"][0].as_array().unwrap().len(), 1);
    }

    #[test]
    fn the_page_fills_each_placeholder_once_and_escapes_the_data() {
        let data = json!({"name": "a <b> {{data}}", "x": "</script>"});
        let html = page(&data);
        assert!(html.contains("<title>a &lt;b&gt; {{data}}</title>"), "{html}");
        assert!(html.contains(r#""x":"<\/script>""#));
        // The data is inlined once, in its element.
        assert_eq!(html.matches(r#""x":"<\/script>""#).count(), 1);
        assert!(html.contains(r#"<script type="application/json" id="lagrange-data">{"#));
        assert!(!html.contains("<!--"));
        assert_eq!(fill("{{a}}{{b}}{{c}}", &[("a", "{{b}}"), ("b", "2")]), "{{b}}2{{c}}");
    }
}
