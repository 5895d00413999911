//! Inertia tensors of rigid bodies (notes, Sec. 3.2.3): the mass, the centre of
//! mass and I_jk = Σ m (r² δ_jk − x_j x_k) of a body made of parts, exact where
//! the input is, about the centre of mass or any point (Steiner's parallel-axis
//! theorem), with principal moments and axes.
//!
//! Enter with [`BodyFile::parse`] and [`BodyFile::mass_properties`]; then
//! [`MassProperties::about`] moves the tensor to a point and
//! [`MassProperties::report`] builds the `lagrange.inertia/1` report.
//!
//! ```
//! let body = mech::inertia::BodyFile::parse(
//!     "[parameters]\nM = 1.0\na = 1.0\n[[parts]]\nshape = \"box\"\nmass = \"M\"\nsize = [\"a\", \"a\", \"a\"]\ncenter = [\"a/2\", \"a/2\", \"a/2\"]\n",
//!     &[],
//! ).unwrap();
//! let mut props = body.mass_properties().unwrap();
//! let corner = props.parse_about("0,0,0").unwrap();
//! let i = props.about(corner);
//! assert_eq!(props.exact_text(i[0][1]).unwrap(), "-M*a^2/4");
//! ```
//!
//! Each part contributes its mass m, its centre of mass c and its tensor about
//! c in the body's axes: a shape's diagonal tensor turned by its orientation
//! (`R·diag(I₁, I₂, I₃)·Rᵀ` with `R = Dᵀ`, `D` the notes' Euler rotation), a
//! given tensor turned the same way (`R·I·Rᵀ`), or a
//! density's moments integrated over its box, exactly when ρ is a polynomial in
//! x, y, z and by adaptive cubature otherwise. The body's tensor about its
//! centre of mass R is `Σ I_c + m (|d|² 1 − d dᵀ)`, d = c − R, built both about
//! the origin and moved to R, and pairwise as `(1/M) Σ_{i<j} m_i m_j (|Δ|² 1 −
//! Δ Δᵀ)`, Δ = c_i − c_j; each entry keeps the shorter form (the pairwise one on a tie). Every quantity is an expression in a [`Pool`]; its number is its value
//! at the parameters. Numeric cubature enters as float constants, and then the
//! results are marked inexact.

mod body_file;
mod cubature;
mod polynomial;
mod shapes;

pub use body_file::{BodyFile, Part, PartKind, DENSITY_VARIABLES, TENSOR_RTOL};
pub(crate) use cubature::N_MOMENTS;
pub(crate) use polynomial::{as_polynomial, integrate_monomials};

use crate::error::ModelError;
use nalgebra::{Matrix3, SymmetricEigen};
use serde::Serialize;
use sym::{ExprId, ParseOptions, Pool};

/// Relative tolerance of the adaptive cubature of non-polynomial densities.
pub const CUBATURE_RTOL: f64 = 1e-10;

/// A cubature that misses its tolerance is still reported (with a warning)
/// while its estimated relative error of the tensor stays below this; beyond
/// it the density is rejected as too singular to integrate.
pub const CUBATURE_FAIL_RTOL: f64 = 1e-6;

/// Principal moments closer than this (relative to the largest) count as
/// equal when the body's symmetry is named and degenerate axes are chosen.
pub const DEGENERACY_RTOL: f64 = 1e-9;

/// A 3×3 matrix of expressions.
pub type ExprMatrix = [[ExprId; 3]; 3];

/// What one part contributes, in the body's axes.
#[derive(Debug, Clone)]
pub struct PartProperties {
    /// The part's name.
    pub name: String,
    /// Its shape's name (`box`, …, `density`, `tensor`).
    pub shape: &'static str,
    /// Its mass.
    pub mass: ExprId,
    /// Its centre of mass.
    pub center_of_mass: [ExprId; 3],
    /// Its tensor about its own centre of mass, in the body's axes.
    pub tensor: ExprMatrix,
    /// How it was found: `"closed form"`, `"exact polynomial integration"`,
    /// `"adaptive cubature"`, or `"given"` (a tensor part's own).
    pub method: &'static str,
}

