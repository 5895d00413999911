//! Taylor series of the motion in Lagrange form, for the Taylor integrator:
//! the normalized coefficients of `y = [q, q']` to any order, on `L` lanes
//! (trajectories) at once.
//!
//! The tape of M's stored entries and f runs in Taylor mode
//! ([`sym::TaylorTape`], native code where the host has a code generator);
//! the accelerations `a = q''` follow order by order from `M a = f` without
//! differentiating M⁻¹: the Cauchy product gives
//! `M[0] a[k] = f[k] − Σ_{j=1..k} M[j] a[k−j]`, so M is inverted once per
//! expansion (at order 0) and each order costs one product with M[0]⁻¹, plus
//! the convolutions of the entries of M that vary (none for a chain of
//! masses). Then `q[k+1] = q'[k]/(k+1)` and `q'[k+1] = a[k]/(k+1)`.
//!
//! M[0]⁻¹ is applied as reciprocals when M is diagonal, as an explicit
//! inverse up to [`EXPLICIT_INVERSE_MAX`] coordinates (a few multiply-adds
//! per order, and the 2×2 of a double pendulum is solved thirteen times per
//! step), and by LU solves beyond.

use crate::clock::Instant;
use num::{LinearSolver, RhsError};
use std::sync::Arc;
use sym::{ClosedFormInverse, Lanes, LinearSecondOrder, Tape, TaylorCode, TaylorTape};

/// Up to this many coordinates M[0]⁻¹ is formed explicitly.
const EXPLICIT_INVERSE_MAX: usize = 6;

/// How M[0]⁻¹ is applied.
#[derive(Debug, Clone)]
enum Inverse<const L: usize> {
    /// 1 / M_ii, per coordinate.
    Diagonal(Vec<Lanes<L>>),
    /// M⁻¹ row-major, n × n.
    Explicit(Vec<Lanes<L>>),
    /// One factorization per lane.
    Lu(Vec<LinearSolver>),
}

/// Which code expands an ensemble's series, and what it cost to get
/// ([`crate::Sweep::code`]): the numbers are the same whichever it is.
#[derive(Debug, Clone, PartialEq)]
pub struct SeriesCode {
    /// The code: the system C compiler's, cranelift's, or the interpreter.
    pub code: TaylorCode,
    /// Seconds spent compiling it (or finding it in the cache and loading it).
    pub seconds: f64,
    /// Why the system C compiler's code is not the one (None when it is, or
    /// was not asked for).
    pub not_c: Option<String>,
    /// Trajectories per expansion.
    pub lanes: usize,
}

impl std::fmt::Display for SeriesCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let lanes = self.lanes;
        match &self.code {
            TaylorCode::C(b) if b.cached => write!(
                f,
                "the Taylor expansion for {lanes} lanes, compiled by {}, came from the cache ({}) in {:.3} s",
                b.compiler.display(),
                b.library.display(),
                self.seconds
            ),
            TaylorCode::C(b) => write!(
                f,
                "the Taylor expansion for {lanes} lanes was compiled by {} in {:.2} s (cached in {} for the next run)",
                b.compiler.display(),
                self.seconds,
                b.library.display()
            ),
            TaylorCode::Cranelift => {
                write!(f, "the Taylor expansion for {lanes} lanes was compiled by cranelift in {:.2} s", self.seconds)
            }
            TaylorCode::Interpreted => write!(f, "the Taylor expansion for {lanes} lanes is interpreted"),
        }?;
        match &self.not_c {
            Some(why) => write!(f, "; not by the C compiler: {why}"),
            None => Ok(()),
        }
    }
}

