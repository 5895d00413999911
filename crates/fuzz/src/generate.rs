//! Valid models from a small grammar, for derive (target (c)) and for the
//! differential test against SymPy. Enter with [`model`].
//!
//! A model has 1 to 3 coordinates and 2 to 6 parameters (all positive), and is
//! one of: a `lagrangian`; `kinetic` and `potential`; `[[particles]]` (with
//! gravity, particle potentials, and sometimes an extra `kinetic`); or, with
//! three coordinates, a rigid body whose Euler angles they are. The kinetic
//! energy is ½ Σ (P + E(q)²) q'² plus couplings |c| ≤ 1/10 and velocity-linear
//! terms, so its mass matrix is diagonally dominant and regular (particles alone
//! may be singular; derive must then say so). Sometimes: a quartic velocity
//! term (L not quadratic), a velocity-dependent potential, explicit time,
//! dissipation, generalized forces, a constraint. Expressions are sums,
//! products and powers of coordinates, parameters and small numbers under sin,
//! cos, exp, sqrt, log, atan, tanh and cosh, kept finite on the whole state space.

use crate::rng::Rng;
use std::fmt::Write;

/// Names coordinates are drawn from.
const COORDINATES: &[&str] = &["x", "y", "z", "th", "ph", "r", "s", "u"];
/// Names parameters are drawn from (`g` is the gravity's when there is one).
const PARAMETERS: &[&str] = &["m", "k", "l", "c", "w", "a", "b", "M"];

/// The names a model's expressions may use.
struct Names {
    coordinates: Vec<&'static str>,
    parameters: Vec<&'static str>,
}

