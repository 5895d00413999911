//! The C99 file of `lagrange export --to c`: see [`to_c`].

use super::{hamiltonian, Read, Reads};
use crate::derive::Derivation;
use crate::error::ModelError;
use sym::emit::{literal, Emit, Language};
use sym::{ExprId, Tape};

/// The smallest ratio of the smallest to the largest pivot of M that the
/// written solve takes for a regular matrix (the run's `num` LU uses the same
/// kind of test): below it `lagrange_rhs` returns 1.
pub const SINGULAR_PIVOT_RATIO: f64 = 1e-14;

/// The model's equations as one C99 file needing only libm, with a header
/// comment naming the model and lagrange's `version`:
///
/// - `LAGRANGE_N`, `LAGRANGE_N_PARAMETERS`, `LAGRANGE_N_INPUTS`,
///   `LAGRANGE_N_CONSTRAINTS`; the names of the coordinates, parameters,
///   inputs and constraints, and the parameters' values in the model file;
/// - `lagrange_rhs(t, state, params, dstate)`, returning 0, 1 where M (or the
///   saddle-point matrix of a constrained model) is singular, 2 where a value
///   is not finite; `lagrange_mass_matrix`, `lagrange_forcing`,
///   `lagrange_hamiltonian` and `lagrange_energy`;
/// - with `[inputs]`: `lagrange_inputs` (their values in t, which
///   `lagrange_rhs` and `lagrange_forcing` use), and `lagrange_rhs_u`,
///   `lagrange_forcing_u`, `lagrange_input_matrix` (B) taking u as an argument;
/// - with `[[constraints]]`: `lagrange_constraint_residuals`,
///   `lagrange_constraint_rates` (A q' + a_t), `lagrange_constraint_jacobian`
///   (A) and `lagrange_multipliers` (λ).
pub fn to_c(d: &Derivation, version: &str) -> Result<String, ModelError> {
    super::refuse_impacts(d)?;
    let model = d.model();
    let reads = Reads::new(d, &[]);
    let inputs = d.inputs().len();
    let constraints = &d.constraints().list;
    let u = if inputs > 0 { "_u" } else { "" };
    let mut out = String::new();
    out.push_str(&format!("/* {} — equations of motion written by lagrange {version}.\n", comment_text(&model.name)));
    out.push_str(" *\n");
    out.push_str(" * state  = [q, q'] in the order of lagrange_coordinates,\n");
    out.push_str(" * params = the parameters in the order of lagrange_parameters (their\n");
    out.push_str(" *          model-file values in lagrange_parameter_defaults).\n");
    if inputs > 0 {
        out.push_str(" * u      = the inputs in the order of lagrange_input_names, for the *_u\n");
        out.push_str(" *          functions; the others take their values in t (lagrange_inputs).\n");
    }
    out.push_str(" * int lagrange_rhs(t, state, params, dstate): dstate = [q', q''] from M q'' = f");
    if constraints.is_empty() {
        out.push_str(";\n");
    } else {
        out.push_str(" + Aᵀλ\n *     with the constraints at acceleration level (no projection: watch\n");
        out.push_str(" *     lagrange_constraint_residuals);\n");
    }
    out.push_str(" *     returns 0, or non-zero where M is singular or a value is not finite.\n");
    out.push_str(" * C99 and libm only: cc -std=c99 -c this.c (link with -lm).\n");
    out.push_str(" */\n\n#include <math.h>\n\n");
    out.push_str(&format!("#define LAGRANGE_N {}\n", d.q.len()));
    out.push_str(&format!("#define LAGRANGE_N_PARAMETERS {}\n", model.parameters.len()));
    out.push_str(&format!("#define LAGRANGE_N_INPUTS {inputs}\n"));
    out.push_str(&format!("#define LAGRANGE_N_CONSTRAINTS {}\n\n", constraints.len()));
    let names = |what: &str, array: &str, size: &str, names: Vec<&str>| {
        let list: Vec<String> = names.iter().map(|s| format!("\"{}\"", c_string(s))).chain(["0".to_string()]).collect();
        format!(
            "/* The {what}' names, then a null pointer. */\nconst char *const {array}[{size} + 1] = {{{}}};\n",
            list.join(", ")
        )
    };
    out.push_str(&names("coordinates", "lagrange_coordinates", "LAGRANGE_N", d.coordinate_names()));
    let parameters = model.parameters.iter().map(|p| p.name.as_str()).collect();
    out.push_str(&names("parameters", "lagrange_parameters", "LAGRANGE_N_PARAMETERS", parameters));
    let list: Vec<String> =
        model.parameters.iter().map(|p| literal(Language::C, p.value)).chain(["0.0".to_string()]).collect();
    out.push_str("/* The parameters' values in the model file, then a 0. */\n");
    out.push_str(&format!(
        "const double lagrange_parameter_defaults[LAGRANGE_N_PARAMETERS + 1] = {{{}}};\n",
        list.join(", ")
    ));
    if inputs > 0 {
        let list = model.inputs.iter().map(|u| u.name.as_str()).collect();
        out.push_str(&names("inputs", "lagrange_input_names", "LAGRANGE_N_INPUTS", list));
    }
    if !constraints.is_empty() {
        let list = constraints.iter().map(|c| c.name.as_str()).collect();
        out.push_str(&names("constraints", "lagrange_constraint_names", "LAGRANGE_N_CONSTRAINTS", list));
    }
    out.push('\n');

    let pool = d.pool();
    let w = Writer { reads: &reads };
    let mass: Vec<ExprId> = d.mass_matrix.iter().flatten().copied().collect();
    let mass_tape = reads.compile(pool, &mass)?;
    let forcing_tape = reads.compile(pool, &d.forcing)?;
    w.function(&mut out, "lagrange_mass_matrix", false, "m", "M, row by row (n × n)", &mass_tape);
    if inputs > 0 {
        let values: Vec<ExprId> = model.inputs.iter().map(|u| u.value.expr).collect();
        w.function(
            &mut out,
            "lagrange_inputs",
            false,
            "u",
            "The inputs' values in t (the model's [inputs])",
            &reads.compile(pool, &values)?,
        );
        w.function(&mut out, "lagrange_forcing_u", true, "f", "f of M q'' = f at the inputs u", &forcing_tape);
        out.push_str(
            "/* f of M q'' = f with the inputs' values in t. */\n\
             void lagrange_forcing(double t, const double *state, const double *params, double *f) {\n    \
             double u[LAGRANGE_N_INPUTS];\n    \
             lagrange_inputs(t, state, params, u);\n    \
             lagrange_forcing_u(t, state, params, u, f);\n}\n\n",
        );
        let b: Vec<ExprId> = d.input_matrix().iter().flatten().copied().collect();
        let what = if d.inputs_affine() {
            "B = ∂f/∂u, row by row (n × LAGRANGE_N_INPUTS): f = f₀ + B u"
        } else {
            "B = ∂f/∂u at u, row by row (n × LAGRANGE_N_INPUTS): f is not affine in u"
        };
        w.function(&mut out, "lagrange_input_matrix", true, "b", what, &reads.compile(pool, &b)?);
    } else {
        w.function(&mut out, "lagrange_forcing", false, "f", "f of M q'' = f", &forcing_tape);
    }
    w.scalar(
        &mut out,
        "lagrange_hamiltonian",
        "The energy function h = Σ q' ∂L/∂q' − L (H in q, q')",
        &reads.compile(pool, &[hamiltonian(d)])?,
    );
    if let Some(energy) = d.energy {
        w.scalar(&mut out, "lagrange_energy", "The energy T + U₀", &reads.compile(pool, &[energy])?);
    }
    let finish = "    for (int i = 0; i < LAGRANGE_N; i++) {\n        \
         if (!isfinite(a[i]) || !isfinite(state[LAGRANGE_N + i])) return 2;\n        \
         dstate[i] = state[LAGRANGE_N + i];\n        \
         dstate[LAGRANGE_N + i] = a[i];\n    \
         }\n    \
         return 0;\n\
         }\n\n";
    let signature = |name: &str, with_u: bool, last: &str| format!("int {name}({}, double *{last})", arguments(with_u));
    if !constraints.is_empty() {
        let a: Vec<ExprId> = constraints.iter().flat_map(|c| c.jacobian.iter().copied()).collect();
        let residuals: Vec<ExprId> = constraints.iter().map(crate::Constraint::residual).collect();
        let rates: Vec<ExprId> = constraints.iter().map(|c| c.velocity_form).collect();
        let c: Vec<ExprId> = constraints.iter().map(|c| c.acceleration_rhs).collect();
        w.function(&mut out, "lagrange_constraint_residuals", false, "r", "The constraints' residuals: f(q, t) for a holonomic constraint, A q' + a_t for a velocity one (0 on the constraint)", &reads.compile(pool, &residuals)?);
        w.function(
            &mut out,
            "lagrange_constraint_rates",
            false,
            "r",
            "The constraints at velocity level, A q' + a_t (0 on the constraint)",
            &reads.compile(pool, &rates)?,
        );
        w.function(
            &mut out,
            "lagrange_constraint_jacobian",
            false,
            "a",
            "A, row by row (LAGRANGE_N_CONSTRAINTS × n): the constraints' rows A q' + a_t = 0",
            &reads.compile(pool, &a)?,
        );
        w.function_of(
            &mut out,
            "static void",
            "lagrange_constraint_accelerations",
            false,
            "c",
            "c of the constraints at acceleration level, A q'' = c",
            &reads.compile(pool, &c)?,
        );
        out.push_str(&solve_c());
        let forcing_call = if inputs > 0 {
            "lagrange_forcing_u(t, state, params, u, x)"
        } else {
            "lagrange_forcing(t, state, params, x)"
        };
        out.push_str(&format!(
            "/* Solves [M −Aᵀ; A 0] [q''; λ] = [f; c] into x = [q''; λ]; returns 1 where the\n \
             * matrix is singular (a pivot below {ratio:e} of the largest). */\n\
             static int lagrange_saddle({}, double *x) {{\n    \
             enum {{ N = LAGRANGE_N, K = LAGRANGE_N + LAGRANGE_N_CONSTRAINTS }};\n    \
             double m[N * N], a[LAGRANGE_N_CONSTRAINTS * N], k[K * K];\n    \
             lagrange_mass_matrix(t, state, params, m);\n    \
             lagrange_constraint_jacobian(t, state, params, a);\n    \
             {forcing_call};\n    \
             lagrange_constraint_accelerations(t, state, params, x + N);\n    \
             for (int i = 0; i < K * K; i++) k[i] = 0.0;\n    \
             for (int i = 0; i < N; i++)\n        \
             for (int j = 0; j < N; j++) k[i * K + j] = m[i * N + j];\n    \
             for (int r = 0; r < LAGRANGE_N_CONSTRAINTS; r++)\n        \
             for (int j = 0; j < N; j++) {{\n            \
             k[(N + r) * K + j] = a[r * N + j];\n            \
             k[j * K + N + r] = -a[r * N + j];\n        \
             }}\n    \
             return lagrange_solve(K, k, x);\n}}\n\n",
            arguments(inputs > 0),
            ratio = SINGULAR_PIVOT_RATIO
        ));
        let call =
            if inputs > 0 { "lagrange_saddle(t, state, params, u, x)" } else { "lagrange_saddle(t, state, params, x)" };
        out.push_str(&format!(
            "/* The multipliers λ of M q'' = f + Aᵀλ. Returns 0; 1 where the saddle-point\n \
             * matrix is singular. */\n\
             {} {{\n    \
             double x[LAGRANGE_N + LAGRANGE_N_CONSTRAINTS];\n    \
             if ({call}) return 1;\n    \
             for (int i = 0; i < LAGRANGE_N_CONSTRAINTS; i++) lambda[i] = x[LAGRANGE_N + i];\n    \
             return 0;\n}}\n\n",
            signature(&format!("lagrange_multipliers{u}"), inputs > 0, "lambda")
        ));
        out.push_str(&format!(
            "/* dstate = [q', q''] with M q'' = f + Aᵀλ and A q'' = c. Returns 0; 1 where the\n \
             * saddle-point matrix is singular; 2 where a value is not finite. */\n\
             {} {{\n    \
             double a[LAGRANGE_N + LAGRANGE_N_CONSTRAINTS];\n    \
             if ({}) return 1;\n{finish}",
            signature(&format!("lagrange_rhs{u}"), inputs > 0, "dstate"),
            call.replace(", x)", ", a)")
        ));
    } else if let Some(tape) = articulated_body(d, &reads, mass_tape.len() + forcing_tape.len())? {
        out.push_str(&format!(
            "/* q'' by the articulated-body algorithm over the model's tree of bodies\n \
             * (shorter than M, f and their solve). */\n\
             static void lagrange_accelerations({}, double *a) {{\n    {}\n{}}}\n\n",
            arguments(inputs > 0),
            unused(inputs > 0),
            w.emit(&tape, "a")
        ));
        let call = if inputs > 0 {
            "lagrange_accelerations(t, state, params, u, a)"
        } else {
            "lagrange_accelerations(t, state, params, a)"
        };
        out.push_str(&format!(
            "/* dstate = [q', q''] with M q'' = f, by the articulated-body algorithm.\n \
             * Returns 0; 2 where a value is not finite (M singular included). */\n\
             {} {{\n    \
             double a[LAGRANGE_N];\n    \
             {call};\n{finish}",
            signature(&format!("lagrange_rhs{u}"), inputs > 0, "dstate")
        ));
    } else {
        out.push_str(&solve_c());
        let forcing_call = if inputs > 0 {
            "lagrange_forcing_u(t, state, params, u, a)"
        } else {
            "lagrange_forcing(t, state, params, a)"
        };
        out.push_str(&format!(
            "/* dstate = [q', q''] with M q'' = f. Returns 0; 1 where M is singular\n \
             * (a pivot below {ratio:e} of the largest); 2 where a value is not finite. */\n\
             {} {{\n    \
             double m[LAGRANGE_N * LAGRANGE_N], a[LAGRANGE_N];\n    \
             lagrange_mass_matrix(t, state, params, m);\n    \
             {forcing_call};\n    \
             if (lagrange_solve(LAGRANGE_N, m, a)) return 1;\n{finish}",
            signature(&format!("lagrange_rhs{u}"), inputs > 0, "dstate"),
            ratio = SINGULAR_PIVOT_RATIO
        ));
    }
    if inputs > 0 {
        out.push_str(
            "/* dstate = [q', q''] with the inputs' values in t: lagrange_rhs_u at lagrange_inputs. */\n\
             int lagrange_rhs(double t, const double *state, const double *params, double *dstate) {\n    \
             double u[LAGRANGE_N_INPUTS];\n    \
             lagrange_inputs(t, state, params, u);\n    \
             return lagrange_rhs_u(t, state, params, u, dstate);\n}\n\n",
        );
        if !constraints.is_empty() {
            out.push_str(
                "/* λ with the inputs' values in t: lagrange_multipliers_u at lagrange_inputs. */\n\
                 int lagrange_multipliers(double t, const double *state, const double *params, double *lambda) {\n    \
                 double u[LAGRANGE_N_INPUTS];\n    \
                 lagrange_inputs(t, state, params, u);\n    \
                 return lagrange_multipliers_u(t, state, params, u, lambda);\n}\n\n",
            );
        }
    }
    Ok(out)
}

