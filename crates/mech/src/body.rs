//! Rigid bodies in model files (`[[bodies]]`, notes 3.2.4–3.2.6 and appendix A.5):
//! reading a body's table, and turning it into its kinetic energy, its gravity
//! potential and its body-frame angular velocity and angular momentum.
//!
//! A body has a mass M, an inertia tensor `I` about its *reference point* (three
//! principal moments or a symmetric 3×3 tensor, body components), three
//! coordinates used as Euler angles (α, β, γ in the notes' convention, see
//! [`crate::euler`]), the reference point's position `x_ref(q, t)` in space, and
//! the centre of mass `c` relative to the reference point in body components.
//! With `r = Dᵀc` the centre of mass relative to the reference point in space,
//!
//! ```text
//! T = ½M|v_ref|² + M v_ref·(ω × r) + ½ωᵀ I ω        (ω, I in body components)
//! U = M g z_cm,   z_cm = x_ref,3 + (Dᵀc)₃
//! L = I ω + M c × (D v_ref)                       (about the reference point, body components)
//! ```
//!
//! For a fixed pivot (v_ref = 0) T = ½ωᵀIω with I about the pivot (the notes'
//! heavy top); for the reference point at the centre of mass (c = 0) T splits
//! into ½Mv² + ½ωᵀIω. The cross term is computed as M (D v_ref)·(ω × c), all in
//! body components.
//!
//! The Euler angles are singular where sin β = 0 (α and γ turn about the same
//! axis; the angles' mass matrix loses rank): [`gimbal_guards`] gives the runs
//! a condition to stop on before the integrator produces garbage there.

use crate::error::ModelError;
use crate::euler;
use crate::model::{Located, NumOrText, Reader, Scope};
use crate::probe;
use serde::Deserialize;
use std::ops::Range;
use sym::{ExprId, Func, Pool, Symbol};
use toml::Spanned;

/// A rigid body of a model.
#[derive(Debug, Clone)]
pub struct Body {
    /// Its name (`name`, or `body1`, `body2`, … in file order).
    pub name: String,
    /// Its mass M (an expression in the parameters).
    pub mass: ExprId,
    /// The inertia tensor about the reference point, body components, symmetric.
    pub inertia: [[ExprId; 3]; 3],
    /// Whether the inertia was given as three principal moments.
    pub principal: bool,
    /// The coordinates used as Euler angles (α, β, γ), as coordinate indices.
    pub angles: [usize; 3],
    /// The reference point in space, functions of (q, t).
    pub position: [ExprId; 3],
    /// The centre of mass relative to the reference point, body components (parameters).
    pub center_of_mass: [ExprId; 3],
    /// Where the body's table is.
    pub span: Range<usize>,
    /// Where its `inertia` is.
    pub inertia_span: Range<usize>,
}

/// The `[[bodies]]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBody {
    name: Option<Spanned<String>>,
    mass: Option<Spanned<NumOrText>>,
    inertia: Spanned<toml::Value>,
    angles: Spanned<Vec<Spanned<String>>>,
    position: Option<Spanned<Vec<Spanned<NumOrText>>>>,
    center_of_mass: Option<Spanned<Vec<Spanned<NumOrText>>>>,
}

/// Reads every `[[bodies]]` table. `gravity` says whether the model has gravity
/// (bodies fall along −z, so particles of the same model need 3-D positions).
pub(crate) fn read_all(r: &mut Reader<'_>, raw: &[Spanned<RawBody>]) -> Result<Vec<Body>, ModelError> {
    let mut bodies: Vec<Body> = Vec::new();
    for (k, b) in raw.iter().enumerate() {
        let body = read(r, b, k)?;
        for other in &bodies {
            if let Some(&shared) = body.angles.iter().find(|a| other.angles.contains(a)) {
                let span = b.get_ref().angles.span();
                return Err(ModelError::at(
                    span,
                    format!(
                        "coordinate '{}' is already an Euler angle of body '{}'",
                        r.coordinates[shared].name, other.name
                    ),
                )
                .with_help("each body turns with its own three angles"));
            }
            if other.name == body.name {
                let span = b.get_ref().name.as_ref().map_or(b.span(), |n| n.span());
                return Err(ModelError::at(span, format!("two bodies are named '{}'", body.name)));
            }
        }
        bodies.push(body);
    }
    Ok(bodies)
}