/// The result of a numeric cubature, for the report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CubatureSummary {
    /// Estimated absolute error of the tensor entries (summed over the density parts).
    pub tensor_error: f64,
    /// Estimated absolute error of the mass.
    pub mass_error: f64,
    /// Estimated absolute error of the centre of mass's coordinates.
    pub center_of_mass_error: f64,
    /// Density evaluations.
    pub evaluations: u64,
    /// Whether every density met the tolerance [`CUBATURE_RTOL`].
    pub converged: bool,
}

/// Mass, centre of mass and inertia tensor of a body, as expressions with
/// their values. Built by [`BodyFile::mass_properties`].
#[derive(Debug, Clone)]
pub struct MassProperties {
    pool: Pool,
    parameters: Vec<(String, f64)>,
    /// The body's name.
    pub name: String,
    /// True when every expression is exact (no density was integrated numerically).
    pub exact: bool,
    /// Total mass M.
    pub mass: ExprId,
    /// Centre of mass R.
    pub center_of_mass: [ExprId; 3],
    /// The tensor about the centre of mass, in the body's axes.
    pub tensor: ExprMatrix,
    /// The parts' contributions.
    pub parts: Vec<PartProperties>,
    /// Present when a density was integrated numerically.
    pub cubature: Option<CubatureSummary>,
}

/// Principal moments (ascending) and unit axes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Principal {
    /// I₁ ≤ I₂ ≤ I₃.
    pub moments: [f64; 3],
    /// The axis of each moment, a unit vector in the body's axes, its largest
    /// component positive (the first of equal ones); within a degenerate
    /// eigenspace the axes are the projections of x, y, z in that order,
    /// orthonormalized.
    pub axes: [[f64; 3]; 3],
    /// The kind of top the moments make.
    pub symmetry: Symmetry,
}

/// What the principal moments say about the body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Symmetry {
    /// All three equal: every axis is principal.
    Spherical,
    /// Two equal: a symmetric top about the third axis.
    Symmetric,
    /// All different.
    Asymmetric,
}

impl Symmetry {
    /// The name in the text output.
    pub fn name(self) -> &'static str {
        match self {
            Symmetry::Spherical => "spherical top",
            Symmetry::Symmetric => "symmetric top",
            Symmetry::Asymmetric => "asymmetric top",
        }
    }
}

/// The `lagrange.inertia/1` report.
#[derive(Debug, Clone, Serialize)]
pub struct InertiaReport {
    /// `"lagrange.inertia/1"`.
    pub format: &'static str,
    /// The body's name.
    pub name: String,
    /// Total mass.
    pub mass: f64,
    /// Total mass, exact (null after numeric cubature).
    pub mass_exact: Option<String>,
    /// Centre of mass.
    pub center_of_mass: [f64; 3],
    /// Centre of mass, exact.
    pub center_of_mass_exact: Option<[String; 3]>,
    /// The reference point of `tensor`.
    pub about: [f64; 3],
    /// The reference point, exact.
    pub about_exact: Option<[String; 3]>,
    /// The tensor about `about`.
    pub tensor: [[f64; 3]; 3],
    /// The tensor about `about`, exact (null when an entry has no exact form).
    pub tensor_exact: Option<[[String; 3]; 3]>,
    /// The tensor about the centre of mass.
    pub tensor_com: [[f64; 3]; 3],
    /// The tensor about the centre of mass, exact.
    pub tensor_com_exact: Option<[[String; 3]; 3]>,
    /// Principal moments of `tensor`, ascending.
    pub principal_moments: [f64; 3],
    /// The unit principal axis of each moment.
    pub principal_axes: [[f64; 3]; 3],
    /// `"spherical"`, `"symmetric"` or `"asymmetric"`.
    pub symmetry: Symmetry,
    /// Numeric cubature statistics (null when everything is exact).
    pub cubature: Option<CubatureSummary>,
    /// The parts: name, shape, mass, centre of mass and tensor about it.
    pub parts: Vec<PartReport>,
}

/// One part in the report.
#[derive(Debug, Clone, Serialize)]
pub struct PartReport {
    /// Its name.
    pub name: String,
    /// Its shape.
    pub shape: &'static str,
    /// How its tensor was found.
    pub method: &'static str,
    /// Its mass.
    pub mass: f64,
    /// Its centre of mass.
    pub center_of_mass: [f64; 3],
    /// Its tensor about its centre of mass, in the body's axes.
    pub tensor: [[f64; 3]; 3],
    /// The same, exact.
    pub tensor_exact: Option<[[String; 3]; 3]>,
}