/// The parameters of an exported function before its output array.
fn arguments(with_u: bool) -> &'static str {
    if with_u {
        "double t, const double *state, const double *params, const double *u"
    } else {
        "double t, const double *state, const double *params"
    }
}

/// Marks the arguments used, so that a function whose expressions do not read
/// one of them compiles under `-Wall -Wextra -Werror`.
fn unused(with_u: bool) -> &'static str {
    if with_u {
        "(void)t; (void)state; (void)params; (void)u;"
    } else {
        "(void)t; (void)state; (void)params;"
    }
}

/// Writes the C functions of tapes over [`Reads`].
struct Writer<'a> {
    reads: &'a Reads,
}

impl Writer<'_> {
    /// A C function over (t, state, params[, u]) that stores the tape's outputs in `array`.
    fn function(&self, out: &mut String, name: &str, with_u: bool, array: &str, what: &str, tape: &Tape) {
        self.function_of(out, "void", name, with_u, array, what, tape);
    }

    /// As [`Writer::function`], with the return type (and linkage) `returns`.
    #[allow(clippy::too_many_arguments)]
    fn function_of(
        &self,
        out: &mut String,
        returns: &str,
        name: &str,
        with_u: bool,
        array: &str,
        what: &str,
        tape: &Tape,
    ) {
        out.push_str(&format!(
            "/* {what}. */\n{returns} {name}({}, double *{array}) {{\n    {}\n{}}}\n\n",
            arguments(with_u),
            unused(with_u),
            self.emit(tape, array)
        ));
    }

    /// A C function over (t, state, params) that returns the tape's one output.
    fn scalar(&self, out: &mut String, name: &str, what: &str, tape: &Tape) {
        out.push_str(&format!(
            "/* {what}. */\ndouble {name}({}) {{\n    double value[1];\n    {}\n{}    return value[0];\n}}\n\n",
            arguments(false),
            unused(false),
            self.emit(tape, "value")
        ));
    }

    /// The tape as C statements storing into `array`: q and q' from `state`,
    /// `t`, the parameters from `params`, the inputs from `u`.
    fn emit(&self, tape: &Tape, array: &str) -> String {
        let input = |k: usize| match self.reads.which(k) {
            Read::State(k) => format!("state[{k}]"),
            Read::Time => "t".to_string(),
            Read::Parameter(i) => format!("params[{i}]"),
            Read::Input(i) => format!("u[{i}]"),
            Read::Extra(_) => unreachable!("the C export compiles over the layout and the inputs only"),
        };
        tape.emit(&Emit { language: Language::C, input: &input, output: array, indent: "    ", temporary: "v" })
    }
}

