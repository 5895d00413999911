//! The numpy module of `lagrange export --to python`: see [`to_python`].

use super::{hamiltonian, Read, Reads};
use crate::derive::Derivation;
use crate::error::{ModelError, ModelErrorKind};
use sym::emit::{literal, Emit, Language};
use sym::{ExprId, Func, Node, Pool};

/// The model's equations as a Python module needing only numpy: `rhs(t, y,
/// p=None)` as `scipy.integrate.solve_ivp` calls it (y of shape (2n,) or
/// (2n, k)), `jac(t, y, p=None)` from the symbolic derivatives, `mass_matrix`,
/// `forcing`, `hamiltonian` and `energy`, `COORDINATES` and `PARAMETERS`
/// (name → default); with `[inputs]`, `INPUTS`, `inputs` and `input_matrix`,
/// and a `u=None` argument (the inputs' values in t) on what reads them; with
/// `[[constraints]]`, `CONSTRAINTS`, `constraint_residuals`,
/// `constraint_rates`, `constraint_jacobian` and `multipliers`. A model with
/// `abs()` in its equations is refused: its Jacobian has no value at the kink.
pub fn to_python(d: &Derivation, version: &str) -> Result<String, ModelError> {
    super::refuse_impacts(d)?;
    let model = d.model();
    let n = d.q.len();
    let constraints = &d.constraints().list;
    let nc = constraints.len();
    let has_inputs = !d.inputs().is_empty();
    let mass: Vec<ExprId> = d.mass_matrix.iter().flatten().copied().collect();
    let a: Vec<ExprId> = constraints.iter().flat_map(|c| c.jacobian.iter().copied()).collect();
    let c: Vec<ExprId> = constraints.iter().map(|c| c.acceleration_rhs).collect();
    let reads = Reads::new(d, &[]);
    // One walk of the DAG, not a compile: the statements below compile them.
    let differentiated = [&mass[..], &d.forcing[..], &a[..], &c[..]].concat();
    let pool = d.pool();
    if pool.reachable(&differentiated).iter().any(|&id| matches!(pool.node(id), Node::Func(Func::Abs, _))) {
        return Err(ModelError::whole(
            "the equations contain abs(), whose derivative has no value at its kink: the Jacobian jac() cannot be written",
        )
        .with_help("write the model without abs() (a smooth approximation such as sqrt(x^2 + eps^2)), or export it to C, which writes no Jacobian")
        .with_kind(ModelErrorKind::Unsupported));
    }
    // The Jacobian of the accelerations: with x = [q''; λ] the solution of
    // K x = [f; c], K = [M −Aᵀ; A 0] (K = M without constraints), K ∂x/∂y is
    // ∂R/∂y for R = [f + Aᵀλ − M q''; c − A q''] with q'' and λ held as
    // symbols: (n + m) n expressions per half, not (n + m)² n.
    let mut pool = d.pool().clone();
    let lambda: Vec<ExprId> = constraints.iter().map(|c| c.multiplier).collect();
    let mut rows = Vec::with_capacity(n + nc);
    for i in 0..n {
        let mut terms = vec![d.forcing[i]];
        for l in 0..n {
            let ma = pool.mul2(d.mass_matrix[i][l], d.qdd[l]);
            terms.push(pool.neg(ma));
        }
        for (r, c) in constraints.iter().enumerate() {
            terms.push(pool.mul2(c.jacobian[i], lambda[r]));
        }
        rows.push(pool.add(&terms));
    }
    for c in constraints {
        let mut terms = vec![c.acceleration_rhs];
        for l in 0..n {
            let aq = pool.mul2(c.jacobian[l], d.qdd[l]);
            terms.push(pool.neg(aq));
        }
        rows.push(pool.add(&terms));
    }
    let mut jacobian = Vec::with_capacity(2 * (n + nc) * n);
    for wrt in [&d.q, &d.qd] {
        for r in &rows {
            for &x in wrt.iter() {
                jacobian.push(pool.diff(*r, x));
            }
        }
    }
    let extra: Vec<ExprId> = d.qdd.iter().chain(&lambda).copied().collect();
    let jacobian_reads = Reads::new(d, &extra);

    let mut out = String::new();
    out.push_str(&format!(
        "\"\"\"{} — equations of motion written by lagrange {version}.\n\n",
        python_docstring_text(&model.name)
    ));
    out.push_str("The state y = [q, q'] is in the order of COORDINATES; the parameters p are a\n");
    out.push_str("sequence in the order of PARAMETERS, a dict of those to change, or None for\n");
    out.push_str("the model file's values (PARAMETERS maps each name to it).\n");
    if has_inputs {
        out.push_str("The inputs u are None for their values in t (INPUTS maps each name to its\n");
        out.push_str("expression), a dict of those to change, a sequence in the order of INPUTS,\n");
        out.push_str("or a function u(t, y) returning one of these.\n");
    }
    out.push_str("\nrhs(t, y, p=None");
    out.push_str(if has_inputs { ", u=None" } else { "" });
    out.push_str("): dy/dt = [q', q''] with M q'' = f");
    out.push_str(if nc > 0 { " + Aᵀλ" } else { "" });
    out.push_str(
        ", as scipy.integrate.solve_ivp\n    calls it; y of shape (2n,) or (2n, k) (solve_ivp's vectorized=True).\n",
    );
    out.push_str("jac(t, y, p=None");
    out.push_str(if has_inputs { ", u=None" } else { "" });
    out.push_str("): the Jacobian d(rhs)/dy, shape (2n, 2n), from the symbolic\n");
    out.push_str("    derivatives (solve_ivp's jac= for the stiff methods).\n");
    out.push_str("mass_matrix, forcing, hamiltonian (h = Σ q' ∂L/∂q' − L), energy (T + U₀): the same\n");
    out.push_str("    quantities as the derivation gives them, at (t, y).\n");
    if has_inputs {
        out.push_str("inputs(t, y, p=None): the inputs' values in t; input_matrix: B = ∂f/∂u.\n");
    }
    if nc > 0 {
        out.push_str("constraint_residuals, constraint_rates (A q' + a_t), constraint_jacobian (A) and\n");
        out.push_str("    multipliers (λ): the constraints of CONSTRAINTS. rhs holds them at acceleration\n");
        out.push_str("    level only (no projection): their residuals drift as any such system's do.\n");
    }
    out.push_str("\"\"\"\n\nimport numpy as np\n\n");
    let names: Vec<String> = d.coordinate_names().iter().map(|c| python_string(c)).collect();
    out.push_str(&format!("COORDINATES = [{}]\n", names.join(", ")));
    let params: Vec<String> = model
        .parameters
        .iter()
        .map(|p| format!("{}: {}", python_string(&p.name), literal(Language::Python, p.value)))
        .collect();
    out.push_str(&format!("PARAMETERS = {{{}}}\n", params.join(", ")));
    if has_inputs {
        let inputs: Vec<String> = model
            .inputs
            .iter()
            .map(|u| {
                format!("{}: {}", python_string(&u.name), python_string(&d.pool().display(u.value.expr).to_string()))
            })
            .collect();
        out.push_str(&format!("INPUTS = {{{}}}\n", inputs.join(", ")));
    }
    if nc > 0 {
        let names: Vec<String> = constraints.iter().map(|c| python_string(&c.name)).collect();
        out.push_str(&format!("CONSTRAINTS = [{}]\n", names.join(", ")));
    }
    out.push_str(&format!("N = {n}\nN_INPUTS = {}\nN_CONSTRAINTS = {nc}\n\n\n", d.inputs().len()));
    out.push_str(PYTHON_HELPERS);
    if has_inputs {
        out.push_str(PYTHON_INPUTS);
    }
    if nc > 0 {
        out.push_str(PYTHON_SADDLE);
    }
    let w = Writer { pool: &pool, reads: &reads };
    // What a function that reads u takes and does first.
    let (u_arg, u_read) = if has_inputs { (", u=None", "    u = _inputs(t, y, p, u)\n") } else { ("", "") };
    out.push_str(&format!(
        "def mass_matrix(t, y, p=None):\n    \"\"\"M of M q'' = f, shape (n, n), or (n, n, k) for y of shape (2n, k).\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n    out = np.empty((N * N,) + y.shape[1:])\n{}    \
         return out.reshape((N, N) + y.shape[1:])\n\n\n",
        w.statements(&mass, "out")?
    ));
    if has_inputs {
        let values: Vec<ExprId> = model.inputs.iter().map(|u| u.value.expr).collect();
        out.push_str(&format!(
            "def inputs(t, y, p=None):\n    \"\"\"The inputs' values in t (INPUTS), shape (N_INPUTS,) or (N_INPUTS, k).\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    out = np.empty((N_INPUTS,) + y.shape[1:])\n{}    return out\n\n\n",
            w.statements(&values, "out")?
        ));
        let b: Vec<ExprId> = d.input_matrix().iter().flatten().copied().collect();
        out.push_str(&format!(
            "def input_matrix(t, y, p=None, u=None):\n    \"\"\"B = ∂f/∂u, shape (n, N_INPUTS) or (n, N_INPUTS, k).\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n{u_read}    out = np.empty((N * N_INPUTS,) + y.shape[1:])\n{}    \
             return out.reshape((N, N_INPUTS) + y.shape[1:])\n\n\n",
            w.statements(&b, "out")?
        ));
    }
    out.push_str(&format!(
        "def forcing(t, y, p=None{u_arg}):\n    \"\"\"f of M q'' = f, shape (n,) or (n, k).\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n{u_read}    out = np.empty((N,) + y.shape[1:])\n{}    return out\n\n\n",
        w.statements(&d.forcing, "out")?
    ));
    out.push_str(&format!(
        "def hamiltonian(t, y, p=None):\n    \"\"\"The energy function h = Σ q' ∂L/∂q' − L (H written in q and q').\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n    out = np.empty((1,) + y.shape[1:])\n{}    return out[0]\n\n\n",
        w.statements(&[hamiltonian(d)], "out")?
    ));
    if let Some(energy) = d.energy {
        out.push_str(&format!(
            "def energy(t, y, p=None):\n    \"\"\"The energy T + U₀.\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    out = np.empty((1,) + y.shape[1:])\n{}    return out[0]\n\n\n",
            w.statements(&[energy], "out")?
        ));
    }
    if nc > 0 {
        let residuals: Vec<ExprId> = constraints.iter().map(crate::Constraint::residual).collect();
        let rates: Vec<ExprId> = constraints.iter().map(|c| c.velocity_form).collect();
        out.push_str(&format!(
            "def constraint_residuals(t, y, p=None):\n    \"\"\"Each constraint's residual (f(q, t), or A q' + a_t for a velocity constraint), shape (m,) or (m, k).\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    out = np.empty((N_CONSTRAINTS,) + y.shape[1:])\n{}    return out\n\n\n",
            w.statements(&residuals, "out")?
        ));
        out.push_str(&format!(
            "def constraint_rates(t, y, p=None):\n    \"\"\"The constraints at velocity level, A q' + a_t, shape (m,) or (m, k).\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    out = np.empty((N_CONSTRAINTS,) + y.shape[1:])\n{}    return out\n\n\n",
            w.statements(&rates, "out")?
        ));
        out.push_str(&format!(
            "def constraint_jacobian(t, y, p=None):\n    \"\"\"A of the constraints A q' + a_t = 0, shape (m, n) or (m, n, k).\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    out = np.empty((N_CONSTRAINTS * N,) + y.shape[1:])\n{}    \
             return out.reshape((N_CONSTRAINTS, N) + y.shape[1:])\n\n\n",
            w.statements(&a, "out")?
        ));
        out.push_str(&format!(
            "def _accelerations_of_constraints(t, y, p):\n    out = np.empty((N_CONSTRAINTS,) + y.shape[1:])\n{}    return out\n\n\n",
            w.statements(&c, "out")?
        ));
        let u_pass = if has_inputs { ", u" } else { "" };
        out.push_str(&format!(
            "def _saddle_solution(t, y, p{u_arg}):\n    \
             m = mass_matrix(t, y, p)\n    a = constraint_jacobian(t, y, p)\n    \
             f = forcing(t, y, p{u_pass})\n    c = _accelerations_of_constraints(t, y, p)\n    \
             return _saddle(m, a, f, c)\n\n\n\
             def multipliers(t, y, p=None{u_arg}):\n    \"\"\"The multipliers λ of M q'' = f + Aᵀλ, shape (m,) or (m, k).\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    return _saddle_solution(t, y, p{u_pass})[N:]\n\n\n\
             def rhs(t, y, p=None{u_arg}):\n    \"\"\"dy/dt = [q', q''] with M q'' = f + Aᵀλ and A q'' = c; y of shape (2n,) or (2n, k).\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    \
             return np.concatenate([y[N:], _saddle_solution(t, y, p{u_pass})[:N]])\n\n\n"
        ));
    } else {
        let u_pass = if has_inputs { ", u" } else { "" };
        out.push_str(&format!(
            "def rhs(t, y, p=None{u_arg}):\n    \"\"\"dy/dt = [q', q''] with M q'' = f; y of shape (2n,) or (2n, k).\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    \
             a = _solve(mass_matrix(t, y, p), forcing(t, y, p{u_pass}))\n    \
             return np.concatenate([y[N:], a])\n\n\n",
        ));
    }
    let jacobian_writer = Writer { pool: &pool, reads: &jacobian_reads };
    let (solution, matrix) = if nc > 0 {
        ("_saddle_solution(t, y, p{u_pass})", "_saddle_matrix(m, constraint_jacobian(t, y, p))")
    } else {
        ("np.linalg.solve(m, forcing(t, y, p{u_pass}))", "m")
    };
    let u_pass = if has_inputs { ", u" } else { "" };
    out.push_str(&format!(
        "def jac(t, y, p=None{u_arg}):\n    \"\"\"The Jacobian d(rhs)/dy at one state y of shape (2n,): shape (2n, 2n) (u held at its value).\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n    \
         if y.ndim != 1:\n        raise ValueError(f\"jac takes one state of shape ({{2 * N}},), not {{y.shape}}\")\n\
         {u_read}    \
         m = mass_matrix(t, y, p)\n    \
         x = {}\n    \
         qdd, lam = x[:N], x[N:]\n    \
         k = {matrix}\n    \
         out = np.empty(2 * (N + N_CONSTRAINTS) * N)\n{}    \
         rows = N + N_CONSTRAINTS\n    \
         j = np.zeros((2 * N, 2 * N))\n    \
         j[:N, N:] = np.eye(N)\n    \
         j[N:, :N] = np.linalg.solve(k, out[: rows * N].reshape(rows, N))[:N]\n    \
         j[N:, N:] = np.linalg.solve(k, out[rows * N :].reshape(rows, N))[:N]\n    \
         return j\n",
        solution.replace("{u_pass}", u_pass),
        jacobian_writer.statements(&jacobian, "out")?
    ));
    Ok(out)
}

