//! How a body's inertia looks (notes, Sec. 3.2.3): [`text`] gives its parts,
//! the total mass and centre of mass, the tensor about the centre of mass and
//! about a chosen point (Steiner's parallel-axis step), exact and numeric, the
//! principal moments and axes and the symmetry they show. The computation is
//! `mech::inertia`.

use crate::human;
use mech::inertia::{BodyFile, InertiaReport, MassProperties, PartKind, Symmetry};
use std::fmt::Write as _;
use sym::ExprId;

/// A vector of numbers, `(x, y, z)`.
fn vector(v: &[f64; 3]) -> String {
    format!("({}, {}, {})", human(v[0]), human(v[1]), human(v[2]))
}

/// A vector of expressions, `(x, y, z)`.
fn exact_vector(p: &MassProperties, v: &[ExprId; 3]) -> String {
    let s: Vec<String> = v.iter().map(|&e| p.pool().display(e).to_string()).collect();
    format!("({})", s.join(", "))
}

/// `exact = number`, or the number alone when the exact text says nothing more.
fn both(exact: Option<&str>, number: &str) -> String {
    match exact {
        Some(e) if e != number => format!("{e} = {number}"),
        _ => number.to_string(),
    }
}

/// A 3×3 matrix as aligned rows, each line indented.
fn matrix(cells: &[[String; 3]; 3], indent: &str) -> String {
    let widths: Vec<usize> = (0..3).map(|k| cells.iter().map(|r| r[k].chars().count()).max().unwrap_or(1)).collect();
    let mut s = String::new();
    for row in cells {
        let parts: Vec<String> = (0..3).map(|k| format!("{:>w$}", row[k], w = widths[k])).collect();
        let _ = writeln!(s, "{indent}[ {} ]", parts.join("  "));
    }
    s
}

/// The exact matrix (when there is one and it differs from the numbers), then the numbers.
fn exact_and_numeric(s: &mut String, exact: Option<&[[String; 3]; 3]>, values: &[[f64; 3]; 3]) {
    let numeric = numbers(values);
    if let Some(cells) = exact.filter(|c| **c != numeric) {
        s.push_str(&matrix(cells, "  "));
        s.push_str("  =\n");
    }
    s.push_str(&matrix(&numeric, "  "));
}

fn numbers(m: &[[f64; 3]; 3]) -> [[String; 3]; 3] {
    m.map(|row| row.map(human))
}

/// The report with numbers below the cubature's estimated error set to 0
/// (round-off noise such as 1e-18 off the diagonal of a symmetric density).
fn denoised(r: &InertiaReport) -> InertiaReport {
    let mut r = r.clone();
    if let Some(c) = r.cubature {
        let clean = |x: &mut f64, noise: f64| {
            if x.abs() <= noise {
                *x = 0.0;
            }
        };
        for x in r.tensor.iter_mut().chain(r.tensor_com.iter_mut()).flatten() {
            clean(x, c.tensor_error);
        }
        for x in r.center_of_mass.iter_mut() {
            clean(x, c.center_of_mass_error);
        }
        for part in r.parts.iter_mut().filter(|p| p.method == "adaptive cubature") {
            for x in part.tensor.iter_mut().flatten() {
                clean(x, c.tensor_error);
            }
            for x in part.center_of_mass.iter_mut() {
                clean(x, c.center_of_mass_error);
            }
        }
    }
    r
}