/// |v|² 1 − v vᵀ scaled by m: the tensor of a point mass m at v.
fn point_tensor(pool: &mut Pool, m: ExprId, v: [ExprId; 3]) -> ExprMatrix {
    let sq: Vec<ExprId> = v.iter().map(|&x| pool.powi(x, 2)).collect();
    let r2 = pool.add(&sq);
    let mut out = [[pool.zero(); 3]; 3];
    for j in 0..3 {
        for k in 0..3 {
            let xx = pool.mul2(v[j], v[k]);
            let inner = if j == k { pool.sub(r2, xx) } else { pool.neg(xx) };
            out[j][k] = pool.mul2(m, inner);
        }
    }
    out
}

fn mat_add(pool: &mut Pool, a: &ExprMatrix, b: &ExprMatrix) -> ExprMatrix {
    std::array::from_fn(|j| std::array::from_fn(|k| pool.add2(a[j][k], b[j][k])))
}

fn mat_sub(pool: &mut Pool, a: &ExprMatrix, b: &ExprMatrix) -> ExprMatrix {
    std::array::from_fn(|j| std::array::from_fn(|k| pool.sub(a[j][k], b[j][k])))
}

fn simplify_matrix(pool: &mut Pool, a: &ExprMatrix) -> ExprMatrix {
    std::array::from_fn(|j| std::array::from_fn(|k| pool.simplify(a[j][k])))
}

