//! How small oscillations look (notes, Sec. 3.3): [`text`] gives the
//! equilibrium, T and U, the secular equation, the normal frequencies and mode
//! shapes; [`animation`] an SVG of every mode, animated. The computation is
//! `mech::normal_modes`.

use crate::{human, markup, Terms};
use mech::{Derivation, ModeKind, Modes, ModesConfig};
use std::fmt::Write as _;

/// Most modes drawn by [`animation`].
const MAX_ANIMATED: usize = 12;
/// Most coordinates whose mode shapes are printed in the text output.
const MAX_PRINTED_SHAPE: usize = 8;

/// A point or a mode shape in the coordinates: `(a = 1, b = -0.5)`.
pub fn vector(names: &[String], values: &[f64]) -> String {
    let parts: Vec<String> = names.iter().zip(values).map(|(n, v)| format!("{n} = {}", human(*v))).collect();
    format!("({})", parts.join(", "))
}

fn matrix_lines(m: &[Vec<f64>]) -> Vec<String> {
    let cells: Vec<Vec<String>> = m.iter().map(|row| row.iter().map(|v| human(*v)).collect()).collect();
    let width = cells.iter().flatten().map(|c| c.chars().count()).max().unwrap_or(1);
    cells
        .iter()
        .map(|row| format!("[ {} ]", row.iter().map(|c| format!("{c:>width$}")).collect::<Vec<_>>().join("  ")))
        .collect()
}

/// The modes as text that follows the notes; `config` says where the search
/// for the equilibrium started, `terms` how the front end names its settings.
pub fn text(d: &Derivation, m: &Modes, config: &ModesConfig, terms: &Terms) -> String {
    let from_initial = config.at.is_empty();
    let n = m.coordinates.len();
    let mut s = String::new();
    let _ = writeln!(s, "{} — small oscillations (notes, Sec. 3.3)\n", d.model().name);
    let _ = writeln!(
        s,
        "Equilibrium (∂U/∂q = 0; damped Newton from {}, {} iteration{}, |∂U/∂q| = {}):",
        if from_initial { "[initial]" } else { terms.start_at },
        m.newton_iterations,
        if m.newton_iterations == 1 { "" } else { "s" },
        human(m.gradient_norm)
    );
    let width = m.coordinates.iter().map(|c| c.chars().count()).max().unwrap_or(1);
    if n > MAX_PRINTED_SHAPE && m.equilibrium.iter().all(|&v| v == 0.0) {
        let _ = writeln!(s, "  every coordinate = 0");
    } else {
        for (c, v) in m.coordinates.iter().zip(&m.equilibrium).take(MAX_PRINTED_SHAPE) {
            let _ = writeln!(s, "  {c:<width$} = {}", human(*v));
        }
        if n > MAX_PRINTED_SHAPE {
            let _ = writeln!(s, "  … ({} more; see {})", n - MAX_PRINTED_SHAPE, terms.full_output);
        }
    }
    match &m.effective_potential {
        Some(t0) => {
            let _ = writeln!(
                s,
                "  U(q₀) = {}   (the effective potential U − T₀ with T₀ = {t0}, not derive's U)",
                human(m.potential)
            );
        }
        None => {
            let _ = writeln!(s, "  U(q₀) = {}", human(m.potential));
        }
    }
    if m.equilibria.len() > 1 || m.landing != Some(m.chosen) {
        let _ = writeln!(s, "Equilibria found near the start:");
        for (i, e) in m.equilibria.iter().enumerate() {
            let mut marks = Vec::new();
            if m.landing == Some(i) {
                marks.push("reached from the start");
            }
            if m.chosen == i {
                marks.push("analysed here");
            }
            let marks = if marks.is_empty() { String::new() } else { format!("  ({})", marks.join("; ")) };
            let at: Vec<String> = m.coordinates.iter().zip(&e.x).map(|(c, v)| format!("{c} = {}", human(*v))).collect();
            let _ = writeln!(s, "  {}: {}{marks}", at.join(", "), e.stability.word());
        }
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "L ≈ ½ q'ᵀ T q' − ½ (q − q₀)ᵀ U (q − q₀), with T = M(q₀) and U = ∂²U/∂q∂q at q₀:");
    if n <= MAX_PRINTED_SHAPE {
        let (tl, ul) = (matrix_lines(&m.t_matrix), matrix_lines(&m.u_matrix));
        let tw = tl.iter().map(|l| l.chars().count()).max().unwrap_or(0);
        for i in 0..n {
            let (tlabel, ulabel) = if i == 0 { ("T = ", "U = ") } else { ("    ", "    ") };
            let _ = writeln!(s, "  {tlabel}{:<tw$}    {ulabel}{}", tl[i], ul[i]);
        }
    } else {
        let _ = writeln!(s, "  ({n}×{n} matrices; see {})", terms.full_output);
    }
    if let Some(sym) = &m.symbolic {
        let pool = &sym.pool;
        let rows = |mm: &[Vec<sym::ExprId>]| -> String {
            let r: Vec<String> = mm
                .iter()
                .map(|row| {
                    format!("[{}]", row.iter().map(|&e| pool.display(e).to_string()).collect::<Vec<_>>().join(", "))
                })
                .collect();
            format!("[{}]", r.join(", "))
        };
        let _ = writeln!(s, "  symbolically: T = {}", rows(&sym.t_matrix));
        let _ = writeln!(s, "                U = {}", rows(&sym.u_matrix));
        let _ = writeln!(s, "\nSecular equation det(U − Ω²T) = 0 (Om is Ω):");
        let _ = writeln!(s, "  {} = 0", pool.display(sym.secular));
    }
    let _ = writeln!(s, "\nNormal frequencies, ascending; mode shapes a with aᵀ T a = 1 (U a = Ω² T a):");
    let exact = m.symbolic.as_ref().and_then(|x| x.frequencies.as_ref().map(|f| (f, &x.pool)));
    for (j, mode) in m.modes.iter().enumerate() {
        let label = format!("Ω{}", j + 1);
        let value = match mode.kind {
            ModeKind::Oscillation => human(mode.frequency.unwrap_or(0.0)),
            ModeKind::Free => "0   (free motion: U is constant along this mode)".into(),
            ModeKind::Unstable => {
                format!(
                    "imaginary: Ω² = {}, growth rate {}",
                    human(mode.omega_squared),
                    human((-mode.omega_squared).sqrt())
                )
            }
        };
        let _ = writeln!(s, "  {label} = {value}");
        if let Some((ex, pool)) = exact {
            let _ = writeln!(s, "       = {}", pool.display(ex[j]));
        }
        if n <= MAX_PRINTED_SHAPE {
            let _ = writeln!(s, "       a = {}", vector(&m.coordinates, &mode.shape));
        }
    }
    if n > MAX_PRINTED_SHAPE {
        let _ = writeln!(s, "  (mode shapes of {n} coordinates: see {} or {})", terms.full_output, terms.animation);
    }
    let _ = writeln!(s);
    if m.stable {
        let _ = writeln!(
            s,
            "Stable: every Ω² ≥ 0, so U has a minimum at q₀ (up to free motions) and a small displacement q − q₀ = Σ a_λ A_λ cos(Ω_λ t + δ_λ) stays small."
        );
    } else {
        let _ = writeln!(
            s,
            "Unstable: some Ω² < 0, so U is not a minimum at q₀; a displacement along such a mode grows exponentially."
        );
    }
    if let Some(damping) = &m.damping {
        damped_text(&mut s, m, damping, terms);
    }
    for note in &m.notes {
        let _ = writeln!(s, "Note: {note}.");
    }
    s
}

