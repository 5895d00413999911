//! The system C compiler as a code generator: compiles generated C
//! (`taylor/c.rs`) into a shared library for this machine, caches it per
//! source and machine, and loads it.
//!
//! Every machine that builds lagrange has a C compiler, since Rust links with
//! one. Told `-march=native`, it writes vector code at the processor's full
//! width, which cranelift cannot (128-bit vectors). Its cost is the
//! compilation, a fraction of a second, which a large ensemble wins back many
//! times and which the cache pays once per model and machine.
//!
//! Which compiler: `LAGRANGE_CC`, else `CC`, else `cc` on the `PATH`;
//! `LAGRANGE_CC=off` turns the path off (the caller falls back to
//! cranelift). Where: `LAGRANGE_CACHE_DIR`, else `$XDG_CACHE_HOME/lagrange`,
//! else `~/.cache/lagrange`, else the temporary directory (no cache then).
//!
//! A library is found again by a key that holds everything its code depends
//! on: the source, the flags, the compiler (its path, size and modification
//! time) and the processor (its model and features, as `-march=native`
//! sees them). The key is stored beside the library and compared in full, so
//! a hash collision can only cost a compilation, never load the wrong code.
//! Files appear under their final names only once complete (written aside,
//! then renamed), so processes sharing the cache never see half a library.
//!
//! The flags keep the arithmetic the interpreter's: `-ffp-contract=off`
//! (only the source's explicit multiply-adds fuse), no fast-math.
//! `-fno-math-errno` only lets `sqrt` be the instruction (it rounds
//! correctly either way).

// Loading a library and calling into it is foreign code; `CLibrary::get`
// holds the one unsafe block, and its callers hold the calls.
#![allow(unsafe_code)]

use std::hash::{Hash, Hasher};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

pub(crate) use crate::native::{CBuild, CcError};

/// The flags every source is compiled with (before the output and input).
/// The source is written in vectors already (`taylor/c.rs`), so `-O1`
/// serves: register allocation and common subexpressions are what the code
/// needs, and `-O3` would take six times as long for the same speed.
const FLAGS: &[&str] =
    &["-O1", "-march=native", "-ffp-contract=off", "-fno-math-errno", "-fno-semantic-interposition", "-fPIC"];

/// [`FLAGS`], then those of `LAGRANGE_CFLAGS` (split at white space).
fn flags() -> Vec<String> {
    let extra = std::env::var("LAGRANGE_CFLAGS").unwrap_or_default();
    FLAGS.iter().map(|f| f.to_string()).chain(extra.split_whitespace().map(str::to_string)).collect()
}

/// A loaded library; its functions live as long as it does.
pub(crate) struct CLibrary {
    library: libloading::Library,
    pub(crate) build: CBuild,
}

impl std::fmt::Debug for CLibrary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CLibrary").field("build", &self.build).finish_non_exhaustive()
    }
}

/// The function type every generated function has.
pub(crate) type PartFn = unsafe extern "C" fn(coef: *mut f64, series: *mut f64);

impl CLibrary {
    /// The generated function `name`.
    pub(crate) fn get(&self, name: &str) -> Result<PartFn, CcError> {
        // SAFETY: the library was compiled from a source this crate generated,
        // whose every exported function has the signature `PartFn`; the
        // pointer is used only while `self` (which owns the library) lives.
        unsafe {
            self.library
                .get::<PartFn>(name.as_bytes())
                .map(|f| *f)
                .map_err(|e| CcError::Io(format!("{}: {e}", self.build.library.display())))
        }
    }
}

