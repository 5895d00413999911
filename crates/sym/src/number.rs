//! Numbers of the expression language: exact rationals beside f64 constants.
//!
//! Exact arithmetic uses `i128` numerators and denominators with checked
//! operations: when a result would overflow, the operation reports `None` and the
//! caller falls back to floating point (never to a silently wrong exact value).
//! Hand-written expressions rarely need more than a few digits of exactness (½, ⅓, 2/3, …), so
//! a big-integer crate would cost build time for nothing.

use std::cmp::Ordering;
use std::fmt;

/// An exact rational number `num/den`, always reduced, with `den > 0`.
/// Neither is ever `i128::MIN`, so that negation and reciprocal stay exact:
/// a result that would be `i128::MIN` overflows like any larger one
/// (otherwise `(-2)^127` would be exact and `1/(-2)^127` not, and the same
/// number would have two forms).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Rational {
    num: i128,
    den: i128,
}

/// gcd of the magnitudes; `None` when it does not fit an i128 (only for i128::MIN).
fn gcd(a: i128, b: i128) -> Option<i128> {
    let (mut a, mut b) = (a.unsigned_abs(), b.unsigned_abs());
    while b != 0 {
        let r = a % b;
        a = b;
        b = r;
    }
    i128::try_from(a).ok()
}

impl Rational {
    /// Zero.
    pub const ZERO: Rational = Rational { num: 0, den: 1 };
    /// One.
    pub const ONE: Rational = Rational { num: 1, den: 1 };
    /// Minus one.
    pub const MINUS_ONE: Rational = Rational { num: -1, den: 1 };

    /// The reduced fraction `num/den`, or `None` when `den` is zero or reduction overflows.
    pub fn new(num: i128, den: i128) -> Option<Rational> {
        if den == 0 {
            return None;
        }
        let g = gcd(num, den)?.max(1);
        let (mut n, mut d) = (num / g, den / g);
        if d < 0 {
            n = n.checked_neg()?;
            d = d.checked_neg()?;
        }
        if n == i128::MIN {
            return None;
        }
        Some(Rational { num: n, den: d })
    }

    /// The integer `n`, or `None` for `i128::MIN` (see [`Rational`]).
    fn checked_int(n: i128) -> Option<Rational> {
        (n != i128::MIN).then_some(Rational { num: n, den: 1 })
    }

    /// The integer `n`.
    ///
    /// # Panics
    ///
    /// For `i128::MIN` (see [`Rational`]).
    pub const fn int(n: i128) -> Rational {
        assert!(n != i128::MIN, "i128::MIN is not an exact number here");
        Rational { num: n, den: 1 }
    }

    /// Numerator (carries the sign).
    pub fn numer(self) -> i128 {
        self.num
    }

    /// Denominator (positive).
    pub fn denom(self) -> i128 {
        self.den
    }

    /// True when the denominator is one.
    pub fn is_integer(self) -> bool {
        self.den == 1
    }

    /// True for zero.
    pub fn is_zero(self) -> bool {
        self.num == 0
    }

    /// True for one.
    pub fn is_one(self) -> bool {
        self.num == 1 && self.den == 1
    }

    /// True when negative.
    pub fn is_negative(self) -> bool {
        self.num < 0
    }

    /// The nearest f64.
    pub fn to_f64(self) -> f64 {
        self.num as f64 / self.den as f64
    }

    /// Checked sum.
    pub fn checked_add(self, o: Rational) -> Option<Rational> {
        // Integers (the common case) need no gcd: i128 division is slow.
        if self.den == 1 && o.den == 1 {
            return Rational::checked_int(self.num.checked_add(o.num)?);
        }
        let g = gcd(self.den, o.den)?;
        let a = self.num.checked_mul(o.den / g)?;
        let b = o.num.checked_mul(self.den / g)?;
        Rational::new(a.checked_add(b)?, self.den.checked_mul(o.den / g)?)
    }

    /// Checked product.
    pub fn checked_mul(self, o: Rational) -> Option<Rational> {
        if self.den == 1 && o.den == 1 {
            return Rational::checked_int(self.num.checked_mul(o.num)?);
        }
        let g1 = gcd(self.num, o.den)?.max(1);
        let g2 = gcd(o.num, self.den)?.max(1);
        let n = (self.num / g1).checked_mul(o.num / g2)?;
        let d = (self.den / g2).checked_mul(o.den / g1)?;
        Rational::new(n, d)
    }

