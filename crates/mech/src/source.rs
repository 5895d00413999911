//! Reading the TOML files the library knows — model files, body files and
//! variational problems — with their shared rules: the size limit, names and
//! reserved words, symbol ranks, and where a string's text starts in the file
//! (so that an error inside an expression points at its column).

use crate::error::ModelError;
use std::ops::Range;
use sym::{ExprId, Pool};
use toml::Spanned;

/// Largest model file read, in bytes (hostile input is bounded).
pub const MAX_FILE_BYTES: usize = 1 << 20;

/// Names the expression language reserves.
const RESERVED: &[&str] = &[
    "t", "pi", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "ln",
    "sqrt", "abs",
];

/// The symbol rank of parameters: they print first in products (`m*l^2*q''`).
pub const RANK_PARAMETER: u8 = 0;
/// The symbol rank of the time.
pub const RANK_TIME: u8 = 1;
/// The symbol rank of coordinates, velocities and accelerations.
pub const RANK_COORDINATE: u8 = 2;
/// The symbol rank of momenta.
pub const RANK_MOMENTUM: u8 = 3;

/// A float from the file, kept exact when it is an integer (`2` → 2, `0.5` → 0.5).
pub(crate) fn number_expr(pool: &mut Pool, x: f64) -> ExprId {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        pool.int(x as i64)
    } else {
        pool.float(x)
    }
}

/// Where the text of a TOML string value starts, if its characters map one to
/// one onto the file (no escapes); otherwise errors point at the whole value.
/// Shared by every file the library reads (models, body files, problems).
pub(crate) fn content_offset(source: &str, span: &Range<usize>, value: &str) -> Option<usize> {
    let raw = source.get(span.clone())?;
    for quote in ["\"\"\"", "'''", "\"", "'"] {
        if raw.len() >= 2 * quote.len() && raw.starts_with(quote) && raw.ends_with(quote) {
            let mut start = quote.len();
            let inner = &raw[start..raw.len() - quote.len()];
            let inner = if quote.len() == 3 {
                let trimmed = inner.strip_prefix("\r\n").or_else(|| inner.strip_prefix('\n'));
                if let Some(t) = trimmed {
                    start += inner.len() - t.len();
                    t
                } else {
                    inner
                }
            } else {
                inner
            };
            return (inner == value).then_some(span.start + start);
        }
    }
    None
}

/// A name is letters, digits and '_', starting with a letter or '_'.
pub(crate) fn check_name_shape(name: &Spanned<String>, what: &str) -> Result<(), ModelError> {
    let n = name.get_ref();
    let mut chars = n.chars();
    let ok = matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        return Err(ModelError::at(
            name.span(),
            format!("{what} '{n}' is not a valid name: expected letters, digits and '_', starting with a letter"),
        ));
    }
    Ok(())
}

/// Reads the TOML of a file the library knows (`what`: "model", "body", …),
/// with the size limit, into its raw table; errors carry the TOML span.
pub(crate) fn read_toml<T: serde::de::DeserializeOwned>(source: &str, what: &str) -> Result<T, ModelError> {
    if source.len() > MAX_FILE_BYTES {
        return Err(ModelError::whole(format!(
            "the {what} file is {} bytes; the limit is {MAX_FILE_BYTES}",
            source.len()
        )));
    }
    toml::from_str(source).map_err(|e| {
        let message = e.message().trim().to_string();
        match e.span() {
            Some(span) => {
                let help = primed_key_hint(source, span.start);
                let error = ModelError::at(span, message);
                match help {
                    Some(h) => error.with_help(h),
                    None => error,
                }
            }
            None => ModelError::whole(message),
        }
    })
}

/// A hint for a bare key with a prime (`x' = 0`), which TOML does not allow
/// unquoted: the key as it must be written.
fn primed_key_hint(source: &str, at: usize) -> Option<String> {
    if !source.get(at..)?.starts_with('\'') {
        return None;
    }
    let line_start = source[..at].rfind('\n').map_or(0, |i| i + 1);
    let name = source[line_start..at].trim_start();
    let primes = source[at..].chars().take_while(|&c| c == '\'').count();
    let is_name = !name.is_empty() && name.chars().all(|c| c.is_alphanumeric() || c == '_');
    is_name.then(|| {
        let key = format!("{name}{}", "'".repeat(primes));
        format!("a key with a prime must be quoted: \"{key}\" = ...")
    })
}

pub(crate) fn check_identifier(name: &Spanned<String>, what: &str) -> Result<(), ModelError> {
    check_name_shape(name, what)?;
    let n = name.get_ref();
    if RESERVED.contains(&n.as_str()) {
        return Err(ModelError::at(name.span(), format!("{what} '{n}' uses a reserved name"))
            .with_help("t is the time, pi the constant; function names cannot be symbols"));
    }
    Ok(())
}

/// Name prefixes lagrange makes symbols with: `p_q` the momentum of q,
/// `lambda_c` the multiplier of constraint c. No model name may use them.
const GENERATED_PREFIXES: &[&str] = &["p_", "lambda_"];

/// CSV column names `simulate` makes besides `t` and the coordinates: the
/// invariants, the event column and the constraints' work, exactly; the
/// constraints' forces and residuals by prefix; a body's ω and L by suffix.
const COLUMN_NAMES: &[&str] = &["H", "E", "event", "W_constraints", "omega1", "omega2", "omega3", "L1", "L2", "L3"];
const COLUMN_PREFIXES: &[&str] = &["force_", "residual_"];
const COLUMN_SUFFIXES: &[&str] = &["_omega1", "_omega2", "_omega3", "_L1", "_L2", "_L3"];

/// A model name that would collide with a name lagrange makes: a symbol
/// (`p_x`, `lambda_rod`) for any name, and for a coordinate also an output
/// column (`H`, `force_rod`, `omega1`, ...), so that no output holds two
/// things under one name.
pub(crate) fn check_not_generated(name: &Spanned<String>, what: &str, is_coordinate: bool) -> Result<(), ModelError> {
    let n = name.get_ref();
    let symbol = GENERATED_PREFIXES.iter().find(|p| n.starts_with(*p));
    let column = is_coordinate
        && (COLUMN_NAMES.contains(&n.as_str())
            || COLUMN_PREFIXES.iter().any(|p| n.starts_with(p))
            || COLUMN_SUFFIXES.iter().any(|s| n.ends_with(s)));
    if symbol.is_none() && !column {
        return Ok(());
    }
    let made = match symbol {
        Some(&"p_") => "p_NAME is the momentum of the coordinate NAME",
        Some(_) => "lambda_NAME is the multiplier of the constraint NAME",
        None => "simulate's CSV has columns H, E, event, W_constraints, force_NAME, residual_NAME and a body's omega1..3 and L1..3",
    };
    Err(ModelError::at(name.span(), format!("{what} '{n}' has a name that lagrange makes itself: {made}"))
        .with_help("rename it so that the outputs cannot mix it up with the generated one"))
}

/// A parameter with its numeric value.
#[derive(Debug, Clone)]
pub struct Parameter {
    /// Its name (`g`).
    pub name: String,
    /// Its value (from the file or `--set`).
    pub value: f64,
    /// Where it is declared.
    pub span: Range<usize>,
}
