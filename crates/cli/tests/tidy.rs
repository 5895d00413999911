//! Tidy checks on the source tree, like rust-analyzer's `xtask/src/tidy.rs`.
//!
//! Every Rust file under `crates/*/{src,tests,benches}` opens with a `//!` comment
//! that says what the file is for and where to enter it (see `STYLE.md`, "Files
//! and modules"). Test files and test helpers are no exception.

mod common;

use common::repo_root;
use std::path::{Path, PathBuf};

/// The folders of each crate whose Rust files are checked.
const CHECKED_DIRS: &[&str] = &["src", "tests", "benches"];

/// Every `.rs` file under `dir`, recursively, in a stable order.
fn rust_files(dir: &Path, files: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<PathBuf> = entries.map(|e| e.expect("a directory entry").path()).collect();
    paths.sort();
    for path in paths {
        if path.is_dir() {
            rust_files(&path, files);
        } else if path.extension().is_some_and(|ext| ext == "rs") {
            files.push(path);
        }
    }
}

#[test]
fn every_file_opens_with_a_module_doc_comment() {
    let root = repo_root();
    let mut crates: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .expect("crates/ exists")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .collect();
    crates.sort();
    assert!(crates.len() >= 4, "expected the workspace's crates under crates/, found {crates:?}");

    let mut files = Vec::new();
    for krate in &crates {
        for dir in CHECKED_DIRS {
            rust_files(&krate.join(dir), &mut files);
        }
    }
    assert!(files.len() > 20, "found only {} Rust files", files.len());

    let missing: Vec<String> = files
        .iter()
        .filter(|path| {
            let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
            !text.starts_with("//!")
        })
        .map(|path| path.strip_prefix(&root).unwrap_or(path).display().to_string())
        .collect();
    assert!(
        missing.is_empty(),
        "these files do not open with a `//!` comment saying what they are for:\n  {}",
        missing.join("\n  ")
    );
}