/// What every exported module shares: reading p and y, and solving M a = f
/// for one state or a batch.
const PYTHON_HELPERS: &str = r#"def _parameters(p):
    if p is None:
        return np.array(list(PARAMETERS.values()), dtype=float)
    if isinstance(p, dict):
        for name in p:
            if name not in PARAMETERS:
                raise KeyError(f"{name!r} is not a parameter; the parameters are {', '.join(PARAMETERS)}")
        return np.array([float(p.get(name, value)) for name, value in PARAMETERS.items()])
    p = np.asarray(p, dtype=float)
    if p.shape != (len(PARAMETERS),):
        raise ValueError(f"p has shape {p.shape}: give the {len(PARAMETERS)} parameters {', '.join(PARAMETERS)} in order")
    return p


def _state(y):
    y = np.asarray(y, dtype=float)
    if y.ndim not in (1, 2) or y.shape[0] != 2 * N:
        raise ValueError(f"y has shape {y.shape}: give [q, q'] of length {2 * N}, or {2 * N} rows of states")
    return y


def _solve(m, f):
    if m.ndim == 2:
        return np.linalg.solve(m, f)
    return np.linalg.solve(np.moveaxis(m, -1, 0), np.moveaxis(f, -1, 0)[..., None])[..., 0].T


"#;

