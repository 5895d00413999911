//! `sweep --resume`: continues a sweep from the partial output of a run that
//! was stopped (a signal, a full disk, a job scheduler's time limit). The file
//! is read line by line (memory: one line, whatever its size) and must be this
//! sweep's: the same two header lines, byte for byte, then rows of the
//! sweep's first runs in grid order. Its whole rows are kept, a last line cut
//! short (by a kill that could not be caught) is dropped, and the rest of the
//! runs are appended; the finished file equals an uninterrupted run's.
//!
//! Enter at [`open`].

use crate::diagnostics::Failure;
use crate::stream::RowWriter;
use mech::{Shard, SweepHeader, TableRow};
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// The longest line a partial output may have: far above any row (a few
/// hundred bytes and a failure's message), far below what strains memory.
const MAX_LINE_BYTES: u64 = 1 << 20;

/// A partial output, opened to continue.
pub struct Kept {
    /// Appends after the kept rows.
    pub writer: RowWriter,
    /// The rows kept: the sweep's first runs.
    pub rows: usize,
    /// What was found that the user should know (no rows yet, a line dropped).
    pub note: Option<String>,
}

/// One line of the file.
enum Line {
    /// A line and its newline.
    Whole,
    /// Text without a newline at the end of the file.
    Cut,
    /// Nothing more.
    End,
}

/// Reads the next line into `buf` (newline included), at most [`MAX_LINE_BYTES`].
fn next_line(reader: &mut impl BufRead, buf: &mut Vec<u8>) -> std::io::Result<Line> {
    buf.clear();
    reader.take(MAX_LINE_BYTES + 1).read_until(b'\n', buf)?;
    Ok(match buf.last() {
        None => Line::End,
        Some(b'\n') => Line::Whole,
        Some(_) => Line::Cut,
    })
}

/// Opens the partial output `path` of the sweep with `header` (the runs of
/// `shard`, `runs` of them), hands each row it keeps to `take`, and returns
/// the writer that appends the rest. Refuses (exit 2) a file that is not this
/// sweep's output or whose rows are not its first runs in order.
pub fn open(
    path: &Path,
    header: &SweepHeader,
    shard: Shard,
    runs: usize,
    mut take: impl FnMut(&TableRow),
) -> Result<Kept, Failure> {
    let refuse = |reason: String| {
        Failure::input(
            path,
            format!("cannot resume: {reason}; resume only with the same model, grid and settings, or write to another --out"),
        )
    };
    let io = |e: std::io::Error| Failure::input(path, format!("cannot read it to resume: {e}"));
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        return Err(Failure::input(path, "not a regular file (a pipe, device or folder holds no rows to continue)"));
    }
    let file = crate::files::open_locked(path).map_err(|e| Failure::input(path, format!("cannot open it: {e}")))?;
    let name = path.display().to_string();
    let expected = header.to_csv();
    let mut reader = BufReader::new(&file);
    let mut buf = Vec::new();

    // The header: two lines, equal to this sweep's.
    let mut head: Vec<u8> = Vec::new();
    let mut whole_lines = 0;
    while whole_lines < 2 {
        let line = next_line(&mut reader, &mut buf).map_err(io)?;
        head.extend_from_slice(&buf);
        match line {
            Line::Whole => whole_lines += 1,
            Line::Cut | Line::End => break,
        }
    }
    let mut kept = head.len() as u64;
    let mut note = None;
    let rows = if head != expected.as_bytes() {
        if !expected.as_bytes().starts_with(&head) || whole_lines == 2 {
            return Err(refuse(mismatch(&head, header, &name)));
        }
        // Empty, or its header cut short: nothing to keep.
        kept = 0;
        note = Some(format!("{name} holds no rows yet: the sweep starts at its first run"));
        0
    } else {
        let mut rows = 0;
        loop {
            let line_no = rows + 3;
            match next_line(&mut reader, &mut buf).map_err(io)? {
                Line::End => break,
                Line::Cut if buf.len() as u64 > MAX_LINE_BYTES => {
                    return Err(refuse(format!("line {line_no} is longer than {MAX_LINE_BYTES} bytes")));
                }
                Line::Cut => {
                    note = Some(format!(
                        "{name}: line {line_no} was cut short (a run stopped in the middle of a write); it is dropped and its run done again"
                    ));
                    break;
                }
                Line::Whole => {
                    let text = std::str::from_utf8(&buf[..buf.len() - 1])
                        .map_err(|_| refuse(format!("line {line_no} is not UTF-8 text")))?;
                    let row = TableRow::parse(text, header, &name, line_no).map_err(|e| refuse(e.to_string()))?;
                    if rows >= runs || row.run != shard.nth(rows) {
                        return Err(refuse(format!(
                            "line {line_no} holds run {} where {} was expected (the rows of a partial output are the sweep's first runs, in grid order)",
                            row.run,
                            if rows >= runs { "no further run".to_string() } else { format!("run {}", shard.nth(rows)) },
                        )));
                    }
                    take(&row);
                    rows += 1;
                    kept += buf.len() as u64;
                }
            }
        }
        rows
    };
    drop(reader);
    // What follows the kept rows (a line cut short) goes; the rest is appended.
    let header = if kept == 0 { expected.as_bytes() } else { &[] };
    let _held = crate::interrupt::gate();
    let writer =
        RowWriter::start(file, kept, header).map_err(|e| Failure::input(path, format!("cannot continue it: {e}")))?;
    Ok(Kept { writer, rows, note })
}

/// Why the header lines `head` of file `name` are not those of the sweep of `header`.
fn mismatch(head: &[u8], header: &SweepHeader, name: &str) -> String {
    let text = String::from_utf8_lossy(head);
    let mut lines = text.lines();
    let found = match SweepHeader::parse(lines.next().unwrap_or_default(), lines.next().unwrap_or_default(), name) {
        Ok(found) => found,
        Err(e) => return e.to_string(),
    };
    if found.columns != header.columns {
        return format!(
            "its columns are {}, and this sweep's are {}",
            found.columns.join(","),
            header.columns.join(",")
        );
    }
    let value = |h: &SweepHeader, k: &str| h.meta(k).unwrap_or("(none)").to_string();
    let keys = header.meta.iter().chain(&found.meta).map(|(k, _)| k.as_str());
    for key in keys {
        if value(&found, key) != value(header, key) {
            return format!(
                "it is the output of another sweep: {key} is '{}' there and '{}' here",
                value(&found, key),
                value(header, key)
            );
        }
    }
    "its header differs from this sweep's".into()
}
