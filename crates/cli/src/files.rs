//! The files a command reads and writes. Reads are bounded: only regular files
//! (a FIFO or a device such as /dev/zero would block or never end), and never
//! more than a limit, checked while reading rather than after. Streamed outputs
//! are locked while written, so two runs cannot interleave their rows in one
//! file, and no output may replace an input of the same command: every file
//! read is remembered (device and inode), the model's own and those it names,
//! and every output is compared with them, both before the run and when it is
//! opened. Figures are drawn by `view` and written whole.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Write};
use std::path::Path;
use std::sync::Mutex;

/// Largest sweep CSV that `sweep --merge` reads, in bytes: far above any shard
/// of the largest allowed sweep at a few hundred bytes a row that fits in memory
/// comfortably, far below what exhausts it.
pub const MAX_CSV_BYTES: u64 = 1 << 30;

/// Writes a figure that `view` drew (or could not draw) to `path`; `what`
/// names it in the messages ("the plot", "the heat map").
pub fn write_figure(path: &Path, what: &str, svg: Result<String, view::DrawError>) -> Result<(), String> {
    let svg = svg.map_err(|err| format!("cannot draw {what} {}: {err}", path.display()))?;
    write_whole(path, svg.as_bytes()).map_err(|err| format!("cannot write {what} {}: {err}", path.display()))
}

/// Writes `bytes` as the whole of the file at `path`, under the same lock a
/// streamed output holds: a file another run is writing (a CSV being
/// streamed) is refused and left as it is, never emptied.
pub fn write_whole(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let mut file = create_locked(path)?;
    file.write_all(bytes).and_then(|()| file.flush()).map_err(|e| e.to_string())
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

/// Every file this process has read: no output may replace one of them, the
/// model or a file it names (a body file), whichever path or link names it.
static READ: Mutex<Vec<FileId>> = Mutex::new(Vec::new());

/// Whether the file `id` is one this process has read.
fn was_read(id: &FileId) -> bool {
    READ.lock().unwrap_or_else(std::sync::PoisonError::into_inner).contains(id)
}

/// The text of the regular file at `path`, if it has at most `limit` bytes.
/// The file is remembered as an input of this command.
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
    (&file).take(limit + 1).read_to_end(&mut bytes).map_err(ReadError::Io)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge { limit });
    }
    if let Some(id) = FileId::of_open(&file, path) {
        READ.lock().unwrap_or_else(std::sync::PoisonError::into_inner).push(id);
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
/// continues), and locks it as [`create_locked`] says. A file this process
/// has read (an input) is refused as it is opened, before anything is written
/// (the commands refuse it before the run too; this is the last word).
pub fn open_locked(path: &Path) -> Result<File, String> {
    let file =
        OpenOptions::new().read(true).write(true).create(true).truncate(false).open(path).map_err(|e| e.to_string())?;
    if FileId::of_open(&file, path).is_some_and(|id| was_read(&id)) {
        return Err(INPUT.into());
    }
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(TryLockError::WouldBlock) => Err("in use by another run (it is being written); choose another file".into()),
        Err(TryLockError::Error(e)) => Err(format!("cannot lock it: {e}")),
    }
}

/// Why an output that is an input is refused.
const INPUT: &str = "is an input of this command; it would be overwritten by an output";

/// An error, before anything is computed, when an output path names one of the
/// inputs (`inputs`: the model file, a shard to merge; and every file read so
/// far: the files the model names), whose writing would destroy what
/// the run reads, names the same file as another output, is being written by
/// another run (it holds the file's lock: a CSV being streamed), or is a place
/// no file can be created (a folder, or inside a folder that does not exist).
/// Such paths are bad input (exit 2); a write that fails later, after the run
/// (a full disk), is a failed run (exit 1).
pub fn refuse_overwrite(inputs: &[&Path], outputs: &[Option<&Path>]) -> Result<(), String> {
    let outputs: Vec<&Path> = outputs.iter().flatten().copied().collect();
    for out in &outputs {
        if out.is_dir() {
            return Err(format!("{} is a folder; an output must name a file", out.display()));
        }
        let parent = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if !parent.is_dir() {
            return Err(format!("cannot write {}: the folder {} does not exist", out.display(), parent.display()));
        }
    }
    // Only an output that exists can be an input, or locked.
    for (k, out) in outputs.iter().enumerate() {
        let Some(id) = FileId::of(out) else { continue };
        if was_read(&id) || inputs.iter().any(|input| FileId::of(input).as_ref() == Some(&id)) {
            return Err(format!("{} {INPUT}", out.display()));
        }
        if outputs[..k].iter().any(|other| FileId::of(other).as_ref() == Some(&id)) {
            return Err(format!("{} is named for two outputs of this command; give each its own file", out.display()));
        }
        if in_use(out) {
            return Err(format!("{}: in use by another run (it is being written); choose another file", out.display()));
        }
    }
    // Two outputs not yet created, spelled differently (`a.svg`, `./a.svg`).
    for (k, out) in outputs.iter().enumerate() {
        let place = |p: &Path| Some((p.parent().map(absolute_folder)?, p.file_name()?.to_owned()));
        if place(out).is_some() && outputs[..k].iter().any(|other| place(other) == place(out)) {
            return Err(format!("{} is named for two outputs of this command; give each its own file", out.display()));
        }
    }
    Ok(())
}

