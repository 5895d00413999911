//! How a linearization looks: [`text`] gives the operating point and how it
//! was found (every equilibrium met near the start, with its stability), the
//! constraints eliminated, the state, A, its eigenvalues (decay rate and
//! damped frequency) and the verdict. The computation is `mech::linearize`.

use crate::{human, Terms};
use mech::{About, Derivation, Linearization, LinearizeConfig, Stability};
use std::fmt::Write as _;

/// Largest state whose A is printed in the text output.
const MAX_PRINTED_STATE: usize = 12;

fn matrix_lines(m: &[Vec<f64>]) -> Vec<String> {
    let cells: Vec<Vec<String>> = m.iter().map(|row| row.iter().map(|v| human(*v)).collect()).collect();
    let width = cells.iter().flatten().map(|c| c.chars().count()).max().unwrap_or(1);
    cells
        .iter()
        .map(|row| format!("[ {} ]", row.iter().map(|c| format!("{c:>width$}")).collect::<Vec<_>>().join("  ")))
        .collect()
}

fn point(names: &[String], values: &[f64]) -> String {
    let parts: Vec<String> = names.iter().zip(values).map(|(n, v)| format!("{n} = {}", human(*v))).collect();
    parts.join(", ")
}

/// The eigenvalues, a conjugate pair on one line, equal ones counted.
pub fn eigenvalue_lines(ev: &[(f64, f64)]) -> Vec<String> {
    let mut lines = Vec::new();
    let mut k = 0;
    while k < ev.len() {
        let (re, im) = ev[k];
        let pair = im > 0.0 && ev.get(k + 1).is_some_and(|&(r2, i2)| r2 == re && i2 == -im);
        if pair {
            lines.push(format!(
                "s = {} ± {}i    decay rate {}, damped frequency {}",
                human(re),
                human(im),
                human(-re),
                human(im)
            ));
            k += 2;
        } else if im == 0.0 {
            let same = ev[k..].iter().take_while(|&&e| e == (re, 0.0)).count();
            let times = if same > 1 { format!(" (×{same})") } else { String::new() };
            let what = if re == 0.0 { "neutral: neither grows nor decays" } else { "no oscillation" };
            lines.push(format!("s = {}{times}    decay rate {}  ({what})", human(re), human(-re)));
            k += same;
        } else {
            let sign = if im < 0.0 { "−" } else { "+" };
            lines.push(format!("s = {} {sign} {}i    decay rate {}", human(re), human(im.abs()), human(-re)));
            k += 1;
        }
    }
    lines
}