    /// Checked negation.
    pub fn checked_neg(self) -> Option<Rational> {
        Some(Rational { num: self.num.checked_neg()?, den: self.den })
    }

    /// Checked reciprocal; `None` for zero.
    pub fn recip(self) -> Option<Rational> {
        Rational::new(self.den, self.num)
    }

    /// Checked integer power; `None` on overflow or `0^negative`.
    pub fn pow(self, e: i64) -> Option<Rational> {
        let base = if e < 0 { self.recip()? } else { self };
        let e = u32::try_from(e.unsigned_abs()).ok()?;
        Rational::new(base.num.checked_pow(e)?, base.den.checked_pow(e)?)
    }

    /// The exact root `self^(1/n)` when it is rational (`4^(1/2) = 2`).
    pub fn exact_root(self, n: u32) -> Option<Rational> {
        if n == 0 || (self.num < 0 && n.is_multiple_of(2)) {
            return None;
        }
        let root = |v: i128| -> Option<i128> {
            let guess = (v.unsigned_abs() as f64).powf(1.0 / n as f64).round() as i128;
            (guess.saturating_sub(1)..=guess + 1).find(|c| c.checked_pow(n) == Some(v.abs())).map(|c| {
                if v < 0 {
                    -c
                } else {
                    c
                }
            })
        };
        Rational::new(root(self.num)?, root(self.den)?)
    }
}

impl PartialOrd for Rational {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Rational {
    fn cmp(&self, other: &Self) -> Ordering {
        match (self.num.checked_mul(other.den), other.num.checked_mul(self.den)) {
            (Some(a), Some(b)) => a.cmp(&b),
            _ => self.to_f64().total_cmp(&other.to_f64()),
        }
    }
}

impl fmt::Display for Rational {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.den == 1 {
            write!(f, "{}", self.num)
        } else {
            write!(f, "{}/{}", self.num, self.den)
        }
    }
}

/// A float sum smaller than this times the sum of its terms' sizes is round-off
/// (a few ulps of each term, as floats that came out of a few operations carry)
/// and is taken as 0.
pub const CANCELLATION: f64 = 16.0 * f64::EPSILON;

/// A numeric constant: exact, or a floating-point value from the input.
#[derive(Clone, Copy, Debug)]
pub enum Number {
    /// An exact rational.
    Rational(Rational),
    /// A finite f64 (never NaN; `-0.0` is stored as `0.0`).
    Float(f64),
}

impl PartialEq for Number {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Number::Rational(a), Number::Rational(b)) => a == b,
            (Number::Float(a), Number::Float(b)) => a.to_bits() == b.to_bits(),
            _ => false,
        }
    }
}

impl Eq for Number {}

impl std::hash::Hash for Number {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        match self {
            Number::Rational(r) => r.hash(state),
            Number::Float(x) => x.to_bits().hash(state),
        }
    }
}

impl Number {
    /// Zero, exactly.
    pub const ZERO: Number = Number::Rational(Rational::ZERO);
    /// One, exactly.
    pub const ONE: Number = Number::Rational(Rational::ONE);
    /// Minus one, exactly.
    pub const MINUS_ONE: Number = Number::Rational(Rational::MINUS_ONE);

    /// A float constant, normalized (`-0.0` becomes `0.0`); integral floats stay floats.
    pub fn float(x: f64) -> Number {
        Number::Float(if x == 0.0 { 0.0 } else { x })
    }

    /// The value as f64.
    pub fn to_f64(self) -> f64 {
        match self {
            Number::Rational(r) => r.to_f64(),
            Number::Float(x) => x,
        }
    }

    /// True for an exact or floating zero.
    pub fn is_zero(self) -> bool {
        match self {
            Number::Rational(r) => r.is_zero(),
            Number::Float(x) => x == 0.0,
        }
    }

    /// True for exact one (a float 1.0 is kept as a float on purpose).
    pub fn is_one(self) -> bool {
        matches!(self, Number::Rational(r) if r.is_one())
    }

    /// True when negative.
    pub fn is_negative(self) -> bool {
        match self {
            Number::Rational(r) => r.is_negative(),
            Number::Float(x) => x < 0.0,
        }
    }

    /// The exact rational, if this is one.
    pub fn as_rational(self) -> Option<Rational> {
        match self {
            Number::Rational(r) => Some(r),
            Number::Float(_) => None,
        }
    }