fn read(r: &mut Reader<'_>, b: &Spanned<RawBody>, index: usize) -> Result<Body, ModelError> {
    let raw = b.get_ref();
    let name = match &raw.name {
        Some(n) => {
            crate::model::check_identifier(n, "body name")?;
            n.get_ref().clone()
        }
        None => format!("body{}", index + 1),
    };
    // A body file gives the mass, the centre of mass and the tensor at once.
    let file = match raw.inertia.get_ref() {
        toml::Value::String(s) if s.trim_end().ends_with(".toml") => {
            Some(load_body_file(r, s.trim_end(), raw.inertia.span())?)
        }
        _ => None,
    };
    let mass = match (&raw.mass, &file) {
        (Some(m), _) => r.num_or_expr(m, Scope::Parameters, "the body's mass")?,
        (None, Some(f)) => Located { expr: crate::model::number_expr(&mut r.pool, f.mass), span: raw.inertia.span() },
        (None, None) => {
            return Err(ModelError::at(b.span(), "the body has no `mass`").with_help(
                "give mass = \"M\" (a number or an expression in the parameters), or a body file as `inertia`",
            ))
        }
    };

    // Angles: three distinct coordinates.
    let angles_raw = raw.angles.get_ref();
    if angles_raw.len() != 3 {
        return Err(ModelError::at(
            raw.angles.span(),
            format!("`angles` names the three Euler angles (α, β, γ), not {}", angles_raw.len()),
        )
        .with_help("e.g. angles = [\"al\", \"be\", \"ga\"], each one of the model's coordinates"));
    }
    let mut angles = [0usize; 3];
    for (k, a) in angles_raw.iter().enumerate() {
        let Some(i) = r.coordinates.iter().position(|c| &c.name == a.get_ref()) else {
            return Err(ModelError::at(a.span(), format!("Euler angle '{}' is not a coordinate", a.get_ref()))
                .with_help("list it in `coordinates`"));
        };
        if angles[..k].contains(&i) {
            return Err(ModelError::at(a.span(), format!("Euler angle '{}' is listed twice", a.get_ref()))
                .with_help("α, β and γ are three different coordinates"));
        }
        angles[k] = i;
    }

    // Reference point and centre of mass: three components each.
    let three = |r: &mut Reader<'_>,
                 v: &Option<Spanned<Vec<Spanned<NumOrText>>>>,
                 scope: Scope,
                 what: &str|
     -> Result<[ExprId; 3], ModelError> {
        let Some(v) = v else { return Ok([r.pool.zero(); 3]) };
        if v.get_ref().len() != 3 {
            return Err(ModelError::at(
                v.span(),
                format!("a body's {what} has 3 components (x, y, z), not {}", v.get_ref().len()),
            )
            .with_help("rigid bodies live in three dimensions"));
        }
        let mut out = [r.pool.zero(); 3];
        for (k, x) in v.get_ref().iter().enumerate() {
            out[k] = r.num_or_expr(x, scope, &format!("the body's {what}"))?.expr;
        }
        Ok(out)
    };
    let position = three(r, &raw.position, Scope::Configuration, "position")?;
    let mut center_of_mass = three(r, &raw.center_of_mass, Scope::Parameters, "center_of_mass")?;
    let (inertia, principal) = match &file {
        Some(f) => {
            agree_with_file(r, mass.expr, f.mass, mass.span.clone(), "mass")?;
            match &raw.center_of_mass {
                Some(c) => {
                    for k in 0..3 {
                        let what = format!("centre of mass component {}", k + 1);
                        agree_with_file(r, center_of_mass[k], f.center_of_mass[k], c.span(), &what)?;
                    }
                }
                None => center_of_mass = f.center_of_mass.map(|x| crate::model::number_expr(&mut r.pool, x)),
            }
            let tensor = f.tensor.map(|row| row.map(|x| crate::model::number_expr(&mut r.pool, x)));
            let diagonal = (0..3).all(|i| (0..3).all(|j| i == j || f.tensor[i][j] == 0.0));
            (tensor, diagonal)
        }
        None => read_inertia(r, &raw.inertia)?,
    };

    // Numeric sanity at the parameters' values: M > 0, I positive definite.
    let values = |r: &Reader<'_>, e: ExprId| {
        let env = |n: &str| r.parameters.iter().find(|p| p.name == n).map(|p| p.value);
        r.pool.eval(e, &env).ok()
    };
    if let Some(m) = values(r, mass.expr) {
        if m.is_nan() || m <= 0.0 {
            return Err(ModelError::at(mass.span.clone(), format!("the body's mass must be positive, not {m}")));
        }
    }
    let mut num = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            num[i][j] = values(r, inertia[i][j]).unwrap_or(f64::NAN);
        }
    }
    if num.iter().flatten().all(|v| v.is_finite()) && !positive_definite(&num) {
        return Err(ModelError::at(
            raw.inertia.span(),
            format!("the inertia tensor {num:?} is not positive definite at the parameters' values"),
        )
        .with_help("principal moments are positive (and each is at most the sum of the other two)"));
    }
    Ok(Body {
        name,
        mass: mass.expr,
        inertia,
        principal,
        angles,
        position,
        center_of_mass,
        span: b.span(),
        inertia_span: raw.inertia.span(),
    })
}

