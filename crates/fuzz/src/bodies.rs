//! Target (d): the body-tree loader on random `[[bodies]]` trees, mutated
//! hostilely. Enter with [`check_bodies`] (one model text) or [`BodiesTarget`].
//!
//! A tree ([`tree`]) has one to four bodies, each on a parent or on space:
//! three angles in any of the twelve sequences, one angle about `"x"`, `"y"`,
//! `"z"` or a vector, or none; positions with translational coordinates or
//! constants; masses and inertias (principal or a tensor); in 3-D or planar.
//! Around it: `[[loads]]` (forces, torques, in space or body axes) fed by
//! `[inputs]`, and rolling contacts (`rolling = "BODY"`, `radius`, `axle`,
//! `contact`). Then up to three hostile edits ([`hostile`]): a name that
//! points nowhere, at itself or forward (a cycle), a key dropped or misspelt,
//! a degenerate axis, a zero, negative or infinite radius, huge and tiny
//! numbers, values of the wrong type, tables swapped; sometimes a byte-level
//! mutation on top.
//!
//! Checks: no panic, no hang; every error's span inside the text; a model that
//! loads has its initial state evaluated and derives or is refused with an
//! error, and is compared with the oracle (as the loader target does); a tree
//! left unedited (its first line says so) has T ≥ 0 at random states with the
//! parameters' own values (masses positive, inertias that satisfy the
//! triangle inequality about the centre of mass).

use crate::derive::check_model;
use crate::mutate::mutate;
use crate::oracle::Oracle;
use crate::rng::Rng;
use crate::run::{FindingKind, Outcome, Target};
use crate::spans::{check_model_error, signature_of};
use mech::{Derivation, Model};

/// The first line of a tree left unedited.
const INTACT: &str = "# intact tree";

/// A TOML table: its header (empty for the top level) and its `key = value` lines.
#[derive(Clone, Debug)]
struct Table {
    header: String,
    entries: Vec<(String, String)>,
}

impl Table {
    fn new(header: &str) -> Table {
        Table { header: header.into(), entries: Vec::new() }
    }
    fn set(&mut self, key: &str, value: impl Into<String>) {
        self.entries.push((key.into(), value.into()));
    }
}

/// The twelve sequences of turns.
const SEQUENCES: [&str; 12] = ["zxz", "xyx", "yzy", "zyz", "xzx", "yxy", "xyz", "yzx", "zxy", "xzy", "zyx", "yxz"];

fn quoted(items: &[&str]) -> String {
    let items: Vec<String> = items.iter().map(|s| format!("\"{s}\"")).collect();
    format!("[{}]", items.join(", "))
}

