//! How a central-force orbit looks (notes, Sec. 3.1): [`text`] gives μ and
//! U(r) read from the derivation, l, E, U_eff, the turning points, the kind of
//! orbit, the period and the apsidal angle; [`figure`] draws U_eff with the
//! energy line and the turning points, and the orbit in the plane. The
//! computation is `mech::Orbit`.

use crate::{human, DrawError};
use mech::{Derivation, Orbit, OrbitKind};
use plotters::prelude::*;
use std::error::Error;
use std::f64::consts::PI;
use std::fmt::Write as _;

/// The orbit as text that follows the notes.
pub fn text(d: &Derivation, o: &Orbit) -> String {
    let pool = &o.pool;
    let [rn, an] = &o.names;
    let mut s = String::new();
    let _ = writeln!(s, "{} — central-force orbit (notes, Sec. 3.1)\n", d.model().name);
    let _ = writeln!(s, "L = μ/2·({rn}'^2 + {rn}^2*{an}'^2) − U({rn}), read from the derivation:");
    let _ = writeln!(s, "  reduced mass      μ = {} = {}", pool.display(o.mu_expr), human(o.mu));
    let _ = writeln!(s, "  potential         U({rn}) = {}", pool.display(o.potential_expr));
    let _ = writeln!(
        s,
        "  angular momentum  l = p_{an} = μ {rn}^2 {an}' = {}  ({an} is cyclic: l is conserved, the motion stays in a plane)",
        human(o.angular_momentum)
    );
    let _ = writeln!(s, "  energy            E = μ/2·{rn}'^2 + U_eff({rn}) = {}", human(o.energy));
    let _ = writeln!(
        s,
        "  effective potential U_eff({rn}) = l^2/(2μ{rn}^2) + U({rn}); the radial motion needs E ≥ U_eff\n"
    );
    match o.apoapsis {
        Some(r2) if (r2 - o.periapsis).abs() <= 1e-12 * r2 => {
            let _ =
                writeln!(s, "Turning points: none; E = U_eff at its minimum: a circular orbit of radius {}", human(r2));
        }
        Some(r2) => {
            let _ = writeln!(
                s,
                "Turning points (E = U_eff): periapsis {rn} = {}, apoapsis {rn} = {}",
                human(o.periapsis),
                human(r2)
            );
        }
        None => {
            let _ = writeln!(
                s,
                "Turning point (E = U_eff): periapsis {rn} = {}; E > U_eff beyond it, so {rn} grows without bound",
                human(o.periapsis)
            );
        }
    }
    let _ = writeln!(s, "Kind: {}", o.kind.name());
    if let Some(k) = &o.kepler {
        let _ = writeln!(s, "\nKepler problem U = −k/{rn} with k = {} = {}:", pool.display(k.k_expr), human(k.k));
        let _ = writeln!(s, "  α = l^2/(μk) = {}   (1/{rn} = (1 + ε cos({an} − {an}₀))/α)", human(k.alpha));
        let _ = writeln!(s, "  ε = sqrt(1 + 2El^2/(μk^2)) = {}", human(k.eccentricity));
        let _ = writeln!(s, "  periapsis α/(1 + ε) = {}", human(o.periapsis));
        if let (Some(r2), Some(t)) = (o.apoapsis, o.period) {
            let a = k.alpha / (1.0 - k.eccentricity * k.eccentricity);
            let _ = writeln!(s, "  apoapsis α/(1 − ε) = {}", human(r2));
            let _ = writeln!(s, "  semi-major axis a = α/(1 − ε^2) = {}", human(a));
            let _ = writeln!(s, "  period (Kepler's third law) T = 2π·sqrt(μa^3/k) = {}", human(t));
            let _ = writeln!(s, "  apsidal angle π: the orbit closes on itself, no precession");
        }
        let [ax, ay] = k.runge_lenz;
        let _ = writeln!(
            s,
            "  Laplace–Runge–Lenz vector A = p × l − μk r/r = ({}, {}), |A| = μkε = {}, pointing at periapsis ({an} = {})",
            human(ax),
            human(ay),
            human(ax.hypot(ay)),
            human(o.periapsis_angle)
        );
    } else if let (Some(t), Some(dth)) = (o.period, o.apsidal_angle) {
        let _ = writeln!(s, "\nBy quadrature (r = (r1 + r2)/2 + (r2 − r1)/2·sin φ, Gauss–Legendre):");
        let _ = writeln!(s, "  radial period (periapsis to periapsis) T_r = 2∫ dr/sqrt(2(E − U_eff)/μ) = {}", human(t));
        let _ = writeln!(
            s,
            "  apsidal angle (periapsis to apoapsis) Δ{an} = ∫ l/(μr^2) dr/sqrt(2(E − U_eff)/μ) = {} = {}°",
            human(dth),
            human(dth.to_degrees())
        );
        let prec = 2.0 * dth - 2.0 * PI;
        let _ = writeln!(
            s,
            "  precession per radial period 2Δ{an} − 2π = {} ({}); the orbit {}",
            human(prec),
            if prec > 0.0 { "the periapsis advances" } else { "the periapsis regresses" },
            if (dth / PI * 2.0 - (dth / PI * 2.0).round()).abs() < 1e-9 {
                "closes (Δθ is a rational multiple of π)"
            } else {
                "is a rosette that does not close after one turn"
            }
        );
    }
    if o.kind == OrbitKind::Unbounded || o.kind == OrbitKind::Hyperbola || o.kind == OrbitKind::Parabola {
        let _ = writeln!(s, "\nThe orbit is unbounded: period and apsidal angle are null.");
    }
    s
}

