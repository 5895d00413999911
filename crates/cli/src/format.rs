//! The human formats of `derive`: text that reads like the lecture notes, and
//! LaTeX. (JSON is the `mech::DeriveReport` serialized as it is.)

use mech::Derivation;
use std::fmt::Write;
use sym::ExprId;

/// The derivation as text, with the notes' names and the reasons behind each verdict.
pub fn text(d: &Derivation) -> String {
    let pool = d.pool();
    let s = |e: ExprId| pool.display(e).to_string();
    let names = d.coordinate_names();
    let n = names.len();
    let mut o = String::new();
    let _ = writeln!(o, "{}", d.model().name);
    if d.constraints().is_empty() {
        let _ = writeln!(o, "{} degree{} of freedom: {}", n, if n == 1 { "" } else { "s" }, names.join(", "));
    } else {
        let k = d.constraints().degrees_of_freedom;
        let _ = writeln!(
            o,
            "{} coordinate{}: {}; {} constraint{}: {} degree{} of freedom",
            n,
            if n == 1 { "" } else { "s" },
            names.join(", "),
            d.constraints().list.len(),
            if d.constraints().list.len() == 1 { "" } else { "s" },
            k,
            if k == 1 { "" } else { "s" }
        );
    }
    if !d.model().parameters.is_empty() {
        let ps: Vec<String> = d.model().parameters.iter().map(|p| format!("{} = {}", p.name, p.value)).collect();
        let _ = writeln!(o, "parameters: {}", ps.join(", "));
    }
    o.push('\n');
    if let Some(t) = d.kinetic() {
        let _ = writeln!(o, "kinetic energy      T = {}", s(t));
    }
    if let Some(u) = d.potential() {
        let _ = writeln!(o, "potential           U = {}", s(u));
    }
    let _ = writeln!(o, "Lagrangian          L = {}", s(d.lagrangian()));
    if let Some(r) = d.dissipation() {
        let _ = writeln!(o, "dissipation         R = {}", s(r));
    }
    for (i, f) in d.forces().iter().enumerate() {
        if !pool.is_zero(*f) {
            let _ = writeln!(o, "generalized force   Q_{} = {}", names[i], s(*f));
        }
    }
    for b in d.bodies() {
        let _ = writeln!(o, "\nrigid body '{}' (body frame, notes A.5)", b.name);
        for k in 0..3 {
            let _ = writeln!(o, "  angular velocity  ω{} = {}", k + 1, s(b.omega[k]));
        }
        for k in 0..3 {
            let _ = writeln!(o, "  angular momentum  L{} = {}", k + 1, s(b.angular_momentum[k]));
        }
    }

    let _ = writeln!(o, "\ngeneralized momenta p_q = ∂L/∂q'");
    for i in 0..n {
        let _ = writeln!(o, "  p_{} = {}", names[i], s(d.momenta()[i]));
    }

    let _ = writeln!(
        o,
        "\nEuler–Lagrange equations  d/dt ∂L/∂q' − ∂L/∂q{}{} = 0",
        if d.dissipation().is_some() { " + ∂R/∂q'" } else { "" },
        if d.forces().iter().any(|f| !pool.is_zero(*f)) { " − Q" } else { "" }
    );
    let label_w = names.iter().map(|n| n.chars().count()).max().unwrap_or(1) + 1;
    for i in 0..n {
        let _ = writeln!(o, "  {:<label_w$} {} = 0", format!("{}:", names[i]), s(d.equations()[i]));
    }

    let _ = writeln!(o, "\nin the form M(q, t) q'' = f(q, q', t)");
    let cells: Vec<Vec<String>> = d.mass_matrix().iter().map(|row| row.iter().map(|&e| s(e)).collect()).collect();
    let widths: Vec<usize> =
        (0..n).map(|j| cells.iter().map(|row| row[j].chars().count()).max().unwrap_or(1)).collect();
    let name_w = names.iter().map(|n| n.chars().count()).max().unwrap_or(1);
    for i in 0..n {
        let row: Vec<String> = (0..n).map(|j| format!("{:<w$}", cells[i][j], w = widths[j])).collect();
        let _ = writeln!(
            o,
            "  {} [ {} ] {:<name_w$}  =  {}",
            if i == n / 2 { "M =" } else { "   " },
            row.join("  "),
            format!("{}''", names[i]),
            s(d.forcing()[i]),
            name_w = name_w + 2
        );
    }

    if !d.constraints().is_empty() {
        constraints_text(d, &mut o);
    }

    let _ = writeln!(o, "\ncyclic coordinates");
    if d.cyclic().is_empty() {
        let _ = writeln!(o, "  none: L depends on every coordinate");
    } else {
        for &i in d.cyclic() {
            let conserved = d.conserved().iter().any(|c| c.name == format!("p_{}", names[i]));
            let _ = writeln!(
                o,
                "  {}: ∂L/∂{} = 0, so p_{} = {} {}",
                names[i],
                names[i],
                names[i],
                s(d.momenta()[i]),
                if conserved {
                    "is conserved"
                } else if d.constraints().list.iter().any(|c| !pool.is_zero(c.jacobian[i])) {
                    "would be conserved, but a constraint force acts on it"
                } else {
                    "would be conserved, but dissipation or a force acts on it"
                }
            );
        }
    }

    let _ = writeln!(o, "\nHamiltonian  H = Σ q'·p − L, in (q, p, t)");
    match d.hamiltonian() {
        Some(h) => {
            let _ = writeln!(o, "  H = {}", s(h));
        }
        None => {
            let _ = writeln!(o, "  (not in closed form) h(q, q', t) = {}", s(d.energy_function()));
            for line in &d.verdicts().hamiltonian {
                let _ = writeln!(o, "    {line}");
            }
        }
    }
    if let Some(e) = d.energy() {
        let _ = writeln!(o, "  energy T + U = {}", s(e));
    }
    let verdict = match d.hamiltonian_is_energy() {
        Some(true) => "H is the energy",
        Some(false) => "H is not the energy",
        None => "whether H is the energy is not known",
    };
    let _ = writeln!(o, "  {verdict}:");
    for line in &d.verdicts().energy {
        let _ = writeln!(o, "    {line}");
    }
    let _ = writeln!(o, "  H is {}conserved:", if d.hamiltonian_conserved() { "" } else { "not " });
    for line in &d.verdicts().conservation {
        let _ = writeln!(o, "    {line}");
    }

    if let Some(eqs) = &d.hamilton() {
        let _ = writeln!(
            o,
            "\nHamilton's equations  q' = ∂H/∂p,  p' = −∂H/∂q{}",
            if d.dissipation().is_some() || d.forces().iter().any(|f| !pool.is_zero(*f)) {
                " − ∂R/∂q' + Q"
            } else {
                ""
            }
        );
        for (i, &(dq, dp)) in eqs.iter().enumerate() {
            let _ = writeln!(o, "  {}' = {}", names[i], s(dq));
            let _ = writeln!(o, "  p_{}' = {}", names[i], s(dp));
        }
    }
    o
}

