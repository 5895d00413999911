//! Target (f): the report page (`lagrange report`) on models whose texts are
//! hostile: the model's name (the one free text a model has: every other name
//! is an identifier) made of pieces that end or escape a script, a comment, a
//! CDATA section or a JavaScript string, and identifiers that mean something
//! to HTML or JavaScript (`script`, `lt`, `__proto__`). Enter with
//! [`check_report`] (one model text) or [`ReportTarget`].
//!
//! The page is made as `lagrange report` makes it (derive, a short run kept
//! by `view::report::Recorder`, its data, `view::report::page`) and read with
//! the tokenizer model of [`crate::script_data`]: exactly the template's two
//! scripts, neither double escaped; the data script's text, as a browser ends
//! it, is JSON equal to the data; the main script is followed by the end of
//! the page; the title and heading are text that reads back as the name; the
//! derivation's markup (put in with innerHTML) holds no script or comment.

use crate::rng::Rng;
use crate::run::{FindingKind, Outcome, Target};
use crate::script_data::scripts;
use mech::{Derivation, Model, Output, RunConfig, RunError};
use std::ops::ControlFlow;

/// Pieces of hostile names.
const PIECES: &[&str] = &[
    "</script>",
    "</SCRIPT ",
    "</script/",
    "<script>",
    "<ScRiPt ",
    "<!--",
    "-->",
    "<!--<script>x",
    "]]>",
    "<![CDATA[",
    "\u{2028}",
    "\u{2029}",
    "\"",
    "'",
    "\\",
    "<\\/script>",
    "\\u003c",
    "\\x3c!--",
    "{{data}}",
    "{{script}}",
    "{{title}}",
    "&lt;",
    "&",
    "</title>",
    "</style>",
    "</h1>",
    "<",
    ">",
    "\u{0}",
    "\u{7f}",
    "\u{feff}",
    "\t",
    "\n",
    "é",
    "𝔏",
    "</",
    "-",
    "--!>",
];

/// Identifiers that are names in HTML or JavaScript.
const IDENTIFIERS: &[&str] =
    &["script", "lt", "amp", "quot", "CDATA", "__proto__", "constructor", "toString", "math", "mi", "nbsp", "x"];

/// The models the names go into: `{name}` is the model's name (a TOML
/// string), `{q}`, `{p}` and `{b}` a coordinate, a parameter and a body
/// or constraint name.
const MODELS: &[&str] = &[
    "name = {name}\ncoordinates = [\"{q}\"]\nkinetic = \"{p}*{q}'^2/2\"\npotential = \"{p}*{q}^2/2\"\n\
     [parameters]\n{p} = 1.0\n[initial]\n{q} = 1.0\n\"{q}'\" = 0\n",
    "name = {name}\ncoordinates = [\"{q}\"]\ngravity = \"g\"\n[parameters]\n{p} = 1.0\ng = 9.81\n\
     [[bodies]]\nname = \"{b}\"\nmass = \"{p}\"\ninertia = \"{p}/3\"\nangle = \"{q}\"\n\
     center_of_mass = [\"0\", \"-1/2\"]\n[initial]\n{q} = 0.5\n\"{q}'\" = 0\n",
    "name = {name}\ncoordinates = [\"{q}\", \"y\"]\nlagrangian = \"({q}'^2 + y'^2)/2 - {p}*y\"\n\
     [parameters]\n{p} = 1.0\n[[constraints]]\nname = \"{b}\"\nholonomic = \"{q}^2 + y^2 - 1\"\n\
     [initial]\n{q} = 0.6\ny = -0.8\n\"{q}'\" = 0.8\n\"y'\" = 0.6\n",
];

/// A hostile name: one to five pieces, with letters between some.
fn hostile_name(rng: &mut Rng) -> String {
    let mut name = String::new();
    for _ in 0..1 + rng.below(5) {
        if rng.chance(0.3) {
            let filler: &&str = rng.pick(&["a", "x ", "model", " "]);
            name.push_str(filler);
        }
        let piece: &&str = rng.pick(PIECES);
        name.push_str(piece);
    }
    name
}

