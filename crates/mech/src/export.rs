//! Code that leaves lagrange: a derivation's equations of motion written as a
//! C99 file that needs nothing beyond libm ([`to_c`]) or as a Python module
//! that needs only numpy ([`to_python`]), for controllers, optimizers and
//! co-simulations that call a right-hand side from their own code.
//!
//! Every function reads the state `[q, q']` in the model's coordinate order and
//! the parameters in the model file's `[parameters]` order, and computes from
//! the same expressions `lagrange derive` prints: M and f of `M q'' = f`, the
//! energy function h (H written in q and q') and, where the model gives T and U,
//! the energy T + U₀. The right-hand side solves `M q'' = f` by Gaussian
//! elimination with partial pivoting, written into the file. Each function's
//! expressions are one straight-line block over their shared subexpressions
//! (`sym::emit`).
//!
//! Models with `[[constraints]]` or `[inputs]` are refused for now, with the
//! reason: their multipliers and inputs are not written yet.

use crate::derive::Derivation;
use crate::error::{ModelError, ModelErrorKind};
use sym::emit::{literal, Emit, Language};
use sym::{ExprId, Tape};

/// The smallest ratio of the smallest to the largest pivot of M that the
/// written solve takes for a regular matrix (the run's `num` LU uses the same
/// kind of test): below it `lagrange_rhs` returns 1.
pub const SINGULAR_PIVOT_RATIO: f64 = 1e-14;

/// The model's equations as one C99 file: see the module comment. `version`
/// is written in the header (lagrange's version).
pub fn to_c(d: &Derivation, version: &str) -> Result<String, ModelError> {
    refuse_unsupported(d, "C")?;
    let model = d.model();
    let n = d.q.len();
    let names = d.coordinate_names();
    let mut out = String::new();
    out.push_str(&format!("/* {} — equations of motion written by lagrange {version}.\n", comment_text(&model.name)));
    out.push_str(" *\n");
    out.push_str(" * state  = [q, q'] in the order of lagrange_coordinates,\n");
    out.push_str(" * params = the parameters in the order of lagrange_parameters (their\n");
    out.push_str(" *          model-file values in lagrange_parameter_defaults).\n");
    out.push_str(" * int lagrange_rhs(t, state, params, dstate): dstate = [q', q''] from M q'' = f;\n");
    out.push_str(" *     returns 0, or non-zero where M is singular or a value is not finite.\n");
    out.push_str(" * C99 and libm only: cc -std=c99 -c this.c (link with -lm).\n");
    out.push_str(" */\n\n#include <math.h>\n\n");
    out.push_str(&format!("#define LAGRANGE_N {n}\n"));
    out.push_str(&format!("#define LAGRANGE_N_PARAMETERS {}\n\n", model.parameters.len()));
    let quoted = |s: &str| format!("\"{}\"", c_string(s));
    let list: Vec<String> = names.iter().map(|s| quoted(s)).chain(["0".to_string()]).collect();
    out.push_str("/* The coordinates' names, then a null pointer. */\n");
    out.push_str(&format!("const char *const lagrange_coordinates[LAGRANGE_N + 1] = {{{}}};\n", list.join(", ")));
    let list: Vec<String> = model.parameters.iter().map(|p| quoted(&p.name)).chain(["0".to_string()]).collect();
    out.push_str("/* The parameters' names, then a null pointer. */\n");
    out.push_str(&format!(
        "const char *const lagrange_parameters[LAGRANGE_N_PARAMETERS + 1] = {{{}}};\n",
        list.join(", ")
    ));
    let list: Vec<String> =
        model.parameters.iter().map(|p| literal(Language::C, p.value)).chain(["0.0".to_string()]).collect();
    out.push_str("/* The parameters' values in the model file, then a 0. */\n");
    out.push_str(&format!(
        "const double lagrange_parameter_defaults[LAGRANGE_N_PARAMETERS + 1] = {{{}}};\n\n",
        list.join(", ")
    ));

    let mass: Vec<ExprId> = d.mass_matrix.iter().flatten().copied().collect();
    function(&mut out, d, "void", "lagrange_mass_matrix", "m", "M, row by row (n × n)", &mass)?;
    function(&mut out, d, "void", "lagrange_forcing", "f", "f of M q'' = f", &d.forcing)?;
    scalar(
        &mut out,
        d,
        "lagrange_hamiltonian",
        "the energy function h = Σ q' ∂L/∂q' − L (H in q, q')",
        hamiltonian(d),
    )?;
    if let Some(energy) = d.energy {
        scalar(&mut out, d, "lagrange_energy", "the energy T + U₀", energy)?;
    }
    let finish = "    for (int i = 0; i < LAGRANGE_N; i++) {\n        \
         if (!isfinite(f[i]) || !isfinite(state[LAGRANGE_N + i])) return 2;\n        \
         dstate[i] = state[LAGRANGE_N + i];\n        \
         dstate[LAGRANGE_N + i] = f[i];\n    \
         }\n    \
         return 0;\n\
         }\n";
    match articulated_body(d, mass.len() + d.forcing.len())? {
        Some(tape) => {
            out.push_str(&format!(
                "/* q'' by the articulated-body algorithm over the model's tree of bodies\n \
                 * (shorter than M, f and their solve). */\n\
                 static void lagrange_accelerations(double t, const double *state, const double *params, double *a) {{\n    \
                 (void)t; (void)state; (void)params;\n{}}}\n\n",
                emit_c(d, &tape, "a")
            ));
            out.push_str(&format!(
                "/* dstate = [q', q''] with M q'' = f, by the articulated-body algorithm.\n \
                 * Returns 0; 2 where a value is not finite (M singular included). */\n\
                 int lagrange_rhs(double t, const double *state, const double *params, double *dstate) {{\n    \
                 double f[LAGRANGE_N];\n    \
                 lagrange_accelerations(t, state, params, f);\n{finish}"
            ));
        }
        None => {
            out.push_str(&solve_c());
            out.push_str(&format!(
                "/* dstate = [q', q''] with M q'' = f. Returns 0; 1 where M is singular\n \
                 * (a pivot below {ratio:e} of the largest); 2 where a value is not finite. */\n\
                 int lagrange_rhs(double t, const double *state, const double *params, double *dstate) {{\n    \
                 double m[LAGRANGE_N * LAGRANGE_N], f[LAGRANGE_N];\n    \
                 lagrange_mass_matrix(t, state, params, m);\n    \
                 lagrange_forcing(t, state, params, f);\n    \
                 if (lagrange_solve(m, f)) return 1;\n{finish}",
                ratio = SINGULAR_PIVOT_RATIO
            ));
        }
    }
    Ok(out)
}

