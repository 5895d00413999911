//! The fuzzing loop: make an input, check it with panics caught and the time
//! taken, record what went wrong, keep what was new. Enter with [`run`].

use crate::rng::Rng;
use std::cell::RefCell;
use std::panic::{self, AssertUnwindSafe};
use std::sync::Once;
use std::time::{Duration, Instant};

/// What a target found wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FindingKind {
    /// The library panicked.
    Panic,
    /// An error's span is outside its text or cuts a character.
    Span,
    /// Printed text does not parse back to the same expression.
    RoundTrip,
    /// A derivation (or a simplification) disagrees with an independent one.
    Invariant,
    /// A page a browser would read otherwise than it was written.
    Page,
    /// One case took longer than [`Config::slow_seconds`].
    Slow,
}

/// One finding, with the input that shows it.
#[derive(Clone, Debug)]
pub struct Finding {
    /// The target's name.
    pub target: &'static str,
    /// What went wrong.
    pub kind: FindingKind,
    /// How, in a sentence.
    pub message: String,
    /// The input.
    pub input: String,
    /// The iteration it came from.
    pub iteration: u64,
}

/// What a check says about one input.
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    /// A short description of what happened (an error's kind, the shape of a
    /// result): an input with a signature not seen before joins the corpus.
    pub signature: String,
    /// What went wrong, if anything.
    pub problem: Option<(FindingKind, String)>,
}

impl Outcome {
    /// A fine outcome with this signature.
    pub fn fine(signature: impl Into<String>) -> Outcome {
        Outcome { signature: signature.into(), problem: None }
    }

    /// A problem.
    pub fn problem(kind: FindingKind, message: impl Into<String>) -> Outcome {
        Outcome { signature: String::new(), problem: Some((kind, message.into())) }
    }
}

/// A fuzz target: makes inputs and checks them.
pub trait Target {
    /// Its name (`expr`, `loader`, `derive`).
    fn name(&self) -> &'static str;
    /// The next input.
    fn input(&mut self, rng: &mut Rng) -> String;
    /// Checks one input. Panics are the runner's to catch.
    fn check(&mut self, input: &str) -> Outcome;
    /// Takes an input whose outcome was new into the corpus (if the target mutates one).
    fn keep(&mut self, _input: String) {}
    /// The number of inputs it mutates from.
    fn corpus_len(&self) -> usize {
        0
    }
}

/// How long to run and how to judge time.
#[derive(Clone, Debug)]
pub struct Config {
    /// Stop after this many inputs.
    pub iterations: Option<u64>,
    /// Stop after this many seconds.
    pub seconds: Option<f64>,
    /// The seed of the run; iteration `i` draws from `Rng::new(seed ^ mix(i))`.
    pub seed: u64,
    /// A case slower than this is a finding. Default 10 s: the slowest valid
    /// model of the generator derives in milliseconds, and a loaded mutant of
    /// an example (at most the 50-coordinate chain) well under a second.
    pub slow_seconds: f64,
}

impl Default for Config {
    fn default() -> Self {
        Config { iterations: None, seconds: None, seed: 1, slow_seconds: 10.0 }
    }
}

/// What a run did.
#[derive(Clone, Debug, Default)]
pub struct Stats {
    /// The target's name.
    pub target: &'static str,
    /// Inputs checked.
    pub iterations: u64,
    /// Wall seconds.
    pub seconds: f64,
    /// Distinct outcome signatures seen.
    pub signatures: usize,
    /// The target's corpus at the end.
    pub corpus: usize,
    /// The slowest case, seconds.
    pub slowest_seconds: f64,
    /// Everything found (at most one per kind and message signature).
    pub findings: Vec<Finding>,
}