/// The constraints section: each constraint with its row of A and its verdicts,
/// the equations with multipliers, and the constraint forces.
fn constraints_text(d: &Derivation, o: &mut String) {
    let pool = d.pool();
    let s = |e: ExprId| pool.display(e).to_string();
    let names = d.coordinate_names();
    let set = &d.constraints();
    let _ =
        writeln!(o, "\nconstraints (A = ∂f/∂q for f(q, t) = 0; the velocity coefficients for a(q, t)·q' + a_t = 0)");
    for c in &set.list {
        let tags = [
            Some(c.kind.name()),
            Some(if c.rheonomic { "rheonomic" } else { "scleronomic" }),
            match (c.kind, c.integrable) {
                (mech::ConstraintKind::Velocity, Some(true)) => Some("integrable"),
                (mech::ConstraintKind::Velocity, _) => Some("not integrable"),
                _ => None,
            },
        ];
        let tags: Vec<&str> = tags.into_iter().flatten().collect();
        let _ = writeln!(o, "  {}: {} = 0   ({})", c.name, s(c.expr), tags.join(", "));
        let row: Vec<String> = c.jacobian.iter().map(|&e| s(e)).collect();
        let _ = writeln!(
            o,
            "    A row = [{}]{}",
            row.join(", "),
            if pool.is_zero(c.time_term) { String::new() } else { format!(",  a_t = {}", s(c.time_term)) }
        );
        for line in &c.explanation {
            let _ = writeln!(o, "    {line}");
        }
    }
    for line in &set.explanation {
        let _ = writeln!(o, "  {line}");
    }
    let lambdas: Vec<String> = set.list.iter().map(|c| s(c.multiplier)).collect();
    let _ = writeln!(o, "\nequations with multipliers  M q'' = f + Aᵀλ,  λ = ({})", lambdas.join(", "));
    let label_w = names.iter().map(|n| n.chars().count()).max().unwrap_or(1) + 1;
    for (i, &e) in set.multiplier_equations.iter().enumerate() {
        let _ = writeln!(o, "  {:<label_w$} {} = 0", format!("{}:", names[i]), s(e));
    }
    let _ = writeln!(
        o,
        "  with the constraints differentiated to A q'' = c (index reduction), q'' and λ follow at each instant."
    );
    let _ = writeln!(o, "\nconstraint forces  Q = Aᵀλ (generalized)");
    for (i, &f) in set.generalized_forces.iter().enumerate() {
        let _ = writeln!(o, "  Q_{} = {}", names[i], s(f));
    }
    if let Some(parts) = &set.cartesian_forces {
        let _ = writeln!(o, "  Cartesian, on each particle (F with Q = (∂x/∂q)ᵀF):");
        for (k, f) in parts.iter().enumerate() {
            let comps: Vec<String> = f.iter().map(|&e| s(e)).collect();
            let _ = writeln!(o, "    particle {}: F = ({})", k + 1, comps.join(", "));
        }
    }
}