/// The Taylor expansion of a Lagrange-form system. See the module documentation.
#[derive(Debug, Clone)]
pub(crate) struct LagrangeSeries<const L: usize> {
    n: usize,
    tape: TaylorTape<L>,
    /// How the expansion was compiled.
    made: SeriesCode,
    /// `(row, column)` of M's stored entries; the tape outputs them first, then f.
    entries: Arc<Vec<(usize, usize)>>,
    /// The stored entries of M that vary along a trajectory.
    varying: Vec<usize>,
    /// Where each input (`[q, q', t]`) and output (M's entries, f) sits in the
    /// tape's coefficient buffer.
    input_at: Vec<usize>,
    output_at: Vec<usize>,
    inverse: Inverse<L>,
    /// Lanes whose M[0] could not be inverted in this expansion.
    failed: [bool; L],
    /// The factorization behind an explicit inverse.
    lu: LinearSolver,
    /// Scratch: M on one lane, the right-hand side of one order.
    mass: Vec<f64>,
    column: Vec<f64>,
    rhs: Vec<Lanes<L>>,
    /// `a[k]`, order-major: `accel[k * n + i]`.
    accel: Vec<Lanes<L>>,
}

impl<const L: usize> LagrangeSeries<L> {
    /// The expansion to `order` of the system whose tape maps `[q, q', t,
    /// parameters]` to M's stored `entries` followed by f; `native` asks for
    /// native code (the interpreter serves where there is none).
    pub(crate) fn new(
        tape: &Tape,
        n: usize,
        entries: Arc<Vec<(usize, usize)>>,
        diagonal: bool,
        order: usize,
        native: bool,
    ) -> LagrangeSeries<L> {
        // Inputs [q, q', t] vary along a trajectory; the parameters do not.
        let variable: Vec<bool> = (0..tape.n_inputs()).map(|k| k <= 2 * n).collect();
        let mut tape = TaylorTape::new(tape, order, &variable);
        // The whole expansion with the coupling when M can be inverted in closed
        // form (diagonal, or at most 3 coordinates), in native code where the
        // host has a code generator; otherwise the tape's orders (native or
        // interpreted), coupled here.
        let closed_form = if diagonal {
            Some(ClosedFormInverse::Diagonal)
        } else if n <= ClosedFormInverse::ADJUGATE_MAX_DIM {
            Some(ClosedFormInverse::Adjugate)
        } else {
            None
        };
        let start = Instant::now();
        let mut not_c = None;
        match closed_form {
            Some(inverse) => {
                let system = LinearSecondOrder { dim: n, entries: &entries, inverse };
                if !native {
                    tape.set_second_order(&system);
                } else if L == 1 {
                    // One trajectory: the interpreter steps while the helper
                    // finishes the code, with the same numbers (see `TaylorTape`).
                    tape.set_second_order(&system);
                    if !tape.compile_second_order_in_background() {
                        // Too large to compile whole: the tape's orders, as below.
                        tape.clear_second_order();
                        let _ = tape.compile_native();
                    }
                } else {
                    // Many lanes: the system C compiler's code at the machine's
                    // vector width, else cranelift's; too large for either, the
                    // tape's orders.
                    let c = tape.compile_second_order_c(&system);
                    if let Err(e) = &c {
                        not_c = Some(e.to_string());
                    }
                    if !matches!(c, Ok(true)) && !matches!(tape.compile_second_order(&system), Ok(true)) {
                        let _ = tape.compile_native();
                    }
                }
            }
            None if native => {
                let _ = tape.compile_native();
            }
            None => {}
        }
        let made = SeriesCode { code: tape.code(), seconds: start.elapsed().as_secs_f64(), not_c, lanes: L };
        let varying = (0..entries.len()).filter(|&e| !tape.output_is_constant(e)).collect();
        let input_at = (0..=2 * n).map(|i| tape.input_index(i)).collect();
        let output_at = (0..entries.len() + n).map(|i| tape.output_index(i)).collect();
        let inverse = if diagonal {
            Inverse::Diagonal(vec![[0.0; L]; n])
        } else if n <= EXPLICIT_INVERSE_MAX {
            Inverse::Explicit(vec![[0.0; L]; n * n])
        } else {
            Inverse::Lu((0..L).map(|_| LinearSolver::new(n)).collect())
        };
        LagrangeSeries {
            n,
            tape,
            made,
            entries,
            varying,
            input_at,
            output_at,
            inverse,
            failed: [false; L],
            lu: LinearSolver::new(n),
            mass: vec![0.0; n * n],
            column: vec![0.0; n],
            rhs: vec![[0.0; L]; n],
            accel: vec![[0.0; L]; n * order.max(1)],
        }
    }

