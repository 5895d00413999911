//! Text put into HTML, SVG and MathML: the one place that escapes it (the
//! report's page, the modes' SVG and the typeset derivation all call it).

/// Text as element content: `&`, `<` and `>` as entities, so that no name
/// a model gives (`<b>`, `&amp;`) becomes markup.
pub(crate) fn text(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Text that may also stand in a quoted attribute: as [`text`], and `"` as an
/// entity too.
pub(crate) fn quoted(s: &str) -> String {
    text(s).replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_in_names_stays_text() {
        assert_eq!(text("a < b && c > \"d\""), "a &lt; b &amp;&amp; c &gt; \"d\"");
        assert_eq!(quoted("<b class=\"x\">&amp;</b>"), "&lt;b class=&quot;x&quot;&gt;&amp;amp;&lt;/b&gt;");
    }
}
