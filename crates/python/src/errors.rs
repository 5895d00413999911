//! Errors as Python exceptions: a `mech::ModelError` becomes
//! `lagrange.ModelError` with the file, line, column, message, hint and the
//! caret snippet the CLI would print (plain text, no colour).
//!
//! The exception classes are defined in Python (`lagrange/errors.py`, with
//! their docstrings); this module looks them up and fills them in.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::ops::Range;

/// Where an error is: a file's name and text, and a byte span into it.
pub struct Place<'a> {
    /// The file's name as the user gave it (`<string>` for text).
    pub file: &'a str,
    /// Its text, which spans point into.
    pub text: &'a str,
}

/// A `lagrange.ModelError` for an error in the file at `place`.
pub fn model_error(py: Python<'_>, place: &Place<'_>, e: &mech::ModelError) -> PyErr {
    if let Some(w) = &e.within {
        // The error is in a file the model names (a body file): locate it there.
        let inner = Place { file: &w.name, text: &w.text };
        let message = format!("in the {} {}: {}", w.what, w.name, w.error.message);
        return located(py, &inner, &message, w.error.span.clone(), w.error.help.as_deref(), e.kind);
    }
    let message = match &e.setting {
        Some(mech::Setting::Parameter { name }) => format!("set[{name:?}]: {}", e.message),
        Some(mech::Setting::Start { name }) => format!("at[{name:?}]: {}", e.message),
        None => e.message.clone(),
    };
    located(py, place, &message, e.span.clone(), e.help.as_deref(), e.kind)
}

/// A `lagrange.ModelError` with no place in a file (a setting, an option).
pub fn plain_error(py: Python<'_>, file: &str, message: &str, help: Option<&str>) -> PyErr {
    located(py, &Place { file, text: "" }, message, None, help, mech::ModelErrorKind::Invalid)
}

/// A `lagrange.ModelError` about an expression the caller passed (`what` names it).
pub fn expression_error(py: Python<'_>, what: &str, text: &str, e: &mech::ModelError) -> PyErr {
    located(py, &Place { file: what, text }, &e.message, e.span.clone(), e.help.as_deref(), e.kind)
}

fn located(
    py: Python<'_>,
    place: &Place<'_>,
    message: &str,
    span: Option<Range<usize>>,
    help: Option<&str>,
    kind: mech::ModelErrorKind,
) -> PyErr {
    let (line, column, snippet) = match span {
        Some(span) => {
            let span = clamp(span, place.text);
            let (line, column) = line_col(place.text, span.start);
            (Some(line), Some(column), snippet(place.text, span, line, column))
        }
        None => (None, None, String::new()),
    };
    let mut full = match (line, column) {
        (Some(l), Some(c)) => format!("{}:{l}:{c}: {message}", place.file),
        _ => format!("{}: {message}", place.file),
    };
    if !snippet.is_empty() {
        full.push('\n');
        full.push_str(&snippet);
    }
    if let Some(h) = help {
        full.push_str(&format!("\nhelp: {h}"));
    }
    raise(py, "ModelError", |kw| {
        kw.set_item("message", message)?;
        kw.set_item("file", place.file)?;
        kw.set_item("line", line)?;
        kw.set_item("column", column)?;
        kw.set_item("help", help)?;
        kw.set_item("snippet", &snippet)?;
        kw.set_item("kind", kind.code())?;
        kw.set_item("text", &full)
    })
}

/// Instantiates `lagrange.errors.NAME(**kwargs)`.
pub fn raise(py: Python<'_>, name: &str, fill: impl FnOnce(&Bound<'_, PyDict>) -> PyResult<()>) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let class = py.import("lagrange.errors")?.getattr(name)?;
        let kw = PyDict::new(py);
        fill(&kw)?;
        Ok(PyErr::from_value(class.call((), Some(&kw))?))
    };
    build().unwrap_or_else(|e| e)
}

/// A `lagrange.LagrangeError` with `message` (the base class, which takes
/// its message alone: for failures that are no model's, file's or run's).
pub fn lagrange_error(py: Python<'_>, message: &str) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let class = py.import("lagrange.errors")?.getattr("LagrangeError")?;
        Ok(PyErr::from_value(class.call1((message,))?))
    };
    build().unwrap_or_else(|e| e)
}

/// A Rust panic caught at an entry point, as a Python error that says so.
pub fn panicked(what: &str, payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let detail = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into());
    PyRuntimeError::new_err(format!("internal error in {what} (please report it): {detail}"))
}

/// Runs `f`, turning a panic into a Python error.
pub fn guarded<T>(what: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|p| Err(panicked(what, p)))
}

/// The 1-based line and column (in characters) of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// A span kept inside the text and on character boundaries.
fn clamp(span: Range<usize>, text: &str) -> Range<usize> {
    let mut start = span.start.min(text.len());
    while !text.is_char_boundary(start) {
        start -= 1;
    }
    let mut end = span.end.clamp(start, text.len());
    while !text.is_char_boundary(end) {
        end += 1;
    }
    start..end
}

/// The line of the span with carets under it:
/// ```text
///  3 | lagrangian = "m*x'^2/2 +"
///    |                        ^
/// ```
fn snippet(text: &str, span: Range<usize>, line: usize, column: usize) -> String {
    let Some(source_line) = text.lines().nth(line - 1) else { return String::new() };
    let width = span.end.saturating_sub(span.start);
    let on_line = text[span.start..span.start + width].split('\n').next().unwrap_or("");
    let carets = on_line.chars().count().max(1);
    let gutter = line.to_string();
    let pad = " ".repeat(gutter.len());
    format!("{pad} |\n{gutter} | {source_line}\n{pad} | {}{}", " ".repeat(column - 1), "^".repeat(carets))
}