    /// How the expansion runs once its code is compiled (this waits for it):
    /// `"whole"` (native functions with the coupling), `"whole, interpreted"`,
    /// `"orders"` (native code per order, coupling here) or `"interpreted"`.
    #[cfg(test)]
    fn code(&self) -> &'static str {
        match (self.tape.is_second_order(), self.tape.wait_for_native(), self.tape.is_native()) {
            (true, true, _) => "whole",
            (true, false, _) => "whole, interpreted",
            (false, _, true) => "orders",
            (false, _, false) => "interpreted",
        }
    }

    /// How the expansion was compiled.
    pub(crate) fn made(&self) -> &SeriesCode {
        &self.made
    }

    /// The order of the expansion.
    pub(crate) fn order(&self) -> usize {
        self.tape.order()
    }

    /// Sets the parameters, `values[k]` for every lane.
    pub(crate) fn set_parameters(&mut self, values: &[Lanes<L>]) {
        for (k, v) in values.iter().enumerate() {
            self.tape.set_constant_input(2 * self.n + 1 + k, *v);
        }
        self.tape.refresh_constants();
    }

    /// Writes the coefficients of orders `0..=order` of `y = [q, q']` at time `t`
    /// into `series` (order-major, `series[k * 2n + i]`), from `y` (`y[i]` on every lane).
    pub(crate) fn expand(&mut self, t: Lanes<L>, y: &[Lanes<L>], series: &mut [Lanes<L>]) -> Result<(), RhsError> {
        let (n, p) = (self.n, self.order());
        let dim = 2 * n;
        let e = self.entries.len();
        if self.tape.is_second_order() {
            let c = self.tape.coefficients_mut();
            for i in 0..dim {
                c[self.input_at[i]] = y[i];
            }
            c[self.input_at[dim]] = t;
            c[self.input_at[dim] + 1] = [1.0; L];
            series[..dim].copy_from_slice(y);
            // The native code writes orders 1..=p into `series` itself.
            self.tape.expand_second_order(&mut series[..(p + 1) * dim]);
            return Ok(());
        }
        series[..dim].copy_from_slice(y);
        for k in 0..p {
            let c = self.tape.coefficients_mut();
            for i in 0..dim {
                c[self.input_at[i] + k] = series[k * dim + i];
            }
            c[self.input_at[dim] + k] = match k {
                0 => t,
                1 => [1.0; L],
                _ => [0.0; L],
            };
            self.tape.compute(k);
            if k == 0 {
                self.invert()?;
            }
            let c = self.tape.coefficients();
            // f[k] − Σ_{j=1..k} M[j] a[k−j]
            for i in 0..n {
                self.rhs[i] = c[self.output_at[e + i] + k];
            }
            for &m in &self.varying {
                let (row, col) = self.entries[m];
                let at = self.output_at[m];
                let mut r = self.rhs[row];
                for j in 1..=k {
                    let (mj, a) = (&c[at + j], &self.accel[(k - j) * n + col]);
                    for l in 0..L {
                        r[l] -= mj[l] * a[l];
                    }
                }
                self.rhs[row] = r;
            }
            let accel = &mut self.accel[k * n..(k + 1) * n];
            match &mut self.inverse {
                Inverse::Diagonal(d) => {
                    for i in 0..n {
                        accel[i] = std::array::from_fn(|l| self.rhs[i][l] * d[i][l]);
                    }
                }
                Inverse::Explicit(inv) => {
                    for i in 0..n {
                        let mut acc = [0.0; L];
                        for j in 0..n {
                            let (m, r) = (&inv[i * n + j], &self.rhs[j]);
                            for l in 0..L {
                                acc[l] += m[l] * r[l];
                            }
                        }
                        accel[i] = acc;
                    }
                }
                Inverse::Lu(lu) => {
                    for (l, lu) in lu.iter().enumerate() {
                        if self.failed[l] {
                            for a in accel.iter_mut() {
                                a[l] = f64::NAN;
                            }
                            continue;
                        }
                        for i in 0..n {
                            self.column[i] = self.rhs[i][l];
                        }
                        lu.solve_in_place(&mut self.column).map_err(RhsError::from)?;
                        for i in 0..n {
                            accel[i][l] = self.column[i];
                        }
                    }
                }
            }
            let next = 1.0 / (k + 1) as f64;
            for i in 0..n {
                let (v, a) = (series[k * dim + n + i], self.accel[k * n + i]);
                series[(k + 1) * dim + i] = std::array::from_fn(|l| v[l] * next);
                series[(k + 1) * dim + n + i] = std::array::from_fn(|l| a[l] * next);
            }
        }
        Ok(())
    }

    /// Inverts (or factors) M[0] on every lane. A single trajectory reports a
    /// singular M as an error; in a batch, only that lane's series becomes NaN
    /// (the batch then fails that lane alone).
    fn invert(&mut self) -> Result<(), RhsError> {
        let n = self.n;
        self.failed = [false; L];
        let c = self.tape.coefficients();
        if let Inverse::Diagonal(d) = &mut self.inverse {
            for (m, &(i, _)) in self.entries.iter().enumerate() {
                let v = c[self.output_at[m]];
                if L == 1 && (v[0] == 0.0 || !v[0].is_finite()) {
                    return Err(RhsError::Singular {
                        detail: format!("M[{i}][{i}] = {} on a diagonal mass matrix", v[0]),
                    });
                }
                d[i] = std::array::from_fn(|l| if v[l] == 0.0 { f64::NAN } else { 1.0 / v[l] });
            }
            return Ok(());
        }
        for lane in 0..L {
            self.mass.fill(0.0);
            for (m, &(i, j)) in self.entries.iter().enumerate() {
                self.mass[i * n + j] = c[self.output_at[m]][lane];
            }
            let result = match &mut self.inverse {
                Inverse::Diagonal(_) => unreachable!("handled above"),
                Inverse::Lu(lu) => lu[lane].factor(&self.mass),
                Inverse::Explicit(inv) => self.lu.factor(&self.mass).and_then(|()| {
                    for col in 0..n {
                        self.column.fill(0.0);
                        self.column[col] = 1.0;
                        self.lu.solve_in_place(&mut self.column)?;
                        for row in 0..n {
                            inv[row * n + col][lane] = self.column[row];
                        }
                    }
                    Ok(())
                }),
            };
            if let Err(e) = result {
                if L == 1 {
                    return Err(e.into());
                }
                self.failed[lane] = true;
                if let Inverse::Explicit(inv) = &mut self.inverse {
                    for x in inv.iter_mut() {
                        x[lane] = f64::NAN;
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::run::dynamics::{Dynamics, Form};
    use crate::{Derivation, Model};
    use num::OdeSystem;

    /// An N-link pendulum from particles (dense M of size N).
    fn pendulum(n: usize) -> String {
        let coords: Vec<String> = (1..=n).map(|k| format!("\"t{k}\"")).collect();
        let mut text =
            format!("name = \"p\"\ncoordinates = [{}]\ngravity = \"g\"\n[parameters]\ng = 9.81\n", coords.join(", "));
        for k in 1..=n {
            let x: Vec<String> = (1..=k).map(|i| format!("sin(t{i})")).collect();
            let y: Vec<String> = (1..=k).map(|i| format!("-cos(t{i})")).collect();
            text += &format!("[[particles]]\nmass = \"1\"\nposition = [\"{}\", \"{}\"]\n", x.join(" + "), y.join(" "));
        }
        text
    }

    const CHAIN: &str = r#"
name = "chain"
coordinates = ["x1", "x2", "x3"]
lagrangian = "m*(x1'^2 + x2'^2 + x3'^2)/2 - k*(x1^2 + (x2 - x1)^2 + (x3 - x2)^2 + x3^2)/2 - c*t*x1"
[parameters]
m = 2.0
k = 3.0
c = 0.5
"#;

    /// y[1] = F(y) and y[2] = (dF/dt along the flow)/2, by central differences.
    fn check(text: &str, native: bool, expect_code: &str) {
        let d = Derivation::new(Model::parse(text, &[]).unwrap()).unwrap();
        let dynamics = Dynamics::new(&d);
        let n = dynamics.n_coords();
        let dim = 2 * n;
        let mut sys = dynamics.system(Form::Lagrange);
        let mut series = dynamics.lagrange_series_with::<1>(9, native);
        assert_eq!(series.code(), expect_code);
        let t = 0.3;
        let y: Vec<f64> = (0..dim).map(|i| 0.4 + 0.37 * i as f64 - 0.9 * (i % 2) as f64).collect();
        let y_lanes: Vec<[f64; 1]> = y.iter().map(|&v| [v]).collect();
        let mut out = vec![[0.0]; dim * 10];
        series.expand([t], &y_lanes, &mut out).unwrap();
        let mut f = vec![0.0; dim];
        sys.rhs(t, &y, &mut f).unwrap();
        for i in 0..dim {
            assert_eq!(out[i][0], y[i]);
            assert!(
                (out[dim + i][0] - f[i]).abs() <= 1e-12 * (1.0 + f[i].abs()),
                "order 1, {i}: {} vs {}",
                out[dim + i][0],
                f[i]
            );
        }
        let h = 1e-5;
        let (mut fp, mut fm) = (vec![0.0; dim], vec![0.0; dim]);
        let yp: Vec<f64> = y.iter().zip(&f).map(|(a, b)| a + h * b).collect();
        let ym: Vec<f64> = y.iter().zip(&f).map(|(a, b)| a - h * b).collect();
        sys.rhs(t + h, &yp, &mut fp).unwrap();
        sys.rhs(t - h, &ym, &mut fm).unwrap();
        for i in 0..dim {
            let want = (fp[i] - fm[i]) / (4.0 * h);
            let got = out[2 * dim + i][0];
            assert!((got - want).abs() <= 1e-6 * (1.0 + want.abs()), "order 2, {i}: {got} vs {want}");
        }
    }

    #[test]
    fn series_start_with_the_right_hand_side_and_its_derivative() {
        check(&pendulum(2), true, "whole");
        check(&pendulum(2), false, "whole, interpreted");
        check(&pendulum(4), true, "orders");
        check(&pendulum(4), false, "interpreted");
        check(CHAIN, true, "whole");
        check(CHAIN, false, "whole, interpreted");
    }

    /// A Lagrangian with most of the elementary functions, in M and in f.
    const FUNCTIONS: &str = r#"
coordinates = ["x", "y"]
lagrangian = "x'^2*(2 + sin(y)^2)/2 + y'^2*(3 + exp(x/4))/2 + x'*y'*atan(x*y)/4 - log(2 + x^2) - sqrt(1 + y^2) - tanh(x)*cosh(y)/10 + t*x/10 - abs(x - y)^1.5/7"
"#;

    /// One trajectory's series is the same to the last bit whether the
    /// interpreter or native code computed it, so a run that switches from
    /// one to the other when the code is ready gives the same rows whenever
    /// that happens.
    #[test]
    fn interpreted_and_native_series_of_one_trajectory_are_the_same_bits() {
        for text in [pendulum(2), pendulum(3), CHAIN.to_string(), FUNCTIONS.to_string()] {
            let d = Derivation::new(Model::parse(&text, &[]).unwrap()).unwrap();
            let dynamics = Dynamics::new(&d);
            let dim = 2 * dynamics.n_coords();
            let p = 13;
            let mut interpreted = dynamics.lagrange_series_with::<1>(p, false);
            let mut native = dynamics.lagrange_series_with::<1>(p, true);
            assert_eq!((interpreted.code(), native.code()), ("whole, interpreted", "whole"), "{text}");
            for point in 0..5 {
                let y: Vec<[f64; 1]> =
                    (0..dim).map(|i| [0.3 * (i + point) as f64 - 0.7 + 0.11 * point as f64]).collect();
                let t = [0.1 * point as f64];
                let (mut a, mut b) = (vec![[0.0]; dim * (p + 1)], vec![[0.0]; dim * (p + 1)]);
                interpreted.expand(t, &y, &mut a).unwrap();
                native.expand(t, &y, &mut b).unwrap();
                for (k, (a, b)) in a.iter().zip(&b).enumerate() {
                    assert_eq!(
                        a[0].to_bits(),
                        b[0].to_bits(),
                        "{text}: coefficient {k} at point {point}: {a:?} vs {b:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_singular_mass_matrix_fails_its_lane_alone() {
        // M = diag(1, x²) is singular at x = 0 (lane 1), regular elsewhere.
        let text = "coordinates = [\"x\", \"y\"]\nlagrangian = \"x'^2/2 + x^2*y'^2/2 - x^2/2\"\n";
        let d = Derivation::new(Model::parse(text, &[]).unwrap()).unwrap();
        let dynamics = Dynamics::new(&d);
        for native in [true, false] {
            let mut s = dynamics.lagrange_series_with::<2>(6, native);
            let y = [[1.0, 0.0], [0.0, 0.0], [0.5, 0.3], [0.2, 0.1]];
            let mut out = vec![[0.0; 2]; 4 * 7];
            s.expand([0.0; 2], &y, &mut out).unwrap();
            assert!(out.iter().all(|c| c[0].is_finite()), "native {native}: {out:?}");
            assert!(out.iter().any(|c| !c[1].is_finite()), "native {native}: {out:?}");
            // One trajectory alone gets an error naming the singular matrix.
            let mut one = dynamics.lagrange_series_with::<1>(6, native);
            let y1 = [[0.0], [0.0], [0.3], [0.1]];
            let mut out1 = vec![[0.0]; 4 * 7];
            let r = one.expand([0.0], &y1, &mut out1);
            assert!(r.is_err() || out1.iter().any(|c| !c[0].is_finite()), "native {native}");
        }
    }

    #[test]
    fn every_way_of_running_gives_the_same_series_and_lanes_are_independent() {
        for text in [pendulum(3), pendulum(4), CHAIN.to_string()] {
            let d = Derivation::new(Model::parse(&text, &[]).unwrap()).unwrap();
            let dynamics = Dynamics::new(&d);
            let dim = 2 * dynamics.n_coords();
            let p = 12;
            let states: Vec<Vec<f64>> =
                (0..4).map(|l| (0..dim).map(|i| 0.1 * (i + l) as f64 - 0.3).collect()).collect();
            let lanes: Vec<[f64; 4]> = (0..dim).map(|i| std::array::from_fn(|l| states[l][i])).collect();
            let mut batch = dynamics.lagrange_series_with::<4>(p, true);
            let mut out4 = vec![[0.0; 4]; dim * (p + 1)];
            batch.expand([0.2; 4], &lanes, &mut out4).unwrap();
            for (l, state) in states.iter().enumerate() {
                let single: Vec<[f64; 1]> = state.iter().map(|&v| [v]).collect();
                for native in [true, false] {
                    let mut s = dynamics.lagrange_series_with::<1>(p, native);
                    let mut out1 = vec![[0.0]; dim * (p + 1)];
                    s.expand([0.2], &single, &mut out1).unwrap();
                    // The native code fuses the convolutions' multiply-adds (one
                    // rounding where the interpreter has two); higher orders carry
                    // that difference along, so compare each order against its
                    // largest coefficient.
                    for (k, (a_order, b_order)) in out1.chunks(dim).zip(out4.chunks(dim)).enumerate() {
                        let scale = a_order.iter().fold(0.0f64, |m, a| m.max(a[0].abs()));
                        for (a, b) in a_order.iter().zip(b_order) {
                            let (a, b) = (a[0], b[l]);
                            assert!((a - b).abs() <= 1e-10 * scale, "order {k}, lane {l}: {a} vs {b}");
                        }
                    }
                }
            }
        }
    }
}