impl BodyFile {
    /// Integrates the parts and combines them: mass, centre of mass and the
    /// tensor about it. Fails (bad input) when a density is not finite in its
    /// box or its mass is not positive, or the body's mass is zero.
    pub fn mass_properties(&self) -> Result<MassProperties, ModelError> {
        let mut pool = self.pool.clone();
        let values: Vec<(String, f64)> = self.parameters.iter().map(|p| (p.name.clone(), p.value)).collect();
        let env = |n: &str| values.iter().find(|(p, _)| p == n).map(|&(_, v)| v);
        let mut parts = Vec::with_capacity(self.parts.len());
        let mut cubature: Option<CubatureSummary> = None;
        for part in &self.parts {
            let props = match &part.kind {
                PartKind::Shape { shape, mass, size, center, orientation } => {
                    let moments = shape.principal_moments(&mut pool, *mass, size);
                    let zero = pool.zero();
                    let diag: ExprMatrix =
                        std::array::from_fn(|j| std::array::from_fn(|k| if j == k { moments[j] } else { zero }));
                    let tensor = match orientation {
                        Some([al, be, ga]) => turn(&mut pool, &diag, *al, *be, *ga),
                        None => diag,
                    };
                    PartProperties {
                        name: part.name.clone(),
                        shape: shape.name(),
                        mass: *mass,
                        center_of_mass: *center,
                        tensor,
                        method: "closed form",
                    }
                }
                PartKind::Tensor { mass, inertia, center, orientation, .. } => {
                    let tensor = match orientation {
                        Some([al, be, ga]) => turn(&mut pool, inertia, *al, *be, *ga),
                        None => *inertia,
                    };
                    PartProperties {
                        name: part.name.clone(),
                        shape: "tensor",
                        mass: *mass,
                        center_of_mass: *center,
                        tensor,
                        method: "given",
                    }
                }
                PartKind::Density { density, span, region } => {
                    let (props, summary) = density_part(&mut pool, &env, &part.name, *density, span, region)?;
                    if let Some(s) = summary {
                        let acc = cubature.get_or_insert(CubatureSummary {
                            tensor_error: 0.0,
                            mass_error: 0.0,
                            center_of_mass_error: 0.0,
                            evaluations: 0,
                            converged: true,
                        });
                        acc.tensor_error += s.tensor_error;
                        acc.mass_error += s.mass_error;
                        // Weighted by the part's mass here, divided by the total below.
                        acc.center_of_mass_error += s.center_of_mass_error * pool.eval(props.mass, &env).unwrap_or(0.0);
                        acc.evaluations += s.evaluations;
                        acc.converged &= s.converged;
                    }
                    props
                }
            };
            parts.push(props);
        }
        let masses: Vec<ExprId> = parts.iter().map(|p| p.mass).collect();
        let total = pool.add(&masses);
        let total = pool.simplify(total);
        let m_value = pool.eval(total, &env).unwrap_or(f64::NAN);
        if m_value.is_nan() || m_value <= 0.0 {
            return Err(ModelError::whole(format!("the body's total mass is {m_value}: expected a positive mass")));
        }
        let inv = pool.powi(total, -1);
        let com: [ExprId; 3] = std::array::from_fn(|a| {
            let terms: Vec<ExprId> = parts.iter().map(|p| pool.mul2(p.mass, p.center_of_mass[a])).collect();
            let first = pool.add(&terms);
            let c = pool.mul2(first, inv);
            pool.simplify(c)
        });
        if let Some(c) = &mut cubature {
            c.center_of_mass_error /= m_value;
        }
        // Two equal forms, and each entry keeps the shorter after simplification.
        // About the origin, then moved to R: short when R is simple (one part, symmetric bodies).
        let mut origin = [[pool.zero(); 3]; 3];
        for p in &parts {
            let shift = point_tensor(&mut pool, p.mass, p.center_of_mass);
            let about_origin = mat_add(&mut pool, &p.tensor, &shift);
            origin = mat_add(&mut pool, &origin, &about_origin);
        }
        let back = point_tensor(&mut pool, total, com);
        let moved = mat_sub(&mut pool, &origin, &back);
        let moved = simplify_matrix(&mut pool, &moved);
        // Pairwise: Σ m_i (|d_i|² 1 − d_i d_iᵀ) with d_i = c_i − R equals
        // (1/M) Σ_{i<j} m_i m_j (|Δ|² 1 − Δ Δᵀ), Δ = c_i − c_j: no R, so no
        // cancellation, and two masses give the reduced mass m₁m₂/(m₁ + m₂).
        let mut tensor = [[pool.zero(); 3]; 3];
        for p in &parts {
            tensor = mat_add(&mut pool, &tensor, &p.tensor);
        }
        for i in 0..parts.len() {
            for j in i + 1..parts.len() {
                let delta: [ExprId; 3] =
                    std::array::from_fn(|a| pool.sub(parts[i].center_of_mass[a], parts[j].center_of_mass[a]));
                let delta = delta.map(|d| pool.simplify(d));
                if delta.iter().all(|&d| pool.is_zero(d)) {
                    continue;
                }
                let mu = pool.mul(&[parts[i].mass, parts[j].mass, inv]);
                let pair = point_tensor(&mut pool, mu, delta);
                tensor = mat_add(&mut pool, &tensor, &pair);
            }
        }
        let pairwise = simplify_matrix(&mut pool, &tensor);
        let tensor: ExprMatrix = std::array::from_fn(|j| {
            std::array::from_fn(|k| {
                let (a, b) = (moved[j][k], pairwise[j][k]);
                if pool.tree_size(b) <= pool.tree_size(a) {
                    b
                } else {
                    a
                }
            })
        });
        for p in &mut parts {
            p.tensor = simplify_matrix(&mut pool, &p.tensor);
        }
        Ok(MassProperties {
            pool,
            parameters: values.clone(),
            name: self.name.clone(),
            exact: cubature.is_none(),
            mass: total,
            center_of_mass: com,
            tensor,
            parts,
            cubature,
        })
    }
}

/// `R·I·Rᵀ` with `R = Dᵀ`: the tensor of a part whose own axes are the body
/// axes of the Euler rotation `D(α, β, γ)` (components r_body = Dᵀ·r_part).
fn turn(pool: &mut Pool, i: &ExprMatrix, al: ExprId, be: ExprId, ga: ExprId) -> ExprMatrix {
    // D in placeholder angles, then sin and cos of each replaced by exact
    // values where the angle is a multiple of π/6 or π/4, so that
    // `orientation = ["pi/2", "pi/2", 0]` turns a part exactly.
    let names = ["inertia·α", "inertia·β", "inertia·γ"];
    let holders = names.map(|n| pool.symbol(n));
    let d = crate::euler::rotation(pool, holders[0], holders[1], holders[2]);
    let mut map = rustc_hash::FxHashMap::default();
    for (h, angle) in holders.into_iter().zip([al, be, ga]) {
        map.insert(h, angle);
        for f in [sym::Func::Sin, sym::Func::Cos] {
            let key = pool.func(f, h);
            let value = exact_trig(pool, f, angle).unwrap_or_else(|| pool.func(f, angle));
            map.insert(key, value);
        }
    }
    let d = d.map(|row| row.map(|e| pool.substitute(e, &map)));
    std::array::from_fn(|j| {
        std::array::from_fn(|k| {
            let mut terms = Vec::with_capacity(9);
            for a in 0..3 {
                for b in 0..3 {
                    if !pool.is_zero(i[a][b]) {
                        terms.push(pool.mul(&[d[a][j], i[a][b], d[b][k]]));
                    }
                }
            }
            let sum = pool.add(&terms);
            pool.simplify(sum)
        })
    })
}

