//! How the extremal of a functional looks (notes, Sec. 2.1 and appendix
//! A.2): [`text`] gives the Euler equation, Beltrami's first integral, the
//! path, its value against the straight line and the second variation, as text
//! that teaches; [`figure`] draws the extremal and the straight line. The
//! computation is `mech::extremal`.

use crate::{human, DrawError, Terms};
use mech::ExtremalReport;
use plotters::prelude::*;
use std::error::Error;
use std::fmt::Write as _;

/// The extremal as text that follows the notes; `terms` names the output
/// that lists the whole path.
pub fn text(r: &ExtremalReport, terms: &Terms) -> String {
    let (x, y) = (r.independent.as_str(), r.unknown.as_str());
    let mut s = String::new();
    let _ = writeln!(s, "{} — extremal of a functional (notes, Sec. 2.1)\n", r.name);
    let _ = writeln!(s, "J[{y}] = ∫ f({y}, {y}', {x}) d{x},   f = {}", r.integrand);
    if !r.parameters.is_empty() {
        let ps: Vec<String> = r.parameters.iter().map(|(n, v)| format!("{n} = {}", human(*v))).collect();
        let _ = writeln!(s, "parameters: {}", ps.join(", "));
    }
    let [x0, y0] = r.boundary["start"];
    let [x1, y1] = r.boundary["end"];
    let _ = writeln!(
        s,
        "boundary: {y}({}) = {}, {y}({}) = {}  (both ends fixed: the variation η vanishes there)\n",
        human(x0),
        human(y0),
        human(x1),
        human(y1)
    );
    let _ = writeln!(s, "Euler equation  ∂f/∂{y} − d/d{x} ∂f/∂{y}' = 0:");
    let _ = writeln!(s, "  {} = 0", r.euler_equation);
    let _ = writeln!(s, "  solved for the highest derivative: {y}'' = {}", r.acceleration);
    match (&r.first_integral, r.first_integral_constant) {
        (Some(h), Some(c)) => {
            let _ = writeln!(
                s,
                "f does not depend on {x}, so Beltrami's first integral holds: {y}'·∂f/∂{y}' − f = const,\n  {h} = {}",
                human(c)
            );
            if let Some(drift) = r.first_integral_drift {
                let _ = writeln!(s, "  (it stays constant along the computed path to {drift:.1e})");
            }
        }
        _ => {
            let _ = writeln!(s, "f depends on {x} explicitly: there is no Beltrami first integral");
        }
    }
    let _ = writeln!(s);
    if let (Some([phi0, lambda]), true) = (r.departure, r.endpoints != "regular") {
        let which = if r.endpoints == "singular_start" { "start" } else { "end" };
        let _ = writeln!(
            s,
            "The {which} is a singular point (f or {y}'' is infinite there): the extremal leaves it at the angle {}° \
             with φ − φ0 ∝ s^{lambda:.4} (local series), and the path is followed by arc length",
            human(phi0.to_degrees())
        );
    }
    let on = if r.departure.is_some() { "the coefficient of the series" } else { "the initial angle" };
    let _ =
        writeln!(s, "Extremals through both ends (shooting on {on}, {} trial paths): {}", r.shots, r.extremals.len());
    for (k, e) in r.extremals.iter().enumerate() {
        let slope = e.start_slope.map_or("vertical".to_string(), |m| format!("{y}'({}) = {}", human(x0), human(m)));
        let mark = if k == 0 { "  ← lowest, reported" } else { "" };
        let conj = e.conjugate_point.map_or(String::new(), |c| format!(" (conjugate point at {x} = {})", human(c)));
        let _ = writeln!(s, "  J = {}   start: {slope}{conj}{mark}", human(e.value));
    }
    if r.extremals.len() > 1 {
        let _ = writeln!(s, "  (the Euler equation only makes J stationary; of several extremals the lowest is kept)");
    }
    if r.unfinished_shots > 0 {
        let _ = writeln!(
            s,
            "  ({} trial paths ran out of steps before reaching the end: other extremals may exist)",
            r.unfinished_shots
        );
    }
    let n = r.path.len();
    let pick = |i: usize| r.path[i];
    let _ = writeln!(s, "\nPath ({n} points; {} lists them all):", terms.full_output);
    // Round-off next to zero (1e-15 where the path crosses x = 0) would read as data.
    let tidy = |v: f64, scale: f64| if v.abs() < 1e-12 * scale { 0.0 } else { v };
    let scale = x0.abs().max(x1.abs()).max(y0.abs()).max(y1.abs());
    for i in [0, n / 4, n / 2, 3 * n / 4, n - 1] {
        let [px, py] = pick(i);
        let (px, py) = (tidy(px, scale), tidy(py, scale));
        let _ = writeln!(s, "  {x} = {:<14} {y} = {}", human(px), human(py));
    }
    let ymin = r.path.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let ymax = r.path.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    let _ = writeln!(s, "  range of {y}: [{}, {}]", human(ymin), human(ymax));
    let _ = writeln!(s, "  end point reached to {:.1e}", r.end_residual);
    let _ = writeln!(s, "\nValue on the extremal       J = {}", human(r.value));
    let _ = writeln!(s, "Value on the straight line  J = {}", human(r.straight_line_value));
    let diff = r.straight_line_value - r.value;
    let verdict = if diff.abs() <= 1e-9 * r.value.abs().max(1e-300) {
        "the same: the straight line is the extremal".to_string()
    } else if diff > 0.0 {
        format!("the extremal is lower by {}", human(diff))
    } else {
        format!("the straight line is lower by {}: the extremal is not a minimum", human(-diff))
    };
    let _ = writeln!(s, "  {verdict}");
    if let Some(sv) = &r.second_variation {
        let _ = writeln!(s, "\nSecond variation (notes, appendix A.2):");
        let _ = writeln!(
            s,
            "  J[{y} + αη] = J[{y}] + α²/2·∫ (P η'^2 + Q η^2) d{x} + O(α³), the η η' term integrated by parts,"
        );
        let _ = writeln!(s, "  with P = ∂²f/∂{y}'² = {}", r.legendre);
        let _ = writeln!(s, "  and  Q = ∂²f/∂{y}² − d/d{x} ∂²f/∂{y}∂{y}' = {}", r.jacobi_q);
        let _ =
            writeln!(s, "  (for f = m/2·{y}'^2 − U({y}) this is the notes' I₂ = ∫ (m η'^2 + F'({y}) η^2), F = −U')");
        let _ = writeln!(
            s,
            "  Legendre: P ranges over [{}, {}] along the path: {}",
            human(sv.legendre_min),
            human(sv.legendre_max),
            if sv.legendre { "P > 0 holds" } else { "P > 0 fails, so this is not a minimum" }
        );
        let from = if sv.from_end { "end" } else { "start" };
        let _ = writeln!(
            s,
            "  Jacobi: d/d{x}(P h') − Q h = 0 with h = 0, h' = 1 at the {from} (h = ∂{y}/∂(initial slope), the\n  \
             neighbouring extremals through the same point)"
        );
        match sv.conjugate_point {
            Some(c) => {
                let _ = writeln!(
                    s,
                    "  h vanishes again at {x} = {}: a conjugate point inside the interval, so a neighbouring path\n  \
                     lowers J: NOT a minimum",
                    human(c)
                );
            }
            None => {
                let _ = writeln!(s, "  h does not vanish again before the other end: no conjugate point");
            }
        }
        let _ = writeln!(
            s,
            "  Verdict: {}",
            if sv.minimum {
                "a (weak) minimum — P > 0 and no conjugate point"
            } else if sv.legendre {
                "not a minimum — past the conjugate point some variations lower J while others raise it (a saddle)"
            } else {
                "not a minimum"
            }
        );
    }
    s
}