/// Two panels as SVG text: U_eff(r) with E and the turning points; the orbit
/// x = r cos θ, y = r sin θ (traced by `o`, hence `&mut`).
pub fn figure(d: &Derivation, o: &mut Orbit) -> Result<String, DrawError> {
    Ok(draw(d, o)?)
}

fn draw(d: &Derivation, o: &mut Orbit) -> Result<String, Box<dyn Error>> {
    let [rn, an] = o.names.clone();
    let r1 = o.periapsis;
    let r_far = o.apoapsis.map_or(4.0 * r1, |r2| r2.max(r1 * 1.01));
    let (lo, hi) = (0.4 * r1, 1.5 * r_far);
    let n = 600;
    let pot: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let r = lo + (hi - lo) * i as f64 / n as f64;
            (r, o.u_eff(r))
        })
        .filter(|p| p.1.is_finite())
        .collect();
    let umin = pot.iter().map(|p| p.1).fold(o.energy, f64::min);
    let spread = (o.energy - umin).abs().max(1e-9 * (1.0 + o.energy.abs()));
    let (ylo, yhi) = (umin - 0.2 * spread, o.energy + 1.5 * spread);

    // The orbit: several radial periods of a precessing orbit, one of a closed one.
    let one = o.path(400, hi * 2.0);
    let mut orbit_pts: Vec<(f64, f64)> = Vec::new();
    let turns = match (o.kepler.is_some(), o.apsidal_angle) {
        (false, Some(_)) => 8,
        _ => 1,
    };
    let advance = o.apsidal_angle.map_or(0.0, |a| 2.0 * a) * o.angular_momentum.signum();
    for k in 0..turns {
        orbit_pts.extend(one.iter().map(|&(th, r)| {
            let th = th + advance * k as f64;
            (r * th.cos(), r * th.sin())
        }));
    }
    let extent = orbit_pts.iter().map(|p| p.0.abs().max(p.1.abs())).fold(0.0f64, f64::max).max(r1) * 1.1;
    let extent = extent.min(hi * 1.2);

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1200, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let (header, body) = root.split_vertically(50);
        header.draw(&Text::new(
            format!(
                "{} — E = {}, l = {}, {}",
                d.model().name,
                human(o.energy),
                human(o.angular_momentum),
                o.kind.name()
            ),
            (20, 15),
            ("sans-serif", 22).into_font(),
        ))?;
        let (left, right) = body.split_horizontally(640);
        let mut c = ChartBuilder::on(&left)
            .caption("effective potential", ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(lo..hi, ylo..yhi)?;
        c.configure_mesh().x_desc(rn.as_str()).y_desc("U_eff").light_line_style(WHITE).draw()?;
        let inside: Vec<Vec<(f64, f64)>> = split_inside(&pot, ylo, yhi);
        for seg in inside {
            c.draw_series(LineSeries::new(seg, BLUE.stroke_width(2)))?;
        }
        c.draw_series(LineSeries::new(vec![(lo, o.energy), (hi, o.energy)], RED.stroke_width(1)))?;
        c.draw_series(std::iter::once(Text::new(
            format!("E = {}", human(o.energy)),
            (lo + 0.02 * (hi - lo), o.energy + 0.05 * spread),
            ("sans-serif", 14).into_font(),
        )))?;
        let mut turning = vec![r1];
        turning.extend(o.apoapsis);
        for &r in &turning {
            c.draw_series(std::iter::once(Circle::new((r, o.energy), 5, RED.filled())))?;
            c.draw_series(LineSeries::new(vec![(r, ylo), (r, o.energy)], RGBColor(0xbb, 0xbb, 0xbb)))?;
        }

        let mut c = ChartBuilder::on(&right)
            .caption(format!("orbit: x = {rn}·cos({an}), y = {rn}·sin({an})"), ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-extent..extent, -extent..extent)?;
        c.configure_mesh().x_desc("x").y_desc("y").light_line_style(WHITE).draw()?;
        let clipped: Vec<(f64, f64)> =
            orbit_pts.into_iter().filter(|p| p.0.abs() <= extent && p.1.abs() <= extent).collect();
        c.draw_series(LineSeries::new(clipped, BLUE.stroke_width(2)))?;
        c.draw_series(std::iter::once(Circle::new((0.0, 0.0), 4, BLACK.filled())))?;
        let [r0, th0, _, _] = o.initial;
        c.draw_series(std::iter::once(Circle::new((r0 * th0.cos(), r0 * th0.sin()), 5, GREEN.filled())))?;
        let pa = o.periapsis_angle;
        c.draw_series(std::iter::once(Circle::new((r1 * pa.cos(), r1 * pa.sin()), 5, RED.filled())))?;
        root.present()?;
    }
    Ok(svg)
}

