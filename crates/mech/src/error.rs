//! Errors about a model: what is wrong and where in the model file.
//!
//! Spans are byte ranges into the model file's text; only the CLI turns them into
//! `file:line:col` and underlines them.

use std::ops::Range;

/// A problem with a model file, located in its text where possible.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct ModelError {
    /// What kind of problem it is, for callers that branch on it; the
    /// message says the rest.
    pub kind: ModelErrorKind,
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

/// What kind of problem a [`ModelError`] is: what a caller can act on without
/// reading the message (fall back to another path, skip a case, map it to its
/// language's own exception).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum ModelErrorKind {
    /// The model as written is wrong: its text does not read, a name is
    /// unknown or repeated, a value is out of its range, a section is missing.
    #[default]
    Invalid,
    /// A file the model names (a body file, a URDF) could not be read.
    File,
    /// The mass matrix is singular: the equations of motion do not determine
    /// every acceleration.
    SingularMassMatrix,
    /// The derivation passed its bound on the work of building expressions.
    TooLarge,
    /// A constraint, force or torque that does nothing: it restricts no
    /// motion or acts on no coordinate.
    DoesNothing,
    /// The start is not one the motion can begin from: it violates a
    /// constraint, a value there is not real, or it is at a gimbal singularity.
    Start,
    /// The analysis asked for does not handle this model (constraints in
    /// the normal modes).
    Unsupported,
}

impl ModelErrorKind {
    /// Its name in snake case (`singular_mass_matrix`), for JSON and Python.
    pub fn code(self) -> &'static str {
        match self {
            ModelErrorKind::Invalid => "invalid",
            ModelErrorKind::File => "file",
            ModelErrorKind::SingularMassMatrix => "singular_mass_matrix",
            ModelErrorKind::TooLarge => "too_large",
            ModelErrorKind::DoesNothing => "does_nothing",
            ModelErrorKind::Start => "start",
            ModelErrorKind::Unsupported => "unsupported",
        }
    }
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
    /// An error (of kind [`ModelErrorKind::Invalid`]) at a span, or about the
    /// file as a whole when there is none.
    pub fn located(span: Option<Range<usize>>, message: impl Into<String>) -> ModelError {
        ModelError {
            kind: ModelErrorKind::Invalid,
            message: message.into(),
            span,
            help: None,
            setting: None,
            within: None,
        }
    }

    /// An error at a span.
    pub fn at(span: Range<usize>, message: impl Into<String>) -> ModelError {
        ModelError::located(Some(span), message)
    }

    /// An error about the file as a whole.
    pub fn whole(message: impl Into<String>) -> ModelError {
        ModelError::located(None, message)
    }

    /// An error about a setting of the caller's.
    pub fn setting(setting: Setting, message: impl Into<String>) -> ModelError {
        ModelError { setting: Some(setting), ..ModelError::whole(message) }
    }

    /// Sets its kind.
    pub fn with_kind(mut self, kind: ModelErrorKind) -> ModelError {
        self.kind = kind;
        self
    }

    /// Adds a hint.
    pub fn with_help(mut self, help: impl Into<String>) -> ModelError {
        self.help = Some(help.into());
        self
    }
}

/// A parameter override's value (`--set`, Python's `set=` and
/// `with_parameters`), refused where it is not finite: every front end's
/// overrides arrive in the readers that call this.
pub(crate) fn finite_override(name: &str, value: f64) -> Result<f64, ModelError> {
    if value.is_finite() {
        return Ok(value);
    }
    Err(ModelError::setting(
        Setting::Parameter { name: name.to_string() },
        format!("the value of parameter '{name}' must be a finite number, not {value}"),
    ))
}
