//! No crate of the workspace has a module cycle: among the children of any
//! module (the top-level modules of a crate, the files of a folder), none uses
//! one that uses it back, directly or around a longer loop. A module's own
//! children are its business; what is checked is between siblings, which is
//! where a cycle makes two files one concept that cannot be read alone.
//!
//! Uses are the `crate::` and `super::` paths of the code (comments and the
//! unit tests at the end of a file left out), resolved to the longest module
//! they name; a name a module re-exports (`crate::Tape`, `super::RunError`)
//! counts as a use of the module it comes from.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fs;
use std::path::{Path, PathBuf};

/// A module by its path from the crate root (`["taylor", "program"]`).
type Module = Vec<String>;

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

/// The module a source file is (`lib.rs` and `main.rs` are the root).
fn module_of(src: &Path, file: &Path) -> Module {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    if parts == ["lib"] || parts == ["main"] {
        parts.clear();
    }
    parts
}

/// The code of a file: no comment lines, no unit tests at its end.
fn code(text: &str) -> String {
    let text = text.find("#[cfg(test)]\nmod tests").map_or(text, |at| &text[..at]);
    text.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n")
}

/// The names `own`'s code re-exports (`pub use eval::{EvalError, Tape};`,
/// `pub(crate) use report::conclude;`), each as its path through `own` with
/// the path it stands for, from the crate root.
fn reexports(own: &Module, code: &str) -> Vec<(Vec<String>, Vec<String>)> {
    let mut found = Vec::new();
    for stmt in code.split(';') {
        let stmt = stmt.trim();
        let Some(path) = ["pub use ", "pub(crate) use ", "pub(super) use "].iter().find_map(|p| stmt.strip_prefix(p))
        else {
            continue;
        };
        // A path without `crate::` or `super::` starts at `own` (a child's name).
        let absolute = if path.starts_with("crate::") || path.starts_with("super::") {
            path.to_string()
        } else {
            format!("crate::{}{path}", own.iter().map(|m| format!("{m}::")).collect::<String>())
        };
        for target in paths(own, &absolute) {
            let name = target.last().cloned().unwrap_or_default();
            let name = name.rsplit(" as ").next().unwrap_or_default().trim().to_string();
            if !name.is_empty() && name != "*" && name != "self" {
                let mut via = own.clone();
                via.push(name);
                found.push((via, target));
            }
        }
    }
    found
}

/// Every path a use or an expression names from `crate::` or `super::`, as
/// segments from the crate root (a group `a::{b, c::d}` gives `a::b` and `a::c::d`).
fn paths(own: &Module, code: &str) -> Vec<Vec<String>> {
    let mut found = Vec::new();
    let bytes = code.as_bytes();
    for start in ["crate::", "super::"] {
        let mut from = 0;
        while let Some(at) = code[from..].find(start).map(|a| a + from) {
            from = at + start.len();
            // Only the start of a path: not `xsuper::` nor `crate::super::`'s second half.
            if at > 0 && (bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_' || bytes[at - 1] == b':') {
                continue;
            }
            let mut base: Module = Vec::new();
            let mut rest = &code[at..];
            if let Some(r) = rest.strip_prefix("crate::") {
                rest = r;
            } else {
                let mut up = 0;
                while let Some(r) = rest.strip_prefix("super::") {
                    up += 1;
                    rest = r;
                }
                base = own[..own.len().saturating_sub(up)].to_vec();
            }
            let head: String =
                rest.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':').collect();
            let head: Vec<String> = head.split("::").filter(|s| !s.is_empty()).map(String::from).collect();
            let after = &rest[head.iter().map(|s| s.len() + 2).sum::<usize>().min(rest.len())..];
            let mut prefix = base.clone();
            prefix.extend(head);
            match after.strip_prefix('{') {
                Some(group) => {
                    for item in group.split('}').next().unwrap_or_default().split(',') {
                        let mut path = prefix.clone();
                        path.extend(item.trim().split("::").map(|s| s.trim().to_string()).filter(|s| !s.is_empty()));
                        found.push(path);
                    }
                }
                None => found.push(prefix),
            }
        }
    }
    found
}