/// The damped motion's section: C and the roots s, a conjugate pair on one line.
fn damped_text(s: &mut String, m: &Modes, damping: &mech::Damping, terms: &Terms) {
    let n = m.coordinates.len();
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Damped motion: T (q − q₀)'' + C (q − q₀)' + U (q − q₀) = 0 with C = ∂²R/∂q'∂q' at q₀, solutions e^(s t) with det(s²T + sC + U) = 0:"
    );
    if n <= MAX_PRINTED_SHAPE {
        for (i, line) in matrix_lines(&damping.c_matrix).iter().enumerate() {
            let label = if i == 0 { "C = " } else { "    " };
            let _ = writeln!(s, "  {label}{line}");
        }
    } else {
        let _ = writeln!(s, "  ({n}×{n} matrix; see {})", terms.full_output);
    }
    let roots = &damping.eigenvalues;
    let mut k = 0;
    while k < roots.len() {
        let (re, im) = roots[k];
        let pair = im > 0.0 && roots.get(k + 1).is_some_and(|&(r2, i2)| r2 == re && i2 == -im);
        if pair {
            let _ = writeln!(
                s,
                "  s = {} ± {}i    decay rate {}, damped frequency {}",
                human(re),
                human(im),
                human(-re),
                human(im)
            );
            k += 2;
        } else {
            let what = if im == 0.0 { "  (overdamped: no oscillation)" } else { "" };
            let im_text = if im == 0.0 {
                String::new()
            } else {
                format!(" {} {}i", if im < 0.0 { "−" } else { "+" }, human(im.abs()))
            };
            let _ = writeln!(s, "  s = {}{im_text}    decay rate {}{what}", human(re), human(-re));
            k += 1;
        }
    }
    let growing = roots.iter().any(|&(re, _)| re > 0.0);
    let _ = writeln!(
        s,
        "{}",
        if growing {
            "Some Re s > 0: a small displacement grows."
        } else if roots.iter().all(|&(re, _)| re < 0.0) {
            "Every Re s < 0: a small displacement dies away."
        } else {
            "No Re s > 0, but some Re s = 0: an undamped or free motion remains."
        }
    );
}