/// The linearization as text; `config` says where the search started, `terms`
/// how the front end names its settings.
pub fn text(d: &Derivation, l: &Linearization, config: &LinearizeConfig, terms: &Terms) -> String {
    let mut s = String::new();
    let what = match l.about {
        About::Equilibrium => "an equilibrium",
        About::Steady => "a steady motion",
    };
    let _ = writeln!(s, "{} — linearization about {what}\n", d.model().name);
    let from = if config.at.is_empty() { "[initial]" } else { terms.start_at };
    match l.about {
        About::Equilibrium => {
            let _ = writeln!(s, "Equilibrium (q' = 0, q'' = 0; Newton from {from}):");
        }
        About::Steady => {
            let _ = writeln!(
                s,
                "Steady motion (cyclic coordinates at constant rates, the others still; Newton from {from}):"
            );
        }
    }
    let width = l.coordinates.iter().map(|c| c.chars().count() + 1).max().unwrap_or(1);
    for (i, c) in l.coordinates.iter().enumerate() {
        let mut line = format!("  {c:<width$} = {}", human(l.q[i]));
        if l.qd[i] != 0.0 {
            let _ = write!(line, "    {:<width$} = {}", format!("{c}'"), human(l.qd[i]));
        }
        if l.qdd[i] != 0.0 {
            let _ = write!(line, "    {c}'' = {}", human(l.qdd[i]));
        }
        let _ = writeln!(s, "{line}");
    }
    if !l.moving.is_empty() {
        let rates: Vec<String> = l.moving.iter().map(|(c, r)| format!("{c}' = {}", human(*r))).collect();
        let _ = writeln!(s, "  moving at constant rates: {}", rates.join(", "));
    }
    for (name, v) in &l.multipliers {
        let _ = writeln!(s, "  λ_{name} = {}", human(*v));
    }
    if l.equilibria.len() > 1 || l.landing != Some(l.chosen) {
        let kind = match l.about {
            About::Equilibrium => "Equilibria",
            About::Steady => "Steady motions",
        };
        let _ = writeln!(s, "{kind} found near the start:");
        for (i, e) in l.equilibria.iter().enumerate() {
            let mut marks = Vec::new();
            if l.landing == Some(i) {
                marks.push("reached from the start");
            }
            if l.chosen == i {
                marks.push("linearized here");
            }
            let marks = if marks.is_empty() { String::new() } else { format!("  ({})", marks.join("; ")) };
            let _ = writeln!(s, "  {}: {}{marks}", point(&l.unknowns, &e.x), e.stability.word());
        }
    }
    if !l.idle.is_empty() {
        let _ = writeln!(s, "Idle (no inertia, left out): {}", l.idle.join(", "));
    }
    if !l.dependent_coordinates.is_empty() || !l.dependent_speeds.is_empty() {
        let _ = writeln!(
            s,
            "Eliminated by the constraints: coordinates {}; speeds {}",
            if l.dependent_coordinates.is_empty() { "none".into() } else { l.dependent_coordinates.join(", ") },
            if l.dependent_speeds.is_empty() { "none".into() } else { l.dependent_speeds.join(", ") }
        );
    }
    let n = l.state.len();
    let _ = writeln!(s, "\nState x = ({}), x' = A x:", l.state.join(", "));
    if n <= MAX_PRINTED_STATE {
        for (i, line) in matrix_lines(&l.a).iter().enumerate() {
            let label = if i == 0 { "A = " } else { "    " };
            let _ = writeln!(s, "  {label}{line}");
        }
    } else {
        let _ = writeln!(s, "  ({n}×{n} matrix; see {})", terms.full_output);
    }
    match &l.b {
        None => {
            let _ = writeln!(s, "  B: none (the model has no inputs)");
        }
        Some(b) => {
            let _ =
                writeln!(s, "\nInputs u = ({}) at u₀ (their values at t = 0), x' = A x + B u:", l.inputs.join(", "));
            if n <= MAX_PRINTED_STATE {
                for (i, line) in matrix_lines(b).iter().enumerate() {
                    let label = if i == 0 { "B = " } else { "    " };
                    let _ = writeln!(s, "  {label}{line}");
                }
            } else {
                let _ = writeln!(s, "  ({n}×{} matrix; see {})", l.inputs.len(), terms.full_output);
            }
        }
    }
    let _ = writeln!(s, "\nEigenvalues s of A (solutions e^(s t)):");
    for line in eigenvalue_lines(&l.eigenvalues) {
        let _ = writeln!(s, "  {line}");
    }
    let _ = writeln!(
        s,
        "\n{}",
        match l.stability {
            Stability::Stable => "Stable: every Re s < 0, so a small deviation dies away.",
            Stability::Marginal => "Marginal: no Re s > 0, but some Re s = 0: the linearization neither grows nor decays along those (an undamped oscillation, a free or cyclic motion); the nonlinear terms decide.",
            Stability::Unstable => "Unstable: some Re s > 0, so a small deviation grows exponentially.",
        }
    );
    for note in &l.notes {
        let _ = writeln!(s, "Note: {note}.");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvalues_pair_up_and_zeros_are_counted() {
        let lines = eigenvalue_lines(&[(0.0, 2.0), (0.0, -2.0), (0.0, 0.0), (0.0, 0.0), (-1.0, 0.0)]);
        assert_eq!(lines[0], "s = 0 ± 2i    decay rate 0, damped frequency 2");
        assert_eq!(lines[1], "s = 0 (×2)    decay rate 0  (neutral: neither grows nor decays)");
        assert_eq!(lines[2], "s = -1    decay rate 1  (no oscillation)");
    }
}