/// A random body tree with its loads, inputs and rolling contacts.
fn tree(rng: &mut Rng) -> Vec<Table> {
    let planar = rng.chance(0.25);
    let dim = if planar { 2 } else { 3 };
    let mut top = Table::new("");
    let mut params = Table::new("[parameters]");
    for (k, v) in [
        ("m", "1.0"),
        ("A", "1.0"),
        ("B", "2.0"),
        ("C", "2.5"),
        ("R", "0.5"),
        ("l", "1.0"),
        ("g", "9.81"),
        ("k", "0.2"),
    ] {
        params.set(k, v);
    }
    let mut coordinates: Vec<String> = Vec::new();
    let mut initial = Table::new("[initial]");
    let mut bodies = Vec::new();
    // Per body: its name and whether it turns about an axle of its own (for rolling).
    let mut turning: Vec<(String, bool)> = Vec::new();
    for i in 0..1 + rng.below(4) {
        let mut b = Table::new("[[bodies]]");
        let name = format!("b{i}");
        b.set("name", format!("\"{name}\""));
        if i > 0 && rng.chance(0.5) {
            b.set("parent", format!("\"b{}\"", rng.below(i)));
        }
        let kind = if planar { [1, 2][rng.below(2)] } else { rng.below(3) };
        let mut turns = false;
        match kind {
            0 => {
                let names = [format!("al{i}"), format!("be{i}"), format!("ga{i}")];
                b.set("angles", quoted(&[&names[0], &names[1], &names[2]]));
                if rng.chance(0.8) {
                    b.set("sequence", format!("\"{}\"", rng.pick(&SEQUENCES)));
                }
                for (k, n) in names.iter().enumerate() {
                    // β away from the sequences' singular 0 and π/2.
                    initial.set(n, ["0.3", "0.7", "-0.2"][k]);
                    initial.set(&format!("\"{n}'\""), ["0.5", "0", "-1.5"][k]);
                }
                coordinates.extend(names);
                b.set(
                    "inertia",
                    if rng.chance(0.7) {
                        quoted(&["A", "B", "C"])
                    } else {
                        "[[\"A\", 0, 0], [0, \"B\", 0.1], [0, 0.1, \"C\"]]".into()
                    },
                );
                turns = true;
            }
            1 => {
                let n = format!("th{i}");
                b.set("angle", format!("\"{n}\""));
                if planar {
                    if rng.chance(0.3) {
                        b.set("axis", "\"z\"");
                    }
                } else {
                    let axis = match rng.below(5) {
                        0 => "\"x\"".to_string(),
                        1 => "\"y\"".to_string(),
                        2 => "\"z\"".to_string(),
                        3 => "[\"sin(k)\", 0, \"cos(k)\"]".to_string(),
                        _ => "[1, 2, 2]".to_string(),
                    };
                    b.set("axis", axis);
                }
                // One moment for a body turning about z in the plane only.
                b.set(
                    "inertia",
                    if planar && rng.chance(0.5) { "\"A\"".to_string() } else { quoted(&["A", "B", "C"]) },
                );
                initial.set(&n, "0.4");
                initial.set(&format!("\"{n}'\""), "0.3");
                coordinates.push(n);
                turns = true;
            }
            _ => {
                b.set("inertia", quoted(&["A", "B", "C"]));
            }
        }
        b.set("mass", if rng.chance(0.5) { "\"m\"" } else { "1.5" });
        let mut position: Vec<String> = (0..dim).map(|_| rng.pick(&["0", "l", "-l/2", "0.3"]).to_string()).collect();
        if rng.chance(0.5) {
            let x = format!("x{i}");
            position[rng.below(dim)] = if rng.chance(0.5) { x.clone() } else { format!("l*{x}") };
            initial.set(&x, "0.1");
            initial.set(&format!("\"{x}'\""), "-0.2");
            coordinates.push(x);
        }
        let moving = position.iter().any(|p| p.contains('x'));
        let position: Vec<&str> = position.iter().map(String::as_str).collect();
        if i > 0 || moving || rng.chance(0.7) {
            b.set("position", quoted(&position));
        }
        if rng.chance(0.4) {
            let com: Vec<&str> = (0..dim).map(|_| *rng.pick(&["0", "0.2", "-l/2"])).collect();
            b.set("center_of_mass", quoted(&com));
        }
        turning.push((name, turns));
        bodies.push(b);
    }
    if coordinates.is_empty() {
        // A fixed body alone moves nothing: give it a coordinate to move along.
        bodies[0].entries.retain(|(k, _)| k != "position");
        let position: Vec<&str> = (0..dim).map(|k| if k == 0 { "x" } else { "0" }).collect();
        bodies[0].set("position", quoted(&position));
        coordinates.push("x".into());
        initial.set("x", "0");
    }
    let coords: Vec<&str> = coordinates.iter().map(String::as_str).collect();
    top.set("name", "\"random body tree\"");
    top.set("coordinates", quoted(&coords));
    if rng.chance(0.7) {
        top.set("gravity", "\"g\"");
    }
    let mut tables = vec![top, params];
    tables.extend(bodies);
    let mut inputs = Table::new("[inputs]");
    for _ in 0..rng.below(3) {
        let mut l = Table::new("[[loads]]");
        let body = &turning[rng.below(turning.len())].0;
        l.set("body", format!("\"{body}\""));
        if rng.chance(0.5) {
            let f: Vec<&str> = (0..dim).map(|k| if k == 0 { "F" } else { *rng.pick(&["0", "-k", "k*t"]) }).collect();
            l.set("force", quoted(&f));
            if rng.chance(0.5) {
                let at: Vec<&str> = (0..dim).map(|_| *rng.pick(&["0", "l", "0.1"])).collect();
                l.set("at", quoted(&at));
            }
        } else if planar && rng.chance(0.7) {
            l.set("torque", "\"tau\"");
        } else {
            l.set("torque", quoted(&["0", "tau", "k"]));
        }
        if rng.chance(0.4) {
            l.set("axes", if rng.chance(0.7) { "\"body\"" } else { "\"space\"" });
        }
        tables.push(l);
    }
    if tables.iter().any(|t| t.header == "[[loads]]") {
        inputs.set("F", "\"k*sin(t)\"");
        inputs.set("tau", "0.1");
        tables.push(inputs);
    }
    if !planar && rng.chance(0.4) {
        let (body, turns) = &turning[rng.below(turning.len())];
        let mut c = Table::new("[[constraints]]");
        c.set("name", "\"roll\"");
        c.set("rolling", format!("\"{body}\""));
        c.set("radius", "\"R\"");
        if !turns || rng.chance(0.3) {
            c.set("axle", format!("\"{}\"", rng.pick(&["x", "y", "z"])));
        }
        if rng.chance(0.4) {
            c.set("contact", if rng.chance(0.7) { "\"constraint\"" } else { "\"kept\"" });
        }
        tables.push(c);
    }
    tables.push(initial);
    tables
}

