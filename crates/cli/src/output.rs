//! What the analyses' outputs share: the `--format` of `modes`, `orbit`, `top`,
//! `inertia` and `extremal`, and numbers written for people.

/// Output formats of the analyses.
#[derive(Clone, Copy, clap::ValueEnum, PartialEq)]
pub enum ReportFormat {
    /// Text that reads like the lecture notes.
    Text,
    /// JSON (`lagrange.modes/1`, `lagrange.orbit/1`, ...).
    Json,
}

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
