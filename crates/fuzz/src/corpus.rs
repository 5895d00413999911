//! The seed corpus: every model, body and problem file of `examples/` and the
//! broken models of `crates/cli/tests/bad*/`, and the expression strings inside
//! them. Enter with [`Corpus::load`] (from the repository) or
//! [`Corpus::from_files`].

use std::path::{Path, PathBuf};

/// Which loader reads a TOML file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A model file (`Model::parse`).
    Model,
    /// A body file of parts (`inertia::BodyFile::parse`).
    Body,
    /// A variational problem (`Problem::parse`).
    Problem,
}

impl FileKind {
    /// The kind of a file by what it holds: `[[parts]]` is a body file,
    /// `integrand` a problem, anything else a model.
    pub fn of(text: &str) -> FileKind {
        if text.contains("[[parts]]") {
            FileKind::Body
        } else if text.contains("integrand") {
            FileKind::Problem
        } else {
            FileKind::Model
        }
    }
}

/// A seed: a file's name (relative to the repository) and its text.
#[derive(Clone, Debug)]
pub struct Seed {
    /// Where it came from, e.g. `examples/pendulum.toml`.
    pub name: String,
    /// Its text.
    pub text: String,
    /// Which loader reads it.
    pub kind: FileKind,
}

/// The seeds of every target.
#[derive(Clone, Debug, Default)]
pub struct Corpus {
    /// TOML files: models, body files, problems (valid and broken).
    pub files: Vec<Seed>,
    /// Expression texts: every string value of the TOML files and [`EXPRESSIONS`].
    pub expressions: Vec<String>,
}

/// Expressions beside those of the files: the corners of the language.
pub const EXPRESSIONS: &[&str] = &[
    "m*l^2*q'^2/2 + m*g*l*cos(q)",
    "-x^2",
    "2^-1",
    "x^-y^2",
    "x**-1",
    "a/b/c",
    "atan2(y, x)",
    "sqrt(1 + x^2)",
    "ln(2)",
    "1e-3*x''",
    "p_q*q' - t",
    "(-2)^127",
    "1/(-64)^171",
    "(x^10)^100",
    "0*exp(1000)",
    "abs(x)*tanh(y)/cosh(z)",
    "asin(1/2) + acos(0) + atan(1)",
    "9223372036854775807*x",
    "170141183460469231731687303715884105727",
    "0.1 + 0.2",
    "1e308*10",
    "x^(1/3)",
    "(x*y^2)^600",
];

/// The folders, relative to the repository, whose `.toml` files are seeds.
pub const SEED_DIRS: &[&str] = &["examples", "crates/cli/tests/bad", "crates/cli/tests/bad_simulate"];

/// Folders of [`SEED_DIRS`] left out: the benchmark bicycle (four bodies, two
/// rolling wheels) takes seconds to derive, which every mutation would repeat,
/// and its T is past the size where the probes decide whether H is the energy;
/// `crates/cli/tests/bicycle.rs` checks it against the published numbers.
pub const SKIPPED_DIRS: &[&str] = &["examples/bicycle"];

impl Corpus {
    /// The repository this crate sits in (two folders up from its manifest).
    pub fn repo_root() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
    }

    /// Reads the seeds under `root` (the repository): every `.toml` of [`SEED_DIRS`], recursively.
    pub fn load(root: &Path) -> std::io::Result<Corpus> {
        let mut paths = Vec::new();
        for dir in SEED_DIRS {
            toml_files(&root.join(dir), &mut paths)?;
        }
        let mut files = Vec::new();
        for path in paths {
            let text = std::fs::read_to_string(&path)?;
            let name = path.strip_prefix(root).unwrap_or(&path).display().to_string();
            files.push((name, text));
        }
        Ok(Corpus::from_files(files))
    }

    /// The corpus of these `(name, text)` files.
    pub fn from_files(files: Vec<(String, String)>) -> Corpus {
        let files: Vec<Seed> =
            files.into_iter().map(|(name, text)| Seed { kind: FileKind::of(&text), name, text }).collect();
        let mut expressions: Vec<String> = EXPRESSIONS.iter().map(|s| s.to_string()).collect();
        for seed in &files {
            if let Ok(value) = seed.text.parse::<toml::Table>() {
                strings_in(&toml::Value::Table(value), &mut expressions);
            }
        }
        expressions.sort();
        expressions.dedup();
        Corpus { files, expressions }
    }

    /// The body files, by file name (how a model names them), for the reader
    /// the model loader is given.
    pub fn body_files(&self) -> Vec<(String, String)> {
        self.files
            .iter()
            .filter(|s| s.kind == FileKind::Body)
            .map(|s| {
                let file = Path::new(&s.name).file_name().map(|f| f.to_string_lossy().into_owned());
                (file.unwrap_or_default(), s.text.clone())
            })
            .collect()
    }
}

