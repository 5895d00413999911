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
/// The bytes a page may take: its derivation is typeset whole when it fits in
/// what the template and the run's data leave, in outline otherwise
/// (`derive::mathml_within`). The data alone stays under about 1.5 MB.
const PAGE_BUDGET: usize = 1_990_000;
/// Significant digits of the positions drawn, relative to the mechanism's size
/// (a millionth of it, far below a pixel); the rows' own numbers are exact.
const DRAWN_DIGITS: i32 = 6;

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

impl Default for Recorder {
    fn default() -> Self {
        Recorder::new()
    }
}

/// A row with its place in the run.
#[derive(Debug, Clone)]
struct Kept {
    index: usize,
    row: Row,
}

/// The rows of a run that the page may show, chosen while the run streams
/// (see the module documentation), so that memory stays bounded however long
/// the run: evenly spaced rows at a stride that doubles whenever they pass
/// twice the page's budget, the pairs of rows around turning points likewise,
/// every event row and the last row. [`Recorder::data`] then thins these as
/// the page's budget says; a run that fits twice the budget keeps every row
/// until then, and the page shows what it would show had all been kept.
#[derive(Debug)]
pub struct Recorder {
    /// Rows pushed.
    total: usize,
    /// Rows each kind may hold before its stride doubles: twice the page's
    /// budget for a row of this shape (at least; [`Recorder::data`] counts
    /// the points drawn too), set by the first row.
    cap: usize,
    /// Rows whose index is a multiple of `stride`.
    even: Vec<Kept>,
    stride: usize,
    /// Turning points: the pair of rows around the k-th, k a multiple of `turn_every`.
    turns: Vec<(usize, Kept, Kept)>,
    turn_count: usize,
    turn_every: usize,
    /// Rows at events.
    events: Vec<Kept>,
    /// The row before (a turning point's first row; at the end, the last row).
    last: Option<Kept>,
}

impl Recorder {
    /// An empty recorder.
    pub fn new() -> Recorder {
        Recorder {
            total: 0,
            cap: 0,
            even: Vec::new(),
            stride: 1,
            turns: Vec::new(),
            turn_count: 0,
            turn_every: 1,
            events: Vec::new(),
            last: None,
        }
    }

    /// Takes one row of the run (`mech::Row`'s fields), keeping it if the page may show it.
    pub fn push(&mut self, row: &mech::Row<'_>) {
        let kept = Kept {
            index: self.total,
            row: Row {
                t: row.t,
                q: row.q.to_vec(),
                qd: row.qd.to_vec(),
                // Drawn as drift: the jumps at impacts are not the integrator's.
                invariants: row.invariants_less_jumps().into_owned(),
                constraints: row.constraints.to_vec(),
                event: row.event.map(str::to_string),
            },
        };
        self.total += 1;
        if self.cap == 0 {
            let numbers = 1 + 2 * kept.row.q.len() + kept.row.invariants.len() + kept.row.constraints.len();
            self.cap = 2 * budget(numbers);
        }
        if kept.row.event.is_some() {
            self.events.push(kept.clone());
        } else if let Some(before) = &self.last {
            if before.row.qd.iter().zip(&kept.row.qd).any(|(x, y)| x.signum() != y.signum()) {
                let k = self.turn_count;
                self.turn_count += 1;
                if k.is_multiple_of(self.turn_every) {
                    self.turns.push((k, before.clone(), kept.clone()));
                    if self.turns.len() > self.cap {
                        self.turn_every *= 2;
                        let every = self.turn_every;
                        self.turns.retain(|(k, _, _)| k.is_multiple_of(every));
                    }
                }
            }
        }
        if kept.index.is_multiple_of(self.stride) {
            self.even.push(kept.clone());
            if self.even.len() > self.cap {
                self.stride *= 2;
                let stride = self.stride;
                self.even.retain(|r| r.index.is_multiple_of(stride));
            }
        }
        self.last = Some(kept);
    }

    /// The number of rows the run gave.
    pub fn len(&self) -> usize {
        self.total
    }

    /// Whether the run gave no row.
    pub fn is_empty(&self) -> bool {
        self.total == 0
    }