/// An SVG with one row per mode: the coordinates side by side, each displaced
/// by its amplitude in the mode, oscillating with the mode's frequency (SMIL
/// animation; a static envelope shows the shape when the file is printed).
pub fn animation(d: &Derivation, m: &Modes) -> String {
    let n = m.coordinates.len();
    let shown = m.modes.len().min(MAX_ANIMATED);
    let (width, row_h, top) = (900.0, 120.0, 60.0);
    let height = top + row_h * shown as f64 + 30.0;
    let left = 190.0;
    let span = width - left - 40.0;
    let x_of = |i: usize| left + if n == 1 { span / 2.0 } else { span * i as f64 / (n - 1) as f64 };
    let min_omega = m.modes.iter().filter_map(|x| x.frequency).filter(|&w| w > 0.0).fold(f64::INFINITY, f64::min);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="20" y="30" font-size="20" font-weight="bold">{} — normal modes</text>"#,
        markup::text(&d.model().name)
    );
    let _ = writeln!(
        s,
        r##"<text x="20" y="50" font-size="13" fill="#666">each dot is one coordinate, displaced by its amplitude in the mode (aᵀTa = 1); animation periods ∝ 1/Ω{}</text>"##,
        if m.modes.len() > shown { format!("; the lowest {shown} of {} modes", m.modes.len()) } else { String::new() }
    );
    for (j, mode) in m.modes.iter().take(shown).enumerate() {
        let y0 = top + row_h * (j as f64 + 0.5);
        let big = mode.shape.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(f64::MIN_POSITIVE);
        let amp = 0.4 * row_h / big;
        let label = match mode.kind {
            ModeKind::Oscillation => format!("Ω{} = {}", j + 1, human(mode.frequency.unwrap_or(0.0))),
            ModeKind::Free => format!("Ω{} = 0 (free)", j + 1),
            ModeKind::Unstable => format!("Ω{}² = {} (unstable)", j + 1, human(mode.omega_squared)),
        };
        let _ = writeln!(s, r##"<text x="20" y="{:.1}" font-size="15">{}</text>"##, y0 + 5.0, markup::text(&label));
        let _ = writeln!(s, r##"<line x1="{left}" y1="{y0:.1}" x2="{:.1}" y2="{y0:.1}" stroke="#ccc"/>"##, left + span);
        let points = |phase: f64| -> String {
            (0..n)
                .map(|i| format!("{:.1},{:.1}", x_of(i), y0 - amp * mode.shape[i] * phase))
                .collect::<Vec<_>>()
                .join(" ")
        };
        // The envelope (static shape).
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#f28e2b" stroke-dasharray="4 3"/>"##,
            points(1.0)
        );
        let dur = match mode.frequency {
            Some(w) if w > 0.0 && min_omega.is_finite() => (3.0 * min_omega / w).max(0.3),
            _ => 3.0,
        };
        let phases: Vec<f64> = (0..=24).map(|k| (2.0 * std::f64::consts::PI * k as f64 / 24.0).cos()).collect();
        let animated = mode.kind != ModeKind::Unstable;
        let values: Vec<String> = phases.iter().map(|&p| points(p)).collect();
        let _ = write!(s, r##"<polyline points="{}" fill="none" stroke="#4e79a7" stroke-width="2">"##, points(1.0));
        if animated {
            let _ = write!(
                s,
                r#"<animate attributeName="points" dur="{dur:.3}s" repeatCount="indefinite" values="{}"/>"#,
                values.join(";")
            );
        }
        let _ = writeln!(s, "</polyline>");
        for i in 0..n {
            let ys: Vec<String> = phases.iter().map(|&p| format!("{:.1}", y0 - amp * mode.shape[i] * p)).collect();
            let _ = write!(
                s,
                r##"<circle cx="{:.1}" cy="{:.1}" r="{}" fill="#4e79a7">"##,
                x_of(i),
                y0 - amp * mode.shape[i],
                if n > 20 { 2.5 } else { 5.0 }
            );
            if animated {
                let _ = write!(
                    s,
                    r#"<animate attributeName="cy" dur="{dur:.3}s" repeatCount="indefinite" values="{}"/>"#,
                    ys.join(";")
                );
            }
            let _ = writeln!(s, "</circle>");
            if n <= MAX_PRINTED_SHAPE && j + 1 == shown {
                let _ = writeln!(
                    s,
                    r##"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle" fill="#666">{}</text>"##,
                    x_of(i),
                    y0 + row_h / 2.0 + 5.0,
                    markup::text(&m.coordinates[i])
                );
            }
        }
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terms::tests::OTHER;

    const COUPLED: &str = r#"
name = "two coupled oscillators"
coordinates = ["q1", "q2"]
kinetic = "m*q1'^2/2 + m*q2'^2/2"
potential = "k*q1^2/2 + k*q2^2/2 + c*(q1 - q2)^2/2"
[parameters]
m = 1.0
k = 1.0
c = 0.625
[initial]
q1 = 1.0
"q1'" = 0.0
q2 = 0.0
"q2'" = 0.0
"#;

    /// A chain of `n` unit masses between walls, longer than the text prints.
    fn chain(n: usize) -> String {
        let q: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
        let kinetic: Vec<String> = q.iter().map(|q| format!("{q}'^2/2")).collect();
        let mut springs = vec![format!("{}^2/2", q[0]), format!("{}^2/2", q[n - 1])];
        springs.extend(q.windows(2).map(|w| format!("({} - {})^2/2", w[1], w[0])));
        let initial: Vec<String> = q.iter().map(|q| format!("{q} = 0.0\n\"{q}'\" = 0.0")).collect();
        format!(
            "name = \"chain\"\ncoordinates = [{}]\nkinetic = \"{}\"\npotential = \"{}\"\n[initial]\n{}\n",
            q.iter().map(|q| format!("\"{q}\"")).collect::<Vec<_>>().join(", "),
            kinetic.join(" + "),
            springs.join(" + "),
            initial.join("\n")
        )
    }

    fn modes(text: &str, config: &ModesConfig) -> (Derivation, Modes) {
        let d = Derivation::new(mech::Model::parse(text, &[]).unwrap()).unwrap();
        let m = mech::normal_modes(&d, config).unwrap();
        (d, m)
    }

    #[track_caller]
    fn check_contains(output: &str, expect: &[&str]) {
        for text in expect {
            assert!(output.contains(text), "{text:?} is missing from\n{output}");
        }
    }

    #[test]
    fn text_gives_frequencies_and_shapes() {
        let config = ModesConfig::default();
        let (d, m) = modes(COUPLED, &config);
        let out = text(&d, &m, &config, &OTHER);
        assert!(out.starts_with("two coupled oscillators — small oscillations (notes, Sec. 3.3)\n"), "{out}");
        check_contains(
            &out,
            &[
                "damped Newton from [initial], 1 iteration",
                "  T = [ 1  0 ]",
                "  Ω1 = 1\n",
                "  Ω2 = 1.5\n",
                "       a = (q1 = 0.7071067812, q2 = -0.7071067812)",
                "Stable: every Ω² ≥ 0",
            ],
        );
        let config = ModesConfig { at: vec![("q1".into(), 0.1)], ..Default::default() };
        let (d, m) = modes(COUPLED, &config);
        check_contains(&text(&d, &m, &config, &OTHER), &["damped Newton from at=,"]);
    }

    #[test]
    fn a_long_chain_points_at_the_full_output() {
        let config = ModesConfig::default();
        let (d, m) = modes(&chain(9), &config);
        let out = text(&d, &m, &config, &OTHER);
        check_contains(
            &out,
            &[
                "  every coordinate = 0",
                "  (9×9 matrices; see the report)",
                "  (mode shapes of 9 coordinates: see the report or animate())",
            ],
        );
        assert!(!out.contains("--"), "a flag of the CLI in\n{out}");
    }

    #[test]
    fn animation_draws_every_mode() {
        let config = ModesConfig::default();
        let (d, m) = modes(COUPLED, &config);
        let svg = animation(&d, &m);
        crate::plot::tests::assert_balanced(&svg);
        check_contains(&svg, &["two coupled oscillators — normal modes", ">Ω1 = 1<", ">Ω2 = 1.5<", ">q2<"]);
        assert_eq!(svg.matches("<animate attributeName=\"points\"").count(), 2);
    }

    #[test]
    fn vectors_name_their_coordinates() {
        assert_eq!(vector(&["a".into(), "b".into()], &[1.0, -0.5]), "(a = 1, b = -0.5)");
        assert_eq!(vector(&[], &[]), "()");
    }
}
