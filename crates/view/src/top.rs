//! How a symmetric top looks (notes, Sec. 3.2.7): [`text`] gives its
//! precession and nutation from the initial state; [`figure`] draws U_eff(β)
//! with E' and the turning angles, and the path of the symmetry axis on the
//! unit sphere seen from above, from a short simulation of the same model.
//! The computation is `mech::Top`.

use crate::{human, DrawError};
use mech::{Derivation, NutationKind, RunConfig, Top};
use plotters::prelude::*;
use std::error::Error;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::ops::ControlFlow;

/// The top as text that follows the notes.
pub fn text(d: &Derivation, t: &Top) -> String {
    let [a, b, g] = &t.angle_names;
    let mut s = String::new();
    let _ = writeln!(s, "{} — {} symmetric top '{}' (notes, Sec. 3.2.7)\n", d.model().name, t.kind.name(), t.body);
    let _ = writeln!(s, "  I = I1 = I2 = {}, I3 = {}", human(t.i), human(t.i3));
    let _ = writeln!(
        s,
        "  initial state: {a} = {}, {b} = {}, {g} = {}; {a}' = {}, {b}' = {}, {g}' = {}",
        human(t.angles[0]),
        human(t.angles[1]),
        human(t.angles[2]),
        human(t.rates[0]),
        human(t.rates[1]),
        human(t.rates[2])
    );
    let _ = writeln!(
        s,
        "  body-frame ω = ({}, {}, {})   (ω3 = {a}' cos {b} + {g}')",
        human(t.omega[0]),
        human(t.omega[1]),
        human(t.omega[2])
    );
    let _ = writeln!(s, "  p_{a} = I {a}' sin²{b} + p_{g} cos {b} = {}   (conserved: {a} is cyclic)", human(t.p_alpha));
    let _ = writeln!(s, "  p_{g} = I3 ω3 = {}   (conserved: {g} is cyclic, so ω3 is constant)", human(t.p_gamma));
    let _ = writeln!(s, "  energy E = {}\n", human(t.energy));
    if let Some(f) = &t.free {
        let _ = writeln!(s, "Free top ({}): Euler's equations give ω3 = const and ω1 + iω2 turning at", f.shape);
        let _ = writeln!(s, "  Ω = (I3 − I)/I·ω3 = {}   (body precession rate)", human(f.body_precession_rate));
        let _ = writeln!(
            s,
            "  A = sqrt(ω1² + ω2²) = {}, |ω| = const, |L| = {}",
            human(f.transverse_omega),
            human(f.angular_momentum)
        );
        let _ = writeln!(
            s,
            "  inclination β0 = atan(I·A/(I3·ω3)) = {} rad = {}°   (the angle between L and the symmetry axis)",
            human(f.inclination),
            human(f.inclination.to_degrees())
        );
        let _ = writeln!(
            s,
            "  space precession rate {a}' = A/sin β0 = |L|/I = {}   (with the fixed z axis along L)",
            human(f.space_precession_rate)
        );
        let _ = writeln!(
            s,
            "  body cone half-angle (ω about the symmetry axis) {} rad, space cone half-angle (ω about L) {} rad",
            human(f.body_cone_angle),
            human(f.space_cone_angle)
        );
    }
    if let Some(h) = &t.heavy {
        let _ = writeln!(s, "Heavy top on a fixed pivot, M g S = {}:", human(h.mgs));
        let _ = writeln!(s, "  E' = E − p_{g}²/(2 I3) = {} = ½ I {b}'² + U_eff({b})", human(h.energy_prime));
        let _ = writeln!(s, "  U_eff({b}) = (p_{a} − p_{g} cos {b})²/(2 I sin²{b}) + M g S cos {b}");
        let _ = writeln!(s, "  nutation between the turning angles (E' = U_eff, roots of the cubic in u = cos {b}):");
        let _ = writeln!(
            s,
            "    {b}1 = {} rad ({}°), {b}2 = {} rad ({}°)",
            human(h.beta_min),
            human(h.beta_min.to_degrees()),
            human(h.beta_max),
            human(h.beta_max.to_degrees())
        );
        let kind = match h.kind {
            NutationKind::Steady => {
                "none: E' is the minimum of U_eff, steady precession at a fixed inclination".to_string()
            }
            NutationKind::Monotonic => {
                format!("{a}' keeps its sign in [{b}1, {b}2]: monotonic precession (a wavy curve)")
            }
            NutationKind::Loops => format!(
                "{a}' changes sign at {b} = {} inside [{b}1, {b}2]: the axis draws loops",
                h.alpha_dot_zero.map_or("?".into(), human)
            ),
            NutationKind::Cusps => {
                format!("{a}' vanishes at a turning angle: the axis draws cusps (released without precession)")
            }
        };
        let _ = writeln!(s, "    kind: {kind}");
        let _ = writeln!(
            s,
            "    nutation period {}, mean precession rate {a}' = {}",
            human(h.nutation_period),
            human(h.mean_precession_rate)
        );
        match h.steady_precession {
            Some([slow, fast]) => {
                let _ = writeln!(
                    s,
                    "  steady precession at {b} = {} (I cos {b} {a}'² − p_{g} {a}' + M g S = 0): slow {a}' = {}, fast {a}' = {}",
                    human(t.angles[1]),
                    slow.map_or("none".into(), human),
                    fast.map_or("none (cos β = 0)".into(), human)
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "  steady precession at {b} = {}: none at this spin (p_{g}² < 4 I M g S cos {b})",
                    human(t.angles[1])
                );
            }
        }
        let _ = writeln!(
            s,
            "  sleeping top (spinning upright): {} (p_{g}² {} 4 I M g S; stable for |ω3| > {})",
            if h.sleeping_stable { "stable" } else { "unstable" },
            if h.sleeping_stable { ">" } else { "≤" },
            human(h.sleeping_omega3_min)
        );
    }
    s
}

