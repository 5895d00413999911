//! Numbers written for people: [`human`], the form every analysis's text uses.

/// A number for people: up to 10 significant digits, no trailing zeros.
pub fn human(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if v.abs() >= 1e-4 && v.abs() < 1e9 {
        let digits = (9 - v.abs().log10().floor() as i32).clamp(0, 15) as usize;
        let s = format!("{v:.digits$}");
        let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
        if s == "-0" {
            "0".into()
        } else {
            s
        }
    } else {
        format!("{v:.9e}")
    }
}

#[cfg(test)]
mod tests {
    use super::human;

    #[track_caller]
    fn check(v: f64, expect: &str) {
        assert_eq!(human(v), expect, "human({v:e})");
    }

    #[test]
    fn digits_and_exponents() {
        check(0.0, "0");
        check(-0.0, "0");
        check(0.1 + 0.2, "0.3");
        check(2.0, "2");
        check(-1.5, "-1.5");
        check(std::f64::consts::PI, "3.141592654");
        check(123456789.0, "123456789");
        check(1e9, "1.000000000e9");
        check(1.5e-5, "1.500000000e-5");
        check(-4e-5, "-4.000000000e-5");
    }
}
