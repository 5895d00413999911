//! The smoke run of every fuzz target, part of `cargo test`: a fixed number of
//! iterations from a fixed seed (a few seconds in all), so that CI repeats the
//! same cases and fails on any finding. Long runs: the `lagrange-fuzz` binary
//! (see the guide's development chapter).

use fuzz::{
    run, BodiesTarget, Config, Corpus, DeriveTarget, ExprTarget, LinearizeTarget, LoaderTarget, ReportTarget, Stats,
    Target,
};

fn smoke(target: &mut dyn Target, iterations: u64) -> Stats {
    let config = Config { iterations: Some(iterations), seed: 0x5eed, ..Config::default() };
    let stats = run(target, &config, &mut |_| {});
    assert_eq!(stats.iterations, iterations);
    let found: Vec<String> =
        stats.findings.iter().map(|f| format!("{:?}: {}\ninput:\n{}", f.kind, f.message, f.input)).collect();
    assert!(found.is_empty(), "the {} target found:\n{}", stats.target, found.join("\n\n"));
    stats
}

fn corpus() -> Corpus {
    Corpus::load(&Corpus::repo_root()).expect("the seed folders are readable")
}

#[test]
fn the_expression_parser_survives_mutated_expressions() {
    let stats = smoke(&mut ExprTarget::new(&corpus()), 50_000);
    // The novelty signal works: mutants with new outcomes joined the corpus.
    assert!(stats.signatures > 100, "{stats:?}");
}

#[test]
fn the_loaders_survive_mutated_files() {
    let stats = smoke(&mut LoaderTarget::new(&corpus()), 4_000);
    assert!(stats.signatures > 50, "{stats:?}");
}

#[test]
fn derive_agrees_with_the_oracle_on_generated_models() {
    let stats = smoke(&mut DeriveTarget, 200);
    // Models that derive, with and without H, cyclic coordinates, conserved H.
    assert!(stats.signatures > 10, "{stats:?}");
}

#[test]
fn body_trees_load_or_are_refused_at_a_place() {
    let stats = smoke(&mut BodiesTarget, 40);
    // Trees that derive and edits refused in many ways.
    assert!(stats.signatures > 15, "{stats:?}");
}

#[test]
fn linearize_finds_the_known_spectra_of_quadratic_systems() {
    // Past cases 94 (a gyroscopic pair beside zero modes, once read as
    // unstable) and 118 (a slow pair once lost beside ±506i) of this seed.
    let stats = smoke(&mut LinearizeTarget, 200);
    // Every verdict, on systems of several sizes.
    assert!(stats.signatures > 10, "{stats:?}");
}

#[test]
fn report_pages_keep_hostile_names_inside_their_scripts() {
    smoke(&mut ReportTarget, 300);
}
