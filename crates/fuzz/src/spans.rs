//! The span rule every error of the library must keep: a byte range inside
//! the text it points into, on character boundaries. Enter with [`check_span`]
//! and [`check_model_error`].

use mech::ModelError;
use std::ops::Range;

/// Why `span` is not a valid place in `text`, if it is not.
pub fn check_span(text: &str, span: &Range<usize>) -> Result<(), String> {
    if span.start > span.end {
        return Err(format!("span {span:?} is reversed"));
    }
    if span.end > text.len() {
        return Err(format!("span {span:?} ends past the text ({} bytes)", text.len()));
    }
    if !text.is_char_boundary(span.start) || !text.is_char_boundary(span.end) {
        return Err(format!("span {span:?} cuts a character"));
    }
    Ok(())
}

/// Checks the span of a model error, and of the error inside a nested file.
pub fn check_model_error(text: &str, err: &ModelError) -> Result<(), String> {
    if let Some(span) = &err.span {
        check_span(text, span).map_err(|e| format!("{e} (error: {})", err.message))?;
    }
    if let Some(within) = &err.within {
        check_model_error(&within.text, &within.error)
            .map_err(|e| format!("in the {} {}: {e}", within.what, within.name))?;
    }
    Ok(())
}

/// A short, stable description of an error's kind for the novelty signal: its
/// message up to the first quote or digit (names and numbers vary).
pub fn signature_of(message: &str) -> String {
    let cut = message.find(|c: char| matches!(c, '\'' | '`' | '"') || c.is_ascii_digit()).unwrap_or(message.len());
    message[..cut].chars().take(60).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_inside_the_text_on_boundaries_pass_and_others_fail() {
        assert!(check_span("aé", &(0..1)).is_ok());
        assert!(check_span("aé", &(3..3)).is_ok());
        assert!(check_span("aé", &(2..3)).is_err());
        assert!(check_span("aé", &(1..4)).is_err());
        #[allow(clippy::reversed_empty_ranges)]
        let reversed = 2..1;
        assert!(check_span("abc", &reversed).is_err());
        assert_eq!(signature_of("unknown name 'x' at 3"), "unknown name ");
    }
}