/// The inertia of `body` as text that follows the notes: `p` its mass
/// properties, `point` the reference point and `r` the report about it.
pub fn text(body: &BodyFile, p: &MassProperties, point: [ExprId; 3], r: &InertiaReport) -> String {
    let at_com = point == p.center_of_mass || r.about == r.center_of_mass;
    let r = &denoised(r);
    let mut s = String::new();
    let _ = writeln!(s, "{} — inertia tensor (notes, Sec. 3.2.3)", r.name);
    let _ = writeln!(
        s,
        "I_jk = Σ m (r² δ_jk − x_j x_k): moments of inertia on the diagonal, minus the products of inertia off it"
    );
    if !body.parameters.is_empty() {
        let ps: Vec<String> = body.parameters.iter().map(|q| format!("{} = {}", q.name, q.value)).collect();
        let _ = writeln!(s, "parameters: {}", ps.join(", "));
    }

    let _ = writeln!(s, "\nParts (each: mass, centre of mass c, tensor about c in the body's axes):");
    for (k, (part, rp)) in body.parts.iter().zip(&r.parts).enumerate() {
        let pp = &p.parts[k];
        let what = match &part.kind {
            PartKind::Shape { shape, orientation, .. } => {
                let turned =
                    if orientation.is_some() { "; turned by Euler angles: I = R diag(I_x, I_y, I_z) Rᵀ" } else { "" };
                format!("{}{}", shape.describe(), turned)
            }
            PartKind::Tensor { principal, orientation, .. } => {
                let given = if *principal { "given principal moments" } else { "given tensor" };
                let turned = if orientation.is_some() {
                    if *principal {
                        "; turned by Euler angles: I = R diag(I_x, I_y, I_z) Rᵀ"
                    } else {
                        "; turned by Euler angles: I = R I_part Rᵀ"
                    }
                } else {
                    ""
                };
                format!("{given} about its centre of mass{turned}")
            }
            PartKind::Density { density, .. } => {
                format!("density ρ = {} over a box, by {}", body.pool().display(*density), rp.method)
            }
        };
        let _ = writeln!(s, "  {}: {}", part.name, what);
        let exact = rp.method != "adaptive cubature";
        let m_exact = exact.then(|| p.pool().display(pp.mass).to_string());
        let c_exact = exact.then(|| exact_vector(p, &pp.center_of_mass));
        let _ = writeln!(
            s,
            "    m = {},  c = {}",
            both(m_exact.as_deref(), &human(rp.mass)),
            both(c_exact.as_deref(), &vector(&rp.center_of_mass))
        );
        match &rp.tensor_exact {
            Some(cells) if !is_diagonal_zero(cells) => {
                let _ = write!(s, "{}", matrix(cells, "    "));
            }
            Some(_) => {}
            None => {
                let _ = write!(s, "{}", matrix(&numbers(&rp.tensor), "    "));
            }
        }
    }

    let _ = writeln!(s);
    let _ = writeln!(s, "total mass       M = Σ m = {}", both(r.mass_exact.as_deref(), &human(r.mass)));
    let c_exact = r.center_of_mass_exact.as_ref().map(|c| format!("({})", c.join(", ")));
    let _ = writeln!(s, "centre of mass   R = Σ m c / M = {}", both(c_exact.as_deref(), &vector(&r.center_of_mass)));

    let _ = writeln!(s, "\nInertia tensor about the centre of mass, I_R = Σ [I_c + m (|d|² 1 − d dᵀ)], d = c − R:");
    exact_and_numeric(&mut s, r.tensor_com_exact.as_ref(), &r.tensor_com);

    if !at_com {
        let rvec: [f64; 3] = std::array::from_fn(|a| r.center_of_mass[a] - r.about[a]);
        let p_exact = r.about_exact.as_ref().map(|e| format!("({})", e.join(", ")));
        let about = format!("P = {}", both(p_exact.as_deref(), &vector(&r.about)));
        let _ = writeln!(s, "\nParallel-axis theorem (Steiner) to {about}:");
        let _ = writeln!(s, "  I_P = I_R + M (|r|² 1 − r rᵀ),  r = R − P = {}", vector(&rvec));
        exact_and_numeric(&mut s, r.tensor_exact.as_ref(), &r.tensor);
    }

    if let Some(c) = &r.cubature {
        let scale = r.tensor.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max);
        let _ = writeln!(
            s,
            "\nAdaptive cubature (nested Gauss–Kronrod 7/15, tolerance {:e} relative): estimated error of the tensor entries ≤ {} ({} relative), of the mass ≤ {}; {} density evaluations; numbers below the estimated error are shown as 0",
            mech::inertia::CUBATURE_RTOL,
            human(c.tensor_error),
            human(if scale > 0.0 { c.tensor_error / scale } else { c.tensor_error }),
            human(c.mass_error),
            c.evaluations
        );
        if !c.converged {
            let _ = writeln!(
                s,
                "  warning: the tolerance was not met within the subdivision limit (is the density singular or discontinuous in its box?)"
            );
        }
        let _ = writeln!(s, "  (the density is not a polynomial in x, y, z, so the tensor has no exact form here)");
    }

    let where_ = if at_com { "the centre of mass" } else { "P" };
    let _ = writeln!(s, "\nPrincipal moments (eigenvalues of the tensor about {where_}, ascending) and unit axes:");
    for k in 0..3 {
        let _ =
            writeln!(s, "  I{} = {:<14} axis {}", k + 1, human(r.principal_moments[k]), vector(&r.principal_axes[k]));
    }
    let m = &r.principal_moments;
    let note = match r.symmetry {
        Symmetry::Spherical => {
            "all three moments are equal: a spherical top; every axis through the point is a principal axis".to_string()
        }
        Symmetry::Symmetric => {
            let unique = if (m[0] - m[1]).abs() <= (m[1] - m[2]).abs() { 2 } else { 0 };
            format!(
                "two moments are equal: a symmetric top about the axis of I{} {}; any axis perpendicular to it is principal",
                unique + 1,
                vector(&r.principal_axes[unique])
            )
        }
        Symmetry::Asymmetric => "three different moments: an asymmetric top".to_string(),
    };
    let _ = writeln!(s, "{note}");
    if m[0].abs() <= mech::inertia::DEGENERACY_RTOL * m[2].abs() {
        let _ = writeln!(s, "I1 = 0: all the mass lies on the axis of I1 (a linear body)");
    }
    s
}

