//! Where a browser ends each `<script>` element of a page: a small model of
//! the HTML tokenizer's script data states (WHATWG HTML, 13.2.5.4–13.2.5.23),
//! enough to tell whether text put inside a script element stays there.
//! Enter with [`scripts`].
//!
//! Outside scripts it follows the data state far enough to skip comments,
//! the text of `<title>`/`<textarea>` (RCDATA) and `<style>` (RAWTEXT), and
//! to read a start tag's attributes with their quotes. Inside a script it
//! walks the states (script data, escaped after `<!--`, double escaped after a
//! further `<script`) and ends the element at the first appropriate end tag
//! `</script` followed by whitespace, `/` or `>` in the states where that ends it.

use std::ops::Range;

/// One script element as the tokenizer sees it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Script {
    /// Its start tag, `<script ...>`.
    pub tag: String,
    /// Its content, the bytes between the start tag and the end tag.
    pub content: Range<usize>,
    /// Whether some `<!--` in it entered the double-escaped state (a
    /// `<script` after it), where `</script>` no longer ends the element.
    pub double_escaped: bool,
}

/// The script elements of `page` in order; an error for a script element
/// that the end of the page cuts off (its end tag never seen).
pub fn scripts(page: &str) -> Result<Vec<Script>, String> {
    let bytes = page.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(lt) = find(bytes, i, b"<") {
        i = lt + 1;
        if bytes[i..].starts_with(b"!--") {
            // A comment: to the next `-->` (or the end of the page).
            i = find(bytes, i + 3, b"-->").map_or(bytes.len(), |e| e + 3);
            continue;
        }
        let name_len = bytes[i..].iter().take_while(|b| b.is_ascii_alphanumeric()).count();
        if name_len == 0 || !bytes[i].is_ascii_alphabetic() {
            continue;
        }
        let name = page[i..i + name_len].to_ascii_lowercase();
        let tag_end =
            end_of_tag(bytes, i + name_len).ok_or_else(|| format!("the tag <{name} at byte {lt} is not closed"))?;
        i = tag_end;
        match name.as_str() {
            "script" => {
                let (end, double_escaped) =
                    script_end(bytes, tag_end).ok_or_else(|| format!("the script at byte {lt} is never closed"))?;
                out.push(Script { tag: page[lt..tag_end].to_string(), content: tag_end..end, double_escaped });
                i = end;
            }
            "title" | "textarea" | "style" => {
                // RCDATA and RAWTEXT end at their own end tag only.
                let mut at = tag_end;
                loop {
                    let Some(p) = find(bytes, at, b"</") else {
                        return Err(format!("the <{name}> at byte {lt} is never closed"));
                    };
                    if ends_element(bytes, p + 2, &name) {
                        i = p;
                        break;
                    }
                    at = p + 2;
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

/// The first `needle` at or after `from`.
fn find(hay: &[u8], from: usize, needle: &[u8]) -> Option<usize> {
    hay.get(from..)?.windows(needle.len()).position(|w| w == needle).map(|p| p + from)
}

/// The byte after the `>` of a tag whose name ends at `from`, reading
/// attribute values in quotes.
fn end_of_tag(bytes: &[u8], from: usize) -> Option<usize> {
    let mut quote = None;
    for (k, &b) in bytes.iter().enumerate().skip(from) {
        match (quote, b) {
            (Some(q), _) if b == q => quote = None,
            (Some(_), _) => {}
            (None, b'"' | b'\'') => quote = Some(b),
            (None, b'>') => return Some(k + 1),
            _ => {}
        }
    }
    None
}

/// Whether the text at `at` (just after `</`) is an end tag named `name`
/// that ends the element: the name (any case), then whitespace, `/` or `>`.
fn ends_element(bytes: &[u8], at: usize, name: &str) -> bool {
    let end = at + name.len();
    end < bytes.len()
        && bytes[at..end].eq_ignore_ascii_case(name.as_bytes())
        && matches!(bytes[end], b'\t' | b'\n' | b'\x0c' | b' ' | b'/' | b'>')
}

/// The tokenizer's states inside a script element.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum State {
    Data,
    Escaped,
    EscapedDash,
    EscapedDashDash,
    DoubleEscaped,
    DoubleEscapedDash,
    DoubleEscapedDashDash,
}

/// Where the script whose content starts at `from` ends (the `<` of its end
/// tag) and whether it went through the double-escaped state; None when the
/// page ends first.
fn script_end(bytes: &[u8], from: usize) -> Option<(usize, bool)> {
    use State::*;
    let mut state = Data;
    let mut double = false;
    let mut i = from;
    while i < bytes.len() {
        let b = bytes[i];
        match state {
            Data | Escaped | EscapedDash | EscapedDashDash if b == b'<' => {
                let rest = &bytes[i + 1..];
                if rest.first() == Some(&b'/') && ends_element(bytes, i + 2, "script") {
                    return Some((i, double));
                }
                if state == Data {
                    // The script data escape start: `<!--` (the `<!` then two dashes).
                    if rest.starts_with(b"!--") {
                        state = EscapedDashDash;
                        i += 4;
                        continue;
                    }
                } else if rest.first().is_some_and(u8::is_ascii_alphabetic) {
                    // Script data double escape start: `<script` then whitespace, `/` or `>`.
                    let len = rest.iter().take_while(|c| c.is_ascii_alphabetic()).count();
                    let after = rest.get(len);
                    if rest[..len].eq_ignore_ascii_case(b"script")
                        && after.is_some_and(|c| matches!(c, b'\t' | b'\n' | b'\x0c' | b' ' | b'/' | b'>'))
                    {
                        state = DoubleEscaped;
                        double = true;
                        i += 1 + len + 1;
                        continue;
                    }
                    state = Escaped;
                    i += 1 + len;
                    continue;
                } else {
                    state = Escaped;
                }
            }
            Data => {}
            Escaped | EscapedDash | EscapedDashDash => {
                state = match (state, b) {
                    (Escaped, b'-') => EscapedDash,
                    (EscapedDash | EscapedDashDash, b'-') => EscapedDashDash,
                    (EscapedDashDash, b'>') => Data,
                    _ => Escaped,
                };
            }
            DoubleEscaped | DoubleEscapedDash | DoubleEscapedDashDash => {
                if b == b'<' {
                    // Double escape end: `</script` then whitespace, `/` or `>`.
                    if bytes.get(i + 1) == Some(&b'/') && ends_element(bytes, i + 2, "script") {
                        state = Escaped;
                        i += 2 + "script".len() + 1;
                        continue;
                    }
                    state = DoubleEscaped;
                } else {
                    state = match (state, b) {
                        (DoubleEscaped, b'-') => DoubleEscapedDash,
                        (DoubleEscapedDash | DoubleEscapedDashDash, b'-') => DoubleEscapedDashDash,
                        (DoubleEscapedDashDash, b'>') => Data,
                        _ => DoubleEscaped,
                    };
                }
            }
        }
        i += 1;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The contents of the page's scripts, and whether each was double escaped.
    #[track_caller]
    fn check(page: &str, expect: &[(&str, bool)]) {
        let got: Vec<(&str, bool)> =
            scripts(page).unwrap().iter().map(|s| (&page[s.content.clone()], s.double_escaped)).collect();
        assert_eq!(got, expect, "{page}");
    }

    #[test]
    fn scripts_end_where_a_browser_ends_them() {
        check("<p>a</p><script>x</script>", &[("x", false)]);
        check("<script type=\"a>b\">x</SCRIPT >y", &[("x", false)]);
        check("<script>a</scripty></script>", &[("a</scripty>", false)]);
        check("<script>a<!--b</script>c", &[("a<!--b", false)]);
        check("<script>a<!--<script>b</script>c</script>d", &[("a<!--<script>b</script>c", true)]);
        check("<script>a<!--<script>b-->c</script>", &[("a<!--<script>b-->c", true)]);
        check("<script><!-- --><script>x</script>", &[("<!-- --><script>x", false)]);
        check("<script>a<!--<scripts>b</script>", &[("a<!--<scripts>b", false)]);
        check("<!-- <script>x</script> --><title></script><script></title><script>y</script>", &[("y", false)]);
        check("<style>a</style><script>\"</script>\"</script>", &[("\"", false)]);
        assert!(scripts("<script>a<!--<script>b</script>c").is_err());
        assert!(scripts("<script>a").is_err());
    }
}
