//! Numbers in the CSV output as `f64`'s `Display` writes them (the shortest
//! digits that read back to the same number, laid out without an exponent),
//! in half the time (about 40 against 90 ns a number).
//!
//! A 1001-row trajectory is about 6000 numbers; through `Display` they cost
//! half a millisecond, a twentieth of a whole double-pendulum run. Ryu finds
//! the same shortest digits (both pick, among the shortest strings that read
//! back, the one nearest the number; at an exact tie Ryu takes the even last
//! digit, `Display` the upper one), but writes them as `1e-7` or `2.0`; here
//! its digits are laid out as `Display` lays them out (`0.0000001`, `2`).

/// Appends `v` to `out` as `format!("{v}")` would.
pub(crate) fn push_f64(out: &mut Vec<u8>, v: f64) {
    if !v.is_finite() || v == 0.0 {
        // NaN, inf, -inf, 0 and -0: rare, and `Display` is the definition.
        use std::io::Write;
        let _ = write!(out, "{v}");
        return;
    }
    let mut buffer = ryu::Buffer::new();
    let text = buffer.format_finite(v).as_bytes();
    if !text.contains(&b'e') {
        // From 1e-5 to 1e16 Ryu lays the digits out as `Display` does, but
        // for the `.0` it adds to whole numbers.
        out.extend_from_slice(text.strip_suffix(b".0").unwrap_or(text));
        return;
    }
    let (negative, text) = match text.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, text),
    };
    // Ryu writes `d.ddde±x` or `de±x`: collect the digits and where the
    // decimal point falls among them.
    let (mantissa, exponent) = match text.iter().position(|&c| c == b'e') {
        Some(e) => (&text[..e], parse_exponent(&text[e + 1..])),
        None => (text, 0),
    };
    let mut digits = [0u8; 40];
    let mut len = 0;
    let mut before_point = None;
    for &c in mantissa {
        if c == b'.' {
            before_point = Some(len);
        } else {
            digits[len] = c;
            len += 1;
        }
    }
    // The value is 0.d₁d₂…dₙ × 10^point.
    let mut point = before_point.unwrap_or(len) as i32 + exponent;
    let mut digits = &digits[..len];
    while let Some((b'0', rest)) = digits.split_first() {
        digits = rest;
        point -= 1;
    }
    while let Some((b'0', rest)) = digits.split_last() {
        digits = rest;
    }
    if negative {
        out.push(b'-');
    }
    let n = digits.len() as i32;
    if point <= 0 {
        out.extend_from_slice(b"0.");
        out.extend(std::iter::repeat_n(b'0', (-point) as usize));
        out.extend_from_slice(digits);
    } else if point >= n {
        out.extend_from_slice(digits);
        out.extend(std::iter::repeat_n(b'0', (point - n) as usize));
    } else {
        let (int, frac) = digits.split_at(point as usize);
        out.extend_from_slice(int);
        out.push(b'.');
        out.extend_from_slice(frac);
    }
}

/// The decimal exponent after Ryu's `e`: an optional `-`, then digits.
fn parse_exponent(text: &[u8]) -> i32 {
    let (sign, digits) = match text.split_first() {
        Some((b'-', rest)) => (-1, rest),
        _ => (1, text),
    };
    sign * digits.iter().fold(0i32, |e, &d| e * 10 + i32::from(d - b'0'))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(v: f64) -> String {
        let mut out = Vec::new();
        push_f64(&mut out, v);
        String::from_utf8(out).expect("ASCII")
    }

    #[test]
    fn matches_display_on_chosen_values() {
        for v in [
            0.0,
            -0.0,
            1.0,
            -2.0,
            0.1,
            1.5,
            100.0,
            1e-7,
            -1.5e-7,
            1e16,
            1.2345e16,
            1e21,
            1e22,
            123456789.0,
            0.000123,
            std::f64::consts::PI,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            16.024019801570354,
            99.60000000000001,
        ] {
            assert_eq!(text(v), format!("{v}"), "{v:e}");
        }
    }

    /// Random bit patterns (every exponent) and random values of the sizes a
    /// trajectory has: the same text as `Display`, but for a handful of
    /// 17-digit numbers exactly halfway between two shortest strings, where
    /// Ryu rounds the last digit to even and `Display` up (28 of 200 000);
    /// both read back to the number.
    #[test]
    fn matches_display_on_random_values() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            // xorshift64*
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            state.wrapping_mul(0x2545_F491_4F6C_DD1D)
        };
        let mut ties = 0;
        for i in 0..200_000 {
            let bits = next();
            let v = if i % 2 == 0 {
                f64::from_bits(bits)
            } else {
                // Uniform in ±[1e-6, 1e6).
                let unit = (bits >> 11) as f64 / (1u64 << 53) as f64;
                let sign = if bits & 1 == 0 { 1.0 } else { -1.0 };
                sign * 10f64.powf(unit * 12.0 - 6.0)
            };
            let (ours, display) = (text(v), format!("{v}"));
            if v.is_nan() {
                assert_eq!(ours, display);
                continue;
            }
            assert_eq!(ours.parse::<f64>().ok(), Some(v), "{ours} does not read back as {display}");
            if ours != display {
                // A tie between two shortest strings, broken the other way.
                ties += 1;
                assert_eq!(ours.len(), display.len(), "{ours} against {display}");
                assert_eq!(ours[..ours.len() - 1], display[..display.len() - 1], "{ours} against {display}");
            }
        }
        assert!(ties < 100, "{ties} differences in the last digit");
    }
}