/// True when every entry of an exact matrix is 0 (a point mass about itself).
fn is_diagonal_zero(cells: &[[String; 3]; 3]) -> bool {
    cells.iter().flatten().all(|c| c == "0")
}

#[cfg(test)]
mod tests {
    use super::*;

    const DUMBBELL: &str = r#"
name = "dumbbell"
[parameters]
m = 1.0
r = 0.1
l = 1.0
[[parts]]
name = "left ball"
shape = "sphere"
mass = "m"
size = ["r"]
center = ["-l/2", 0, 0]
[[parts]]
name = "right ball"
shape = "sphere"
mass = "m"
size = ["r"]
center = ["l/2", 0, 0]
"#;

    #[track_caller]
    fn check(about: &str, expect: &[&str], absent: &[&str]) {
        let body = BodyFile::parse(DUMBBELL, &[]).unwrap();
        let mut props = body.mass_properties().unwrap();
        let point = props.parse_about(about).unwrap();
        let report = props.report(point);
        let out = text(&body, &props, point, &report);
        for line in expect {
            assert!(out.contains(line), "{line:?} is missing from\n{out}");
        }
        for line in absent {
            assert!(!out.contains(line), "{line:?} is in\n{out}");
        }
    }

    #[test]
    fn text_gives_mass_tensor_and_axes() {
        let common = [
            "dumbbell — inertia tensor (notes, Sec. 3.2.3)\n",
            "  left ball: solid sphere of radius R: I = 2/5 M R^2\n",
            "total mass       M = Σ m = 2*m = 2\n",
            "centre of mass   R = Σ m c / M = (0, 0, 0)\n",
            "two moments are equal: a symmetric top about the axis of I1",
        ];
        check("com", &common, &["Parallel-axis theorem"]);
        check("0,0,1", &[&common[..4], &["Parallel-axis theorem (Steiner) to P = (0, 0, 1):\n"]].concat(), &[]);
    }
}