    /// The `lagrange.report/1` data of the run: `summary` is the run's
    /// `lagrange.simulate/1` summary. The derivation is typeset whole when
    /// the page then stays within [`PAGE_BUDGET`], in outline otherwise.
    pub fn data(&self, d: &Derivation, until: f64, summary: Value) -> Value {
        let mut mech = Mechanism::new(d);
        let names = d.coordinate_names();
        let inv = mech::invariants_of(d);
        let constraint_columns = mech::constraint_columns(d);
        let dim = mech.dimension();
        let points = mech.points().len();
        // A body's axes, and a top's figure axis once more.
        let per_row =
            1 + 2 * names.len() + inv.len() + constraint_columns.len() + points * dim + 12 * mech.bodies().len();
        let rows = self.decimate(per_row);

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
        // The mechanism's size; a body turning about a fixed point alone has
        // none, and its axes are drawn a unit long.
        let extent = match extent(&frames, dim) {
            e if e > 1e-9 => e,
            _ => 1.0 / 0.3,
        };
        let (at_size, at_unit) = (Drawn::new(extent), Drawn::new(1.0));
        let axis = |p: usize, k: usize| -> Vec<f64> { frames.iter().map(|f| at_size.round(f[p * dim + k])).collect() };
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
        let bodies: Vec<Value> = (0..mech.bodies().len())
            .map(|b| {
                let axes: Vec<[[f64; 3]; 3]> = rows.iter().map(|r| mech.axes(b, r.t, &r.q, &r.qd)).collect();
                let per_axis: Vec<Vec<[f64; 3]>> =
                    (0..3).map(|k| axes.iter().map(|a| a[k].map(|x| at_unit.round(x))).collect()).collect();
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
        let events: Vec<Value> = self
            .events
            .iter()
            .filter_map(|r| r.row.event.as_ref().map(|e| json!({"t": r.row.t, "label": e})))
            .collect();

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
        let mut data = json!({
            "format": "lagrange.report/1",
            "name": d.model().name,
            "dimension": dim,
            "derivation": "",
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
        });
        // What the page takes without the derivation, and the derivation as
        // the page would inline it.
        let room = PAGE_BUDGET.saturating_sub(page(&data).len());
        let inlined = |html: &str| script_safe_json(&Value::String(html.to_string())).len();
        data["derivation"] = Value::String(crate::derive::mathml_within(d, room, inlined));
        data
    }

    /// The rows shown, in order: evenly spaced rows up to the budget of
    /// `per_row` numbers each, the ends, the events, and the turning points of
    /// the coordinates (where a velocity changes sign: the rows on both sides),
    /// as many of those as the budget again holds (evenly chosen among them
    /// when there are more: a chain of fifty masses turns all the time).
    fn decimate(&self, per_row: usize) -> Vec<&Row> {
        let budget = budget(per_row);
        let mut shown: std::collections::BTreeMap<usize, &Row> = std::collections::BTreeMap::new();
        let stride = self.even.len().div_ceil(budget).max(1);
        for r in self.even.iter().step_by(stride).chain(&self.events).chain(&self.last) {
            shown.insert(r.index, &r.row);
        }
        let every = self.turns.len().div_ceil(budget / 2).max(1);
        for (_, a, b) in self.turns.iter().step_by(every) {
            shown.insert(a.index, &a.row);
            shown.insert(b.index, &b.row);
        }
        shown.into_values().collect()
    }
}

/// The rows the page shows evenly spaced, for rows of `per_row` numbers.
fn budget(per_row: usize) -> usize {
    (NUMBER_BUDGET / per_row.max(1)).clamp(MIN_ROWS, MAX_ROWS)
}

/// A model's run and its page, as [`run_page`] makes them.
#[derive(Debug)]
pub struct RunPage {
    /// The page's HTML.
    pub html: String,
    /// Rows the run gave.
    pub rows: usize,
    /// Rows the page shows.
    pub shown: usize,
    /// Why the run stopped midway, if it did: the page shows the rows up to there.
    pub failure: Option<String>,
}

/// Most points of a Poincaré section a page holds: beyond, every k-th.
const MAX_SECTION_POINTS: usize = 20_000;

/// Runs `d` with `config` to `until` and makes its page: what `lagrange
/// report` and Python's `Model.report` both do. `started` is when the front
/// end began (reading the model), `derive_seconds` how long reading and
/// deriving took. With a Poincaré `section` (whose condition the caller has
/// made one of `config`'s crossings), its points are drawn among the analyses
/// rather than listed as events. A run that fails midway is a page with its
/// failure; the other errors (the run's input) are the front end's to word.
#[allow(clippy::too_many_arguments)]
pub fn run_page(
    d: &Derivation,
    config: &mech::RunConfig,
    until: f64,
    started: std::time::Instant,
    derive_seconds: f64,
    terms: &crate::Terms,
    mut section: Option<&mut mech::Section>,
) -> Result<RunPage, mech::RunError> {
    let mut rows = Recorder::new();
    let mut first_row = None;
    let mut points: Vec<[f64; 3]> = Vec::new();
    let result = mech::simulate(d, config, |row| {
        first_row.get_or_insert_with(|| started.elapsed().as_secs_f64());
        match section.as_deref_mut() {
            Some(s) if s.takes(row) => {
                let [x, y] = s.point(row.t, row.q, row.qd);
                points.push([row.t, x, y]);
            }
            _ => rows.push(row),
        }
        std::ops::ControlFlow::Continue(())
    });
    let (report, failure) = match result {
        Ok(r) => (r, None),
        Err(mech::RunError::Failed { message, report }) => {
            let message = report.failure.clone().unwrap_or(message);
            (*report, Some(message))
        }
        Err(e) => return Err(e),
    };
    let names: Vec<String> = d.coordinate_names().iter().map(|s| s.to_string()).collect();
    let timing = crate::simulate::Timing { derive_seconds, setup_seconds: first_row };
    let summary = crate::simulate::summary_json(&report, &names, &timing, None, terms);
    let mut data = rows.data(d, until, summary);
    if let (Some(s), Some(analyses)) = (section, data["analyses"].as_object_mut()) {
        analyses.insert("section".into(), section_data(s, &points));
    }
    let shown = data["time"].as_array().map_or(0, Vec::len);
    Ok(RunPage { html: page(&data), rows: rows.len(), shown, failure })
}

/// A section's points for the page: its condition and axes, the time and
/// plane coordinates of each point (every k-th beyond [`MAX_SECTION_POINTS`]).
fn section_data(s: &mech::Section, points: &[[f64; 3]]) -> Value {
    let stride = points.len().div_ceil(MAX_SECTION_POINTS).max(1);
    let kept: Vec<&[f64; 3]> = points.iter().step_by(stride).collect();
    let column = |k: usize| -> Vec<f64> { kept.iter().map(|p| p[k]).collect() };
    json!({
        "condition": s.condition().text,
        "falling": s.condition().direction == num::Direction::Falling,
        "axes": s.axes(),
        "points": points.len(),
        "t": column(0),
        "x": column(1),
        "y": column(2),
    })
}

/// The page: the template with the style, the script and the data inlined.
pub fn page(data: &Value) -> String {
    let title = crate::markup::quoted(data["name"].as_str().unwrap_or("lagrange report"));
    let data = script_safe_json(data);
    fill(&strip_comments(PAGE), &[("title", &title), ("style", STYLE), ("script", SCRIPT), ("data", &data)])
}

/// JSON text that is inert inside a `<script>` element. In script data the
/// HTML tokenizer leaves the element's content only at a `</` (an end tag, as
/// `</script`) or a `<!` (a `<!--` leads to the double-escaped state, where
/// even the element's own end tag no longer ends it: a model named
/// `<!--<script>x` once kept the page's script from running). JSON has `<`
/// only inside strings, so a `</` becomes `<\/` (JSON's escape of `/`, one
/// byte more: the derivation's MathML has a closing tag for every element) and
/// a `<!` becomes `\u003c!`; every other `<` is plain text there, and so are
/// `-->` and `&`. U+2028 and U+2029 are escaped too: older JavaScript parsers
/// take them for line ends.
fn script_safe_json(data: &Value) -> String {
    let text = data.to_string();
    let mut out = String::with_capacity(text.len() + text.len() / 16);
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, chars.peek()) {
            ('<', Some('/')) => {
                chars.next();
                out.push_str("<\\/");
            }
            ('<', Some('!')) => out.push_str("\\u003c"),
            ('\u{2028}', _) => out.push_str("\\u2028"),
            ('\u{2029}', _) => out.push_str("\\u2029"),
            (c, _) => out.push(c),
        }
    }
    out
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

/// Positions for drawing, rounded to [`DRAWN_DIGITS`] digits of a size: a
/// decimal that prints short (a chain of 50 rods: 0.45 MB of positions, not 1 MB).
#[derive(Clone, Copy)]
struct Drawn {
    /// The power of ten of the last digit kept, negated: 6 keeps millionths.
    decimals: i32,
}

impl Drawn {
    fn new(size: f64) -> Drawn {
        let magnitude = if size.is_finite() && size > 0.0 { size.log10().floor() as i32 } else { 0 };
        Drawn { decimals: (DRAWN_DIGITS - magnitude).clamp(-22, 22) }
    }