/// The derivation as LaTeX (an `align*` environment per section).
pub fn latex(d: &Derivation) -> String {
    let pool = d.pool();
    let l = |e: ExprId| pool.latex(e).to_string();
    let names = d.coordinate_names();
    let qtex: Vec<String> = d.q().iter().map(|&q| l(q)).collect();
    let n = names.len();
    let mut o = String::new();
    let _ = writeln!(o, "% {} (lagrange derive --format latex)", d.model().name);
    let _ = writeln!(o, "\\begin{{align*}}");
    if let Some(t) = d.kinetic() {
        let _ = writeln!(o, "T &= {} \\\\", l(t));
    }
    if let Some(u) = d.potential() {
        let _ = writeln!(o, "U &= {} \\\\", l(u));
    }
    let _ = writeln!(o, "L &= {} \\\\", l(d.lagrangian()));
    if let Some(r) = d.dissipation() {
        let _ = writeln!(o, "R &= {} \\\\", l(r));
    }
    for i in 0..n {
        let _ = writeln!(o, "{} &= {} \\\\", l(d.p()[i]), l(d.momenta()[i]));
    }
    for i in 0..n {
        let sep = if i + 1 < n || d.hamiltonian().is_some() { " \\\\" } else { "" };
        let _ = writeln!(o, "0 &= {}{}  % equation of motion for ${}$", l(d.equations()[i]), sep, qtex[i]);
    }
    if let Some(h) = d.hamiltonian() {
        let _ = writeln!(o, "H &= {}", l(h));
    }
    let _ = writeln!(o, "\\end{{align*}}");
    if !d.constraints().is_empty() {
        // The constraints and the equations with multipliers.
        let _ = writeln!(o, "\\begin{{align*}}");
        for c in &d.constraints().list {
            let _ = writeln!(o, "0 &= {} \\\\  % constraint {} ({})", l(c.expr), c.name, c.kind.name());
        }
        let eqs = &d.constraints().multiplier_equations;
        for (i, &e) in eqs.iter().enumerate() {
            let sep = if i + 1 < eqs.len() { " \\\\" } else { "" };
            let _ = writeln!(o, "0 &= {}{}  % with multipliers, for ${}$", l(e), sep, qtex[i]);
        }
        let _ = writeln!(o, "\\end{{align*}}");
    }
    if let Some(eqs) = &d.hamilton() {
        let _ = writeln!(o, "\\begin{{align*}}");
        for (i, &(dq, dp)) in eqs.iter().enumerate() {
            let qd = l(d.qd()[i]);
            let pd = format!("\\dot{{{}}}", l(d.p()[i]));
            let end = if i + 1 < n { " \\\\" } else { "" };
            let _ = writeln!(o, "{} &= {}, & {} &= {}{}", qd, l(dq), pd, l(dp), end);
        }
        let _ = writeln!(o, "\\end{{align*}}");
    }
    o
}
