//! Target (b): the loaders of TOML files — models, body files, variational
//! problems — on text mutated from the corpus. Enter with [`check_file`] (one
//! text) or [`LoaderTarget`] (the fuzz loop).
//!
//! For every text: no panic, and every error's span (and the span of an error
//! inside a body file the model names) lies inside the text it points into. A
//! model that loads has its initial state evaluated and is derived, with the
//! checks of [`crate::check_derivation`]; a body file that loads has its mass
//! properties computed.

use crate::corpus::{Corpus, FileKind, Inputs};
use crate::derive::check_model;
use crate::mutate::mutate;
use crate::rng::Rng;
use crate::run::{FindingKind, Outcome, Target};
use crate::spans::{check_model_error, signature_of};
use mech::inertia::BodyFile;
use mech::{Model, Problem};

/// Models with more coordinates than this are loaded but not derived: a
/// mutant of the 50-mass chain derives in well under a second, but thousands
/// of them would crowd out everything else.
const MAX_DERIVED_COORDS: usize = 12;

/// Loads `text` with the loader its kind calls for; `body_files` are the
/// files a model may name, by name.
pub fn check_file(text: &str, body_files: &[(String, String)]) -> Outcome {
    let kind = FileKind::of(text);
    let spans = |err: &mech::ModelError, what: &str| match check_model_error(text, err) {
        Err(why) => Outcome::problem(FindingKind::Span, format!("{what}: {why}")),
        Ok(()) => Outcome::fine(format!("{kind:?} {what}: {}", signature_of(&err.message))),
    };
    match kind {
        FileKind::Body => match BodyFile::parse(text, &[]) {
            Err(err) => spans(&err, "load error"),
            Ok(body) => match body.mass_properties() {
                Err(err) => spans(&err, "mass error"),
                Ok(_) => Outcome::fine("body loaded"),
            },
        },
        FileKind::Problem => match Problem::parse(text, &[]) {
            Err(err) => spans(&err, "load error"),
            Ok(_) => Outcome::fine("problem loaded"),
        },
        FileKind::Model => {
            let reader = |name: &str| -> Result<String, String> {
                body_files
                    .iter()
                    .find(|(n, _)| n == name)
                    .map(|(_, t)| t.clone())
                    .ok_or_else(|| format!("no file {name}"))
            };
            let model = match Model::parse_with(text, &[], &reader) {
                Err(err) => return spans(&err, "load error"),
                Ok(model) => model,
            };
            if let Err(err) = model.initial_state() {
                let outcome = spans(&err, "initial state");
                if outcome.problem.is_some() {
                    return outcome;
                }
            }
            if model.n_coords() > MAX_DERIVED_COORDS {
                return Outcome::fine("model loaded (not derived)");
            }
            check_model(text, model)
        }
    }
}

/// The loaders under the fuzz loop: mutants of the corpus's files.
pub struct LoaderTarget {
    inputs: Inputs,
    body_files: Vec<(String, String)>,
    /// Expressions to splice into string values.
    expressions: Vec<String>,
}

impl LoaderTarget {
    /// A target seeded with the corpus's files.
    pub fn new(corpus: &Corpus) -> LoaderTarget {
        LoaderTarget {
            inputs: Inputs::new(corpus.files.iter().map(|s| s.text.clone()).collect(), MAX_KEPT),
            body_files: corpus.body_files(),
            expressions: corpus.expressions.clone(),
        }
    }
}

/// Most mutants kept for a new outcome.
const MAX_KEPT: usize = 2048;

impl Target for LoaderTarget {
    fn name(&self) -> &'static str {
        "loader"
    }

    fn input(&mut self, rng: &mut Rng) -> String {
        let seed = self.inputs.pick(rng).to_string();
        if rng.chance(0.5) {
            if let Some(text) = mutate_a_string(rng, &seed, &self.expressions) {
                return text;
            }
        }
        let others: Vec<String> = (0..2).map(|_| self.inputs.pick(rng).to_string()).collect();
        let others: Vec<&str> = others.iter().map(String::as_str).collect();
        mutate(rng, &seed, &others)
    }

    fn check(&mut self, input: &str) -> Outcome {
        check_file(input, &self.body_files)
    }

    fn keep(&mut self, input: String) {
        self.inputs.keep(input);
    }

    fn corpus_len(&self) -> usize {
        self.inputs.len()
    }
}

/// Mutates the text inside one basic string (`"..."` on one line) of
/// `text`, so that the TOML stays valid and the expression reader and derive
/// see the mutant: its own text mutated, or another expression spliced in.
/// None when the text has no such string.
fn mutate_a_string(rng: &mut Rng, text: &str, expressions: &[String]) -> Option<String> {
    let mut strings = Vec::new();
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let quotes: Vec<usize> = line.match_indices('"').map(|(i, _)| offset + i).collect();
        strings.extend(quotes.chunks_exact(2).map(|pair| (pair[0] + 1, pair[1])));
        offset += line.len();
    }
    if strings.is_empty() {
        return None;
    }
    let (start, end) = *rng.pick(&strings);
    let splice = !expressions.is_empty() && rng.chance(0.3);
    let inner = if splice { rng.pick(expressions).clone() } else { text[start..end].to_string() };
    let others: Vec<&str> = expressions.iter().take(2).map(String::as_str).collect();
    let mutant = mutate(rng, &inner, &others);
    // What would end or escape the string is left out.
    let clean: String = mutant.chars().filter(|c| !matches!(c, '"' | '\\' | '\n' | '\r') && !c.is_control()).collect();
    Some(format!("{}{clean}{}", &text[..start], &text[end..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn string_mutants_keep_the_toml_valid() {
        let mut rng = Rng::new(5);
        let text = "coordinates = [\"x\"]\nlagrangian = \"x'^2/2 - x^2/2\"\n";
        for _ in 0..200 {
            let mutant = mutate_a_string(&mut rng, text, &["sin(x)".to_string()]).expect("the text has strings");
            assert!(mutant.parse::<toml::Table>().is_ok(), "{mutant}");
        }
        assert!(mutate_a_string(&mut rng, "a = 1\n", &[]).is_none());
    }

    #[test]
    fn every_seed_passes_the_checks() {
        let corpus = Corpus::load(&Corpus::repo_root()).unwrap();
        let bodies = corpus.body_files();
        for seed in &corpus.files {
            let outcome = check_file(&seed.text, &bodies);
            assert!(outcome.problem.is_none(), "{}: {:?}", seed.name, outcome.problem);
        }
    }
}