    /// `x` to the nearest multiple of 10^−decimals, as the double nearest that
    /// decimal (an integer and an exact power of ten divided once), which
    /// prints as the decimal itself. What is not finite stays as it is.
    fn round(self, x: f64) -> f64 {
        if !x.is_finite() {
            return x;
        }
        let scale = 10f64.powi(self.decimals.abs());
        if self.decimals >= 0 {
            (x * scale).round() / scale
        } else {
            (x / scale).round() * scale
        }
    }
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
        let at_size = Drawn::new(extent);
        let coord = |p: usize, k: usize| -> Vec<f64> { frames.iter().map(|f| at_size.round(f[p * dim + k])).collect() };
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
    let at_unit = Drawn::new(1.0);
    let e3: Vec<[f64; 3]> = rows.iter().map(|r| mech.axes(0, r.t, &r.q, &r.qd)[2].map(|x| at_unit.round(x))).collect();
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

    /// The rows today's page showed when every row was kept: the same rules
    /// over the whole run at once.
    fn shown_from_all(qd: &[f64], events: &[usize], per_row: usize) -> Vec<usize> {
        let n = qd.len();
        let budget = budget(per_row);
        if n <= budget {
            return (0..n).collect();
        }
        let mut keep = vec![false; n];
        keep[0] = true;
        keep[n - 1] = true;
        for i in (0..n).step_by(n.div_ceil(budget)) {
            keep[i] = true;
        }
        let mut turning = Vec::new();
        for i in 1..n {
            if events.contains(&i) {
                keep[i] = true;
            } else if qd[i - 1].signum() != qd[i].signum() {
                turning.push(i);
            }
        }
        for &i in turning.iter().step_by(turning.len().div_ceil(budget / 2).max(1)) {
            keep[i - 1] = true;
            keep[i] = true;
        }
        (0..n).filter(|&i| keep[i]).collect()
    }