/// The tape of q'' by the articulated-body algorithm (`run/tree.rs`), where
/// the model is a tree of bodies and particles and the program is shorter than
/// M and f (`dense` instructions) with their solve: the rule a run uses.
fn articulated_body(d: &Derivation, reads: &Reads, dense: usize) -> Result<Option<Tape>, ModelError> {
    let n = d.q.len();
    let mut pool = d.pool().clone();
    let Some(program) = crate::run::tree::program(&mut pool, d) else { return Ok(None) };
    let tree = Tape::compile_with_definitions(&pool, &program.definitions, &program.accelerations, &reads.symbols)
        .map_err(|e| ModelError::whole(format!("the equations cannot be written as code: {e}")))?;
    let solve = 2 * n * n * n / 3 + 2 * n * n;
    Ok((tree.len() < dense + solve).then_some(tree))
}

/// Gaussian elimination with partial pivoting on the n × n matrix `m` (row by
/// row) and the right side `b`, which it overwrites with the solution.
fn solve_c() -> String {
    format!(
        "/* Solves m x = b in place (b becomes x) for the n × n matrix m, row by row, by\n \
         * Gaussian elimination with partial pivoting; returns 1 where m is singular (a\n \
         * pivot below {ratio:e} of the largest). */\n\
         static int lagrange_solve(int n, double *m, double *b) {{\n    \
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