/// sin or cos of `angle` exactly (0, ±1/2, ±sqrt(2)/2, ±sqrt(3)/2, ±1) when
/// the angle is a rational multiple of π that is a multiple of π/6 or π/4.
fn exact_trig(pool: &mut Pool, f: sym::Func, angle: ExprId) -> Option<ExprId> {
    let (coeff, rest) = pool.split_coeff(angle);
    let q = coeff.as_rational()?;
    let in_pi = matches!(pool.node(rest), sym::Node::Pi) || (q.is_zero());
    if !in_pi {
        return None;
    }
    // The angle in twelfths of π.
    let t = q.checked_mul(sym::Rational::new(12, 1)?).filter(|t| t.is_integer())?.numer();
    if t % 2 != 0 && t % 3 != 0 {
        return None;
    }
    let x = (t.rem_euclid(24) as f64) * std::f64::consts::PI / 12.0;
    let v = if f == sym::Func::Sin { x.sin() } else { x.cos() };
    let half = pool.rational(1, 2);
    let (two, three) = (pool.int(2), pool.int(3));
    let (r2, r3) = (pool.sqrt(two), pool.sqrt(three));
    let candidates = [
        (0.0, pool.zero()),
        (0.5, half),
        (0.5f64.sqrt(), pool.mul2(half, r2)),
        (0.75f64.sqrt(), pool.mul2(half, r3)),
        (1.0, pool.one()),
    ];
    let &(_, exact) = candidates.iter().find(|(c, _)| (v.abs() - c).abs() < 1e-12)?;
    Some(if v < 0.0 { pool.neg(exact) } else { exact })
}