    /// Sum: exact when both are exact and it fits, float otherwise.
    pub fn plus(self, o: Number) -> Number {
        match (self, o) {
            (Number::Rational(a), Number::Rational(b)) => {
                a.checked_add(b).map(Number::Rational).unwrap_or_else(|| Number::float(a.to_f64() + b.to_f64()))
            }
            _ => {
                let (a, b) = (self.to_f64(), o.to_f64());
                let sum = a + b;
                // Terms that cancel to within their own rounding (0.1*3 − 0.3 is
                // 5.6e-17) leave no digit of information: the sum is 0, not a
                // residue that would decide a verdict.
                if sum.abs() <= CANCELLATION * (a.abs() + b.abs()) {
                    Number::ZERO
                } else {
                    Number::float(sum)
                }
            }
        }
    }

    /// Product: exact when both are exact and it fits, float otherwise.
    pub fn times(self, o: Number) -> Number {
        match (self, o) {
            (Number::Rational(a), Number::Rational(b)) => {
                a.checked_mul(b).map(Number::Rational).unwrap_or_else(|| Number::float(a.to_f64() * b.to_f64()))
            }
            _ => Number::float(self.to_f64() * o.to_f64()),
        }
    }

    /// Negation.
    pub fn negated(self) -> Number {
        self.times(Number::MINUS_ONE)
    }

    /// Absolute value.
    pub fn abs(self) -> Number {
        if self.is_negative() {
            self.negated()
        } else {
            self
        }
    }
}

impl fmt::Display for Number {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Number::Rational(r) => r.fmt(f),
            Number::Float(x) => {
                // Shortest text that reads back to the same f64, always with a
                // decimal point or exponent so it stays a float when parsed.
                let s = format!("{x:?}");
                f.write_str(&s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rational_arithmetic_is_exact_and_reduced() {
        let half = Rational::new(1, 2).unwrap();
        let third = Rational::new(2, 6).unwrap();
        assert_eq!(third, Rational::new(1, 3).unwrap());
        assert_eq!(half.checked_add(third).unwrap(), Rational::new(5, 6).unwrap());
        assert_eq!(half.checked_mul(third).unwrap(), Rational::new(1, 6).unwrap());
        assert_eq!(Rational::new(3, -6).unwrap(), Rational::new(-1, 2).unwrap());
        assert_eq!(Rational::new(2, 3).unwrap().pow(-2).unwrap(), Rational::new(9, 4).unwrap());
        assert_eq!(Rational::new(9, 4).unwrap().exact_root(2), Rational::new(3, 2));
        assert_eq!(Rational::int(2).exact_root(2), None);
        assert!(Rational::new(1, 0).is_none());
        assert!(Rational::ZERO.pow(-1).is_none());
    }

    #[test]
    fn float_sums_that_cancel_to_round_off_are_zero() {
        let (a, b) = (Number::float(0.1).times(Number::Rational(Rational::int(3))), Number::float(-0.3));
        assert_ne!(a.to_f64() + b.to_f64(), 0.0, "the f64 sum leaves a residue");
        assert!(a.plus(b).is_zero());
        // A small difference that is not round-off stays.
        let d = Number::float(1.0 + 1e-12).plus(Number::float(-1.0));
        assert!((d.to_f64() - 1e-12).abs() < 1e-15);
        // Exact rationals are untouched by the rule.
        let third = Number::Rational(Rational::new(1, 3).unwrap());
        assert!(third.plus(third.negated()).is_zero());
        assert_eq!(third.plus(third), Number::Rational(Rational::new(2, 3).unwrap()));
    }

    #[test]
    fn overflow_is_reported_not_wrapped() {
        // i128::MIN counts as an overflow, so negation stays exact.
        assert!(Rational::int(-2).pow(127).is_none());
        assert!(Rational::int(-2).pow(-127).is_none());
        assert!(Rational::new(i128::MIN, 1).is_none());
        assert!(Rational::int(i128::MIN + 1).checked_add(Rational::int(-1)).is_none());
        assert!(Rational::int(-(1 << 64)).checked_mul(Rational::int(1 << 63)).is_none());
        assert_eq!(Rational::int(-2).pow(126).map(|r| r.numer()), Some(1 << 126));
        let big = Rational::int(i128::MAX / 2);
        assert!(big.checked_mul(Rational::int(3)).is_none());
        assert!(Rational::int(2).pow(200).is_none());
        let n = Number::Rational(big).times(Number::Rational(Rational::int(3)));
        assert!(matches!(n, Number::Float(_)));
    }
}