/// h, as the energy T + U₀ where the derivation proves them equal (the shorter
/// expression on the shared path: the same rule as a run's audit of H).
fn hamiltonian(d: &Derivation) -> ExprId {
    match (d.energy, d.hamiltonian_is_energy) {
        (Some(e), Some(true)) => e,
        _ => d.energy_function,
    }
}

/// The tape of q'' by the articulated-body algorithm (`run/tree.rs`), where
/// the model is a tree of bodies and particles and the program is shorter than
/// M and f (`dense` instructions) with their solve: the rule a run uses.
fn articulated_body(d: &Derivation, dense_roots: usize) -> Result<Option<Tape>, ModelError> {
    let n = d.q.len();
    let mut pool = d.pool().clone();
    let Some(program) = crate::run::tree::program(&mut pool, d) else { return Ok(None) };
    let symbols = d.layout().symbols();
    let tree = Tape::compile_with_definitions(&pool, &program.definitions, &program.accelerations, symbols)
        .map_err(|e| ModelError::whole(format!("the equations cannot be written as code: {e}")))?;
    let mass: Vec<ExprId> = d.mass_matrix.iter().flatten().chain(&d.forcing).copied().collect();
    debug_assert_eq!(mass.len(), dense_roots);
    let dense = Tape::compile(d.pool(), &mass, symbols)
        .map_err(|e| ModelError::whole(format!("the equations cannot be written as code: {e}")))?;
    let solve = 2 * n * n * n / 3 + 2 * n * n;
    Ok((tree.len() < dense.len() + solve).then_some(tree))
}

