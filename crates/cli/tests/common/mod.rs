//! What the integration tests share: running the real `lagrange` binary in the
//! repository root, and comparing numbers with a relative tolerance.

// Each test file uses a part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The repository root (examples are named relative to it).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("the repository root exists")
}

/// Exit code, output and arguments of one run of the binary.
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    pub args: Vec<String>,
}

impl Run {
    /// The command and all it printed, for assertion messages.
    pub fn describe(&self) -> String {
        format!(
            "lagrange {}\nexit code {:?}\n--- stdout ---\n{}\n--- stderr ---\n{}",
            self.args.join(" "),
            self.code,
            self.stdout,
            self.stderr
        )
    }
}

/// Runs `lagrange ARGS` in the repository root.
pub fn run(args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_lagrange"))
        .args(args)
        .current_dir(repo_root())
        .output()
        .unwrap_or_else(|e| panic!("cannot start lagrange {args:?}: {e}"));
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        args: args.iter().map(|s| s.to_string()).collect(),
    }
}

/// Exit code (−1 when killed), stdout and stderr of `lagrange ARGS` run in the repository root.
pub fn lagrange(args: &[&str]) -> (i32, String, String) {
    let r = run(args);
    (r.code.unwrap_or(-1), r.stdout, r.stderr)
}

/// A temporary file, unique per process and call, removed when dropped.
pub struct TempFile(pub PathBuf);

impl TempFile {
    pub fn new(tag: &str, ext: &str) -> TempFile {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let k = COUNTER.fetch_add(1, Ordering::Relaxed);
        TempFile(std::env::temp_dir().join(format!("lagrange-test-{}-{k}-{tag}.{ext}", std::process::id())))
    }

    /// A model file holding `text`.
    pub fn with_text(tag: &str, text: &str) -> TempFile {
        let f = TempFile::new(tag, "toml");
        std::fs::write(&f.0, text).expect("write a model");
        f
    }

    pub fn path(&self) -> &str {
        self.0.to_str().expect("temporary paths are UTF-8")
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// |got − want| ≤ rel·|want| (with a floor for want = 0).
#[track_caller]
pub fn close(got: f64, want: f64, rel: f64) {
    assert!((got - want).abs() <= rel * want.abs().max(1e-12), "got {got}, want {want}");
}