/// The symmetry axis in space, Dᵀe₃ = (sin β sin α, −sin β cos α, cos β), along
/// a short simulation of the model.
fn axis_path(d: &Derivation, t: &Top) -> Vec<[f64; 3]> {
    let idx: Vec<usize> =
        t.angle_names.iter().map(|n| d.model().coordinates.iter().position(|c| &c.name == n).unwrap_or(0)).collect();
    let until = match (&t.heavy, &t.free) {
        (Some(h), _) if h.nutation_period.is_finite() && h.nutation_period > 0.0 => {
            // Enough nutations to go once around, at most 40.
            let around =
                if h.mean_precession_rate != 0.0 { 2.0 * PI / h.mean_precession_rate.abs() } else { f64::INFINITY };
            around.min(40.0 * h.nutation_period)
        }
        (_, Some(f)) if f.space_precession_rate > 0.0 => 2.0 * PI / f.space_precession_rate,
        _ => 10.0,
    };
    let config =
        RunConfig { until, output: num::Output::Samples(4001), rtol: 1e-8, atol: 1e-11, ..RunConfig::default() };
    let mut pts = Vec::new();
    let _ = mech::simulate(d, &config, |row| {
        let (al, be) = (row.q[idx[0]], row.q[idx[1]]);
        pts.push([be.sin() * al.sin(), -be.sin() * al.cos(), be.cos()]);
        ControlFlow::Continue(())
    });
    pts
}

/// Two panels as SVG text: U_eff(β) with E' and the turning angles; the
/// symmetry axis seen from above along a short run of the model.
pub fn figure(d: &Derivation, t: &Top) -> Result<String, DrawError> {
    Ok(draw(d, t)?)
}