/// The model's equations as a Python module needing only numpy: `rhs(t, y,
/// p=None)` as `scipy.integrate.solve_ivp` calls it (y of shape (2n,) or
/// (2n, k)), `jac(t, y, p=None)` from the symbolic derivatives, `mass_matrix`,
/// `forcing`, `hamiltonian` and `energy`, `COORDINATES` and `PARAMETERS`
/// (name → default). A model with `abs()` in its equations is refused: its
/// Jacobian has no value at the kink.
pub fn to_python(d: &Derivation, version: &str) -> Result<String, ModelError> {
    refuse_unsupported(d, "Python")?;
    let model = d.model();
    let n = d.q.len();
    let layout = d.layout();
    let mass: Vec<ExprId> = d.mass_matrix.iter().flatten().copied().collect();
    let check = Tape::compile(d.pool(), &[&mass[..], &d.forcing[..]].concat(), layout.symbols())
        .map_err(|e| ModelError::whole(format!("the equations cannot be written as code: {e}")))?;
    if !check.is_analytic() {
        return Err(ModelError::whole(
            "the equations contain abs(), whose derivative has no value at its kink: the Jacobian jac() cannot be written",
        )
        .with_help("write the model without abs() (a smooth approximation such as sqrt(x^2 + eps^2)), or export it to C, which writes no Jacobian")
        .with_kind(ModelErrorKind::Unsupported));
    }
    // The Jacobian of q'' = M⁻¹ f: M ∂q''/∂q = ∂f/∂q − (∂M/∂q) q'' and
    // M ∂q''/∂q' = ∂f/∂q', with q'' as symbols (n² expressions, not n³).
    let mut pool = d.pool().clone();
    let mut residual_terms = Vec::with_capacity(n);
    for i in 0..n {
        let mut terms = vec![d.forcing[i]];
        for l in 0..n {
            let ma = pool.mul2(d.mass_matrix[i][l], d.qdd[l]);
            terms.push(pool.neg(ma));
        }
        residual_terms.push(pool.add(&terms));
    }
    let mut jacobian = Vec::with_capacity(2 * n * n);
    for wrt in [&d.q, &d.qd] {
        for r in &residual_terms {
            for &x in wrt.iter() {
                jacobian.push(pool.diff(*r, x));
            }
        }
    }
    let mut inputs = layout.symbols().to_vec();
    inputs.extend(&d.qdd);

    let mut out = String::new();
    out.push_str(&format!(
        "\"\"\"{} — equations of motion written by lagrange {version}.\n\n",
        python_docstring_text(&model.name)
    ));
    out.push_str("The state y = [q, q'] is in the order of COORDINATES; the parameters p are a\n");
    out.push_str("sequence in the order of PARAMETERS, a dict of those to change, or None for\n");
    out.push_str("the model file's values (PARAMETERS maps each name to it).\n\n");
    out.push_str("rhs(t, y, p=None): dy/dt = [q', q''] with M q'' = f, as scipy.integrate.solve_ivp\n");
    out.push_str("    calls it; y of shape (2n,) or (2n, k) (solve_ivp's vectorized=True).\n");
    out.push_str("jac(t, y, p=None): the Jacobian d(rhs)/dy, shape (2n, 2n), from the symbolic\n");
    out.push_str("    derivatives (solve_ivp's jac= for the stiff methods).\n");
    out.push_str("mass_matrix, forcing, hamiltonian (h = Σ q' ∂L/∂q' − L), energy (T + U₀): the same\n");
    out.push_str("    quantities as the derivation gives them, at (t, y).\n\"\"\"\n\n");
    out.push_str("import numpy as np\n\n");
    let names: Vec<String> = d.coordinate_names().iter().map(|c| python_string(c)).collect();
    out.push_str(&format!("COORDINATES = [{}]\n", names.join(", ")));
    let params: Vec<String> = model
        .parameters
        .iter()
        .map(|p| format!("{}: {}", python_string(&p.name), literal(Language::Python, p.value)))
        .collect();
    out.push_str(&format!("PARAMETERS = {{{}}}\n", params.join(", ")));
    out.push_str(&format!("N = {n}\n\n\n"));
    out.push_str(PYTHON_HELPERS);
    let python = |exprs: &[ExprId], inputs: &[ExprId], array: &str| -> Result<String, ModelError> {
        python_statements(&pool, layout, exprs, inputs, array)
    };
    let symbols = layout.symbols();
    out.push_str(&format!(
        "def mass_matrix(t, y, p=None):\n    \"\"\"M of M q'' = f, shape (n, n), or (n, n, k) for y of shape (2n, k).\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n    out = np.empty((N * N,) + y.shape[1:])\n{}    \
         return out.reshape((N, N) + y.shape[1:])\n\n\n",
        python(&mass, symbols, "out")?
    ));
    out.push_str(&format!(
        "def forcing(t, y, p=None):\n    \"\"\"f of M q'' = f, shape (n,) or (n, k).\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n    out = np.empty((N,) + y.shape[1:])\n{}    return out\n\n\n",
        python(&d.forcing, symbols, "out")?
    ));
    out.push_str(&format!(
        "def hamiltonian(t, y, p=None):\n    \"\"\"The energy function h = Σ q' ∂L/∂q' − L (H written in q and q').\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n    out = np.empty((1,) + y.shape[1:])\n{}    return out[0]\n\n\n",
        python(&[hamiltonian(d)], symbols, "out")?
    ));
    if let Some(energy) = d.energy {
        out.push_str(&format!(
            "def energy(t, y, p=None):\n    \"\"\"The energy T + U₀.\"\"\"\n    \
             y, p = _state(y), _parameters(p)\n    out = np.empty((1,) + y.shape[1:])\n{}    return out[0]\n\n\n",
            python(&[energy], symbols, "out")?
        ));
    }
    out.push_str(
        "def rhs(t, y, p=None):\n    \"\"\"dy/dt = [q', q''] with M q'' = f; y of shape (2n,) or (2n, k).\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n    \
         a = _solve(mass_matrix(t, y, p), forcing(t, y, p))\n    \
         return np.concatenate([y[N:], a])\n\n\n",
    );
    out.push_str(&format!(
        "def jac(t, y, p=None):\n    \"\"\"The Jacobian d(rhs)/dy at one state y of shape (2n,): shape (2n, 2n).\"\"\"\n    \
         y, p = _state(y), _parameters(p)\n    \
         if y.ndim != 1:\n        raise ValueError(f\"jac takes one state of shape ({{2 * N}},), not {{y.shape}}\")\n    \
         m = mass_matrix(t, y, p)\n    \
         a = np.linalg.solve(m, forcing(t, y, p))\n    \
         out = np.empty(2 * N * N)\n{}    \
         j = np.zeros((2 * N, 2 * N))\n    \
         j[:N, N:] = np.eye(N)\n    \
         j[N:, :N] = np.linalg.solve(m, out[: N * N].reshape(N, N))\n    \
         j[N:, N:] = np.linalg.solve(m, out[N * N :].reshape(N, N))\n    \
         return j\n",
        python(&jacobian, &inputs, "out")?
    ));
    Ok(out)
}