    fn record(qd: &[f64], events: &[usize]) -> Recorder {
        let mut r = Recorder::new();
        for (i, v) in qd.iter().enumerate() {
            let event = events.contains(&i).then_some("x = 0");
            r.push(&mech::Row {
                t: i as f64,
                q: &[0.0],
                qd: &[*v],
                invariants: &[],
                is_event: event.is_some(),
                event,
                constraints: &[],
                jumps: &[],
            });
            assert!(r.even.len() <= r.cap && r.turns.len() <= r.cap, "row {i}: memory grows");
        }
        r
    }

    #[test]
    fn rows_are_thinned_while_they_stream_and_a_run_within_twice_the_budget_shows_what_all_rows_show() {
        let per_row = 3;
        let cap = 2 * budget(per_row);
        for n in [10, budget(per_row), budget(per_row) + 1, 3 * budget(per_row) / 2, cap] {
            for period in [2.0, 7.3, 1000.0] {
                let qd: Vec<f64> = (0..n).map(|i| (i as f64 * std::f64::consts::TAU / period).cos()).collect();
                let events = [n / 3, n / 2];
                let r = record(&qd, &events);
                let shown: Vec<f64> = r.decimate(per_row).iter().map(|row| row.t).collect();
                let expected: Vec<f64> = shown_from_all(&qd, &events, per_row).iter().map(|&i| i as f64).collect();
                assert_eq!(shown, expected, "n = {n}, period {period}");
            }
        }
        // Far past the budget: bounded, the ends and the events kept, and the
        // page's rows within the budget twice over plus the events.
        let n = 200 * cap + 17;
        let qd: Vec<f64> = (0..n).map(|i| (i as f64 * 0.9).sin()).collect();
        let r = record(&qd, &[5, n - 3]);
        let shown: Vec<f64> = r.decimate(per_row).iter().map(|row| row.t).collect();
        assert_eq!((shown[0], *shown.last().unwrap()), (0.0, (n - 1) as f64));
        assert!(shown.contains(&5.0) && shown.contains(&((n - 3) as f64)));
        assert!(shown.len() <= 3 * budget(per_row) + 4, "{} rows", shown.len());
        assert!(shown.len() >= budget(per_row) / 2, "{} rows", shown.len());
        assert_eq!(r.len(), n);
    }

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
        let data = rec.data(&d, 20.0, json!({}));
        let time: Vec<f64> = data["time"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert!(time.len() < 5000, "{} rows shown", time.len());
        assert_eq!((time[0], time[time.len() - 1]), (0.0, 20.0));
        // Period of a 0.5 rad swing with l = 2: about 2.87; a turning point every half period.
        let qd: Vec<f64> =
            data["coordinates"][0]["qd"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        let shown = qd.windows(2).filter(|w| w[0].signum() != w[1].signum()).count();
        let all = rec.turn_count;
        assert_eq!(shown, all);
        assert!(all >= 13, "{all} turning points");
    }

    #[test]
    fn the_pendulum_hangs_on_a_rod_from_the_origin_and_its_angle_wraps() {
        let (d, rec) = run(201);
        let data = rec.data(&d, 20.0, json!({}));
        assert_eq!(data["rods"], json!([[-1, 0]]));
        assert_eq!(data["coordinates"][0]["angle"], json!(true));
        assert_eq!(data["dimension"], json!(2));
        // Drawn to a millionth of the mechanism's size (2), printed short.
        let x0 = &data["points"][0]["x"][0];
        assert_eq!(x0.to_string(), "0.958851");
        assert!((x0.as_f64().unwrap() - 2.0 * 0.5f64.sin()).abs() < 5e-7);
        // The rows' own numbers are exact.
        assert_eq!(data["coordinates"][0]["q"][0].as_f64(), Some(0.5));
        // ω = √(g/l) = 2.2147; the frames of mode 0, point 0, as the page reads them.
        let modes = &data["analyses"]["modes"];
        assert!((modes["frequencies"][0].as_f64().unwrap() - (9.81f64 / 2.0).sqrt()).abs() < 1e-9);
        let x = modes["points"][0][0]["x"].as_array().unwrap();
        assert!(x.len() >= MIN_MODE_FRAMES, "{} frames", x.len());
        assert_eq!(modes["modes"][0].as_array().unwrap().len(), 1);
    }

    #[test]
    fn the_page_fills_each_placeholder_once_and_escapes_the_data() {
        let data = json!({"name": "a <b> {{data}}", "x": "</script>", "y": "<!--<script>", "z": "<mi>"});
        let html = page(&data);
        assert!(html.contains("<title>a &lt;b&gt; {{data}}</title>"), "{html}");
        assert!(html.contains(r#""x":"<\/script>""#));
        assert!(html.contains(r#""y":"\u003c!--<script>""#));
        assert!(html.contains(r#""z":"<mi>""#));
        // The data is inlined once, in its element, and reads back as it was.
        assert_eq!(html.matches(r#""x":"<\/script>""#).count(), 1);
        let start = html.find(r#"id="lagrange-data">"#).unwrap() + r#"id="lagrange-data">"#.len();
        let inlined = &html[start..start + html[start..].find("</script>").unwrap()];
        assert_eq!(serde_json::from_str::<Value>(inlined).unwrap(), data);
        assert!(html.contains(r#"<script type="application/json" id="lagrange-data">{"#));
        assert!(!html.contains("<!--"));
        assert_eq!(fill("{{a}}{{b}}{{c}}", &[("a", "{{b}}"), ("b", "2")]), "{{b}}2{{c}}");
    }
}