/// A density part's mass, centre of mass and tensor about it: exact for a
/// polynomial density, by cubature (with its summary) otherwise.
fn density_part(
    pool: &mut Pool,
    env: &dyn Fn(&str) -> Option<f64>,
    name: &str,
    density: ExprId,
    span: &std::ops::Range<usize>,
    region: &[[ExprId; 2]; 3],
) -> Result<(PartProperties, Option<CubatureSummary>), ModelError> {
    let vars = DENSITY_VARIABLES.map(|v| pool.symbol(v));
    // The ten moments ∫ρ·(1, x, y, z, x², y², z², xy, xz, yz) dV, about the origin.
    const WEIGHTS: [[u32; 3]; N_MOMENTS] =
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [2, 0, 0], [0, 2, 0], [0, 0, 2], [1, 1, 0], [1, 0, 1], [0, 1, 1]];
    let moments: [ExprId; N_MOMENTS] = match as_polynomial(pool, density, vars) {
        Some(poly) => std::array::from_fn(|k| {
            let i = integrate_monomials(pool, &poly, WEIGHTS[k], region);
            pool.simplify(i)
        }),
        None => {
            let bounds = region.map(|r| r.map(|e| pool.eval(e, env).unwrap_or(f64::NAN)));
            let numbers: Vec<(ExprId, sym::Number)> = pool
                .symbols(density)
                .into_iter()
                .filter_map(|s| {
                    let text = pool.symbol_text(s);
                    env(&text).map(|v| (pool.sym(s), sym::Number::float(v)))
                })
                .collect();
            let rho = pool.substitute_numbers(density, &numbers);
            let mut tape = sym::Tape::compile(pool, &[rho], &vars)
                .map_err(|e| ModelError::at(span.clone(), format!("the density cannot be evaluated: {e}")))?;
            let mut out = [0.0];
            let mut f = |x: [f64; 3]| {
                tape.eval(&x, &mut out);
                out[0]
            };
            let m = cubature::moments(&mut f, bounds, CUBATURE_RTOL).map_err(|bad| {
                ModelError::at(
                    span.clone(),
                    format!(
                        "the density is {} at (x, y, z) = ({}, {}, {}): expected a finite value throughout the region",
                        bad.value, bad.at[0], bad.at[1], bad.at[2]
                    ),
                )
            })?;
            let [v, e] = [m.estimate.value, m.estimate.error];
            let summary = CubatureSummary {
                tensor_error: 2.0 * e[4..].iter().sum::<f64>(),
                mass_error: e[0],
                center_of_mass_error: (e[1..4].iter().sum::<f64>()
                    + e[0] * v[1..4].iter().map(|x| x.abs()).sum::<f64>() / v[0].abs())
                    / v[0].abs(),
                evaluations: m.evaluations,
                converged: m.converged,
            };
            if v[0].is_nan() || v[0] <= 0.0 {
                return Err(mass_error(span, name, v[0]));
            }
            let scale = (v[4] + v[5] + v[6]).abs();
            let rel = summary.tensor_error / scale.max(f64::MIN_POSITIVE);
            if !m.converged && (rel > CUBATURE_FAIL_RTOL || summary.mass_error > CUBATURE_FAIL_RTOL * v[0]) {
                return Err(ModelError::at(
                    span.clone(),
                    format!(
                        "the cubature of this density did not converge: estimated relative error {rel:.1e} of the tensor and {:.1e} of the mass after {} evaluations",
                        summary.mass_error / v[0],
                        m.evaluations
                    ),
                )
                .with_help("the density may be singular or discontinuous in its region; split the region where it jumps, or check that ∫ρ dV is finite"));
            }
            // Central second moments C = S − m d dᵀ (d: the CM from the box's
            // centre), then I = tr(C) 1 − C, all in floats about the CM.
            let d = [v[1] / v[0], v[2] / v[0], v[3] / v[0]];
            let s = |j: usize, k: usize| v[second_index(j, k)] - v[0] * d[j] * d[k];
            let trace = s(0, 0) + s(1, 1) + s(2, 2);
            let tensor: ExprMatrix = std::array::from_fn(|j| {
                std::array::from_fn(|k| pool.float(if j == k { trace - s(j, j) } else { -s(j, k) }))
            });
            let com = std::array::from_fn(|a| pool.float(m.center[a] + d[a]));
            let mass = pool.float(v[0]);
            let props = PartProperties {
                name: name.to_string(),
                shape: "density",
                mass,
                center_of_mass: com,
                tensor,
                method: "adaptive cubature",
            };
            return Ok((props, Some(summary)));
        }
    };
    let mass = moments[0];
    let m_value = pool.eval(mass, env).unwrap_or(f64::NAN);
    if m_value.is_nan() || m_value <= 0.0 {
        return Err(mass_error(span, name, m_value));
    }
    let inv = pool.powi(mass, -1);
    let com: [ExprId; 3] = std::array::from_fn(|a| {
        let c = pool.mul2(moments[1 + a], inv);
        pool.simplify(c)
    });
    // I about the origin from the second moments S: I = tr(S) 1 − S.
    let s = second_index;
    let trace = pool.add(&[moments[4], moments[5], moments[6]]);
    let origin: ExprMatrix = std::array::from_fn(|j| {
        std::array::from_fn(|k| if j == k { pool.sub(trace, moments[s(j, j)]) } else { pool.neg(moments[s(j, k)]) })
    });
    let back = point_tensor(pool, mass, com);
    let tensor = mat_sub(pool, &origin, &back);
    let method = "exact polynomial integration";
    let props = PartProperties { name: name.to_string(), shape: "density", mass, center_of_mass: com, tensor, method };
    Ok((props, None))
}

/// Where ∫ρ x_j x_k sits among the ten moments.
fn second_index(j: usize, k: usize) -> usize {
    match (j.min(k), j.max(k)) {
        (0, 0) => 4,
        (1, 1) => 5,
        (2, 2) => 6,
        (0, 1) => 7,
        (0, 2) => 8,
        _ => 9,
    }
}

fn mass_error(span: &std::ops::Range<usize>, name: &str, m: f64) -> ModelError {
    ModelError::at(
        span.clone(),
        format!("the mass of part '{name}' (∫ρ dV over its region) is {m}: expected a positive mass"),
    )
}