/// A random valid model file.
pub fn model(rng: &mut Rng) -> String {
    let n = 1 + rng.below(3);
    let mut coordinates: Vec<&str> = Vec::new();
    while coordinates.len() < n {
        let c = *rng.pick(COORDINATES);
        if !coordinates.contains(&c) {
            coordinates.push(c);
        }
    }
    let n_params = 2 + rng.below(5);
    let mut parameters: Vec<&str> = Vec::new();
    while parameters.len() < n_params {
        let p = *rng.pick(PARAMETERS);
        if !parameters.contains(&p) {
            parameters.push(p);
        }
    }
    let names = Names { coordinates, parameters };
    let time = rng.chance(0.2);

    let mut out = String::new();
    let list = |items: &[&str]| items.iter().map(|c| format!("\"{c}\"")).collect::<Vec<_>>().join(", ");
    let _ = writeln!(out, "name = \"generated\"");
    let _ = writeln!(out, "coordinates = [{}]", list(&names.coordinates));
    // 0: lagrangian, 1: kinetic and potential, 2: particles, 3: a rigid body
    // whose Euler angles are the three coordinates.
    let style = if names.coordinates.len() == 3 && rng.chance(0.25) { 3 } else { rng.below(3) };
    let gravity = style >= 2 && rng.chance(0.5);
    if gravity {
        let _ = writeln!(out, "gravity = \"g\"");
    }
    match style {
        0 => {
            let t = kinetic(rng, &names);
            let u = potential(rng, &names, time);
            let _ = writeln!(out, "lagrangian = \"{t} - ({u})\"");
        }
        1 => {
            let _ = writeln!(out, "kinetic = \"{}\"", kinetic(rng, &names));
            let _ = writeln!(out, "potential = \"{}\"", potential(rng, &names, time));
        }
        2 => {
            if rng.chance(0.5) {
                let _ = writeln!(out, "kinetic = \"{}\"", kinetic(rng, &names));
            }
            if rng.chance(0.3) {
                let _ = writeln!(out, "potential = \"{}\"", potential(rng, &names, time));
            }
        }
        _ => {
            if rng.chance(0.3) {
                let _ = writeln!(out, "potential = \"{}\"", potential(rng, &names, time));
            }
        }
    }
    if rng.chance(0.3) {
        let mut terms = Vec::new();
        for c in &names.coordinates {
            if rng.chance(0.7) {
                let p = rng.pick(&names.parameters);
                terms.push(format!("1/2*{p}*(1 + ({})^2)*{c}'^2", config(rng, &names, 1, false)));
            }
        }
        if !terms.is_empty() {
            let _ = writeln!(out, "dissipation = \"{}\"", terms.join(" + "));
        }
    }

    let _ = writeln!(out, "\n[parameters]");
    for p in &names.parameters {
        let _ = writeln!(out, "{p} = {:.3}", rng.range(0.5, 2.5));
    }
    if gravity {
        let _ = writeln!(out, "g = 9.81");
    }

    if style == 3 {
        let p = |rng: &mut Rng| rng.pick(&names.parameters).to_string();
        // Principal moments from second moments a, b, c ≥ 0 of the mass
        // (I1 = b + c, I2 = a + c, I3 = a + b), so that each is at most the
        // sum of the other two, as a rigid body's are; a = b for a symmetric one.
        let (a, b, c) = (p(rng), p(rng), p(rng));
        let (i1, i2, i3) = if rng.chance(0.5) {
            (format!("{b} + {c}"), format!("{b} + {c}"), format!("2*{b}"))
        } else {
            (format!("{b} + {c}"), format!("{a} + {c}"), format!("{a} + {b}"))
        };
        let position = if rng.chance(0.7) {
            "\"0\", \"0\", \"0\"".to_string()
        } else {
            format!("\"0\", \"0\", \"{}*cos(t)\"", p(rng))
        };
        let angles = names.coordinates.iter().map(|c| format!("\"{c}\"")).collect::<Vec<_>>().join(", ");
        let _ = writeln!(
            out,
            "\n[[bodies]]\nmass = \"{}\"\ninertia = [\"{i1}\", \"{i2}\", \"{i3}\"]\nangles = [{angles}]\nposition = [{position}]\ncenter_of_mass = [\"0\", \"0\", \"{}\"]",
            p(rng),
            p(rng)
        );
    }
    if style == 2 {
        for _ in 0..1 + rng.below(3) {
            let dims = if gravity { 2 + rng.below(2) } else { 1 + rng.below(3) };
            let mut position = Vec::new();
            for _ in 0..dims {
                let moving = time && rng.chance(0.3);
                position.push(format!("\"{}\"", config(rng, &names, 2, moving)));
            }
            let mass = if rng.chance(0.7) { format!("\"{}\"", rng.pick(&names.parameters)) } else { "1.5".into() };
            let _ = writeln!(out, "\n[[particles]]\nmass = {mass}\nposition = [{}]", position.join(", "));
            if rng.chance(0.2) {
                let _ = writeln!(out, "potential = \"{}\"", config(rng, &names, 1, false));
            }
        }
    }

    let mut forced = Vec::new();
    for &c in &names.coordinates {
        if rng.chance(0.2) {
            let p = rng.pick(&names.parameters);
            forced.push((c, format!("-{p}*{c}' + {}", config(rng, &names, 1, time))));
        }
    }
    if !forced.is_empty() {
        let _ = writeln!(out, "\n[forces]");
        for (c, f) in forced {
            let _ = writeln!(out, "{c} = \"{f}\"");
        }
    }

    if names.coordinates.len() >= 2 && rng.chance(0.15) {
        let (a, b) = (names.coordinates[0], names.coordinates[1]);
        let _ = writeln!(out, "\n[[constraints]]\nname = \"link\"");
        if rng.chance(0.6) {
            let moving = rng.chance(0.3);
            let _ = writeln!(out, "holonomic = \"{a} - {}\"", config(rng, &names, 1, moving));
        } else {
            let _ = writeln!(out, "velocity = \"{a}' - ({})*{b}'\"", config(rng, &names, 1, false));
        }
    }

    let _ = writeln!(out, "\n[initial]");
    for c in &names.coordinates {
        let _ = writeln!(out, "{c} = {:.3}\n\"{c}'\" = {:.3}", rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
    }
    out
}

/// T: ½ Σ (P + E(q)²) q'², couplings at most 1/10, sometimes velocity-linear
/// and quartic terms.
fn kinetic(rng: &mut Rng, names: &Names) -> String {
    let qs = &names.coordinates;
    let mut terms = Vec::new();
    for q in qs {
        let p = rng.pick(&names.parameters);
        if rng.chance(0.5) {
            terms.push(format!("1/2*({p} + ({})^2)*{q}'^2", config(rng, names, 1, false)));
        } else {
            terms.push(format!("1/2*{p}*{q}'^2"));
        }
    }
    for i in 0..qs.len() {
        for j in i + 1..qs.len() {
            if rng.chance(0.4) {
                terms.push(format!("1/10*sin({})*{}'*{}'", config(rng, names, 1, false), qs[i], qs[j]));
            }
        }
    }
    if rng.chance(0.3) {
        let q = rng.pick(qs);
        terms.push(format!("({})*{q}'", config(rng, names, 1, false)));
    }
    if rng.chance(0.1) {
        let q = rng.pick(qs);
        terms.push(format!("{}/12*{q}'^4", rng.pick(&names.parameters)));
    }
    terms.join(" + ")
}

/// U: 1 to 3 terms in (q, t), sometimes a velocity-dependent term.
fn potential(rng: &mut Rng, names: &Names, time: bool) -> String {
    let mut terms: Vec<String> = (0..1 + rng.below(3)).map(|_| config(rng, names, 2, time)).collect();
    if rng.chance(0.2) {
        let q = rng.pick(&names.coordinates);
        terms.push(format!("({})*{q}'", config(rng, names, 1, false)));
    }
    terms.join(" + ")
}

/// An expression in the coordinates, parameters and (when `time`) t, of depth
/// at most `depth`, finite everywhere.
fn config(rng: &mut Rng, names: &Names, depth: usize, time: bool) -> String {
    if depth == 0 || rng.chance(0.3) {
        return match rng.below(10) {
            0..=3 => rng.pick(&names.coordinates).to_string(),
            4..=5 => rng.pick(&names.parameters).to_string(),
            6 => (1 + rng.below(4)).to_string(),
            7 => rng.pick(&["1/2", "3/2", "0.3", "2.5"]).to_string(),
            _ if time => "t".into(),
            _ => rng.pick(&names.coordinates).to_string(),
        };
    }
    let mut sub = || config(rng, names, depth - 1, time);
    let (a, b) = (sub(), sub());
    match rng.below(14) {
        0 | 1 => format!("{a} + {b}"),
        2 => format!("{a} - {b}"),
        3 | 4 => format!("({a})*({b})"),
        5 => format!("sin({a})"),
        6 => format!("cos({a})"),
        7 => format!("({a})^2"),
        8 => format!("({a})^3"),
        9 => format!("exp(-({a})^2)"),
        10 => format!("sqrt(2 + ({a})^2)"),
        11 => format!("log(3 + sin({a}))"),
        12 => format!("atan({a}) + tanh({b})"),
        _ => format!("({a})/(2 + cos({b}))"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_models_load_and_most_derive() {
        let mut derived = 0;
        for i in 0..200 {
            let text = model(&mut Rng::new(i));
            let m = mech::Model::parse(&text, &[]).unwrap_or_else(|e| panic!("{text}\n{e}"));
            derived += usize::from(mech::Derivation::new(m).is_ok());
        }
        assert!(derived > 150, "only {derived} of 200 models derive");
    }
}