/// Reading u in a module of a model with `[inputs]`.
const PYTHON_INPUTS: &str = r#"def _inputs(t, y, p, u):
    if callable(u):
        u = u(t, y)
    values = inputs(t, y, p)
    if u is None:
        return values
    if isinstance(u, dict):
        for name in u:
            if name not in INPUTS:
                raise KeyError(f"{name!r} is not an input; the inputs are {', '.join(INPUTS)}")
        for i, name in enumerate(INPUTS):
            if name in u:
                values[i] = u[name]
        return values
    u = np.asarray(u, dtype=float)
    if u.shape[:1] != (N_INPUTS,):
        raise ValueError(f"u has shape {u.shape}: give the {N_INPUTS} inputs {', '.join(INPUTS)} in order")
    return u


"#;

/// Solving the saddle-point system of a constrained model, for one state or a
/// batch.
const PYTHON_SADDLE: &str = r#"def _saddle_matrix(m, a):
    return np.block([[m, -a.T], [a, np.zeros((N_CONSTRAINTS, N_CONSTRAINTS))]])


def _saddle(m, a, f, c):
    if m.ndim == 2:
        return np.linalg.solve(_saddle_matrix(m, a), np.concatenate([f, c]))
    m, a = np.moveaxis(m, -1, 0), np.moveaxis(a, -1, 0)
    zeros = np.zeros((m.shape[0], N_CONSTRAINTS, N_CONSTRAINTS))
    k = np.concatenate([np.concatenate([m, -np.swapaxes(a, 1, 2)], axis=2), np.concatenate([a, zeros], axis=2)], axis=1)
    b = np.concatenate([np.moveaxis(f, -1, 0), np.moveaxis(c, -1, 0)], axis=1)
    return np.linalg.solve(k, b[..., None])[..., 0].T


