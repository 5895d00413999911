//! The stages of `mech` form a one-way pipeline: each top-level module uses
//! only the modules of the groups declared above its own in `lib.rs` (model →
//! derive → run → analyses, with the shared leaves first). This test reads the sources and
//! fails on any `crate::` path that points at the same level or upward, so
//! that a module cycle cannot come back unnoticed.
//!
//! Below every front end, `mech` also speaks none of their words: no flag
//! (`--dt`) and no command (`lagrange derive`) in its messages. What a user
//! should change comes back as data (`RunWarning`) that the front end words.

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The top-level modules of `lib.rs`, each with the rank of its group: groups
/// are runs of `mod` lines separated by comment lines, in the order of the file.
fn stages(lib: &str) -> Vec<(String, usize)> {
    let mut group = 0;
    let mut in_group = false;
    let mut stages = Vec::new();
    for line in lib.lines().map(str::trim) {
        let declared =
            line.strip_prefix("pub mod ").or_else(|| line.strip_prefix("mod ")).and_then(|r| r.strip_suffix(';'));
        match declared {
            Some(name) => {
                stages.push((name.to_string(), group));
                in_group = true;
            }
            None if line.starts_with("//") && !line.starts_with("//!") && in_group => {
                group += 1;
                in_group = false;
            }
            None => {}
        }
    }
    stages
}

/// The names `lib.rs` re-exports, each with the top-level module it comes from,
/// so that `crate::Derivation` counts as a use of `derive`.
fn reexports(lib: &str) -> HashMap<String, String> {
    let mut map = HashMap::new();
    let flat = lib.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join(" ");
    for stmt in flat.split(';') {
        let Some(path) = stmt.trim().strip_prefix("pub use ") else { continue };
        let module = path.split("::").next().unwrap_or_default().trim().to_string();
        let names = match (path.find('{'), path.rfind('}')) {
            (Some(a), Some(b)) => path[a + 1..b].to_string(),
            _ => path.rsplit("::").next().unwrap_or_default().to_string(),
        };
        for name in names.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            map.insert(name.to_string(), module.clone());
        }
    }
    map
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level modules a source text names through `crate::`, comments and
/// the unit tests at the end of a file (`#[cfg(test)] mod tests`, which may run
/// the whole pipeline) left out.
fn uses(text: &str, reexports: &HashMap<String, String>) -> Vec<String> {
    let code = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    let mut found = Vec::new();
    for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
        let mut rest = line;
        while let Some(at) = rest.find("crate::") {
            rest = &rest[at + "crate::".len()..];
            let items: Vec<&str> = match rest.strip_prefix('{') {
                Some(group) => group.split('}').next().unwrap_or_default().split(',').collect(),
                None => vec![rest],
            };
            for item in items {
                let ident: String =
                    item.trim().chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
                if ident.is_empty() {
                    continue;
                }
                found.push(reexports.get(&ident).cloned().unwrap_or(ident));
            }
        }
    }
    found
}

#[test]
fn every_stage_uses_only_the_stages_before_it() {
    let lib = fs::read_to_string(src().join("lib.rs")).unwrap();
    let order = stages(&lib);
    let reexports = reexports(&lib);
    let rank = |m: &str| order.iter().find(|(s, _)| s == m).map(|&(_, r)| r);
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut wrong = Vec::new();
    for file in &files {
        let rel = file.strip_prefix(src()).unwrap();
        let top = rel.components().next().unwrap().as_os_str().to_string_lossy().trim_end_matches(".rs").to_string();
        if top == "lib" {
            continue;
        }
        let own = rank(&top).unwrap_or_else(|| panic!("{} is not declared in lib.rs", rel.display()));
        let text = fs::read_to_string(file).unwrap();
        for used in uses(&text, &reexports) {
            match rank(&used) {
                Some(r) if r < own || used == top => {}
                Some(_) => wrong.push(format!("{} uses `{used}`, a later stage", rel.display())),
                None => wrong.push(format!(
                    "{} names `crate::{used}`, which lib.rs neither declares nor re-exports",
                    rel.display()
                )),
            }
        }
    }
    assert!(wrong.is_empty(), "the stages of mech must form a one-way pipeline:\n{}", wrong.join("\n"));
}

#[test]
fn the_checker_sees_uses_in_groups_and_through_reexports() {
    let reexports = HashMap::from([("Derivation".to_string(), "derive".to_string())]);
    let text =
        "use crate::{Derivation, model::Model};\n// crate::run in a comment\nlet x = crate::probe::is_zero(p, e);";
    assert_eq!(uses(text, &reexports), ["derive", "model", "probe"]);
}

/// Where a line of library code names a front end's flag or command.
fn front_end_words(line: &str) -> Option<&'static str> {
    let code = line.trim_start();
    if code.starts_with("//") || !code.contains('"') {
        return None;
    }
    let flag = line.match_indices("--").any(|(i, _)| line[i + 2..].starts_with(|c: char| c.is_ascii_lowercase()));
    if flag {
        Some("a flag")
    } else if line.contains("`lagrange ") {
        Some("a command")
    } else {
        None
    }
}

#[test]
fn the_library_names_no_flag_or_command_of_a_front_end() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut found = Vec::new();
    for path in files {
        let text = fs::read_to_string(&path).unwrap();
        let library = text.split("#[cfg(test)]").next().unwrap_or("");
        for (k, line) in library.lines().enumerate() {
            if let Some(what) = front_end_words(line) {
                found.push(format!("{}:{}: {what}: {}", path.display(), k + 1, line.trim()));
            }
        }
    }
    assert!(found.is_empty(), "library messages in front-end words:\n{}", found.join("\n"));
    assert_eq!(front_end_words(r#"    "give a smaller --dt","#), Some("a flag"));
    assert_eq!(front_end_words(r#"    .with_help("use `lagrange derive`")"#), Some("a command"));
    assert_eq!(front_end_words("    // see --dt"), None);
    assert_eq!(front_end_words(r#"    format!("{a} -- {b}")"#), None);
}
