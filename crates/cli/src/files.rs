//! The files a command reads and writes. Reads are bounded: only regular files
//! (a FIFO or a device such as /dev/zero would block or never end), and never
//! more than a limit, checked while reading rather than after. Streamed outputs
//! are locked while written, so two runs cannot interleave their rows in one
//! file, and no output may replace an input of the same command. Figures are
//! drawn by `view` and written whole.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::Read;
use std::path::Path;

/// Largest sweep CSV that `sweep --merge` reads, in bytes: far above any shard
/// of the largest allowed sweep at a few hundred bytes a row that fits in memory
/// comfortably, far below what exhausts it.
pub const MAX_CSV_BYTES: u64 = 1 << 30;

/// Writes a figure that `view` drew (or could not draw) to `path`; `what`
/// names it in the messages ("the plot", "the heat map").
pub fn write_figure(path: &Path, what: &str, svg: Result<String, view::DrawError>) -> Result<(), String> {
    let svg = svg.map_err(|err| format!("cannot draw {what} {}: {err}", path.display()))?;
    std::fs::write(path, svg).map_err(|err| format!("cannot write {what} {}: {err}", path.display()))
}

/// Why a file could not be read.
#[derive(Debug)]
pub enum ReadError {
    /// The operating system's error.
    Io(std::io::Error),
    /// Not a regular file.
    NotRegular,
    /// Longer than the limit.
    TooLarge {
        /// The limit, in bytes.
        limit: u64,
    },
    /// Not UTF-8 text.
    NotText(std::string::FromUtf8Error),
}

impl std::fmt::Display for ReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReadError::Io(e) => write!(f, "{e}"),
            ReadError::NotRegular => f.write_str("not a regular file (a pipe, device or folder cannot be read as one)"),
            ReadError::TooLarge { limit } => {
                write!(f, "the file is larger than {limit} bytes, the limit for this kind of file")
            }
            ReadError::NotText(e) => write!(f, "the file is not UTF-8 text: {e}"),
        }
    }
}

impl ReadError {
    /// The message, with `io_prefix` ("cannot read the file") before an error of
    /// the operating system's.
    pub fn message(&self, io_prefix: &str) -> String {
        match self {
            ReadError::Io(e) => format!("{io_prefix}: {e}"),
            other => other.to_string(),
        }
    }
}

/// The text of the regular file at `path`, if it has at most `limit` bytes.
pub fn read_text(path: &Path, limit: u64) -> Result<String, ReadError> {
    // Opening a FIFO for reading blocks until a writer comes: its type is
    // checked before opening, and again on the open file (it may have changed).
    if !std::fs::metadata(path).map_err(ReadError::Io)?.is_file() {
        return Err(ReadError::NotRegular);
    }
    let file = File::open(path).map_err(ReadError::Io)?;
    let meta = file.metadata().map_err(ReadError::Io)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular);
    }
    let mut bytes = Vec::with_capacity(meta.len().min(limit) as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(ReadError::Io)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge { limit });
    }
    String::from_utf8(bytes).map_err(ReadError::NotText)
}

/// Creates (or empties) the output file at `path` for this run alone: it is
/// opened without truncating, locked exclusively, and only then emptied, so a
/// second run that names the same file is refused and leaves the first one's
/// rows alone. The lock lasts as long as the file is open.
pub fn create_locked(path: &Path) -> Result<File, String> {
    let file = open_locked(path)?;
    file.set_len(0).map_err(|e| e.to_string())?;
    Ok(file)
}

/// Opens (or creates) the output file at `path` for reading and writing by
/// this run alone, keeping what it holds (the partial output a resumed run
/// continues), and locks it as [`create_locked`] says.
pub fn open_locked(path: &Path) -> Result<File, String> {
    let file =
        OpenOptions::new().read(true).write(true).create(true).truncate(false).open(path).map_err(|e| e.to_string())?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(TryLockError::WouldBlock) => Err("in use by another run (it is being written); choose another file".into()),
        Err(TryLockError::Error(e)) => Err(format!("cannot lock it: {e}")),
    }
}

/// An error, before anything is computed, when an output path names one of the
/// inputs (the model file, a shard to merge), whose writing would destroy what
/// the run reads, or a place no file can be created (a folder, or inside a
/// folder that does not exist). Such paths are bad input (exit 2); a write
/// that fails later, after the run (a full disk), is a failed run (exit 1).
pub fn refuse_overwrite(inputs: &[&Path], outputs: &[Option<&Path>]) -> Result<(), String> {
    for out in outputs.iter().flatten() {
        if out.is_dir() {
            return Err(format!("{} is a folder; an output must name a file", out.display()));
        }
        let parent = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if !parent.is_dir() {
            return Err(format!("cannot write {}: the folder {} does not exist", out.display(), parent.display()));
        }
    }
    // Only an output that exists can be an input; both sides as the file system
    // resolves them (links, `./`, `..`).
    let inputs: Vec<_> = inputs.iter().filter_map(|p| p.canonicalize().ok()).collect();
    for out in outputs.iter().flatten() {
        if let Ok(resolved) = out.canonicalize() {
            if inputs.contains(&resolved) {
                return Err(format!(
                    "{} is an input of this command; it would be overwritten by an output",
                    out.display()
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_device_is_refused_before_anything_is_read() {
        assert!(matches!(read_text(Path::new("/dev/zero"), 1 << 20), Err(ReadError::NotRegular)));
    }

    #[test]
    fn a_locked_output_is_refused_and_left_alone() {
        let path = std::env::temp_dir().join(format!("lagrange-lock-{}.csv", std::process::id()));
        std::fs::write(&path, "first run's rows\n").unwrap();
        let held = File::open(&path).unwrap();
        held.lock().unwrap();
        assert!(create_locked(&path).unwrap_err().contains("in use by another run"));
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "first run's rows\n", "not truncated");
        drop(held);
        let mut f = create_locked(&path).unwrap();
        std::io::Write::write_all(&mut f, b"x").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "x");
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn an_output_that_is_an_input_is_refused() {
        let path = std::env::temp_dir().join(format!("lagrange-overwrite-{}.toml", std::process::id()));
        std::fs::write(&path, "x").unwrap();
        let other = path.with_extension("csv");
        assert!(refuse_overwrite(&[&path], &[Some(&path)]).is_err());
        assert!(refuse_overwrite(&[&path], &[None, Some(&other)]).is_ok());
        assert!(refuse_overwrite(&[], &[Some(&std::env::temp_dir())]).unwrap_err().contains("is a folder"));
        let nowhere = std::env::temp_dir().join("lagrange-no-such-folder").join("out.csv");
        assert!(refuse_overwrite(&[], &[Some(&nowhere)]).unwrap_err().contains("does not exist"));
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn a_file_over_the_limit_is_refused() {
        let path = std::env::temp_dir().join(format!("lagrange-input-{}.txt", std::process::id()));
        std::fs::write(&path, "x".repeat(101)).unwrap();
        assert!(matches!(read_text(&path, 100), Err(ReadError::TooLarge { limit: 100 })));
        assert_eq!(read_text(&path, 101).unwrap().len(), 101);
        let _ = std::fs::remove_file(&path);
    }
}