impl MassProperties {
    /// The arena holding every expression.
    pub fn pool(&self) -> &Pool {
        &self.pool
    }

    /// The parameters' values.
    pub fn parameters(&self) -> &[(String, f64)] {
        &self.parameters
    }

    /// The value of an expression at the parameters (NaN if it has none).
    pub fn value(&self, e: ExprId) -> f64 {
        let env = |n: &str| self.parameters.iter().find(|(p, _)| p == n).map(|&(_, v)| v);
        self.pool.eval(e, &env).unwrap_or(f64::NAN)
    }

    /// The values of a matrix of expressions.
    pub fn values(&self, m: &ExprMatrix) -> [[f64; 3]; 3] {
        m.map(|row| row.map(|e| self.value(e)))
    }

    /// An expression as text in the expression language, when the results are exact.
    pub fn exact_text(&self, e: ExprId) -> Option<String> {
        self.exact.then(|| self.pool.display(e).to_string())
    }

    /// The tensor about `point`: I_P = I_cm + M (|r|² 1 − r rᵀ), r = R − P
    /// (Steiner's parallel-axis theorem), simplified.
    pub fn about(&mut self, point: [ExprId; 3]) -> ExprMatrix {
        let pool = &mut self.pool;
        let r: [ExprId; 3] = std::array::from_fn(|a| pool.sub(self.center_of_mass[a], point[a]));
        let shift = point_tensor(pool, self.mass, r);
        let sum = mat_add(pool, &self.tensor, &shift);
        simplify_matrix(pool, &sum)
    }

    /// The tensor about `point` in numbers only (no expressions are built).
    pub fn about_values(&self, point: [f64; 3]) -> [[f64; 3]; 3] {
        let t = self.values(&self.tensor);
        let m = self.value(self.mass);
        let r: [f64; 3] = std::array::from_fn(|a| self.value(self.center_of_mass[a]) - point[a]);
        let r2: f64 = r.iter().map(|x| x * x).sum();
        std::array::from_fn(|j| std::array::from_fn(|k| t[j][k] + m * (if j == k { r2 } else { 0.0 } - r[j] * r[k])))
    }

    /// Reads a reference point: `com` (the centre of mass) or three
    /// comma-separated numbers or expressions in the parameters (`0,0,0`,
    /// `a/2,0,0`). Error spans are byte ranges into `text`.
    pub fn parse_about(&mut self, text: &str) -> Result<[ExprId; 3], ModelError> {
        if text.trim() == "com" {
            return Ok(self.center_of_mass);
        }
        let pieces: Vec<(usize, &str)> = {
            let mut start = 0;
            let mut out = Vec::new();
            for piece in text.split(',') {
                out.push((start, piece));
                start += piece.len() + 1;
            }
            out
        };
        if pieces.len() != 3 {
            return Err(ModelError::at(
                0..text.len(),
                format!("expected `com` or a point x,y,z, found {} components", pieces.len()),
            ));
        }
        let names: Vec<String> = self.parameters.iter().map(|(n, _)| n.clone()).collect();
        let known = |name: &str, order: u8| order == 0 && names.iter().any(|p| p == name);
        let opts = ParseOptions::default().with_known(&known);
        let mut point = [self.pool.zero(); 3];
        for (a, (start, piece)) in pieces.into_iter().enumerate() {
            let e = self.pool.parse_with(piece, &opts).map_err(|err| {
                let s = start + err.span.start as usize;
                let end = start + (err.span.end as usize).max(err.span.start as usize + 1);
                ModelError::at(s..end.min(text.len().max(s + 1)), format!("in the point: {err}"))
                    .with_help("use numbers or expressions in the body's parameters")
            })?;
            if !self.value(e).is_finite() {
                return Err(ModelError::at(start..start + piece.len(), "this coordinate is not a finite number"));
            }
            point[a] = e;
        }
        Ok(point)
    }

