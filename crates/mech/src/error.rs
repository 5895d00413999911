//! Errors about a model: what is wrong and where in the model file.
//!
//! Spans are byte ranges into the model file's text; only the CLI turns them into
//! `file:line:col` and underlines them.

use std::ops::Range;

/// A problem with a model file, located in its text where possible.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct ModelError {
    /// What is wrong and what was expected, as one sentence.
    pub message: String,
    /// Where, as a byte range into the model file (None: the file as a whole).
    pub span: Option<Range<usize>>,
    /// A hint on how to fix it.
    pub help: Option<String>,
    /// The caller's setting the error is about, when it is not a place in a
    /// file (a front end names it in its own terms, e.g. a command-line flag).
    pub setting: Option<Setting>,
    /// When the error is inside another file the model names (a body file):
    /// that file and the error there, for a front end to locate.
    pub within: Option<Box<Within>>,
}

/// An error inside a file named by the model file (`message` of the outer error
/// says "in the body file NAME: ..."; a front end may add the line and column).
#[derive(Debug, Clone, PartialEq)]
pub struct Within {
    /// What the file is (`body file`).
    pub what: String,
    /// Its name as the model gives it.
    pub name: String,
    /// Its text, which `error`'s span points into.
    pub text: String,
    /// The error in it.
    pub error: ModelError,
}

/// A value the caller set beside the files: the library names it by what it
/// is, and a front end by how it is given (the CLI: `--set`, `--at`).
#[derive(Debug, Clone, PartialEq)]
pub enum Setting {
    /// A parameter's value, overriding the file's.
    Parameter {
        /// The parameter's name.
        name: String,
    },
    /// A coordinate's value at the start of an analysis (`modes`).
    Start {
        /// The coordinate's name.
        name: String,
    },
}

impl ModelError {
    /// An error at a span.
    pub fn at(span: Range<usize>, message: impl Into<String>) -> ModelError {
        ModelError { message: message.into(), span: Some(span), help: None, setting: None, within: None }
    }

    /// An error about the file as a whole.
    pub fn whole(message: impl Into<String>) -> ModelError {
        ModelError { message: message.into(), span: None, help: None, setting: None, within: None }
    }

    /// An error about a setting of the caller's.
    pub fn setting(setting: Setting, message: impl Into<String>) -> ModelError {
        ModelError { message: message.into(), span: None, help: None, setting: Some(setting), within: None }
    }

    /// Adds a hint.
    pub fn with_help(mut self, help: impl Into<String>) -> ModelError {
        self.help = Some(help.into());
        self
    }
}