/// The runs of consecutive points with y inside [lo, hi].
fn split_inside(points: &[(f64, f64)], lo: f64, hi: f64) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut cur = Vec::new();
    for &p in points {
        if p.1 >= lo && p.1 <= hi {
            cur.push(p);
        } else if !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEPLER: &str = r#"
name = "Kepler problem"
coordinates = ["r", "th"]
lagrangian = "mu*(r'^2 + r^2*th'^2)/2 + k/r"
[parameters]
mu = 1.0
k = 1.0
[initial]
r = 1.0
"r'" = 0.0
th = 0.0
"th'" = 1.2
"#;

    fn orbit() -> (Derivation, Orbit) {
        let d = Derivation::new(mech::Model::parse(KEPLER, &[]).unwrap()).unwrap();
        let o = Orbit::new(&d).unwrap();
        (d, o)
    }

    #[test]
    fn text_gives_the_turning_points_and_the_kind() {
        let (d, o) = orbit();
        let out = text(&d, &o);
        for line in [
            "Kepler problem — central-force orbit (notes, Sec. 3.1)\n",
            "  energy            E = μ/2·r'^2 + U_eff(r) = -0.28\n",
            "Turning points (E = U_eff): periapsis r = 1, apoapsis r = 2.571428571\n",
            "Kind: ellipse\n",
            "  apsidal angle π: the orbit closes on itself, no precession\n",
        ] {
            assert!(out.contains(line), "{line:?} is missing from\n{out}");
        }
    }

    #[test]
    fn figure_has_both_panels() {
        let (d, mut o) = orbit();
        let svg = figure(&d, &mut o).unwrap();
        crate::plot::tests::assert_balanced(&svg);
        for text in ["Kepler problem — E = -0.28, l = 1.2, ellipse", "effective potential", "orbit: x = r·cos(th)"] {
            assert!(svg.contains(text), "the figure lacks {text:?}");
        }
    }
}
