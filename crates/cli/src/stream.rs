//! Streamed CSV output that is whole to its last row whatever stops it: rows
//! are gathered in a buffer and written out in chunks that end at a row's end,
//! each in one write under the interrupt gate (`interrupt.rs`), so that an exit
//! on a second signal falls between two chunks; a write that fails midway is
//! cut back to the last whole row. Memory: one chunk.
//!
//! Enter at [`RowWriter::start`] or [`RowWriter::stdout`], then
//! [`RowWriter::push`] per line and [`RowWriter::flush`] at the end.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::time::{Duration, Instant};

/// Bytes gathered before a write: large enough that writes cost nothing next
/// to the rows' formatting, small enough to be no memory at all.
const CHUNK_BYTES: usize = 64 * 1024;

/// The longest time rows wait in the buffer: a slow run's file still shows its
/// progress, and a kill that cannot be caught (SIGKILL) loses at most this much.
const CHUNK_SECONDS: Duration = Duration::from_secs(1);

/// Where rows go.
enum Target {
    /// A file, with the length known to end at a row's end.
    File {
        file: File,
        whole: u64,
    },
    Stdout,
}

/// Whole lines out, in chunks (module documentation).
pub struct RowWriter {
    target: Target,
    buffer: Vec<u8>,
    since: Instant,
}

impl RowWriter {
    /// Rows in `file` after its first `kept` bytes (0 for a new file, the whole
    /// rows a resumed run keeps), beginning with the lines `header` (empty
    /// when the kept part has them): the file is cut to `kept` and the header
    /// written in one step. The caller holds the interrupt gate from opening
    /// the file to here, so that a signal finds it as it was or with its
    /// header whole.
    pub fn start(mut file: File, kept: u64, header: &[u8]) -> std::io::Result<RowWriter> {
        // A device (`/dev/null`) has no length to cut.
        if file.metadata()?.is_file() {
            file.set_len(kept)?;
            file.seek(SeekFrom::Start(kept))?;
        }
        file.write_all(header)?;
        Ok(RowWriter::new(Target::File { file, whole: kept + header.len() as u64 }))
    }

    /// Rows to standard output.
    pub fn stdout() -> RowWriter {
        RowWriter::new(Target::Stdout)
    }

    fn new(target: Target) -> RowWriter {
        RowWriter { target, buffer: Vec::with_capacity(CHUNK_BYTES), since: Instant::now() }
    }

    /// Adds whole lines (each ending in a newline); writes the buffer once it
    /// is a chunk's worth or has waited long enough.
    pub fn push(&mut self, lines: &[u8]) -> std::io::Result<()> {
        debug_assert!(lines.ends_with(b"\n"), "whole lines only");
        self.buffer.extend_from_slice(lines);
        if self.buffer.len() >= CHUNK_BYTES || self.since.elapsed() >= CHUNK_SECONDS {
            self.flush()?;
        }
        Ok(())
    }

    /// Writes what the buffer holds, in one write under the interrupt gate.
    /// A file whose write fails midway (a full disk) is cut back to its last
    /// whole row.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.since = Instant::now();
        if self.buffer.is_empty() {
            return Ok(());
        }
        let _held = crate::interrupt::gate();
        let result = match &mut self.target {
            Target::File { file, whole } => match file.write_all(&self.buffer) {
                Ok(()) => {
                    *whole += self.buffer.len() as u64;
                    Ok(())
                }
                Err(e) => {
                    let _ = file.set_len(*whole);
                    Err(e)
                }
            },
            Target::Stdout => {
                let mut out = std::io::stdout().lock();
                out.write_all(&self.buffer).and_then(|()| out.flush())
            }
        };
        self.buffer.clear();
        result
    }
}