/// What every exported module shares: reading p and y.
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

/// The expressions as Python statements storing into `array`, over `inputs`:
/// the layout's q and q' read from `y`, `t`, the parameters from `p`, and
/// anything after the layout (q'') from `a`.
fn python_statements(
    pool: &sym::Pool,
    layout: &crate::derive::Layout,
    exprs: &[ExprId],
    inputs: &[ExprId],
    array: &str,
) -> Result<String, ModelError> {
    let tape = Tape::compile(pool, exprs, inputs)
        .map_err(|e| ModelError::whole(format!("the equations cannot be written as code: {e}")))?;
    let (t, parameters) = (layout.t(), layout.parameters());
    let input = |k: usize| {
        if k < t {
            format!("y[{k}]")
        } else if k == t {
            "t".to_string()
        } else if parameters.contains(&k) {
            format!("p[{}]", k - parameters.start)
        } else {
            format!("a[{}]", k - parameters.end)
        }
    };
    Ok(tape.emit(&Emit { language: Language::Python, input: &input, output: array, indent: "    ", temporary: "v" }))
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

/// A C function over (t, state, params) that stores the expressions in `out`.
fn function(
    out: &mut String,
    d: &Derivation,
    returns: &str,
    name: &str,
    array: &str,
    what: &str,
    exprs: &[ExprId],
) -> Result<(), ModelError> {
    let body = statements(d, exprs, array)?;
    out.push_str(&format!(
        "/* {what}. */\n{returns} {name}(double t, const double *state, const double *params, double *{array}) {{\n    \
         (void)t; (void)state; (void)params;\n{body}}}\n\n"
    ));
    Ok(())
}

/// A C function over (t, state, params) that returns one expression.
fn scalar(out: &mut String, d: &Derivation, name: &str, what: &str, e: ExprId) -> Result<(), ModelError> {
    let body = statements(d, &[e], "value")?;
    out.push_str(&format!(
        "/* {what}. */\ndouble {name}(double t, const double *state, const double *params) {{\n    \
         double value[1];\n    (void)t; (void)state; (void)params;\n{body}    return value[0];\n}}\n\n"
    ));
    Ok(())
}

/// The expressions as C statements storing into `array`, over the derivation's
/// layout: q and q' from `state`, `t`, the parameters from `params`.
fn statements(d: &Derivation, exprs: &[ExprId], array: &str) -> Result<String, ModelError> {
    let tape = Tape::compile(d.pool(), exprs, d.layout().symbols())
        .map_err(|e| ModelError::whole(format!("the equations cannot be written as code: {e}")))?;
    Ok(emit_c(d, &tape, array))
}

/// A tape over the derivation's layout as C statements storing into `array`.
fn emit_c(d: &Derivation, tape: &Tape, array: &str) -> String {
    let layout = d.layout();
    let (t, parameters) = (layout.t(), layout.parameters());
    let input = |k: usize| {
        if k < t {
            format!("state[{k}]")
        } else if k == t {
            "t".to_string()
        } else {
            format!("params[{}]", k - parameters.start)
        }
    };
    tape.emit(&Emit { language: Language::C, input: &input, output: array, indent: "    ", temporary: "v" })
}

/// Gaussian elimination with partial pivoting on the n × n matrix `m` (row by
/// row) and the right side `b`, which it overwrites with the solution.
fn solve_c() -> String {
    format!(
        "/* Solves m x = b in place (b becomes x) by Gaussian elimination with partial\n \
         * pivoting; returns 1 where m is singular (a pivot below {ratio:e} of the largest). */\n\
         static int lagrange_solve(double *m, double *b) {{\n    \
         const int n = LAGRANGE_N;\n    \
         double largest = 0.0;\n    \
         for (int k = 0; k < n; k++) {{\n        \
         int p = k;\n        \
         for (int i = k + 1; i < n; i++)\n            \
         if (fabs(m[i * n + k]) > fabs(m[p * n + k])) p = i;\n        \
         if (p != k) {{\n            \
         for (int j = 0; j < n; j++) {{ double s = m[k * n + j]; m[k * n + j] = m[p * n + j]; m[p * n + j] = s; }}\n            \
         double s = b[k]; b[k] = b[p]; b[p] = s;\n        \
         }}\n        \
         double pivot = m[k * n + k];\n        \
         if (!(fabs(pivot) > 0.0)) return 1;\n        \
         if (fabs(pivot) > largest) largest = fabs(pivot);\n        \
         for (int i = k + 1; i < n; i++) {{\n            \
         double l = m[i * n + k] / pivot;\n            \
         for (int j = k + 1; j < n; j++) m[i * n + j] -= l * m[k * n + j];\n            \
         b[i] -= l * b[k];\n        \
         }}\n    \
         }}\n    \
         for (int k = 0; k < n; k++)\n        \
         if (!(fabs(m[k * n + k]) >= {ratio:e} * largest)) return 1;\n    \
         for (int k = n - 1; k >= 0; k--) {{\n        \
         double s = b[k];\n        \
         for (int j = k + 1; j < n; j++) s -= m[k * n + j] * b[j];\n        \
         b[k] = s / m[k * n + k];\n    \
         }}\n    \
         return 0;\n\
         }}\n\n",
        ratio = SINGULAR_PIVOT_RATIO
    )
}

/// Refuses what the export does not write yet, saying why, at the place in the
/// model file.
fn refuse_unsupported(d: &Derivation, to: &str) -> Result<(), ModelError> {
    let model = d.model();
    if let Some(c) = d.constraints().list.first() {
        return Err(ModelError::at(
            c.span.clone(),
            format!(
                "the export to {to} does not write [[constraints]] yet: the multipliers' equations are not exported"
            ),
        )
        .with_help(
            "eliminate the constraint by generalized coordinates, or integrate the constrained model with `simulate`",
        )
        .with_kind(ModelErrorKind::Unsupported));
    }
    if let Some(u) = model.inputs.first() {
        return Err(ModelError::at(u.value.span.clone(), format!("the export to {to} does not write [inputs] yet"))
            .with_help("write the input's expression in t into the model's forces, or simulate the model")
            .with_kind(ModelErrorKind::Unsupported));
    }
    Ok(())
}

/// Text safe inside a C comment (no `*/`).
fn comment_text(s: &str) -> String {
    s.replace("*/", "* /")
}

/// Text as the contents of a C string literal.
fn c_string(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\{:03o}", c as u32)),
            c => out.push(c),
        }
    }
    out
}