/// The cycles among the children of each module of the crate at `src`, as
/// loops of sibling names under their parent.
fn cycles(src: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeMap<Module, PathBuf> = files.iter().map(|f| (module_of(src, f), f.clone())).collect();
    let codes: BTreeMap<&Module, String> =
        modules.iter().map(|(m, f)| (m, code(&fs::read_to_string(f).unwrap()))).collect();
    let reexported: HashMap<Vec<String>, Vec<String>> =
        codes.iter().flat_map(|(own, code)| reexports(own, code)).collect();
    // Each use, as (module, module used): a re-exported name stands for what it
    // re-exports (followed a few times: a name may be re-exported twice), and
    // a path for the longest module it names.
    let mut edges = BTreeSet::new();
    for (own, code) in &codes {
        let own = *own;
        for mut path in paths(own, code) {
            for _ in 0..4 {
                match (1..=path.len()).rev().find_map(|k| reexported.get(&path[..k]).map(|to| (k, to))) {
                    Some((k, to)) if to[..] != path[..k] => {
                        let mut next = to.clone();
                        next.extend_from_slice(&path[k..]);
                        path = next;
                    }
                    _ => break,
                }
            }
            let target = (1..=path.len()).rev().map(|k| path[..k].to_vec()).find(|m| modules.contains_key(m));
            if let Some(target) = target.filter(|t| t != own) {
                edges.insert((own.clone(), target));
            }
        }
    }
    let mut found = Vec::new();
    let parents: BTreeSet<Module> =
        modules.keys().filter(|m| !m.is_empty()).map(|m| m[..m.len() - 1].to_vec()).collect();
    for parent in parents {
        let depth = parent.len();
        let child = |m: &Module| (m.len() > depth && m[..depth] == parent[..]).then(|| m[depth].clone());
        let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (a, b) in &edges {
            if let (Some(x), Some(y)) = (child(a), child(b)) {
                if x != y {
                    graph.entry(x).or_default().insert(y);
                }
            }
        }
        // Depth-first search; a node on the stack reached again closes a loop.
        fn visit(
            v: &str,
            graph: &BTreeMap<String, BTreeSet<String>>,
            done: &mut BTreeSet<String>,
            stack: &mut Vec<String>,
            out: &mut Vec<Vec<String>>,
        ) {
            if let Some(at) = stack.iter().position(|s| s == v) {
                let mut cycle = stack[at..].to_vec();
                cycle.push(v.to_string());
                out.push(cycle);
                return;
            }
            if done.contains(v) {
                return;
            }
            stack.push(v.to_string());
            for w in graph.get(v).into_iter().flatten() {
                visit(w, graph, done, stack, out);
            }
            stack.pop();
            done.insert(v.to_string());
        }
        let (mut done, mut loops) = (BTreeSet::new(), Vec::new());
        for v in graph.keys() {
            visit(v, &graph, &mut done, &mut Vec::new(), &mut loops);
        }
        let under = if parent.is_empty() { "the crate root".to_string() } else { parent.join("::") };
        found.extend(loops.into_iter().map(|l| format!("under {under}: {}", l.join(" → "))));
    }
    found
}

#[test]
fn no_crate_of_the_workspace_has_a_module_cycle() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut checked = 0;
    let mut wrong = Vec::new();
    for entry in fs::read_dir(crates).unwrap() {
        let src = entry.unwrap().path().join("src");
        if src.is_dir() {
            checked += 1;
            wrong.extend(cycles(&src).into_iter().map(|c| format!("{}: {c}", src.display())));
        }
    }
    assert!(checked >= 8, "{checked} crates found in {}", crates.display());
    assert!(wrong.is_empty(), "module cycles:\n{}", wrong.join("\n"));
}

#[test]
fn the_checker_finds_a_cycle_through_a_group_a_reexport_and_super() {
    let dir = std::env::temp_dir().join(format!("lagrange-cycles-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(dir.join("b")).unwrap();
    fs::write(dir.join("lib.rs"), "mod a;\nmod b;\npub use a::{Thing, Other};\n").unwrap();
    fs::write(dir.join("a.rs"), "// crate::b in a comment is no use\npub struct Thing;\npub struct Other;\n").unwrap();
    fs::write(dir.join("b/mod.rs"), "mod x;\nmod y;\n").unwrap();
    fs::write(dir.join("b/x.rs"), "use super::y::Y;\npub struct X;\n").unwrap();
    fs::write(dir.join("b/y.rs"), "pub struct Y;\n").unwrap();
    assert!(cycles(&dir).is_empty(), "{:?}", cycles(&dir));
    // y uses x back, through a group: a loop under b.
    fs::write(dir.join("b/y.rs"), "use crate::b::{x::X, y};\npub struct Y;\n").unwrap();
    assert_eq!(cycles(&dir), ["under b: x → y → x"]);
    // y uses x back through b's re-export of X.
    fs::write(dir.join("b/mod.rs"), "mod x;\nmod y;\npub(crate) use x::X;\n").unwrap();
    fs::write(dir.join("b/y.rs"), "pub struct Y(super::X);\n").unwrap();
    assert_eq!(cycles(&dir), ["under b: x → y → x"]);
    fs::write(dir.join("b/mod.rs"), "mod x;\nmod y;\n").unwrap();
    fs::write(dir.join("b/y.rs"), "pub struct Y;\n").unwrap();
    // a uses b, and b uses a through the root's re-export of Thing.
    fs::write(dir.join("a.rs"), "pub struct Thing(crate::b::Z);\npub struct Other;\n").unwrap();
    fs::write(dir.join("b/mod.rs"), "mod x;\nmod y;\npub struct Z(crate::Thing);\n").unwrap();
    assert_eq!(cycles(&dir), ["under the crate root: a → b → a"]);
    let _ = fs::remove_dir_all(&dir);
}