/// The compiler to use, if any (see the module documentation).
pub fn compiler() -> Result<PathBuf, CcError> {
    let chosen = std::env::var("LAGRANGE_CC").ok().filter(|v| !v.trim().is_empty());
    if let Some(v) = &chosen {
        if matches!(v.trim(), "off" | "none" | "0") {
            return Err(CcError::NoCompiler("LAGRANGE_CC is off".into()));
        }
    }
    let name = chosen.or_else(|| std::env::var("CC").ok().filter(|v| !v.trim().is_empty())).unwrap_or("cc".into());
    let name = name.trim();
    let path = Path::new(name);
    if path.components().count() > 1 {
        return if path.is_file() {
            Ok(path.to_path_buf())
        } else {
            Err(CcError::NoCompiler(format!("{name} is not a file")))
        };
    }
    std::env::var_os("PATH")
        .and_then(|paths| std::env::split_paths(&paths).map(|d| d.join(name)).find(|p| p.is_file()))
        .ok_or_else(|| CcError::NoCompiler(format!("{name} is not on the PATH")))
}

/// The directory of cached libraries, made if missing.
fn cache_dir() -> PathBuf {
    let base = std::env::var_os("LAGRANGE_CACHE_DIR")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("XDG_CACHE_HOME").map(|d| PathBuf::from(d).join("lagrange")))
        .or_else(|| std::env::var_os("HOME").map(|d| PathBuf::from(d).join(".cache").join("lagrange")));
    let dir = base.map(|b| b.join("native"));
    match dir {
        Some(d) if std::fs::create_dir_all(&d).is_ok() => d,
        _ => std::env::temp_dir(),
    }
}

/// What `-march=native` depends on: the processor's model and features.
fn machine() -> String {
    let mut id = format!("{} {}", std::env::consts::ARCH, std::env::consts::OS);
    if let Ok(info) = std::fs::read_to_string("/proc/cpuinfo") {
        for key in ["vendor_id", "model name", "flags", "Features", "CPU part"] {
            if let Some(line) = info.lines().find(|l| l.split(':').next().is_some_and(|k| k.trim() == key)) {
                id.push('\n');
                id.push_str(line);
            }
        }
    }
    id
}

/// The compiler's identity without running it: its path, size and time.
fn compiler_identity(cc: &Path) -> String {
    let meta = std::fs::metadata(cc).ok();
    let modified = meta.as_ref().and_then(|m| m.modified().ok()).map(|t| format!("{t:?}")).unwrap_or_default();
    format!("{} {} {modified}", cc.display(), meta.map_or(0, |m| m.len()))
}

/// A file name from the key: 128 bits of two seeded hashes (the key file
/// settles collisions).
fn stem(key: &str) -> String {
    let hash = |seed: u64| {
        let mut h = rustc_hash::FxHasher::default();
        seed.hash(&mut h);
        key.hash(&mut h);
        h.finish()
    };
    format!("lagrange-{:016x}{:016x}", hash(0x9e37_79b9_7f4a_7c15), hash(0xc2b2_ae3d_27d4_eb4f))
}

/// Compiles the files of one library with the system compiler, side by side
/// (or finds the library in the cache), and loads it.
pub(crate) fn build(files: &[String]) -> Result<CLibrary, CcError> {
    let source = files.join("\n/* next file */\n");
    let start = Instant::now();
    let cc = compiler()?;
    let flags = flags();
    let key = format!("{}\n{}\n{}\n{source}", compiler_identity(&cc), flags.join(" "), machine());
    let dir = cache_dir();
    let stem = stem(&key);
    let library = dir.join(format!("{stem}.{}", std::env::consts::DLL_EXTENSION));
    let key_file = dir.join(format!("{stem}.key"));
    let cached = std::fs::read_to_string(&key_file).is_ok_and(|k| k == key) && library.is_file();
    if !cached {
        compile(&cc, &flags, files, &dir, &stem, &library)?;
        write_atomically(&dir, &key_file, key.as_bytes())?;
    }
    // SAFETY: loading runs the library's initializers; ours has none (it is
    // plain C with no constructors), compiled from a source we generated.
    let loaded = unsafe { libloading::Library::new(&library) }
        .map_err(|e| CcError::Io(format!("cannot load {}: {e}", library.display())))?;
    let build = CBuild { compiler: cc, library, seconds: start.elapsed().as_secs_f64(), cached };
    Ok(CLibrary { library: loaded, build })
}

