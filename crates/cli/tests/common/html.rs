//! The `<script>` elements of a page as a browser's HTML tokenizer splits
//! them: the script data states of the HTML standard (§13.2.5.4 ff.), where an
//! element's content ends at the first `</script` followed by a space, `/` or
//! `>`, unless a `<!--` and then a `<script` put the tokenizer in the
//! double-escaped state, in which that end tag no longer ends the element.
//! Enough of the tokenizer to tell whether a page's scripts are the ones it
//! was written with; comments and attributes outside scripts are skipped as
//! the page's own markup needs.

/// Whether `s` starts with `tag` (ASCII, any case) followed by a character
/// that ends a tag name.
fn tag_at(s: &[u8], tag: &[u8]) -> bool {
    s.len() > tag.len()
        && s[..tag.len()].eq_ignore_ascii_case(tag)
        && matches!(s[tag.len()], b' ' | b'\t' | b'\n' | b'\x0c' | b'\r' | b'/' | b'>')
}

#[derive(Clone, Copy, PartialEq)]
enum State {
    Data,
    Escaped,
    DoubleEscaped,
}

/// The content of each `<script>` element of `html`, in order; `None` when a
/// script element is never closed (the rest of the page was swallowed).
pub fn scripts(html: &str) -> Option<Vec<String>> {
    let b = html.as_bytes();
    let mut found = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"<!--") {
            i = html[i + 4..].find("-->").map_or(b.len(), |e| i + 4 + e + 3);
            continue;
        }
        if !(b[i] == b'<' && tag_at(&b[i + 1..], b"script")) {
            i += 1;
            continue;
        }
        // The start tag's end (the page's attributes hold no `>`).
        let open = i + html[i..].find('>')? + 1;
        let (mut state, mut k) = (State::Data, open);
        let close = loop {
            if k >= b.len() {
                return None;
            }
            let rest = &b[k..];
            match state {
                State::Data | State::Escaped if rest.starts_with(b"</") && tag_at(&rest[2..], b"script") => break k,
                State::Data if rest.starts_with(b"<!--") => {
                    // `<!-->` and `<!--->` close at once (escape start dash states).
                    state = State::Escaped;
                    k += 4;
                    if b.get(k) == Some(&b'>') {
                        state = State::Data;
                    }
                    continue;
                }
                State::Escaped | State::DoubleEscaped if rest.starts_with(b"-->") => {
                    state = State::Data;
                    k += 3;
                    continue;
                }
                State::Escaped if rest[0] == b'<' && tag_at(&rest[1..], b"script") => {
                    state = State::DoubleEscaped;
                    k += 7;
                    continue;
                }
                State::DoubleEscaped if rest.starts_with(b"</") && tag_at(&rest[2..], b"script") => {
                    state = State::Escaped;
                    k += 8;
                    continue;
                }
                _ => k += 1,
            }
        };
        found.push(html[open..close].to_string());
        i = close + html[close..].find('>')? + 1;
    }
    Some(found)
}