/// The extremal and the straight line between the ends, as SVG text.
pub fn figure(r: &ExtremalReport) -> Result<String, DrawError> {
    Ok(draw(r)?)
}

fn draw(r: &ExtremalReport) -> Result<String, Box<dyn Error>> {
    let (x, y) = (r.independent.as_str(), r.unknown.as_str());
    let [x0, y0] = r.boundary["start"];
    let [x1, y1] = r.boundary["end"];
    let xs = r.path.iter().map(|p| p[0]);
    let ys = r.path.iter().map(|p| p[1]).chain([y0, y1]);
    let (xlo, xhi) = xs.fold((x0, x1), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (ylo, yhi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let pad_x = 0.05 * (xhi - xlo).max(1e-12);
    let pad_y = 0.08 * (yhi - ylo).max(1e-3 * (xhi - xlo)).max(1e-12);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut c = ChartBuilder::on(&root)
            .caption(format!("{} — f = {}", r.name, r.integrand), ("sans-serif", 20))
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((xlo - pad_x)..(xhi + pad_x), (ylo - pad_y)..(yhi + pad_y))?;
        c.configure_mesh().x_desc(x).y_desc(y).light_line_style(WHITE).draw()?;
        let path: Vec<(f64, f64)> = r.path.iter().map(|p| (p[0], p[1])).collect();
        c.draw_series(LineSeries::new(path, BLUE.stroke_width(3)))?
            .label(format!("extremal, J = {}", human(r.value)))
            .legend(|(px, py)| PathElement::new(vec![(px, py), (px + 20, py)], BLUE.stroke_width(3)));
        c.draw_series(LineSeries::new(vec![(x0, y0), (x1, y1)], RGBColor(0x99, 0x99, 0x99).stroke_width(2)))?
            .label(format!("straight line, J = {}", human(r.straight_line_value)))
            .legend(|(px, py)| PathElement::new(vec![(px, py), (px + 20, py)], RGBColor(0x99, 0x99, 0x99)));
        if let Some(Some(cx)) = r.conjugate_point {
            let i = r.path.iter().position(|p| p[0] >= cx).unwrap_or(r.path.len() - 1);
            c.draw_series(std::iter::once(Circle::new((cx, r.path[i][1]), 6, RED.filled())))?
                .label(format!("conjugate point {x} = {}", human(cx)))
                .legend(|(px, py)| Circle::new((px + 10, py), 5, RED.filled()));
        }
        c.draw_series([(x0, y0), (x1, y1)].map(|p| Circle::new(p, 5, BLACK.filled())))?;
        c.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
        root.present()?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terms::tests::OTHER;

    const SHORTEST: &str = r#"
name = "shortest path"
independent = "x"
unknown = "y"
integrand = "sqrt(1 + y'^2)"
[boundary]
start = [0.0, 0.0]
end = [3.0, 4.0]
"#;

    fn report(check_minimum: bool) -> ExtremalReport {
        let problem = mech::Problem::parse(SHORTEST, &[]).unwrap();
        mech::extremal(&problem, &mech::ExtremalConfig { check_minimum, points: 201 }).unwrap()
    }

    #[test]
    fn text_teaches_the_extremal() {
        let out = text(&report(true), &OTHER);
        for line in [
            "shortest path — extremal of a functional (notes, Sec. 2.1)\n",
            "  solved for the highest derivative: y'' = 0\n",
            "  J = 5   start: y'(0) = 1.333333333  ← lowest, reported\n",
            "Path (201 points; the report lists them all):\n",
            "  x = 1.5            y = 2\n",
            "  the same: the straight line is the extremal\n",
            "  Verdict: a (weak) minimum — P > 0 and no conjugate point\n",
        ] {
            assert!(out.contains(line), "{line:?} is missing from\n{out}");
        }
        assert!(!text(&report(false), &OTHER).contains("Second variation"));
    }

    #[test]
    fn figure_has_both_paths() {
        let svg = figure(&report(false)).unwrap();
        crate::plot::tests::assert_balanced(&svg);
        for text in ["shortest path — f = ", "extremal, J = 5", "straight line, J = 5"] {
            assert!(svg.contains(text), "the figure lacks {text:?}");
        }
    }
}