"#;

/// Writes Python statements of expressions over [`Reads`].
struct Writer<'a> {
    pool: &'a Pool,
    reads: &'a Reads,
}

impl Writer<'_> {
    /// The expressions as Python statements storing into `array`: q and q'
    /// read from `y`, `t`, the parameters from `p`, the inputs from `u`, and
    /// the Jacobian's q'' and λ from `qdd` and `lam`.
    fn statements(&self, exprs: &[ExprId], array: &str) -> Result<String, ModelError> {
        let tape = self.reads.compile(self.pool, exprs)?;
        let n = self.reads.t / 2;
        let input = |k: usize| match self.reads.which(k) {
            Read::State(k) => format!("y[{k}]"),
            Read::Time => "t".to_string(),
            Read::Parameter(i) => format!("p[{i}]"),
            Read::Input(i) => format!("u[{i}]"),
            Read::Extra(i) if i < n => format!("qdd[{i}]"),
            Read::Extra(i) => format!("lam[{}]", i - n),
        };
        Ok(tape.emit(&Emit {
            language: Language::Python,
            input: &input,
            output: array,
            indent: "    ",
            temporary: "v",
        }))
    }
}

/// A Python string literal.
fn python_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\x{:02x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Text safe inside a Python docstring.
fn python_docstring_text(s: &str) -> String {
    s.replace('\\', "\\\\").replace("\"\"\"", "\\\"\\\"\\\"")
}