/// Values that break things.
const HOSTILE_VALUES: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "\"1e300*1e300\"",
    "\"0*R\"",
    "\"-R\"",
    "\"nan\"",
    "\"1/0\"",
    "\"\"",
    "[]",
    "true",
    "{}",
    "[[1, 2], [3]]",
    "[0, 0, 0]",
    "[\"0\", \"0\", \"1e-300\"]",
    "[\"k-k\", 0, 0]",
    "\"w\"",
    "[1, 2]",
    "\"zzx\"",
    "\"XYZ\"",
    "\"zxzx\"",
    "\"b0\"",
    "\"nobody\"",
    "\"x\"",
    "\"al0\"",
    "\"th0\"",
    "[\"A\"]",
    "\"q'\"",
    "[\"A\", \"B\", \"C\", \"A\"]",
    "[[\"A\", 1, 0], [0, \"B\", 0], [0, 0, \"C\"]]",
    "\"-A\"",
    "\"t\"",
];

/// Keys misspelt or out of place.
const HOSTILE_KEYS: &[&str] = &[
    "inerta", "positon", "paren", "radious", "axel", "angle", "angles", "axis", "sequence", "rolling", "body", "torque",
];

/// One hostile edit of the tables.
fn hostile(rng: &mut Rng, tables: &mut [Table]) {
    let t = rng.below(tables.len());
    let body_names: Vec<String> =
        tables.iter().filter(|t| t.header == "[[bodies]]").enumerate().map(|(k, _)| format!("b{k}")).collect();
    match rng.below(8) {
        0 => {
            // A reference made to point nowhere, at itself or forward.
            let refs: Vec<(usize, usize)> = tables
                .iter()
                .enumerate()
                .flat_map(|(i, t)| {
                    t.entries
                        .iter()
                        .enumerate()
                        .filter(|(_, (k, _))| matches!(k.as_str(), "parent" | "body" | "rolling"))
                        .map(move |(j, _)| (i, j))
                })
                .collect();
            if let (false, Some(last)) = (refs.is_empty(), body_names.last()) {
                let (i, j) = *rng.pick(&refs);
                let own = tables[i].entries.iter().find(|(k, _)| k == "name").map(|(_, v)| v.clone());
                let to = match rng.below(3) {
                    0 => "\"nobody\"".to_string(),
                    1 => own.unwrap_or_else(|| "\"b0\"".into()),
                    _ => format!("\"{last}\""),
                };
                tables[i].entries[j].1 = to;
            }
        }
        1 if !tables[t].entries.is_empty() => {
            let k = rng.below(tables[t].entries.len());
            tables[t].entries.remove(k);
        }
        2 if !tables[t].entries.is_empty() => {
            let k = rng.below(tables[t].entries.len());
            tables[t].entries[k].0 = rng.pick(HOSTILE_KEYS).to_string();
            dedup(&mut tables[t]);
        }
        3 | 4 if !tables[t].entries.is_empty() => {
            let k = rng.below(tables[t].entries.len());
            tables[t].entries[k].1 = rng.pick(HOSTILE_VALUES).to_string();
        }
        5 => {
            let (a, b) = (rng.below(tables.len()), rng.below(tables.len()));
            tables.swap(a, b);
        }
        6 => {
            // A key added where it may not belong.
            let key = rng.pick(HOSTILE_KEYS).to_string();
            tables[t].set(&key, *rng.pick(HOSTILE_VALUES));
            dedup(&mut tables[t]);
        }
        _ => {
            // Two bodies with one name, or one body's angle given to another.
            let bodies: Vec<usize> = (0..tables.len()).filter(|&i| tables[i].header == "[[bodies]]").collect();
            let (a, b) = (*rng.pick(&bodies), *rng.pick(&bodies));
            let key = *rng.pick(&["name", "angle", "angles", "position", "parent"]);
            if let Some(v) = tables[a].entries.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone()) {
                tables[b].entries.retain(|(k, _)| k != key);
                tables[b].set(key, v);
            }
        }
    }
}

