//! Failures and how they are shown: bad input (exit 2) rendered with the file,
//! line and column and the offending text underlined; failed runs (exit 1);
//! runs stopped by SIGINT or SIGTERM (exit 130 or 143).

use ariadne::{Label, Report, ReportKind, Source};
use std::path::Path;

/// Longest source line shown in a diagnostic snippet, in bytes.
const MAX_SNIPPET_LINE: usize = 400;

/// Why the program stops without a result.
pub enum Failure {
    /// Bad input: a message, optionally located in a source text.
    Input { file: String, message: String, located: Option<(String, std::ops::Range<usize>)>, help: Option<String> },
    /// A run that failed midway.
    Run { message: String },
    /// A run stopped by SIGINT or SIGTERM, after flushing what it wrote.
    Interrupted { signal: crate::interrupt::Signal, message: String },
}

impl Failure {
    /// Bad input about a file as a whole.
    pub fn input(path: &Path, message: impl Into<String>) -> Failure {
        Failure::Input { file: path.display().to_string(), message: message.into(), located: None, help: None }
    }

    /// A model error, located in the model's text.
    pub fn model(path: &Path, source: &str, e: mech::ModelError) -> Failure {
        Failure::Input {
            file: path.display().to_string(),
            message: match &e.within {
                Some(w) => nested_message(w),
                None => with_flag(e.setting.as_ref(), e.message),
            },
            located: e.span.map(|s| (source.to_string(), clamp(s, source))),
            help: e.help,
        }
    }

    /// An analysis' error: a model error located in the model file, or its
    /// message and hint (exit 2).
    pub fn analysis<E: Explained>(path: &Path, source: &str, e: E) -> Failure {
        let help = e.help();
        match e.into_model() {
            Ok(m) => Failure::model(path, source, m),
            Err(other) => {
                Failure::Input { file: path.display().to_string(), message: other.to_string(), located: None, help }
            }
        }
    }

    /// Bad command-line usage (exit 2).
    pub fn usage(message: impl Into<String>) -> Failure {
        Failure::Input { file: "command line".into(), message: message.into(), located: None, help: None }
    }

    /// A model error in an expression given on the command line (`what` names
    /// the option); `offset` is where the parsed part starts within `text`.
    pub fn expression(what: &str, text: &str, e: mech::ModelError, offset: usize) -> Failure {
        Failure::Input {
            file: what.to_string(),
            message: e.message,
            located: e.span.map(|s| (text.to_string(), clamp(s.start + offset..s.end + offset, text))),
            help: e.help,
        }
    }

    /// A failed run.
    pub fn run(message: impl Into<String>) -> Failure {
        Failure::Run { message: message.into() }
    }

    /// The process exit code.
    pub fn exit_code(&self) -> u8 {
        match self {
            Failure::Input { .. } => 2,
            Failure::Run { .. } => 1,
            Failure::Interrupted { signal, .. } => signal.exit_code(),
        }
    }

    /// The message for stderr.
    pub fn render(&self) -> String {
        match self {
            Failure::Run { message } => format!("error: {message}\n"),
            Failure::Interrupted { message, .. } => format!("{message}\n"),
            Failure::Input { file, message, located: None, help } => {
                let mut s = format!("error: {file}: {message}\n");
                if let Some(h) = help {
                    s.push_str(&format!("  help: {h}\n"));
                }
                s
            }
            Failure::Input { file, message, located: Some((source, span)), help } => {
                let (line, col) = line_col(source, span.start);
                let mut out = format!("error: {file}:{line}:{col}: {message}\n");
                // The report carries no message: the line above says it once,
                // and the drawing below only shows the place.
                let mut report = Report::build(ReportKind::Error, (file.as_str(), span.clone()))
                    // Spans are byte offsets (TOML and our parser); ariadne counts characters by default.
                    .with_config(ariadne::Config::default().with_color(false).with_index_type(ariadne::IndexType::Byte))
                    .with_label(Label::new((file.as_str(), span.clone())).with_message(short(message)));
                if let Some(h) = help {
                    report = report.with_help(h);
                }
                // A snippet of a very long line (10 000 parentheses) would only
                // repeat it; the first line already says where.
                let line_len = source[..span.start].rsplit('\n').next().map_or(0, str::len)
                    + source[span.start..].split('\n').next().map_or(0, str::len);
                if line_len > MAX_SNIPPET_LINE {
                    if let Some(h) = help {
                        out.push_str(&format!("  help: {h}\n"));
                    }
                    return out;
                }
                let mut buf = Vec::new();
                if report.finish().write((file.as_str(), Source::from(source.as_str())), &mut buf).is_ok() {
                    // Drop the drawing's own header line ("Error: "), which
                    // would repeat the first line.
                    let drawing = String::from_utf8_lossy(&buf);
                    out.push_str(drawing.split_once('\n').map_or("", |(_, rest)| rest));
                } else if let Some(h) = help {
                    out.push_str(&format!("  help: {h}\n"));
                }
                out
            }
        }
    }
}