/// A name for a file being written, unique to this process and call.
fn scratch_name(dir: &Path, stem: &str, ext: &str) -> PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    dir.join(format!("{stem}.{}-{n}.tmp.{ext}", std::process::id()))
}

fn compile(
    cc: &Path,
    flags: &[String],
    files: &[String],
    dir: &Path,
    stem: &str,
    library: &Path,
) -> Result<(), CcError> {
    let io = |what: &str, p: &Path, e: std::io::Error| CcError::Io(format!("cannot {what} {}: {e}", p.display()));
    let out = scratch_name(dir, stem, std::env::consts::DLL_EXTENSION);
    let mut scratch = Vec::new();
    let result = (|| {
        let sources: Vec<PathBuf> = files
            .iter()
            .map(|text| {
                let src = scratch_name(dir, stem, "c");
                scratch.push(src.clone());
                std::fs::write(&src, text).map(|()| src.clone()).map_err(|e| io("write", &src, e))
            })
            .collect::<Result<_, _>>()?;
        if let [one] = sources.as_slice() {
            return run(Command::new(cc).args(flags).arg("-shared").arg("-o").arg(&out).arg(one).arg("-lm"), cc);
        }
        // One object per file, compiled side by side, then linked.
        let objects: Vec<PathBuf> = sources.iter().map(|s| s.with_extension("o")).collect();
        scratch.extend(objects.iter().cloned());
        std::thread::scope(|scope| {
            let jobs: Vec<_> = sources
                .iter()
                .zip(&objects)
                .map(|(src, obj)| {
                    scope.spawn(move || run(Command::new(cc).args(flags).arg("-c").arg("-o").arg(obj).arg(src), cc))
                })
                .collect();
            jobs.into_iter().try_for_each(|j| {
                j.join().unwrap_or_else(|_| Err(CcError::Failed("a compiler thread panicked".into())))
            })
        })?;
        run(Command::new(cc).args(flags).arg("-shared").arg("-o").arg(&out).args(&objects).arg("-lm"), cc)
    })();
    for f in scratch {
        let _ = std::fs::remove_file(f);
    }
    if let Err(e) = result {
        let _ = std::fs::remove_file(&out);
        return Err(e);
    }
    std::fs::rename(&out, library).map_err(|e| {
        let _ = std::fs::remove_file(&out);
        io("move into place", library, e)
    })
}

/// Runs one compiler command; its error output's last lines on failure.
fn run(command: &mut Command, cc: &Path) -> Result<(), CcError> {
    let output = command.output().map_err(|e| CcError::NoCompiler(format!("cannot run {}: {e}", cc.display())))?;
    if output.status.success() {
        return Ok(());
    }
    let text = String::from_utf8_lossy(&output.stderr);
    let lines: Vec<&str> = text.lines().collect();
    let tail = lines[lines.len().saturating_sub(6)..].join("\n");
    let tail = if tail.trim().is_empty() { String::new() } else { format!(": {tail}") };
    Err(CcError::Failed(format!("{} exited with {}{tail}", cc.display(), output.status)))
}

fn write_atomically(dir: &Path, path: &Path, bytes: &[u8]) -> Result<(), CcError> {
    let tmp = scratch_name(dir, "key", "txt");
    let written = std::fs::File::create(&tmp).and_then(|mut f| f.write_all(bytes));
    written.and_then(|()| std::fs::rename(&tmp, path)).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        CcError::Io(format!("cannot write {}: {e}", path.display()))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_name_distinct_files() {
        assert_ne!(stem("a"), stem("b"));
        assert_eq!(stem("a"), stem("a"));
        assert!(machine().contains(std::env::consts::ARCH));
    }
}
