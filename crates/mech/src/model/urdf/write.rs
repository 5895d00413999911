//! A planned robot written as a model file: `coordinates`, gravity `g` along
//! −z (URDF's convention), `[initial]` at rest at zero, and one `[[bodies]]`
//! table per body, with comments saying which link and joint each came from
//! and what of the URDF was left out.
//!
//! Entry: [`model_text`]. Numbers are written with their shortest round-trip
//! digits, so the model holds exactly the numbers the import computed.

use super::tree::{Motion, Plan, PlanBody};
use std::fmt::Write;

/// The model file's text; `source` names the URDF file in the header comment.
pub(crate) fn model_text(plan: &Plan, source: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# The URDF robot '{}' ({source}), as a model file.", one_line(&plan.robot));
    s.push_str(
        "# Each moving joint is a body: it turns about (revolute, continuous) or slides along\n\
         # (prismatic) the joint's axis, from the joint's origin in its parent body's frame;\n\
         # a floating joint gives x, y, z and roll, pitch, yaw (sequence \"xyz\") in the parent's axes.\n\
         # Links on fixed joints are merged into the body they hang from (mass, centre of\n\
         # mass and inertia about the body's reference point, the joint's origin).\n",
    );
    if !plan.grounded.is_empty() {
        let _ = writeln!(
            s,
            "# Fixed to the world (not moving, so not in the model): {}.",
            plan.grounded.iter().map(|l| one_line(l)).collect::<Vec<_>>().join(", ")
        );
    }
    s.push_str("# Left out (no mechanics here): joint limits, effort, velocity, damping and friction, mimic");
    for tag in &plan.ignored {
        let _ = write!(s, ", {}", one_line(tag));
    }
    s.push_str(".\n");
    let _ = writeln!(s, "name = {}", quoted(&plan.robot));
    let names: Vec<String> = plan.coordinates.iter().map(|c| quoted(&c.name)).collect();
    let _ = writeln!(s, "coordinates = [{}]", names.join(", "));
    s.push_str("gravity = \"g\"                 # along -z, as URDF has it\n\n");
    s.push_str("[parameters]\ng = 9.81\n\n[initial]\n");
    for c in &plan.coordinates {
        let from = if c.name == c.joint { String::new() } else { format!("   # joint '{}'", one_line(&c.joint)) };
        let _ = writeln!(s, "{} = 0{from}\n{} = 0", c.name, quoted(&format!("{}'", c.name)));
    }
    for body in &plan.bodies {
        s.push('\n');
        write_body(&mut s, plan, body);
    }
    s
}

fn write_body(s: &mut String, plan: &Plan, b: &PlanBody) {
    s.push_str("[[bodies]]\n");
    let _ = writeln!(s, "# link '{}', {} joint '{}'", one_line(&b.link), b.kind.word(), one_line(&b.joint));
    if !b.merged.is_empty() {
        let merged: Vec<String> = b.merged.iter().map(|l| one_line(l)).collect();
        let _ = writeln!(s, "# with the links on fixed joints merged in: {}", merged.join(", "));
    }
    for note in &b.ignored {
        let _ = writeln!(s, "# left out: {}", one_line(note));
    }
    let _ = writeln!(s, "name = {}", quoted(&b.name));
    if let Some(p) = b.parent {
        let _ = writeln!(s, "parent = {}", quoted(&plan.bodies[p].name));
    }
    let coord = |k: usize| plan.coordinates[k].name.as_str();
    let position: [String; 3] = match b.motion {
        Motion::Turn { .. } => b.offset.map(number),
        Motion::Slide { coord: k, axis } => [0, 1, 2].map(|i| sum(b.offset[i], &[(axis[i], coord(k))])),
        Motion::Free { coords } => [0, 1, 2].map(|i| sum(b.offset[i], &[(1.0, coord(coords[i]))])),
    };
    let _ = writeln!(s, "position = [{}]", position.join(", "));
    match b.motion {
        Motion::Turn { coord: k, axis } => {
            let _ = writeln!(s, "angle = {}", quoted(coord(k)));
            let _ = writeln!(s, "axis = {}", axis_text(axis));
        }
        Motion::Slide { axis, .. } => {
            let _ = writeln!(s, "# slides along [{}]", axis.map(number).join(", "));
        }
        Motion::Free { coords } => {
            let angles: Vec<String> = coords[3..].iter().map(|&k| quoted(coord(k))).collect();
            let _ = writeln!(s, "angles = [{}]", angles.join(", "));
            s.push_str("sequence = \"xyz\"\n");
        }
    }
    let _ = writeln!(s, "mass = {}", number(b.mass));
    let _ = writeln!(s, "center_of_mass = [{}]", b.center_of_mass.map(number).join(", "));
    let rows: Vec<String> = b.inertia.iter().map(|r| format!("[{}]", r.map(number).join(", "))).collect();
    let _ = writeln!(s, "inertia = [{}]", rows.join(", "));
    if b.frame != [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        let rows: Vec<String> = b.frame.iter().map(|r| format!("[{}]", r.map(number).join(", "))).collect();
        let _ = writeln!(s, "# the link's own axes are the columns of [{}] in this body's", rows.join(", "));
    }
}

/// An axis as a name when it is one of the frame's, else its components.
fn axis_text(axis: [f64; 3]) -> String {
    match axis {
        [1.0, 0.0, 0.0] => "\"x\"".into(),
        [0.0, 1.0, 0.0] => "\"y\"".into(),
        [0.0, 0.0, 1.0] => "\"z\"".into(),
        a => format!("[{}]", a.map(number).join(", ")),
    }
}

/// `c + Σ a·name` as an expression string, leaving out zero terms.
fn sum(c: f64, terms: &[(f64, &str)]) -> String {
    let mut out = String::new();
    if c != 0.0 {
        out.push_str(&number(c));
    }
    for &(a, name) in terms {
        if a == 0.0 {
            continue;
        }
        let term = match a {
            1.0 => name.to_string(),
            -1.0 => format!("-{name}"),
            _ => format!("{}*{name}", number(a)),
        };
        if out.is_empty() {
            out = term;
        } else if let Some(rest) = term.strip_prefix('-') {
            let _ = write!(out, " - {rest}");
        } else {
            let _ = write!(out, " + {term}");
        }
    }
    if out.is_empty() {
        "0".into()
    } else {
        quoted(&out)
    }
}

/// A number with its shortest round-trip digits (TOML and the expression
/// language read both `0.1` and `1e-7`).
fn number(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let text = format!("{x:?}");
    text.strip_suffix(".0").map_or(text.clone(), str::to_string)
}

/// A TOML basic string.
fn quoted(text: &str) -> String {
    let mut out = String::from("\"");
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Text for a comment: one line.
fn one_line(text: &str) -> String {
    text.chars().map(|c| if c.is_control() { ' ' } else { c }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_sums_read_back() {
        assert_eq!(number(0.1), "0.1");
        assert_eq!(number(1.0), "1");
        assert_eq!(number(-2.5e-7), "-2.5e-7");
        assert_eq!(number(-0.0), "0");
        assert_eq!(sum(0.0, &[(1.0, "d")]), "\"d\"");
        assert_eq!(sum(0.5, &[(-1.0, "d")]), "\"0.5 - d\"");
        assert_eq!(sum(0.5, &[(-0.25, "d")]), "\"0.5 - 0.25*d\"");
        assert_eq!(sum(0.0, &[(0.0, "d")]), "0");
        assert_eq!(quoted("a\"b\n"), "\"a\\\"b\\u000A\"");
    }
}
