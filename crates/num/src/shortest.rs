//! A number in messages as the user would write it: [`Shortest`], the
//! shortest digits that read back to the same `f64`, laid out without an
//! exponent between 1e-5 and 1e16 and with one outside (`1e300`, not a 1 and
//! three hundred zeros, which is how `f64`'s `Display` lays it out).

use std::fmt;

/// `f64` shown by its shortest round-trip digits (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shortest(pub f64);

impl fmt::Display for Shortest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v != 0.0 && v.is_finite() && !(1e-5..1e16).contains(&v.abs()) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Shortest;

    #[test]
    fn large_and_small_numbers_take_an_exponent_and_read_back() {
        for (v, text) in [
            (1e300, "1e300"),
            (-2.5e-300, "-2.5e-300"),
            (0.1 + 0.2, "0.30000000000000004"),
            (20.0, "20"),
            (1e15, "1000000000000000"),
            (1e16, "1e16"),
            (1e-5, "0.00001"),
            (0.0, "0"),
            (f64::INFINITY, "inf"),
        ] {
            assert_eq!(Shortest(v).to_string(), text);
            if v.is_finite() {
                assert_eq!(text.parse::<f64>().unwrap(), v);
            }
        }
    }
}
