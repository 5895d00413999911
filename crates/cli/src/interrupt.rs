//! SIGINT and SIGTERM during a run: once rows stream, the first asks the run
//! to stop between rows (the command then flushes what it wrote, prints its
//! summary and exits 130 or 143); a second one exits at once, but never in
//! the middle of a write of rows. Before the first row (reading, deriving,
//! compiling, choosing a step) there is nothing to keep, and the first signal
//! exits at once.
//!
//! Enter at [`install`] (once, by the commands that stream rows), [`streaming`]
//! (when rows begin), [`received`] (polled between rows) and [`gate`] (held
//! while rows are written). The
//! signals are caught with `signal-hook`: its iterator delivers them to an
//! ordinary thread, so nothing here runs in a signal handler and no `unsafe`
//! is needed, and it tells SIGINT from SIGTERM, which the exit code needs
//! (`ctrlc` calls one handler for both).

use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::iterator::Signals;
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::{Mutex, MutexGuard};

/// The first signal received, 0 before any.
static RECEIVED: AtomicI32 = AtomicI32::new(0);

/// Whether rows stream: a signal then stops the run between two of them.
static STREAMING: AtomicBool = AtomicBool::new(false);

/// Held by whoever writes rows, so that the exit on a second signal waits for
/// the write under way and never leaves half a row.
static GATE: Mutex<()> = Mutex::new(());

/// A signal that stops a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Signal {
    /// Ctrl-C at a terminal.
    Int,
    /// `kill`, a job scheduler's end of a time slot.
    Term,
}

impl Signal {
    fn from_number(number: i32) -> Option<Signal> {
        match number {
            SIGINT => Some(Signal::Int),
            SIGTERM => Some(Signal::Term),
            _ => None,
        }
    }

    /// The exit code of a process that stops on this signal: 128 + its number,
    /// as a shell reports a process the signal ended.
    pub fn exit_code(self) -> u8 {
        match self {
            Signal::Int => 130,
            Signal::Term => 143,
        }
    }

    /// `SIGINT` or `SIGTERM`.
    pub fn name(self) -> &'static str {
        match self {
            Signal::Int => "SIGINT",
            Signal::Term => "SIGTERM",
        }
    }
}

/// Catches SIGINT and SIGTERM from now on. Where they cannot be caught (no
/// thread to watch them, the operating system refused) they keep their
/// default, which ends the process.
pub fn install() {
    // The watcher registers the signals itself and says when it has: a
    // registration without its thread would swallow them.
    let (registered, wait) = std::sync::mpsc::sync_channel(1);
    let spawned = std::thread::Builder::new().name("signals".into()).spawn(move || {
        let mut signals = match Signals::new([SIGINT, SIGTERM]) {
            Ok(signals) => signals,
            Err(_) => {
                let _ = registered.send(());
                return;
            }
        };
        let _ = registered.send(());
        for number in signals.forever() {
            let Some(signal) = Signal::from_number(number) else { continue };
            let first = RECEIVED.compare_exchange(0, number, Ordering::SeqCst, Ordering::SeqCst).is_ok();
            let why = match (first, STREAMING.load(Ordering::SeqCst)) {
                (true, true) => continue,
                (true, false) => "before the first row",
                (false, _) => "again: stopping at once",
            };
            // Out at once, between two writes of whole rows.
            let _held = gate();
            eprintln!("interrupted by {} {why} (the rows written so far are whole)", signal.name());
            std::process::exit(i32::from(signal.exit_code()));
        }
    });
    if spawned.is_ok() {
        let _ = wait.recv();
    }
}

/// Rows begin to stream: from now on a first signal stops the run between
/// two rows instead of ending the process.
pub fn streaming() {
    STREAMING.store(true, Ordering::SeqCst);
}

/// The first signal received so far, if any.
pub fn received() -> Option<Signal> {
    Signal::from_number(RECEIVED.load(Ordering::SeqCst))
}

/// Holds off the exit on a second signal while the caller writes whole rows.
pub fn gate() -> MutexGuard<'static, ()> {
    GATE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}