/// What a mutating target draws from: its seeds, which stay, and the mutants
/// kept for a new outcome, at most `limit` (then each new one replaces the
/// oldest), so that a long run neither grows without bound nor loses its seeds.
#[derive(Clone, Debug)]
pub struct Inputs {
    seeds: Vec<String>,
    kept: Vec<String>,
    limit: usize,
    next: usize,
}

impl Inputs {
    /// Inputs from these seeds (at least one), keeping at most `limit` mutants.
    pub fn new(seeds: Vec<String>, limit: usize) -> Inputs {
        debug_assert!(!seeds.is_empty());
        Inputs { seeds, kept: Vec::new(), limit, next: 0 }
    }

    /// A seed or a kept mutant, even odds while there are kept ones.
    pub fn pick(&self, rng: &mut crate::rng::Rng) -> &str {
        let from = if self.kept.is_empty() || rng.chance(0.5) { &self.seeds } else { &self.kept };
        rng.pick(from).as_str()
    }

    /// Keeps a mutant whose outcome was new.
    pub fn keep(&mut self, input: String) {
        if self.kept.len() < self.limit {
            self.kept.push(input);
        } else if self.limit > 0 {
            self.kept[self.next] = input;
            self.next = (self.next + 1) % self.limit;
        }
    }

    /// Seeds and kept mutants.
    pub fn len(&self) -> usize {
        self.seeds.len() + self.kept.len()
    }

    /// Never: there is at least one seed.
    pub fn is_empty(&self) -> bool {
        self.seeds.is_empty() && self.kept.is_empty()
    }
}

/// Every `.toml` file under `dir`, recursively, in a stable order.
fn toml_files(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)?.map(|e| e.map(|e| e.path())).collect::<Result<_, _>>()?;
    entries.sort();
    for path in entries {
        if path.is_dir() {
            if SKIPPED_DIRS.iter().any(|d| path.ends_with(d)) {
                continue;
            }
            toml_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "toml") {
            out.push(path);
        }
    }
    Ok(())
}

/// Every string of a TOML value, recursively.
fn strings_in(value: &toml::Value, out: &mut Vec<String>) {
    match value {
        toml::Value::String(s) => out.push(s.clone()),
        toml::Value::Array(items) => items.iter().for_each(|v| strings_in(v, out)),
        toml::Value::Table(table) => table.values().for_each(|v| strings_in(v, out)),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_repository_seeds_every_kind_and_many_expressions() {
        let corpus = Corpus::load(&Corpus::repo_root()).expect("the seed folders are readable");
        for kind in [FileKind::Model, FileKind::Body, FileKind::Problem] {
            assert!(corpus.files.iter().any(|s| s.kind == kind), "no seed of kind {kind:?}");
        }
        assert!(corpus.files.iter().any(|s| s.name.contains("tests/bad/")));
        assert!(corpus.expressions.len() > 100, "{} expressions", corpus.expressions.len());
        assert!(corpus.expressions.iter().any(|e| e == "x^2 + y^2 - l^2"));
        assert!(corpus.body_files().iter().any(|(name, _)| name == "cone_top_body.toml"));
    }

    #[test]
    fn kept_mutants_are_bounded_and_the_seeds_stay() {
        let mut inputs = Inputs::new(vec!["seed".into()], 3);
        for i in 0..10 {
            inputs.keep(format!("mutant {i}"));
        }
        assert_eq!(inputs.len(), 4);
        let mut rng = crate::rng::Rng::new(1);
        let picks: Vec<String> = (0..200).map(|_| inputs.pick(&mut rng).to_string()).collect();
        assert!(picks.iter().any(|p| p == "seed"));
        assert!(picks.iter().any(|p| p == "mutant 9") && !picks.iter().any(|p| p == "mutant 6"));
    }
}
