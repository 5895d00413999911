//! Scalar root finding: Brent's method ([`brent`]), which event location uses on the
//! dense output. It keeps a bracket, so it always converges, and takes inverse
//! quadratic or secant steps where they are safe, so it usually converges fast.

/// Most evaluations of [`brent`]: it converges at least as fast as bisection,
/// which needs about 110 halvings from the widest finite bracket to round-off, so the
/// bound only stops a function that changes under the search (noise) from looping.
const MAX_EVALUATIONS: usize = 200;

/// Finds a root of `f` in `[a, b]` given `fa = f(a)` and `fb = f(b)` of opposite sign
/// (or one of them zero), to within `tol` (plus `4ε|x|`, the round-off of `x`). Errors
/// of `f` are passed through. At most 200 evaluations (`MAX_EVALUATIONS`) are made; the
/// best point so far is returned then.
///
/// ```
/// let root = num::brent(|x| Ok::<_, ()>(x * x - 2.0), 0.0, 2.0, -2.0, 2.0, 1e-15).unwrap();
/// assert!((root - 2f64.sqrt()).abs() < 1e-14);
/// ```
pub fn brent<E>(
    mut f: impl FnMut(f64) -> Result<f64, E>,
    a: f64,
    b: f64,
    fa: f64,
    fb: f64,
    tol: f64,
) -> Result<f64, E> {
    if fa == 0.0 {
        return Ok(a);
    }
    if fb == 0.0 {
        return Ok(b);
    }
    let (mut a, mut b, mut fa, mut fb) = (a, b, fa, fb);
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    let mut reset = true;
    for _ in 0..MAX_EVALUATIONS {
        if reset {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol1 = 2.0 * f64::EPSILON * b.abs() + 0.5 * tol;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol1 || fb == 0.0 {
            return Ok(b);
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                // Secant step.
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                // Inverse quadratic interpolation.
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol1 * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol1 { d } else { tol1.copysign(xm) };
        fb = f(b)?;
        reset = (fb > 0.0) == (fc > 0.0) && fb != 0.0;
    }
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[track_caller]
    fn check(f: impl Fn(f64) -> f64, a: f64, b: f64, root: f64) {
        let x = brent(|x| Ok::<_, ()>(f(x)), a, b, f(a), f(b), 1e-14).unwrap();
        assert!((x - root).abs() < 1e-12, "found {x}, expected {root}");
    }

    #[test]
    fn roots() {
        check(|x| x.cos(), 0.0, 3.0, std::f64::consts::FRAC_PI_2);
        check(|x| x.powi(3) - x - 2.0, 1.0, 2.0, 1.5213797068045676);
        check(|x| (x - 1.0).powi(5), 0.0, 3.0, 1.0);
        check(|x| if x < 0.3 { -1.0 } else { 1.0 }, 0.0, 1.0, 0.3);
        check(|x| x, 0.0, 1.0, 0.0);
    }
}
