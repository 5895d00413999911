//! Tidy checks on the source tree, like rust-analyzer's `xtask/src/tidy.rs`.
//!
//! Every Rust file under `crates/*/{src,tests,benches}` opens with a `//!` comment
//! that says what the file is for and where to enter it (see `STYLE.md`, "Files
//! and modules"). Test files and test helpers are no exception.

use crate::common::repo_root;
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

/// A crate whose tests are one binary (`autotests = false`, `tests/main.rs`) runs
/// only the files `main.rs` names: a file left out would never run, so every
/// `.rs` file and module folder of `tests/` must be named there.
#[test]
fn every_test_file_is_a_module_of_its_test_binary() {
    let root = repo_root();
    let mut checked = 0;
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(root.join("crates")).expect("crates/ exists") {
        let krate = entry.expect("a directory entry").path();
        let Ok(manifest) = std::fs::read_to_string(krate.join("Cargo.toml")) else { continue };
        if !manifest.lines().any(|line| line.trim() == "autotests = false") {
            continue;
        }
        let tests = krate.join("tests");
        let main = std::fs::read_to_string(tests.join("main.rs"))
            .unwrap_or_else(|e| panic!("{} sets autotests = false but has no tests/main.rs: {e}", krate.display()));
        let declared: Vec<&str> =
            main.lines().filter_map(|line| line.trim().strip_prefix("mod ")?.strip_suffix(';')).collect();
        for file in std::fs::read_dir(&tests).expect("tests/ exists") {
            let path = file.expect("a directory entry").path();
            let module = match path.extension() {
                Some(ext) if ext == "rs" => path.file_stem().map(|s| s.to_string_lossy().into_owned()),
                None if path.join("mod.rs").is_file() => path.file_name().map(|s| s.to_string_lossy().into_owned()),
                _ => None,
            };
            let Some(module) = module.filter(|m| m != "main") else { continue };
            checked += 1;
            if !declared.contains(&module.as_str()) {
                missing.push(path.strip_prefix(&root).unwrap_or(&path).display().to_string());
            }
        }
    }
    assert!(checked > 40, "found only {checked} test modules");
    assert!(
        missing.is_empty(),
        "not named by a `mod` line of their tests/main.rs, so never run:\n  {}",
        missing.join("\n  ")
    );
}