fn draw(d: &Derivation, t: &Top) -> Result<String, Box<dyn Error>> {
    let path = axis_path(d, t);
    let b = t.angle_names[1].clone();
    // β around the allowed band (the whole range for a free top).
    let (lo, hi) = match &t.heavy {
        Some(h) => {
            let w = (h.beta_max - h.beta_min).max(0.1);
            ((h.beta_min - w).max(0.01), (h.beta_max + w).min(PI - 0.01))
        }
        None => ((t.angles[1] - 0.8).max(0.02), (t.angles[1] + 0.8).min(PI - 0.02)),
    };
    let n = 800;
    let pot: Vec<(f64, f64)> = (0..=n).map(|i| lo + (hi - lo) * i as f64 / n as f64).map(|x| (x, t.u_eff(x))).collect();
    let level = t.heavy.as_ref().map_or(t.u_eff(t.angles[1]), |h| h.energy_prime);
    let umin = pot.iter().map(|p| p.1).fold(level, f64::min);
    // At a minimum (steady motion) E' = min U_eff: show the well around it.
    let spread = (level - umin).abs().max(0.25 * level.abs()).max(1e-6);
    let (ylo, yhi) = (umin - 0.3 * spread, level + 2.0 * spread);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1200, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let (header, body) = root.split_vertically(50);
        header.draw(&Text::new(
            format!(
                "{} — {} top, p_α = {}, p_γ = {}",
                d.model().name,
                t.kind.name(),
                human(t.p_alpha),
                human(t.p_gamma)
            ),
            (20, 15),
            ("sans-serif", 22).into_font(),
        ))?;
        let (left, right) = body.split_horizontally(640);
        let mut c = ChartBuilder::on(&left)
            .caption("effective potential U_eff(β) and E'", ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(lo..hi, ylo..yhi)?;
        c.configure_mesh().x_desc(b.as_str()).y_desc("U_eff").light_line_style(WHITE).draw()?;
        // The curve, broken where it leaves the drawing.
        let mut segment: Vec<(f64, f64)> = Vec::new();
        for p in pot.into_iter().chain(std::iter::once((f64::NAN, f64::NAN))) {
            if p.1.is_finite() && p.1 <= yhi && p.1 >= ylo {
                segment.push(p);
            } else if !segment.is_empty() {
                c.draw_series(LineSeries::new(std::mem::take(&mut segment), BLUE.stroke_width(2)))?;
            }
        }
        c.draw_series(LineSeries::new(vec![(lo, level), (hi, level)], RED.stroke_width(1)))?;
        let marks = match &t.heavy {
            Some(h) => vec![h.beta_min, h.beta_max],
            None => vec![t.angles[1]],
        };
        {
            for x in marks {
                c.draw_series(std::iter::once(Circle::new((x, level), 5, RED.filled())))?;
                c.draw_series(LineSeries::new(vec![(x, ylo), (x, level)], RGBColor(0xbb, 0xbb, 0xbb)))?;
            }
        }
        let mut c = ChartBuilder::on(&right)
            .caption("symmetry axis on the unit sphere, seen from above", ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-1.05..1.05, -1.05..1.05)?;
        c.configure_mesh().x_desc("x").y_desc("y").light_line_style(WHITE).draw()?;
        let circle: Vec<(f64, f64)> = (0..=360).map(|k| (k as f64).to_radians()).map(|a| (a.cos(), a.sin())).collect();
        c.draw_series(LineSeries::new(circle, RGBColor(0xbb, 0xbb, 0xbb)))?;
        // Upper hemisphere solid, lower hemisphere lighter.
        let upper: Vec<(f64, f64)> = path.iter().filter(|p| p[2] >= 0.0).map(|p| (p[0], p[1])).collect();
        let lower: Vec<(f64, f64)> = path.iter().filter(|p| p[2] < 0.0).map(|p| (p[0], p[1])).collect();
        c.draw_series(upper.into_iter().map(|p| Circle::new(p, 1, BLUE.filled())))?;
        c.draw_series(lower.into_iter().map(|p| Circle::new(p, 1, RGBColor(0x99, 0x99, 0xff).filled())))?;
        c.draw_series(std::iter::once(Circle::new((0.0, 0.0), 3, BLACK.filled())))?;
        root.present()?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAVY: &str = r#"
name = "heavy symmetric top"
coordinates = ["al", "be", "ga"]
gravity = "g"
[parameters]
g = 9.81
[[bodies]]
name = "top"
mass = "1"
inertia = ["1", "1", "0.5"]
angles = ["al", "be", "ga"]
position = ["0", "0", "0"]
center_of_mass = ["0", "0", "0.5"]
[initial]
al = 0.0
"al'" = 0.0
be = 0.6
"be'" = 0.0
ga = 0.0
"ga'" = 12.0
"#;

    fn top() -> (Derivation, Top) {
        let d = Derivation::new(mech::Model::parse(HEAVY, &[]).unwrap()).unwrap();
        let t = Top::new(&d).unwrap();
        (d, t)
    }

    #[test]
    fn text_gives_precession_and_nutation() {
        let (d, t) = top();
        let out = text(&d, &t);
        for line in [
            "heavy symmetric top — heavy symmetric top 'top' (notes, Sec. 3.2.7)\n",
            "  p_ga = I3 ω3 = 6   (conserved: ga is cyclic, so ω3 is constant)\n",
            "Heavy top on a fixed pivot, M g S = 4.905:\n",
            "    kind: al' vanishes at a turning angle: the axis draws cusps (released without precession)\n",
        ] {
            assert!(out.contains(line), "{line:?} is missing from\n{out}");
        }
    }

    #[test]
    fn figure_has_the_potential_and_the_axis() {
        let (d, t) = top();
        let svg = figure(&d, &t).unwrap();
        crate::plot::tests::assert_balanced(&svg);
        for text in ["effective potential U_eff(β) and E", "symmetry axis on the unit sphere, seen from above"] {
            assert!(svg.contains(text), "the figure lacks {text:?}");
        }
        assert!(svg.matches("<circle").count() > 1000, "the axis path is drawn as dots");
    }
}