    /// The report about `point` (see [`MassProperties::parse_about`]).
    pub fn report(&mut self, point: [ExprId; 3]) -> InertiaReport {
        let tensor = self.about(point);
        let values = self.values(&tensor);
        let principal = principal(&values);
        let exact_matrix =
            |s: &Self, m: &ExprMatrix| s.exact.then(|| m.map(|row| row.map(|e| s.pool.display(e).to_string())));
        let exact_vec = |s: &Self, v: &[ExprId; 3]| s.exact.then(|| v.map(|e| s.pool.display(e).to_string()));
        InertiaReport {
            format: "lagrange.inertia/1",
            name: self.name.clone(),
            mass: self.value(self.mass),
            mass_exact: self.exact_text(self.mass),
            center_of_mass: self.center_of_mass.map(|e| self.value(e)),
            center_of_mass_exact: exact_vec(self, &self.center_of_mass),
            about: point.map(|e| self.value(e)),
            about_exact: exact_vec(self, &point),
            tensor: values,
            tensor_exact: exact_matrix(self, &tensor),
            tensor_com: self.values(&self.tensor),
            tensor_com_exact: exact_matrix(self, &self.tensor),
            principal_moments: principal.moments,
            principal_axes: principal.axes,
            symmetry: principal.symmetry,
            cubature: self.cubature,
            parts: self
                .parts
                .iter()
                .map(|p| PartReport {
                    name: p.name.clone(),
                    shape: p.shape,
                    method: p.method,
                    mass: self.value(p.mass),
                    center_of_mass: p.center_of_mass.map(|e| self.value(e)),
                    tensor: self.values(&p.tensor),
                    tensor_exact: (p.method != "adaptive cubature")
                        .then(|| p.tensor.map(|row| row.map(|e| self.pool.display(e).to_string()))),
                })
                .collect(),
        }
    }
}

/// Principal moments (ascending) and axes of a symmetric tensor, with a
/// deterministic choice of signs and of axes within degenerate eigenspaces.
pub fn principal(tensor: &[[f64; 3]; 3]) -> Principal {
    let m = Matrix3::from_fn(|j, k| 0.5 * (tensor[j][k] + tensor[k][j]));
    let eig = SymmetricEigen::new(m);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let moments = order.map(|i| eig.eigenvalues[i]);
    let vectors = order.map(|i| {
        let c = eig.eigenvectors.column(i);
        [c[0], c[1], c[2]]
    });
    let scale = moments.iter().map(|x| x.abs()).fold(0.0, f64::max);
    let same = |a: f64, b: f64| (a - b).abs() <= DEGENERACY_RTOL * scale;
    let mut axes = [[0.0; 3]; 3];
    let mut i = 0;
    while i < 3 {
        // The cluster of equal moments starting at i.
        let mut j = i + 1;
        while j < 3 && same(moments[i], moments[j]) {
            j += 1;
        }
        if j - i == 1 {
            axes[i] = vectors[i];
        } else {
            // Project x, y, z onto the eigenspace in turn and orthonormalize.
            let basis = &vectors[i..j];
            let mut chosen: Vec<[f64; 3]> = Vec::new();
            for e in 0..3 {
                if chosen.len() == j - i {
                    break;
                }
                let mut w = [0.0; 3];
                for b in basis {
                    for (t, wt) in w.iter_mut().enumerate() {
                        *wt += b[e] * b[t];
                    }
                }
                for c in &chosen {
                    let d: f64 = (0..3).map(|t| w[t] * c[t]).sum();
                    for (t, wt) in w.iter_mut().enumerate() {
                        *wt -= d * c[t];
                    }
                }
                let n = w.iter().map(|x| x * x).sum::<f64>().sqrt();
                if n > 1e-6 {
                    chosen.push(w.map(|x| x / n));
                }
            }
            for (k, c) in chosen.into_iter().enumerate() {
                axes[i + k] = c;
            }
        }
        i = j;
    }
    for a in &mut axes {
        let big = a.iter().map(|x| x.abs()).fold(0.0, f64::max);
        let lead = a.iter().find(|x| x.abs() >= big * (1.0 - 1e-9)).copied().unwrap_or(0.0);
        if lead < 0.0 {
            *a = a.map(|x| -x);
        }
        // Round-off below 1e-14 of a unit vector is zero (and −0 is 0).
        *a = a.map(|x| if x.abs() < 1e-14 { 0.0 } else { x });
    }
    let symmetry = match (same(moments[0], moments[1]), same(moments[1], moments[2])) {
        (true, true) => Symmetry::Spherical,
        (true, false) | (false, true) => Symmetry::Symmetric,
        (false, false) => Symmetry::Asymmetric,
    };
    Principal { moments, axes, symmetry }
}

#[cfg(test)]
mod tests;
