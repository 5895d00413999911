//! [`DrawError`]: a figure that could not be drawn. The SVG backend draws into
//! a string, so this is rare (a font the backend cannot lay out, a coordinate
//! it refuses); the front end says which figure and where it was going.

use std::fmt;

/// Why a figure could not be drawn: the drawing backend's message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DrawError {
    message: String,
}

impl fmt::Display for DrawError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for DrawError {}

impl From<Box<dyn std::error::Error>> for DrawError {
    fn from(err: Box<dyn std::error::Error>) -> DrawError {
        DrawError { message: err.to_string() }
    }
}