/// The label under the span: the message up to its first colon-separated detail.
fn short(message: &str) -> String {
    message.rsplit(": ").next().unwrap_or(message).to_string()
}

/// Keeps a span inside the text and on character boundaries.
fn clamp(span: std::ops::Range<usize>, source: &str) -> std::ops::Range<usize> {
    let mut start = span.start.min(source.len());
    while !source.is_char_boundary(start) {
        start -= 1;
    }
    let mut end = span.end.clamp(start, source.len());
    while !source.is_char_boundary(end) {
        end += 1;
    }
    start..end
}

/// 1-based line and column (in characters) of a byte offset.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let before = &source[..offset.min(source.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// The message of an error inside a file the model names, with its line and
/// column there: "in the body file NAME:LINE:COL: ...".
fn nested_message(w: &mech::Within) -> String {
    let place = match &w.error.span {
        Some(s) => {
            let (line, col) = line_col(&w.text, s.start);
            format!("{}:{line}:{col}", w.name)
        }
        None => w.name.clone(),
    };
    format!("in the {} {place}: {}", w.what, w.error.message)
}

/// The message of an error about a setting, prefixed with the flag that gives
/// it: the library names settings by what they are, the CLI by its flags.
fn with_flag(setting: Option<&mech::Setting>, message: String) -> String {
    match setting {
        Some(mech::Setting::Parameter { name }) => format!("--set {name}: {message}"),
        Some(mech::Setting::Start { name }) => format!("--at {name}: {message}"),
        None => message,
    }
}

/// What the CLI needs of an analysis' error.
pub trait Explained: std::fmt::Display + Sized {
    /// The model error inside, or the error itself when it is not one.
    fn into_model(self) -> Result<mech::ModelError, Self>;
    /// A hint on how to fix it, in the CLI's terms.
    fn help(&self) -> Option<String>;
}

impl Explained for mech::ModesError {
    fn into_model(self) -> Result<mech::ModelError, Self> {
        match self {
            mech::ModesError::Model(m) => Ok(m),
            other => Err(other),
        }
    }
    fn help(&self) -> Option<String> {
        match self {
            mech::ModesError::NoEquilibrium { .. } => {
                Some("start elsewhere with --at q=v (e.g. --at th=0), or check that U has a minimum".into())
            }
            other => other.help(),
        }
    }
}

impl Explained for mech::LinearizeError {
    fn into_model(self) -> Result<mech::ModelError, Self> {
        match self {
            mech::LinearizeError::Model(m) => Ok(m),
            other => Err(other),
        }
    }
    fn help(&self) -> Option<String> {
        match self {
            mech::LinearizeError::NoPoint { .. } => {
                Some("start elsewhere with --at q=v, or change the rates with --rate q=v".into())
            }
            other => other.help(),
        }
    }
}

impl Explained for mech::OrbitError {
    fn into_model(self) -> Result<mech::ModelError, Self> {
        match self {
            mech::OrbitError::Model(m) => Ok(m),
            other => Err(other),
        }
    }
    fn help(&self) -> Option<String> {
        self.help()
    }
}

impl Explained for mech::TopError {
    fn into_model(self) -> Result<mech::ModelError, Self> {
        match self {
            mech::TopError::Model(m) => Ok(m),
        }
    }
    fn help(&self) -> Option<String> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_and_columns_are_one_based() {
        let s = "a = 1\nbé = \"x\"\n";
        assert_eq!(line_col(s, 0), (1, 1));
        assert_eq!(line_col(s, 6), (2, 1));
        assert_eq!(line_col(s, 11), (2, 5));
    }
}
