//! Errors as the editor shows them: a `lagrange.error/1` JSON value with the
//! message, the hint, and where (the line and column of the start and end, as
//! the CLI prints them, and the same range in UTF-16 code units, which is how
//! JavaScript indexes the editor's text). An error inside a file the model
//! names (a body file) is located in that file, which `file` names.

use serde_json::{json, Value};
use std::ops::Range;

/// The format of an error value.
pub const ERROR_FORMAT: &str = "lagrange.error/1";

/// A place in a text: 1-based line and column (in characters), and the
/// 0-based offset in UTF-16 code units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Place {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1, counted in characters.
    pub column: usize,
    /// Offset from the start of the text in UTF-16 code units.
    pub utf16: usize,
}

/// The place of byte `offset` of `text` (clamped to the text, and back to the
/// start of a character).
pub fn place(text: &str, offset: usize) -> Place {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    Place {
        line: before.matches('\n').count() + 1,
        column: before[line_start..].chars().count() + 1,
        utf16: before.encode_utf16().count(),
    }
}

/// A model error (`mech::ModelError`) located in `source`.
pub fn model_error(source: &str, e: &mech::ModelError) -> Value {
    let mut v = match &e.within {
        Some(w) => {
            let mut v = error(&e.message, e.help.as_deref(), w.error.span.clone().map(|s| (w.text.as_str(), s)));
            v["file"] = json!(w.name);
            v["inner"] = json!(w.error.message);
            v
        }
        None => error(&e.message, e.help.as_deref(), e.span.clone().map(|s| (source, s))),
    };
    v["kind"] = json!(e.kind.code());
    v
}

/// An error value: `message`, optional `help`, and where in which text.
pub fn error(message: &str, help: Option<&str>, at: Option<(&str, Range<usize>)>) -> Value {
    let mut v = json!({"format": ERROR_FORMAT, "message": message, "help": help});
    if let Some((text, span)) = at {
        let (start, end) = (place(text, span.start), place(text, span.end.max(span.start)));
        v["line"] = json!(start.line);
        v["column"] = json!(start.column);
        v["end_line"] = json!(end.line);
        v["end_column"] = json!(end.column);
        v["start"] = json!(start.utf16);
        v["end"] = json!(end.utf16);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_count_lines_and_characters_from_one_and_utf16_units_from_zero() {
        let text = "a = 1\nθ = \"x +\"\n𝑥 = 2";
        assert_eq!(place(text, 0), Place { line: 1, column: 1, utf16: 0 });
        let plus = text.find('+').unwrap();
        // θ is one character (two bytes, one UTF-16 unit).
        assert_eq!(place(text, plus), Place { line: 2, column: 8, utf16: 13 });
        // 𝑥 is one character, two UTF-16 units.
        let two = text.find('2').unwrap();
        assert_eq!(place(text, two), Place { line: 3, column: 5, utf16: 21 });
        assert_eq!(&text.encode_utf16().collect::<Vec<_>>()[21..22], &"2".encode_utf16().collect::<Vec<_>>()[..]);
        // Past the end, or inside a character: clamped back.
        assert_eq!(place(text, 999).line, 3);
        assert_eq!(place(text, text.find('θ').unwrap() + 1).column, 1);
    }
}
