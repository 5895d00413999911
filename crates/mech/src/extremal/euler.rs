//! The Euler equation of `J[y] = ∫ f(y, y', x) dx` and the expressions built
//! with it: `∂f/∂y − d/dx ∂f/∂y' = 0`, solved for y'' (it is linear in y''),
//! Beltrami's first integral `y'·∂f/∂y' − f` when f has no x, and the
//! coefficients of the second variation, `P = f_{y'y'}` and
//! `Q = f_{yy} − d/dx f_{yy'}` (notes, appendix A.2).
//!
//! Entry point: [`Euler::new`]. The total derivative along a curve is written
//! out here: `d/dx g = ∂g/∂x + y'·∂g/∂y + y''·∂g/∂y'`.

use sym::{ExprId, Pool};

/// The symbols of an extremal problem.
#[derive(Debug, Clone, Copy)]
pub struct Vars {
    /// The independent variable x.
    pub x: ExprId,
    /// The unknown y.
    pub y: ExprId,
    /// y'.
    pub p: ExprId,
    /// y''.
    pub a: ExprId,
}

/// The symbolic results of the first and second variation.
#[derive(Debug, Clone)]
pub struct Euler {
    /// The symbols.
    pub vars: Vars,
    /// `∂f/∂y − d/dx ∂f/∂y'`, simplified; it vanishes on extremals.
    pub equation: ExprId,
    /// y'' as a function of (x, y, y'), solved from the Euler equation.
    pub acceleration: ExprId,
    /// `y'·∂f/∂y' − f` when f does not depend on x (constant on extremals).
    pub first_integral: Option<ExprId>,
    /// `P = ∂²f/∂y'²` (Legendre: P > 0 along a minimum).
    pub legendre: ExprId,
    /// `Q = ∂²f/∂y² − d/dx ∂²f/∂y∂y'` (in x, y, y', y'').
    pub jacobi_q: ExprId,
}

/// Why the Euler equation cannot be solved for y''.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EulerError {
    /// f is linear in y': the Euler equation is not a differential equation.
    #[error(
        "∂²f/∂{y}'² = 0: f is linear in {y}', so the Euler equation has no {y}'' and is not a second-order equation"
    )]
    Degenerate {
        /// The unknown's name.
        y: String,
    },
}

impl Euler {
    /// Derives everything from `f` in `pool` (x, y named `x_name`, `y_name`).
    pub fn new(pool: &mut Pool, f: ExprId, x_name: &str, y_name: &str) -> Result<Euler, EulerError> {
        let vars =
            Vars { x: pool.var(x_name, 0), y: pool.var(y_name, 0), p: pool.var(y_name, 1), a: pool.var(y_name, 2) };
        let f_y = pool.diff(f, vars.y);
        let f_p = pool.diff(f, vars.p);
        let df_p = total_derivative(pool, f_p, vars);
        let raw = pool.sub(f_y, df_p);
        let y_sym = pool.as_symbol(vars.y).map(|s| s.name);
        let is_var = |s: sym::Symbol| Some(s.name) == y_sym;
        let equation = pool.simplify_in(raw, &is_var);
        let equation = pool.simplify_rational(equation);
        let f_pp = pool.diff(f_p, vars.p);
        let f_pp = pool.simplify(f_pp);
        let f_pp = pool.simplify_rational(f_pp);
        if pool.is_zero(f_pp) {
            return Err(EulerError::Degenerate { y: y_name.to_string() });
        }
        // E = E0 − f_pp·y'' with E0 free of y'': y'' = E0 / f_pp.
        let f_px = pool.diff(f_p, vars.x);
        let f_py = pool.diff(f_p, vars.y);
        let p_f_py = pool.mul2(vars.p, f_py);
        let e0 = pool.sub(f_y, f_px);
        let e0 = pool.sub(e0, p_f_py);
        let acc = pool.div(e0, f_pp);
        let acceleration = pool.simplify(acc);
        let acceleration = pool.simplify_rational(acceleration);
        let first_integral = if pool.free_of(f, vars.x) {
            let pf = pool.mul2(vars.p, f_p);
            let h = pool.sub(pf, f);
            let h = pool.simplify(h);
            Some(pool.simplify_rational(h))
        } else {
            None
        };
        let f_yy = pool.diff(f_y, vars.y);
        let f_yp = pool.diff(f_y, vars.p);
        let d_f_yp = total_derivative(pool, f_yp, vars);
        let q = pool.sub(f_yy, d_f_yp);
        let jacobi_q = pool.simplify_in(q, &is_var);
        let jacobi_q = pool.simplify_rational(jacobi_q);
        Ok(Euler { vars, equation, acceleration, first_integral, legendre: f_pp, jacobi_q })
    }
}

/// `d/dx g(y, y', x) = ∂g/∂x + y'·∂g/∂y + y''·∂g/∂y'` along a curve y(x).
pub fn total_derivative(pool: &mut Pool, g: ExprId, v: Vars) -> ExprId {
    let g_x = pool.diff(g, v.x);
    let g_y = pool.diff(g, v.y);
    let g_p = pool.diff(g, v.p);
    let t1 = pool.mul2(v.p, g_y);
    let t2 = pool.mul2(v.a, g_p);
    pool.add(&[g_x, t1, t2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[track_caller]
    fn check(f: &str, equation: &str, acceleration: &str, first_integral: Option<&str>) {
        let mut pool = Pool::default();
        let f = pool.parse(f).unwrap();
        let e = Euler::new(&mut pool, f, "x", "y").unwrap();
        assert_eq!(pool.display(e.equation).to_string(), equation);
        assert_eq!(pool.display(e.acceleration).to_string(), acceleration);
        assert_eq!(e.first_integral.map(|h| pool.display(h).to_string()).as_deref(), first_integral);
    }

    #[test]
    fn euler_equations() {
        check("y'^2/2 - y^2/2", "-y - y''", "-y", Some("y^2/2 + y'^2/2"));
        check("y'^2 + x*y", "x - 2*y''", "x/2", None);
    }

    #[test]
    fn quotients_read_as_written() {
        // Catenary: y'' = (1 + y'^2)/y.
        check("y*sqrt(1 + y'^2)", "(y'^2 - y*y'' + 1)/(y'^2 + 1)^(3/2)", "(y'^2 + 1)/y", Some("-y/sqrt(y'^2 + 1)"));
        // Brachistochrone: y'' = -(1 + y'^2)/(2y).
        check(
            "sqrt((1 + y'^2)/(2*g*y))",
            "-(y'^2 + 2*y*y'' + 1)*sqrt((y'^2 + 1)/(2*g*y))/(2*y*(y'^2 + 1)^2)",
            "-(y'^2 + 1)/(2*y)",
            Some("-sqrt((y'^2 + 1)/(2*g*y))/(y'^2 + 1)"),
        );
        let mut pool = Pool::default();
        let f = pool.parse("y*sqrt(1 + y'^2)").unwrap();
        let e = Euler::new(&mut pool, f, "x", "y").unwrap();
        assert_eq!(pool.display(e.legendre).to_string(), "y/(y'^2 + 1)^(3/2)");
        assert_eq!(pool.display(e.jacobi_q).to_string(), "-y''/(y'^2 + 1)^(3/2)");
    }

    #[test]
    fn linear_in_slope_is_degenerate() {
        let mut pool = Pool::default();
        let f = pool.parse("y*y' + x").unwrap();
        assert!(Euler::new(&mut pool, f, "x", "y").is_err());
    }
}