/// Keeps the first of equal keys (a TOML table has each key once).
fn dedup(t: &mut Table) {
    let mut seen = std::collections::HashSet::new();
    t.entries.retain(|(k, _)| seen.insert(k.clone()));
}

fn render(tables: &[Table]) -> String {
    let mut text = String::new();
    // The top level's keys come before every header.
    for t in tables.iter().filter(|t| t.header.is_empty()).chain(tables.iter().filter(|t| !t.header.is_empty())) {
        if !t.header.is_empty() {
            text.push_str(&t.header);
            text.push('\n');
        }
        for (k, v) in &t.entries {
            text.push_str(&format!("{k} = {v}\n"));
        }
    }
    text
}

/// A random tree, edited hostilely with probability ¾.
pub fn hostile_tree(rng: &mut Rng) -> String {
    let mut tables = tree(rng);
    if rng.chance(0.25) {
        return format!("{INTACT}\n{}", render(&tables));
    }
    for _ in 0..1 + rng.below(3) {
        hostile(rng, &mut tables);
    }
    let text = format!("# edited tree\n{}", render(&tables));
    if rng.chance(0.15) {
        mutate(rng, &text, &[])
    } else {
        text
    }
}

/// Loads, derives and checks a body-tree model.
pub fn check_bodies(text: &str) -> Outcome {
    let spans = |err: &mech::ModelError, what: &str| match check_model_error(text, err) {
        Err(why) => Outcome::problem(FindingKind::Span, format!("{what}: {why}")),
        Ok(()) => Outcome::fine(format!("{what}: {}", signature_of(&err.message))),
    };
    let model = match Model::parse(text, &[]) {
        Err(err) => return spans(&err, "load error"),
        Ok(model) => model,
    };
    if let Err(err) = model.initial_state() {
        let outcome = spans(&err, "initial state");
        if outcome.problem.is_some() {
            return outcome;
        }
    }
    if text.starts_with(INTACT) {
        if let Some(problem) = kinetic_energy_not_negative(text, &model) {
            return problem;
        }
    }
    check_model(text, model)
}

/// A finding when T < 0 somewhere, at the parameters' own values.
fn kinetic_energy_not_negative(text: &str, model: &Model) -> Option<Outcome> {
    let d = Derivation::new(model.clone().with_inputs_applied()).ok()?;
    let (tt, uu) = (d.kinetic()?, d.potential()?);
    let o = Oracle::with_energies(d.model(), d.pool().clone(), tt, uu, None);
    let mut rng = Rng::new(text.len() as u64);
    for _ in 0..4 {
        let Some(mut point) = o.point(&mut rng) else { continue };
        point.params = model.parameters.iter().map(|p| p.value).collect();
        let Ok(t) = o.eval(d.pool(), tt, &point) else { continue };
        let speeds = point.qd.iter().map(|v| v * v).sum::<f64>();
        if t < -1e-9 * (1.0 + speeds) {
            return Some(Outcome::problem(FindingKind::Invariant, format!("T = {t:e} < 0 at {point:?}")));
        }
    }
    None
}

/// The body-tree loader under the fuzz loop.
#[derive(Default)]
pub struct BodiesTarget;