/// What the runner tells its caller as it goes.
pub enum Event<'a> {
    /// A case is about to be checked (a watchdog keeps it for a hang).
    Start(&'a str),
    /// A new finding.
    Found(&'a Finding),
}

thread_local! {
    /// Set while a case runs under the runner: the panic hook stores the
    /// message here instead of printing it.
    static CAUGHT: RefCell<Option<Option<String>>> = const { RefCell::new(None) };
}

/// Installs (once) a panic hook that is silent for cases under the runner and
/// the previous hook for everything else.
fn install_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            let fuzzing = CAUGHT.with(|c| {
                let mut c = c.borrow_mut();
                match c.as_mut() {
                    Some(slot) => {
                        let location = info.location().map(|l| format!(" at {}:{}", l.file(), l.line()));
                        let payload = info
                            .payload()
                            .downcast_ref::<&str>()
                            .map(|s| s.to_string())
                            .or_else(|| info.payload().downcast_ref::<String>().cloned())
                            .unwrap_or_default();
                        *slot = Some(format!("{payload}{}", location.unwrap_or_default()));
                        true
                    }
                    None => false,
                }
            });
            if !fuzzing {
                previous(info);
            }
        }));
    });
}

/// The seed of iteration `i` of a run seeded `seed`.
fn iteration_seed(seed: u64, i: u64) -> u64 {
    Rng::new(seed ^ i.wrapping_mul(0x2545_f491_4f6c_dd1d)).next_u64()
}

/// Runs `target` for the budget of `config`, telling `events` about each case
/// and finding. Findings are kept once per (kind, signature of the message).
pub fn run(target: &mut dyn Target, config: &Config, events: &mut dyn FnMut(Event)) -> Stats {
    install_hook();
    let started = Instant::now();
    let deadline = config.seconds.map(|s| started + Duration::from_secs_f64(s));
    let mut stats = Stats { target: target.name(), ..Stats::default() };
    let mut seen = std::collections::HashSet::new();
    let mut reported = std::collections::HashSet::new();
    let mut i = 0u64;
    loop {
        if config.iterations.is_some_and(|n| i >= n) || deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        if config.iterations.is_none() && deadline.is_none() {
            break;
        }
        let mut rng = Rng::new(iteration_seed(config.seed, i));
        let input = target.input(&mut rng);
        events(Event::Start(&input));
        let case_started = Instant::now();
        CAUGHT.with(|c| *c.borrow_mut() = Some(None));
        let result = panic::catch_unwind(AssertUnwindSafe(|| target.check(&input)));
        let caught = CAUGHT.with(|c| c.borrow_mut().take()).flatten();
        let elapsed = case_started.elapsed().as_secs_f64();
        stats.slowest_seconds = stats.slowest_seconds.max(elapsed);
        let outcome = match result {
            Ok(outcome) => outcome,
            Err(_) => Outcome::problem(FindingKind::Panic, caught.unwrap_or_else(|| "a panic".into())),
        };
        let mut problem = outcome.problem.clone();
        if problem.is_none() && elapsed > config.slow_seconds {
            problem = Some((FindingKind::Slow, format!("took {elapsed:.1} s")));
        }
        if let Some((kind, message)) = problem {
            let key = (kind, crate::spans::signature_of(&message));
            if reported.insert(key) {
                let finding = Finding { target: stats.target, kind, message, input: input.clone(), iteration: i };
                events(Event::Found(&finding));
                stats.findings.push(finding);
            }
        } else if seen.insert(outcome.signature) {
            target.keep(input);
        }
        i += 1;
    }
    stats.iterations = i;
    stats.seconds = started.elapsed().as_secs_f64();
    stats.signatures = seen.len();
    stats.corpus = target.corpus_len();
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A target that panics on inputs with a 7 and is slow on none.
    struct Sevens(u64);

    impl Target for Sevens {
        fn name(&self) -> &'static str {
            "sevens"
        }
        fn input(&mut self, rng: &mut Rng) -> String {
            self.0 += 1;
            rng.below(10).to_string()
        }
        fn check(&mut self, input: &str) -> Outcome {
            assert!(!input.contains('7'), "seven in {input}");
            Outcome::fine(input)
        }
    }

    #[test]
    fn panics_are_caught_once_with_their_input_and_the_budget_holds() {
        let mut target = Sevens(0);
        let config = Config { iterations: Some(300), ..Config::default() };
        let stats = run(&mut target, &config, &mut |_| {});
        assert_eq!((stats.iterations, target.0), (300, 300));
        assert_eq!(stats.findings.len(), 1, "{:?}", stats.findings);
        let f = &stats.findings[0];
        assert_eq!((f.kind, f.input.as_str()), (FindingKind::Panic, "7"));
        assert!(f.message.starts_with("seven in 7 at "), "{}", f.message);
        assert_eq!(stats.signatures, 9);
    }
}