/// The folder `p` as the file system resolves it (`""` is the working folder).
fn absolute_folder(p: &Path) -> Option<std::path::PathBuf> {
    let p = if p.as_os_str().is_empty() { Path::new(".") } else { p };
    p.canonicalize().ok()
}

/// What makes two paths one file: on Unix its device and inode, so that a hard
/// link, a symbolic link or another spelling of a path is the same file;
/// elsewhere the path as the file system resolves it.
#[derive(Debug, Clone, PartialEq)]
enum FileId {
    #[cfg(unix)]
    Inode(u64, u64),
    #[cfg(not(unix))]
    Path(std::path::PathBuf),
}

impl FileId {
    /// The file at `path`, if it exists.
    fn of(path: &Path) -> Option<FileId> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            let meta = std::fs::metadata(path).ok()?;
            Some(FileId::Inode(meta.dev(), meta.ino()))
        }
        #[cfg(not(unix))]
        {
            path.canonicalize().ok().map(FileId::Path)
        }
    }

    /// The file `file`, open at `path`: on Unix the open file itself, so that
    /// what was read or is about to be written is the file compared.
    fn of_open(file: &File, path: &Path) -> Option<FileId> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            let _ = path;
            let meta = file.metadata().ok()?;
            Some(FileId::Inode(meta.dev(), meta.ino()))
        }
        #[cfg(not(unix))]
        {
            let _ = file;
            FileId::of(path)
        }
    }
}

/// Whether another process holds the lock of the regular file at `path` (a
/// run streaming its rows there). Opened for reading only, which neither
/// creates nor changes it; the lock taken to find out is let go at once.
fn in_use(path: &Path) -> bool {
    // A FIFO would block the open: only regular files are looked at.
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return false;
    }
    match File::open(path).map(|f| f.try_lock()) {
        Ok(Err(TryLockError::WouldBlock)) => true,
        Ok(_) | Err(_) => false,
    }
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
    fn a_hard_link_to_an_input_is_the_input_and_a_locked_output_is_refused_before_the_run() {
        let dir = std::env::temp_dir().join(format!("lagrange-links-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let model = dir.join("m.toml");
        std::fs::write(&model, "model").unwrap();
        let link = dir.join("h.csv");
        let _ = std::fs::remove_file(&link);
        std::fs::hard_link(&model, &link).unwrap();
        assert!(refuse_overwrite(&[&model], &[Some(&link)]).unwrap_err().contains("is an input"));
        let spelled = dir.join(".").join("m.toml");
        assert!(refuse_overwrite(&[&model], &[Some(&spelled)]).unwrap_err().contains("is an input"));
        // Two outputs, one file: existing or not yet.
        let a = dir.join("a.svg");
        let _ = std::fs::remove_file(&a);
        let also_a = dir.join(".").join("a.svg");
        assert!(refuse_overwrite(&[], &[Some(&a), Some(&also_a)]).unwrap_err().contains("two outputs"));
        std::fs::write(&a, "").unwrap();
        assert!(refuse_overwrite(&[], &[Some(&a), Some(&also_a)]).unwrap_err().contains("two outputs"));
        // A file another run holds.
        let streamed = dir.join("run.csv");
        std::fs::write(&streamed, "t,x\n").unwrap();
        let held = File::open(&streamed).unwrap();
        held.lock().unwrap();
        assert!(refuse_overwrite(&[&model], &[Some(&streamed)]).unwrap_err().contains("in use by another run"));
        assert!(write_whole(&streamed, b"<html>").unwrap_err().contains("in use by another run"));
        assert_eq!(std::fs::read_to_string(&streamed).unwrap(), "t,x\n");
        drop(held);
        assert!(refuse_overwrite(&[&model], &[Some(&streamed)]).is_ok());
        assert_eq!(std::fs::read_to_string(&model).unwrap(), "model");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_file_over_the_limit_is_refused() {
        // A file that stays: a file read is an input for the rest of the
        // process, and a deleted one's inode could come back as another
        // test's output.
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml");
        let len = std::fs::metadata(&path).unwrap().len();
        assert!(matches!(read_text(&path, len - 1), Err(ReadError::TooLarge { limit }) if limit == len - 1));
        assert_eq!(read_text(&path, len).unwrap().len() as u64, len);
    }

    #[test]
    fn a_file_read_is_an_input_whatever_names_it() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("src").join("main.rs");
        let text = read_text(&path, 1 << 20).unwrap();
        let spelled = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/../src/main.rs");
        assert!(refuse_overwrite(&[], &[Some(&spelled)]).unwrap_err().contains("is an input"));
        assert!(open_locked(&spelled).unwrap_err().contains("is an input"));
        assert!(write_whole(&path, b"").unwrap_err().contains("is an input"));
        assert_eq!(std::fs::read_to_string(&path).unwrap(), text, "left as it was");
    }
}