impl Target for BodiesTarget {
    fn name(&self) -> &'static str {
        "bodies"
    }

    fn input(&mut self, rng: &mut Rng) -> String {
        hostile_tree(rng)
    }

    fn check(&mut self, input: &str) -> Outcome {
        check_bodies(input)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intact_trees_load_and_derive() {
        let mut rng = Rng::new(2);
        let mut derived = 0;
        for _ in 0..40 {
            let text = render(&tree(&mut rng));
            let model = match Model::parse(&text, &[]) {
                Ok(model) => model,
                // Generated pieces that cannot act (a rolling contact whose
                // point the tree keeps still, a torque on a body that does not
                // turn, a force at a point nothing moves), which the loader refuses.
                Err(e) if e.kind == mech::ModelErrorKind::DoesNothing => continue,
                Err(e) => panic!("{e:?}\n{text}"),
            };
            derived += usize::from(Derivation::new(model).is_ok());
        }
        assert!(derived > 25, "{derived}");
    }

    #[test]
    fn an_undecided_energy_verdict_is_no_finding() {
        // A tree whose h − (T + U₀) is zero but not proven so by rewriting:
        // derive says "undecided" (EnergyUndecided), which the oracle took
        // for a wrong answer.
        let text = "# intact tree\n\
name = \"random body tree\"\n\
coordinates = [\"al0\", \"be0\", \"ga0\", \"x0\", \"th1\", \"th2\", \"x2\"]\n\
[parameters]\n\
m = 1.0\n\
A = 1.0\n\
B = 2.0\n\
C = 2.5\n\
R = 0.5\n\
l = 1.0\n\
g = 9.81\n\
k = 0.2\n\
[[bodies]]\n\
name = \"b0\"\n\
angles = [\"al0\", \"be0\", \"ga0\"]\n\
inertia = [\"A\", \"B\", \"C\"]\n\
mass = \"m\"\n\
position = [\"0.3\", \"x0\", \"0.3\"]\n\
[[bodies]]\n\
name = \"b1\"\n\
parent = \"b0\"\n\
angle = \"th1\"\n\
axis = \"z\"\n\
inertia = [\"A\", \"B\", \"C\"]\n\
mass = 1.5\n\
position = [\"0.3\", \"0.3\", \"0.3\"]\n\
[[bodies]]\n\
name = \"b2\"\n\
angle = \"th2\"\n\
axis = \"x\"\n\
inertia = \"A\"\n\
mass = 1.5\n\
position = [\"0.3\", \"-l/2\", \"l*x2\"]\n\
center_of_mass = [\"0\", \"0.2\", \"0.2\"]\n\
[[constraints]]\n\
name = \"roll\"\n\
rolling = \"b0\"\n\
radius = \"R\"\n\
contact = \"constraint\"\n\
[initial]\n\
al0 = 0.3\n\
\"al0'\" = 0.5\n\
be0 = 0.7\n\
\"be0'\" = 0\n\
ga0 = -0.2\n\
\"ga0'\" = -1.5\n\
x0 = 0.1\n\
\"x0'\" = -0.2\n\
th1 = 0.4\n\
\"th1'\" = 0.3\n\
th2 = 0.4\n\
\"th2'\" = 0.3\n\
x2 = 0.1\n\
\"x2'\" = -0.2\n";
        let outcome = check_bodies(text);
        // Since float sums that cancel to round-off are zero, derive decides
        // this one; either answer must leave the oracle content.
        assert!(outcome.problem.is_none(), "{outcome:?}");
    }

    #[test]
    fn an_undecided_cyclic_coordinate_is_no_finding() {
        // th0 turns the whole tree about a fixed axis without gravity: ∂L/∂th0
        // is zero, but derive cannot prove it and says so (CyclicReason::Undecided).
        let text = "# intact tree\n\
coordinates = [\"th0\", \"al1\", \"be1\", \"ga1\"]\n\
[[bodies]]\n\
name = \"b0\"\n\
angle = \"th0\"\n\
axis = [1, 2, 2]\n\
inertia = [1, 2, 2.5]\n\
mass = 1\n\
[[bodies]]\n\
name = \"b1\"\n\
parent = \"b0\"\n\
angles = [\"al1\", \"be1\", \"ga1\"]\n\
inertia = [1, 2, 2.5]\n\
mass = 1.5\n\
position = [1, -0.5, 0]\n\
[initial]\n\
th0 = 0.4\n\
al1 = 0.3\n\
be1 = 0.7\n\
ga1 = -0.2\n\
\"th0'\" = 0.3\n\
\"al1'\" = 0.5\n\
\"be1'\" = 0\n\
\"ga1'\" = -1.5\n";
        let outcome = check_bodies(text);
        // Derive now proves it (float sums that cancel to round-off are zero);
        // either answer must leave the oracle content.
        assert!(outcome.problem.is_none(), "{outcome:?}");
    }
}
