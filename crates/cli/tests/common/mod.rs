//! What the integration tests share: running the real `lagrange` binary in the
//! repository root ([`run`], [`ok`], [`json`]), reading the CSV of a run
//! ([`Csv`]), temporary files ([`TempFile`], [`scratch`]), and comparing
//! numbers ([`is_close`], [`close`]).
//!
//! Include it with `mod common;` in a test file and use what it needs.

// Each test file uses a part of it.
#![allow(dead_code)]

pub mod html;

use serde_json::Value;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::thread;
use std::time::{Duration, Instant};

/// No run of the binary in the tests takes near this long; the limit only turns
/// a hang into a failure.
const TIMEOUT: Duration = Duration::from_secs(300);

/// The repository root (examples are named relative to it).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("the repository root exists")
}

/// Exit code, output and arguments of one run of the binary.
pub struct Run {
    /// The exit code; `None` when a signal ended the process.
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

    /// Stdout parsed as JSON.
    #[track_caller]
    pub fn json(&self) -> Value {
        serde_json::from_str(&self.stdout).unwrap_or_else(|e| panic!("stdout is not JSON ({e}):\n{}", self.describe()))
    }
}

/// Starts `lagrange ARGS` in the repository root, with stdout and stderr piped.
pub fn start(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_lagrange"))
        .args(args)
        .current_dir(repo_root())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start lagrange {args:?}: {e}"))
}

/// Runs `lagrange ARGS` in the repository root, reading stdout and stderr while
/// it runs, and fails the test when it runs past [`TIMEOUT`].
pub fn run(args: &[&str]) -> Run {
    let mut child = start(args);
    let read = |mut pipe: Box<dyn Read + Send>| {
        thread::spawn(move || {
            let mut buf = Vec::new();
            let _ = pipe.read_to_end(&mut buf);
            String::from_utf8_lossy(&buf).into_owned()
        })
    };
    let stdout = read(Box::new(child.stdout.take().expect("stdout is piped")));
    let stderr = read(Box::new(child.stderr.take().expect("stderr is piped")));
    let start = Instant::now();
    let status = loop {
        match child.try_wait().expect("wait for lagrange") {
            Some(status) => break Some(status),
            None if start.elapsed() > TIMEOUT => {
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
            None => thread::sleep(Duration::from_millis(5)),
        }
    };
    let run = Run {
        code: status.and_then(|s| s.code()),
        stdout: stdout.join().expect("stdout reader"),
        stderr: stderr.join().expect("stderr reader"),
        args: args.iter().map(|s| s.to_string()).collect(),
    };
    assert!(status.is_some(), "ran past {TIMEOUT:?}: {}", run.describe());
    run
}

/// `lagrange ARGS`, which must exit with code 0.
#[track_caller]
pub fn ok(args: &[&str]) -> Run {
    let r = run(args);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    r
}

/// `lagrange ARGS`, which must exit with code 0; its stdout as JSON.
#[track_caller]
pub fn json(args: &[&str]) -> Value {
    ok(args).json()
}

/// The CSV a run wrote: the header and the rows, every value a number.
pub struct Csv {
    pub header: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Csv {
    pub fn read(path: &str) -> Csv {
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("cannot read the CSV {path}: {e}"));
        let mut lines = text.lines();
        let header: Vec<String> = lines.next().expect("a header row").split(',').map(str::to_string).collect();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| {
                let row: Vec<f64> = l
                    .split(',')
                    .map(|v| v.parse::<f64>().unwrap_or_else(|e| panic!("CSV value `{v}` in row `{l}`: {e}")))
                    .collect();
                assert_eq!(row.len(), header.len(), "row `{l}` has {} values for {} columns", row.len(), header.len());
                row
            })
            .collect();
        Csv { header, rows }
    }

    /// The index of column `name`.
    pub fn col(&self, name: &str) -> usize {
        self.header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column `{name}` in {:?}", self.header))
    }

    /// Column `name`'s values.
    pub fn column(&self, name: &str) -> Vec<f64> {
        let k = self.col(name);
        self.rows.iter().map(|r| r[k]).collect()
    }
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

/// `name` in a temporary folder of this test process (`tag` names the test
/// file), for files that stay for the rest of the run.
pub fn scratch(tag: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lagrange-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    dir.join(name)
}

/// Whether |got − want| ≤ rel·max(|want|, floor): `rel` relative to the value
/// wanted, and to `floor` where that value is smaller.
pub fn is_close(got: f64, want: f64, rel: f64, floor: f64) -> bool {
    (got - want).abs() <= rel * want.abs().max(floor)
}

/// Asserts [`is_close`] with a floor of 1e-12 (for want = 0).
#[track_caller]
pub fn close(got: f64, want: f64, rel: f64) {
    assert!(is_close(got, want, rel, 1e-12), "got {got}, want {want}");
}
