//! Signals during a long run with the GIL released: between rows, at most
//! every [`POLL`], the run takes the GIL back for a moment so that Python runs
//! its signal handlers (Ctrl-C raises KeyboardInterrupt there).

use pyo3::prelude::*;
use std::time::{Duration, Instant};

/// How often a run looks for a pending signal.
pub const POLL: Duration = Duration::from_millis(20);

/// The signal poll of one run.
pub struct Signals {
    polled: Instant,
}

impl Signals {
    /// A poll whose first look is [`POLL`] from now.
    pub fn new() -> Signals {
        Signals { polled: Instant::now() }
    }

    /// Runs Python's signal handlers if [`POLL`] has passed since the last
    /// look; the exception a handler raised, if any.
    pub fn check(&mut self) -> Result<(), PyErr> {
        if self.polled.elapsed() < POLL {
            return Ok(());
        }
        self.polled = Instant::now();
        Python::attach(|py| py.check_signals())
    }
}
