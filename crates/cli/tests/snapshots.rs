//! Snapshots of what `lagrange derive` prints: the text output of every model in
//! `examples/`, and the exit code and message of every broken model in `tests/bad/`.
//!
//! Each snapshot holds the exit code, stdout and stderr of one run of the real
//! binary, started in the repository root with a relative path, so the snapshots do
//! not depend on where the repository is checked out. Review a change with
//! `git diff crates/cli/tests/snapshots`; accept it by regenerating:
//!
//! ```text
//! INSTA_UPDATE=always cargo test -p lagrange-cli --test cli snapshots::
//! ```
//!
//! A new example or bad model gets its snapshot the same way; a snapshot whose model
//! is gone fails `no_orphan_snapshots`.

use crate::common::{repo_root, run};
use std::path::Path;

/// The `.toml` files of a folder (relative to the repository root), sorted by name.
fn models(dir: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(repo_root().join(dir))
        .unwrap_or_else(|e| panic!("cannot list {dir}: {e}"))
        .map(|entry| entry.expect("a directory entry").file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".toml"))
        .collect();
    names.sort();
    names
}

/// Runs `lagrange ARGS` in the repository root; exit code, stdout and stderr as one text.
fn snapshot(args: &[&str]) -> String {
    let root = repo_root().display().to_string();
    let r = run(args);
    let code = r.code.map_or_else(|| "killed by a signal".to_string(), |c| c.to_string());
    let normalize = |text: &str| text.replace(&root, "[ROOT]");
    format!(
        "exit code: {code}\n----- stdout -----\n{}----- stderr -----\n{}",
        normalize(&r.stdout),
        normalize(&r.stderr)
    )
}

/// Checks one snapshot per model, and reports every mismatch rather than the first.
fn check_all(dir: &str, prefix: &str, extra_args: &[&str]) {
    let files = models(dir);
    assert!(!files.is_empty(), "{dir} has no models");
    let mut failed = Vec::new();
    for file in &files {
        let path = format!("{dir}/{file}");
        let mut args = vec!["derive", path.as_str()];
        args.extend_from_slice(extra_args);
        let output = snapshot(&args);
        // Named in full (`snapshots__derive__pendulum`), not after the module path,
        // which depends on how the test binary is laid out.
        let name = format!("snapshots__{prefix}{}", file.trim_end_matches(".toml"));
        let result = std::panic::catch_unwind(|| {
            insta::with_settings!({
                description => format!("lagrange {}", args.join(" ")),
                omit_expression => true,
                prepend_module_to_snapshot => false,
            }, {
                insta::assert_snapshot!(name, output);
            });
        });
        if result.is_err() {
            failed.push(path);
        }
    }
    assert!(failed.is_empty(), "snapshots differ for: {}", failed.join(", "));
}

#[test]
fn derive_examples() {
    check_all("examples", "derive__", &[]);
}

#[test]
fn bad_models() {
    check_all("crates/cli/tests/bad", "bad__", &[]);
}

/// Every snapshot file belongs to a model that still exists.
#[test]
fn no_orphan_snapshots() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots");
    let examples = models("examples");
    let bad = models("crates/cli/tests/bad");
    let Ok(entries) = std::fs::read_dir(&dir) else { return };
    let mut orphans = Vec::new();
    for entry in entries {
        let file = entry.expect("a directory entry").file_name().to_string_lossy().into_owned();
        let Some(stem) = file.strip_prefix("snapshots__").and_then(|f| f.strip_suffix(".snap")) else { continue };
        let known = match stem.split_once("__") {
            Some(("derive", model)) => examples.contains(&format!("{model}.toml")),
            Some(("bad", model)) => bad.contains(&format!("{model}.toml")),
            _ => false,
        };
        if !known {
            orphans.push(file);
        }
    }
    assert!(orphans.is_empty(), "snapshots without a model (delete them): {}", orphans.join(", "));
}