/// What a body file says about a body, as numbers at the file's own parameters.
struct FileBody {
    mass: f64,
    center_of_mass: [f64; 3],
    /// The tensor about the file's origin (the body's reference point), body axes.
    tensor: [[f64; 3]; 3],
}

/// Reads and evaluates the body file `name` (see `lagrange inertia`): its
/// origin is the body's reference point and its axes are the body axes.
fn load_body_file(r: &mut Reader<'_>, name: &str, span: Range<usize>) -> Result<FileBody, ModelError> {
    let text = (r.files)(name)
        .map_err(|e| ModelError::at(span.clone(), format!("cannot read the body file '{name}': {e}")))?;
    let nested = |e: ModelError| {
        let place = match &e.span {
            Some(s) => {
                let before = &text[..s.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let col = before.chars().rev().take_while(|&c| c != '\n').count() + 1;
                format!("{name}:{line}:{col}")
            }
            None => name.to_string(),
        };
        let mut err = ModelError::at(span.clone(), format!("in the body file {place}: {}", e.message));
        err.help = e.help;
        err
    };
    let body = crate::inertia::BodyFile::parse(&text, &[]).map_err(nested)?;
    let props = body.mass_properties().map_err(nested)?;
    Ok(FileBody {
        mass: props.value(props.mass),
        center_of_mass: props.center_of_mass.map(|c| props.value(c)),
        tensor: props.about_values([0.0; 3]),
    })
}

/// A value the model gives beside a body file must be the file's (to 1e-9 relative).
fn agree_with_file(r: &Reader<'_>, given: ExprId, want: f64, span: Range<usize>, what: &str) -> Result<(), ModelError> {
    let env = |n: &str| r.parameters.iter().find(|p| p.name == n).map(|p| p.value);
    match r.pool.eval(given, &env) {
        Ok(v) if (v - want).abs() <= 1e-9 * want.abs().max(1.0) => Ok(()),
        Ok(v) => Err(ModelError::at(span, format!("the body's {what} is {v} here but {want} in its body file"))
            .with_help(format!("leave the {what} out to take it from the body file"))),
        Err(e) => Err(ModelError::at(span, e.to_string())),
    }
}

/// Leading principal minors all positive.
fn positive_definite(m: &[[f64; 3]; 3]) -> bool {
    let d1 = m[0][0];
    let d2 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let d3 = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    d1 > 0.0 && d2 > 0.0 && d3 > 0.0
}

/// The inertia: three principal moments, or a symmetric 3×3 tensor.
fn read_inertia(r: &mut Reader<'_>, v: &Spanned<toml::Value>) -> Result<([[ExprId; 3]; 3], bool), ModelError> {
    let span = v.span();
    let expected = "expected three principal moments [\"I1\", \"I2\", \"I3\"] or a 3×3 tensor [[..], [..], [..]]";
    match v.get_ref() {
        toml::Value::Array(rows) if rows.len() == 3 && rows.iter().all(|x| x.is_array()) => {
            let mut cursor = span.start;
            let mut m = [[r.pool.zero(); 3]; 3];
            for (i, row) in rows.iter().enumerate() {
                let row = row.as_array().expect("checked");
                if row.len() != 3 {
                    return Err(ModelError::at(
                        span.clone(),
                        format!("row {} of the inertia tensor has {} entries, not 3", i + 1, row.len()),
                    ));
                }
                for (j, x) in row.iter().enumerate() {
                    m[i][j] = entry(r, x, &span, &mut cursor, &format!("the inertia entry I{}{}", i + 1, j + 1))?;
                }
            }
            for i in 0..3 {
                for j in i + 1..3 {
                    if !probe::are_equal(&mut r.pool, m[i][j], m[j][i]) {
                        return Err(ModelError::at(
                            span,
                            format!(
                                "the inertia tensor is not symmetric: I{}{} = {} but I{}{} = {}",
                                i + 1,
                                j + 1,
                                r.pool.display(m[i][j]),
                                j + 1,
                                i + 1,
                                r.pool.display(m[j][i])
                            ),
                        ));
                    }
                }
            }
            Ok((m, false))
        }
        toml::Value::Array(items) if items.len() == 3 && items.iter().all(|x| !x.is_array()) => {
            let mut cursor = span.start;
            let zero = r.pool.zero();
            let mut m = [[zero; 3]; 3];
            for (k, x) in items.iter().enumerate() {
                m[k][k] = entry(r, x, &span, &mut cursor, &format!("the principal moment I{}", k + 1))?;
            }
            Ok((m, true))
        }
        toml::Value::Array(items) => {
            Err(ModelError::at(span, format!("the inertia has {} entries: {expected}", items.len())))
        }
        _ => Err(ModelError::at(span, format!("the inertia is not a list: {expected}"))),
    }
}

/// One number or expression of the inertia, located in the file by searching
/// for its text from `cursor` (toml gives the span of the whole array only).
fn entry(
    r: &mut Reader<'_>,
    x: &toml::Value,
    span: &Range<usize>,
    cursor: &mut usize,
    what: &str,
) -> Result<ExprId, ModelError> {
    match x {
        toml::Value::Integer(i) => Ok(crate::model::number_expr(&mut r.pool, *i as f64)),
        toml::Value::Float(f) if f.is_finite() => Ok(crate::model::number_expr(&mut r.pool, *f)),
        toml::Value::String(s) => {
            let hay = r.source.get(*cursor..span.end).unwrap_or("");
            let at = ["\"", "'"].iter().find_map(|q| hay.find(&format!("{q}{s}{q}")).map(|p| (p, q.len())));
            let located = match at {
                Some((p, ql)) => {
                    let start = *cursor + p;
                    *cursor = start + s.len() + 2 * ql;
                    start..*cursor
                }
                None => span.clone(),
            };
            Ok(r.expr_str(s, located, Scope::Parameters, what)?.expr)
        }
        _ => Err(ModelError::at(span.clone(), format!("{what} must be a number or an expression string"))),
    }
}

/// What a body contributes to a derivation, as expressions in (q, q', t).
#[derive(Debug, Clone)]
pub struct BodyTerms {
    /// Its kinetic energy.
    pub kinetic: ExprId,
    /// M g z_cm, when the model has gravity.
    pub potential: Option<ExprId>,
    /// Body-frame angular velocity (ω₁, ω₂, ω₃).
    pub omega: [ExprId; 3],
    /// Body-frame angular momentum about the reference point.
    pub angular_momentum: [ExprId; 3],
}

/// A body's angular velocity and angular momentum in a derivation (simplified).
#[derive(Debug, Clone)]
pub struct BodyMotion {
    /// The body's name.
    pub name: String,
    /// Body-frame angular velocity (ω₁, ω₂, ω₃), in (q, q').
    pub omega: [ExprId; 3],
    /// Body-frame angular momentum (L₁, L₂, L₃) about the reference point.
    pub angular_momentum: [ExprId; 3],
}

/// The kinetic energy, gravity potential, ω and L of a body (see the module text).
pub fn terms(
    pool: &mut Pool,
    body: &Body,
    q: &[ExprId],
    qd: &[ExprId],
    t: ExprId,
    gravity: Option<ExprId>,
) -> BodyTerms {
    let [a, b, c] = body.angles;
    let omega = euler::angular_velocity(pool, [q[a], q[b], q[c]], [qd[a], qd[b], qd[c]]);
    let d = euler::rotation(pool, q[a], q[b], q[c]);
    // v_ref = Σ ∂x/∂q_i q_i' + ∂x/∂t, space components.
    let v_ref: Vec<ExprId> = body
        .position
        .iter()
        .map(|&x| {
            let mut terms: Vec<ExprId> = q
                .iter()
                .zip(qd)
                .map(|(&qi, &vi)| {
                    let dx = pool.diff(x, qi);
                    pool.mul2(dx, vi)
                })
                .collect();
            terms.push(pool.diff(x, t));
            pool.add(&terms)
        })
        .collect();
    let moving = v_ref.iter().any(|&v| !pool.is_zero(v));
    let half = pool.rational(1, 2);
    let mut t_terms = Vec::new();
    // ½ωᵀIω.
    let i_omega: Vec<ExprId> = (0..3)
        .map(|i| {
            let terms: Vec<ExprId> = (0..3).map(|j| pool.mul2(body.inertia[i][j], omega[j])).collect();
            pool.add(&terms)
        })
        .collect();
    if body.principal {
        for k in 0..3 {
            let w2 = pool.powi(omega[k], 2);
            t_terms.push(pool.mul(&[half, body.inertia[k][k], w2]));
        }
    } else {
        for k in 0..3 {
            t_terms.push(pool.mul(&[half, omega[k], i_omega[k]]));
        }
    }
    let mut l = [i_omega[0], i_omega[1], i_omega[2]];
    if moving {
        // ½M|v_ref|².
        let sq: Vec<ExprId> = v_ref.iter().map(|&v| pool.powi(v, 2)).collect();
        let s = pool.add(&sq);
        t_terms.push(pool.mul(&[half, body.mass, s]));
        // v_b = D v_ref; M v_b·(ω × c); L += M c × v_b.
        let v_b: Vec<ExprId> = (0..3)
            .map(|i| {
                let terms: Vec<ExprId> = (0..3).map(|j| pool.mul2(d[i][j], v_ref[j])).collect();
                pool.add(&terms)
            })
            .collect();
        let cvec = body.center_of_mass;
        if cvec.iter().any(|&x| !pool.is_zero(x)) {
            let w_x_c = cross(pool, &omega, &cvec);
            let dots: Vec<ExprId> = (0..3).map(|k| pool.mul2(v_b[k], w_x_c[k])).collect();
            let dot = pool.add(&dots);
            t_terms.push(pool.mul2(body.mass, dot));
            let c_x_v = cross(pool, &cvec, &[v_b[0], v_b[1], v_b[2]]);
            for k in 0..3 {
                let extra = pool.mul2(body.mass, c_x_v[k]);
                l[k] = pool.add2(l[k], extra);
            }
        }
    }
    let kinetic = pool.add(&t_terms);
    let potential = gravity.map(|g| {
        // z_cm = x_ref,3 + Σ_k D_k3 c_k (the third component of Dᵀc).
        let mut z = vec![body.position[2]];
        for k in 0..3 {
            z.push(pool.mul2(d[k][2], body.center_of_mass[k]));
        }
        let z = pool.add(&z);
        pool.mul(&[body.mass, g, z])
    });
    BodyTerms { kinetic, potential, omega, angular_momentum: l }
}

fn cross(pool: &mut Pool, a: &[ExprId; 3], b: &[ExprId; 3]) -> [ExprId; 3] {
    let mut c = [pool.zero(); 3];
    for (k, (i, j)) in [(1, 2), (2, 0), (0, 1)].into_iter().enumerate() {
        let x = pool.mul2(a[i], b[j]);
        let y = pool.mul2(a[j], b[i]);
        c[k] = pool.sub(x, y);
    }
    c
}

/// Simplifies a body's ω and L for printing and recording.
pub(crate) fn motion(pool: &mut Pool, body: &Body, terms: &BodyTerms, is_var: &dyn Fn(Symbol) -> bool) -> BodyMotion {
    let omega = terms.omega.map(|w| pool.simplify_in(w, is_var));
    let angular_momentum = terms.angular_momentum.map(|l| pool.simplify_in(l, is_var));
    BodyMotion { name: body.name.clone(), omega, angular_momentum }
}

/// The CSV column names of the bodies' ω and L: `omega1..3`, `L1..3`, prefixed
/// with `NAME_` when the model has more than one body.
pub fn column_names(bodies: &[BodyMotion]) -> Vec<String> {
    let mut cols = Vec::new();
    for b in bodies {
        let prefix = if bodies.len() > 1 { format!("{}_", b.name) } else { String::new() };
        for k in 1..=3 {
            cols.push(format!("{prefix}omega{k}"));
        }
        for k in 1..=3 {
            cols.push(format!("{prefix}L{k}"));
        }
    }
    cols
}

/// The smallest |sin β| a run accepts for an Euler-angle body at relative
/// tolerance `rtol`. Solving for the accelerations divides by the angles' mass
/// matrix, whose determinant is ∝ sin²β; round-off in the accelerations grows
/// like ε/sin²β (ε the machine epsilon), so below sqrt(ε/rtol) it exceeds the
/// tolerance asked for. Clamped to [1e-6, 1e-3].
pub fn gimbal_threshold(rtol: f64) -> f64 {
    (f64::EPSILON / rtol.max(1e-300)).sqrt().clamp(1e-6, 1e-3)
}

/// A condition a run stops on, as a failure, before a body's Euler angles
/// reach their gimbal singularity.
#[derive(Debug, Clone)]
pub struct GimbalGuard {
    /// g = sin²β − s², which falls through zero where |sin β| reaches s.
    pub expr: ExprId,
    /// The index of β among the coordinates.
    pub beta: usize,
    /// s, from [`gimbal_threshold`].
    pub threshold: f64,
    /// The body's name.
    pub body: String,
    /// β's name.
    pub beta_name: String,
}

impl GimbalGuard {
    /// Whether the state is past the guard.
    pub fn violated(&self, q: &[f64]) -> bool {
        let s = q[self.beta].sin().abs();
        s.is_nan() || s < self.threshold
    }

    /// What happened at time t, in the user's terms.
    pub fn message(&self, t: f64) -> String {
        format!(
            "body '{}' reached the gimbal singularity of its Euler angles at t = {t}: |sin {b}| fell below {:.1e} ({b} near 0 or π), where α and γ turn about the same axis and the angles' mass matrix (determinant ∝ sin²{b}) is singular, so the accelerations cannot be trusted. {}",
            self.body,
            self.threshold,
            self.advice(),
            b = self.beta_name
        )
    }

    /// What to do about it.
    pub fn advice(&self) -> String {
        format!(
            "Euler angles cannot follow a motion through {b} = 0 or π: tilt the fixed frame so that the body's 3-axis stays away from the fixed z axis, or end the run earlier (--until, --stop-when)",
            b = self.beta_name
        )
    }
}

/// One [`GimbalGuard`] per body, for a run at relative tolerance `rtol`.
pub fn gimbal_guards(d: &mut crate::Derivation, rtol: f64) -> Vec<GimbalGuard> {
    let s = gimbal_threshold(rtol);
    let bodies = d.model.bodies.clone();
    let pool = &mut d.model.pool;
    bodies
        .iter()
        .map(|b| {
            let beta = b.angles[1];
            let sb = pool.func(Func::Sin, d.q[beta]);
            let sb2 = pool.powi(sb, 2);
            let s2 = pool.float(s * s);
            GimbalGuard {
                expr: pool.sub(sb2, s2),
                beta,
                threshold: s,
                body: b.name.clone(),
                beta_name: d.model.coordinates[beta].name.clone(),
            }
        })
        .collect()
}

/// Evaluates the bodies' ω and L along a run: one tape over `[q, q', t, parameters]`.
#[derive(Debug, Clone)]
pub struct BodyRecorder {
    tape: sym::Tape,
    inputs: Vec<f64>,
    n: usize,
    columns: Vec<String>,
}

impl BodyRecorder {
    /// None when the derivation has no bodies.
    pub fn new(d: &mut crate::Derivation) -> Option<BodyRecorder> {
        if d.bodies.is_empty() {
            return None;
        }
        let n = d.q.len();
        let mut input_syms: Vec<ExprId> = d.q.clone();
        input_syms.extend(&d.qd);
        input_syms.push(d.t);
        let mut inputs = vec![0.0; 2 * n + 1];
        for p in &d.model.parameters {
            input_syms.push(d.model.pool.symbol(&p.name));
            inputs.push(p.value);
        }
        let exprs: Vec<ExprId> =
            d.bodies.iter().flat_map(|b| b.omega.iter().chain(&b.angular_momentum).copied()).collect();
        let tape = sym::Tape::compile(&d.model.pool, &exprs, &input_syms).ok()?;
        Some(BodyRecorder { tape, inputs, n, columns: column_names(&d.bodies) })
    }

    /// The column names, six per body.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// ω and L of every body at (t, q, q'), into `out` (length `columns().len()`).
    pub fn eval(&mut self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) {
        let n = self.n;
        self.inputs[..n].copy_from_slice(q);
        self.inputs[n..2 * n].copy_from_slice(qd);
        self.inputs[2 * n] = t;
        self.tape.eval(&self.inputs, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Derivation, Model};

    /// Body-frame points (mass, r) of a rigid cluster, not coplanar.
    const POINTS: [(f64, [f64; 3]); 4] =
        [(1.0, [0.3, -0.2, 0.5]), (2.0, [-0.4, 0.1, 0.2]), (0.5, [0.1, 0.6, -0.3]), (1.5, [0.2, 0.3, 0.4])];

    fn env<'a>(vals: &'a [(&'a str, f64)]) -> impl Fn(&str) -> Option<f64> + 'a {
        move |n| vals.iter().find(|(k, _)| *k == n).map(|(_, v)| *v)
    }

    /// The body's T (with the cross term M v_ref·(ω×r) and a full tensor) equals
    /// the particles' T of the same rigid cluster, for a reference point that moves
    /// with the coordinates and the time.
    #[test]
    fn body_kinetic_energy_is_the_sum_over_its_points() {
        let total: f64 = POINTS.iter().map(|p| p.0).sum();
        let mut com = [0.0; 3];
        let mut inertia = [[0.0; 3]; 3];
        for (m, r) in POINTS {
            let r2 = r.iter().map(|x| x * x).sum::<f64>();
            for i in 0..3 {
                com[i] += m * r[i] / total;
                for j in 0..3 {
                    inertia[i][j] += m * (if i == j { r2 } else { 0.0 } - r[i] * r[j]);
                }
            }
        }
        // The reference point moves with a coordinate, an Euler angle and the time.
        let position = ["x + 0.2*sin(be)", "0.3*x^2", "t"];
        let tensor: Vec<String> = inertia
            .iter()
            .map(|row| format!("[{}]", row.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(", ")))
            .collect();
        let body_model = format!(
            "coordinates = [\"x\", \"al\", \"be\", \"ga\"]\ngravity = \"g\"\n[parameters]\ng = 9.81\n[[bodies]]\nmass = {total:?}\ninertia = [{}]\nangles = [\"al\", \"be\", \"ga\"]\nposition = [\"x + 0.2*sin(be)\", \"0.3*x^2\", \"t\"]\ncenter_of_mass = [{:?}, {:?}, {:?}]\n",
            tensor.join(", "),
            com[0],
            com[1],
            com[2]
        );
        // Particles at x_ref + Dᵀr, with D written out in the notes' convention.
        let d = [
            [
                "cos(ga)*cos(al) - sin(ga)*cos(be)*sin(al)",
                "cos(ga)*sin(al) + sin(ga)*cos(be)*cos(al)",
                "sin(ga)*sin(be)",
            ],
            [
                "-sin(ga)*cos(al) - cos(ga)*cos(be)*sin(al)",
                "-sin(ga)*sin(al) + cos(ga)*cos(be)*cos(al)",
                "cos(ga)*sin(be)",
            ],
            ["sin(be)*sin(al)", "-sin(be)*cos(al)", "cos(be)"],
        ];
        let mut particle_model =
            String::from("coordinates = [\"x\", \"al\", \"be\", \"ga\"]\ngravity = \"g\"\n[parameters]\ng = 9.81\n");
        for (m, r) in POINTS {
            let comps: Vec<String> = (0..3)
                .map(|j| {
                    let terms: Vec<String> = (0..3).map(|i| format!("({:?})*({})", r[i], d[i][j])).collect();
                    format!("\"{} + {}\"", position[j], terms.join(" + "))
                })
                .collect();
            particle_model.push_str(&format!("[[particles]]\nmass = {m:?}\nposition = [{}]\n", comps.join(", ")));
        }
        let body = Derivation::new(Model::parse(&body_model, &[]).unwrap()).unwrap();
        let parts = Derivation::new(Model::parse(&particle_model, &[]).unwrap()).unwrap();
        for state in [[0.3, 0.4, 1.1, -0.7, 0.8, -1.2, 0.5, 2.0, 0.7], [-1.0, 2.0, 0.3, 1.9, -0.4, 0.3, -2.2, 0.1, 1.3]]
        {
            let names = ["x", "al", "be", "ga", "x'", "al'", "be'", "ga'", "t"];
            let mut vals: Vec<(&str, f64)> = names.iter().copied().zip(state).collect();
            vals.push(("g", 9.81));
            let e = env(&vals);
            for (what, a, b) in [
                ("T", body.kinetic.unwrap(), parts.kinetic.unwrap()),
                ("U", body.potential.unwrap(), parts.potential.unwrap()),
            ] {
                let (a, b) = (body.pool().eval(a, &e).unwrap(), parts.pool().eval(b, &e).unwrap());
                assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "{what}: body {a} vs particles {b}");
            }
            // L about the reference point, body components: Σ m r_k × v_k with
            // v_k = D v_ref + ω × r_k (body components), v_ref = (x' + 0.2 cos β β', 0.6 x x', 1).
            let [x, al, be, ga, xd, ald, bed, gad, _] = state;
            let dm = euler::rotation_f64(al, be, ga);
            let w = euler::angular_velocity_f64(be, ga, [ald, bed, gad]);
            let v_ref = [xd + 0.2 * be.cos() * bed, 0.6 * x * xd, 1.0];
            let vb: Vec<f64> = (0..3).map(|i| (0..3).map(|j| dm[i][j] * v_ref[j]).sum()).collect();
            let cross = |a: [f64; 3], b: [f64; 3]| {
                [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
            };
            let mut l = [0.0; 3];
            for (m, r) in POINTS {
                let wr = cross(w, r);
                let v = [vb[0] + wr[0], vb[1] + wr[1], vb[2] + wr[2]];
                let rv = cross(r, v);
                for k in 0..3 {
                    l[k] += m * rv[k];
                }
            }
            for k in 0..3 {
                let a = body.pool().eval(body.bodies[0].angular_momentum[k], &e).unwrap();
                assert!((a - l[k]).abs() < 1e-10 * (1.0 + l[k].abs()), "L{}: {a} vs {}", k + 1, l[k]);
            }
            for i in 0..4 {
                let (a, b) =
                    (body.pool().eval(body.momenta[i], &e).unwrap(), parts.pool().eval(parts.momenta[i], &e).unwrap());
                assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "p_{i}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn several_bodies_get_prefixed_columns_and_their_own_angles() {
        let body = |name: &str, a: &str| {
            format!("[[bodies]]\nname = \"{name}\"\nmass = 1\ninertia = [1, 2, 3]\nangles = [\"{a}1\", \"{a}2\", \"{a}3\"]\n")
        };
        let text = format!(
            "coordinates = [\"a1\", \"a2\", \"a3\", \"b1\", \"b2\", \"b3\"]\n{}{}",
            body("left", "a"),
            body("right", "b")
        );
        let d = Derivation::new(Model::parse(&text, &[]).unwrap()).unwrap();
        let cols = column_names(&d.bodies);
        assert_eq!(cols[0], "left_omega1");
        assert_eq!(cols[11], "right_L3");
        let shared = text.replace("[\"b1\", \"b2\", \"b3\"]", "[\"b1\", \"a2\", \"b3\"]");
        let e = Model::parse(&shared, &[]).unwrap_err();
        assert!(e.message.contains("already an Euler angle of body 'left'"), "{}", e.message);
        let single = column_names(&d.bodies[..1]);
        assert_eq!(single, ["omega1", "omega2", "omega3", "L1", "L2", "L3"]);
    }

    #[test]
    fn gimbal_threshold_follows_the_tolerance() {
        assert!((gimbal_threshold(1e-9) - (f64::EPSILON / 1e-9).sqrt()).abs() < 1e-15);
        assert_eq!(gimbal_threshold(1e-3), 1e-6);
        assert_eq!(gimbal_threshold(1e-16), 1e-3);
    }

    #[test]
    fn angular_momentum_of_a_pivoted_top_is_i_omega() {
        let text = "coordinates = [\"al\", \"be\", \"ga\"]\n[parameters]\nI = 2.0\nI3 = 0.7\n[[bodies]]\nmass = 1\ninertia = [\"I\", \"I\", \"I3\"]\nangles = [\"al\", \"be\", \"ga\"]\ncenter_of_mass = [0, 0, 0.4]\n";
        let d = Derivation::new(Model::parse(text, &[]).unwrap()).unwrap();
        let b = &d.bodies[0];
        let p = d.pool();
        assert_eq!(p.display(b.angular_momentum[2]).to_string(), "I3*(ga' + al'*cos(be))");
        assert_eq!(p.display(b.omega[0]).to_string(), "al'*sin(be)*sin(ga) + be'*cos(ga)");
    }
}