/// `s` as a TOML string: basic with escapes, or literal when it can be.
fn toml_string(rng: &mut Rng, s: &str) -> String {
    if !s.contains(['\'', '\n']) && !s.chars().any(|c| c.is_control() && c != '\t') && rng.chance(0.3) {
        return format!("'{s}'");
    }
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if c.is_control() || (c as u32 >= 0x2028 && rng.chance(0.5)) => {
                if (c as u32) > 0xffff {
                    out.push_str(&format!("\\U{:08X}", c as u32))
                } else {
                    out.push_str(&format!("\\u{:04X}", c as u32))
                }
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A model with a hostile name.
pub fn hostile_model(rng: &mut Rng) -> String {
    let name = hostile_name(rng);
    let name = toml_string(rng, &name);
    let pick = |rng: &mut Rng, default: &str| {
        if rng.chance(0.5) {
            rng.pick(IDENTIFIERS).to_string()
        } else {
            default.to_string()
        }
    };
    let q = pick(rng, "q");
    let mut p = pick(rng, "k");
    let mut b = pick(rng, "rod");
    // Names of one model must differ (and `x`/`y` are taken in some models).
    if p == q || p == "x" {
        p = "k".into();
    }
    if b == q || b == p || b == "x" {
        b = "rod".into();
    }
    let q = if q == "x" && rng.chance(0.5) { "q".to_string() } else { q };
    rng.pick(MODELS).replace("{name}", &name).replace("{q}", &q).replace("{p}", &p).replace("{b}", &b)
}

/// The page `lagrange report` writes for the model `text` (a run to t = 1,
/// 21 rows), with its data; the error when the model is refused.
pub fn report_page(text: &str) -> Result<(String, serde_json::Value), String> {
    let d = Model::parse(text, &[]).and_then(Derivation::new).map_err(|e| e.message)?;
    let config = RunConfig { until: 1.0, output: Output::Samples(21), ..RunConfig::default() };
    let mut rows = view::report::Recorder::new();
    let report = match mech::simulate(&d, &config, |row| {
        rows.push(row);
        ControlFlow::Continue(())
    }) {
        Ok(r) => r,
        Err(RunError::Failed { report, .. }) => *report,
        Err(e) => return Err(e.to_string()),
    };
    let names: Vec<String> = d.coordinate_names().iter().map(|s| s.to_string()).collect();
    let timing = view::simulate::Timing { derive_seconds: 0.0, setup_seconds: None };
    let terms = view::Terms {
        step: "--dt",
        start_at: "--at",
        full_output: "--format json",
        animation: "--animate",
        until: "--until",
        method: "--method",
    };
    let summary = view::simulate::summary_json(&report, &names, &timing, None, &terms);
    let data = rows.data(&d, config.until, summary);
    Ok((view::report::page(&data), data))
}

/// Makes the report page of `text` and checks it.
pub fn check_report(text: &str) -> Outcome {
    let (page, data) = match report_page(text) {
        Ok(made) => made,
        Err(why) => return Outcome::fine(format!("refused: {}", crate::spans::signature_of(&why))),
    };
    match check_page(&page, &data) {
        Ok(()) => Outcome::fine("page"),
        Err(why) => Outcome::problem(FindingKind::Page, why),
    }
}

/// Why the page is broken, if it is.
pub fn check_page(page: &str, data: &serde_json::Value) -> Result<(), String> {
    let found = scripts(page)?;
    if let Some(s) = found.iter().find(|s| s.double_escaped) {
        return Err(format!("the script {} enters the double-escaped state", s.tag));
    }
    let [json, main] = found.as_slice() else {
        let tags: Vec<&str> = found.iter().map(|s| s.tag.as_str()).collect();
        return Err(format!("the page has {} script elements, not 2: {tags:?}", found.len()));
    };
    if !json.tag.contains("id=\"lagrange-data\"") {
        return Err(format!("the first script is {}, not the data", json.tag));
    }
    let text = &page[json.content.clone()];
    match serde_json::from_str::<serde_json::Value>(text) {
        Ok(v) if &v == data => {}
        Ok(_) => return Err("the data script reads back as other data".into()),
        Err(e) => return Err(format!("the data script, as a browser ends it, is not JSON: {e}")),
    }
    if page[main.content.clone()].trim().is_empty() {
        return Err("the main script is empty".into());
    }
    let tail = &page[main.content.end..];
    if tail.split_whitespace().collect::<String>() != "</script></body></html>" {
        return Err(format!(
            "the main script is not the end of the page: {:?}",
            tail.chars().take(80).collect::<String>()
        ));
    }
    let name = data["name"].as_str().unwrap_or("lagrange report");
    for (open, close) in [("<title>", "</title>"), ("<h1 id=\"model-name\">", "</h1>")] {
        let start = page.find(open).ok_or_else(|| format!("no {open}"))? + open.len();
        let end = page[start..].find(close).ok_or_else(|| format!("{open} never ends"))? + start;
        let raw = &page[start..end];
        if raw.contains('<') {
            return Err(format!("{open} holds markup: {raw:?}"));
        }
        if decode(raw) != name {
            return Err(format!("{open} reads {:?}, not the name {name:?}", decode(raw)));
        }
    }
    let derivation = data["derivation"].as_str().unwrap_or("").to_ascii_lowercase();
    if derivation.contains("<script") || derivation.contains("<!--") {
        return Err("the derivation's markup holds a script or a comment".into());
    }
    Ok(())
}

/// Text with its character references read (the five a page needs and numeric ones).
fn decode(raw: &str) -> String {
    let mut out = String::new();
    let mut rest = raw;
    while let Some(amp) = rest.find('&') {
        out.push_str(&rest[..amp]);
        rest = &rest[amp..];
        let Some(semi) = rest.find(';') else { break };
        let entity = &rest[1..semi];
        let c = match entity {
            "lt" => Some('<'),
            "gt" => Some('>'),
            "amp" => Some('&'),
            "quot" => Some('"'),
            "apos" => Some('\''),
            _ => entity
                .strip_prefix("#x")
                .and_then(|h| u32::from_str_radix(h, 16).ok())
                .or_else(|| entity.strip_prefix('#').and_then(|d| d.parse().ok()))
                .and_then(char::from_u32),
        };
        match c {
            Some(c) => {
                out.push(c);
                rest = &rest[semi + 1..];
            }
            None => {
                out.push('&');
                rest = &rest[1..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// The report page on models with hostile names.
#[derive(Default)]
pub struct ReportTarget;

impl Target for ReportTarget {
    fn name(&self) -> &'static str {
        "report"
    }

    fn input(&mut self, rng: &mut Rng) -> String {
        hostile_model(rng)
    }

    fn check(&mut self, input: &str) -> Outcome {
        check_report(input)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_models_load_and_a_broken_page_is_caught() {
        let mut rng = Rng::new(3);
        for _ in 0..20 {
            let text = hostile_model(&mut rng);
            assert!(report_page(&text).is_ok(), "{text}\n{:?}", report_page(&text).err());
        }
        let (page, data) =
            report_page(MODELS[0].replace("{name}", "\"ok\"").replace("{q}", "q").replace("{p}", "k").as_str())
                .expect("the oscillator reports");
        assert_eq!(check_page(&page, &data), Ok(()));
        // The data script ended early by a name, as a page without escaping would be.
        let broken = page.replacen("\"name\":\"ok\"", "\"name\":\"</script>\"", 1);
        assert!(check_page(&broken, &data).unwrap_err().contains("not JSON"));
        // `<!--<script>` in the data: its `</script>` no longer ends it, and the
        // main script's start tag starts a double escape again.
        let commented = page.replacen("\"name\":\"ok\"", "\"name\":\"<!--<script>\"", 1);
        assert!(check_page(&commented, &data).unwrap_err().contains("never closed"));
        // Closed again by a `-->` before the end: still a broken page.
        let closed = page.replacen("\"name\":\"ok\"", "\"name\":\"<!--<script>-->\"", 1);
        assert!(check_page(&closed, &data).unwrap_err().contains("double-escaped"));
        assert_eq!(decode("a&lt;b&#x41;&#66;&amp;&zz;"), "a<bAB&&zz;");
    }

    #[test]
    fn hostile_names_read_back_from_their_toml() {
        let mut rng = Rng::new(8);
        for _ in 0..500 {
            let name = hostile_name(&mut rng);
            let text = format!("name = {}", toml_string(&mut rng, &name));
            let table: toml::Table = text.parse().unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(table["name"].as_str(), Some(name.as_str()), "{text}");
        }
    }
}
