//! Target (e): `mech::linearize` on quadratic systems with known spectra.
//! Enter with [`check_linearization`] (one model text) or [`LinearizeTarget`].
//!
//! A system is built from modes: modal coordinates u = R S q (S = diag(sᵢ),
//! sᵢ² the masses, R a rotation written exactly, as products of Pythagorean
//! turns like (3/5, 4/5), or as floats), and
//!
//! ```text
//! L = ½ Σ mᵢ qᵢ'² − ½ Σ ω²ₖ uₖ² + ½ γ (u₁ u₂' − u₂ u₁'),   R = ½ Σ cₖ uₖ'²
//! ```
//!
//! so that each mode is s² + cₖ s + ω²ₖ = 0 and a gyroscopic pair (equal ω²,
//! undamped) is s² ± iγ s + ω² = 0. The ω² spread over 10⁻⁶ … 10⁶, with zeros
//! (a free coordinate: a nilpotent block), negatives, repeats, near repeats and
//! critical damping (a defective pair). The model text carries its modes in
//! comments (`# mode w2 c`, `# gyro w2 g`, `# kappa k`), so a saved input is
//! checked again alone.
//!
//! Checks: no panic and no refusal; 2n eigenvalues, none NaN; each known
//! eigenvalue matched by a computed one within a tolerance from its
//! conditioning (Bauer–Fike on the modal blocks, or the square root of the
//! backward error where a block is defective); the verdict one that the known
//! real parts allow (a real part within linearize's resolution of the
//! imaginary axis, 10⁻⁷ of A's largest entry, may be read as zero).

use crate::rng::Rng;
use crate::run::{FindingKind, Outcome, Target};
use mech::{Derivation, LinearizeConfig, Model, Stability};

/// Tolerance factor over the first-order error estimate.
const SAFETY: f64 = 100.0;
/// The real parts `linearize` reads as zero, a fraction of A's largest entry.
const AXIS: f64 = 1e-7;

/// One block of the system.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Block {
    /// One mode: s² + c s + ω² = 0.
    Mode { w2: f64, c: f64 },
    /// Two modes of equal ω² coupled gyroscopically.
    Gyro { w2: f64, g: f64 },
}

impl Block {
    /// Its eigenvalues (re, im).
    fn eigenvalues(self) -> Vec<(f64, f64)> {
        match self {
            Block::Mode { w2, c } => {
                let disc = c * c - 4.0 * w2;
                if disc >= 0.0 {
                    // The larger root first, the other as w2 / it (no cancellation).
                    let big = -(c + disc.sqrt()) / 2.0;
                    let small = if big == 0.0 { 0.0 } else { w2 / big };
                    vec![(big, 0.0), (small, 0.0)]
                } else {
                    let im = (-disc).sqrt() / 2.0;
                    vec![(-c / 2.0, im), (-c / 2.0, -im)]
                }
            }
            Block::Gyro { w2, g } => {
                let disc = g * g + 4.0 * w2;
                if disc >= 0.0 {
                    let r = disc.sqrt();
                    vec![(0.0, (-g + r) / 2.0), (0.0, (-g - r) / 2.0), (0.0, (g + r) / 2.0), (0.0, (g - r) / 2.0)]
                } else {
                    let re = (-disc).sqrt() / 2.0;
                    vec![(re, -g / 2.0), (-re, -g / 2.0), (re, g / 2.0), (-re, g / 2.0)]
                }
            }
        }
    }

    fn size(self) -> f64 {
        match self {
            Block::Mode { w2, c } => w2.abs().max(c.abs()),
            Block::Gyro { w2, g } => w2.abs().max(g.abs()),
        }
    }
}

/// A random ω²: log-uniform magnitude in 10⁻⁶ … 10⁶, mostly positive.
fn frequency(rng: &mut Rng, previous: Option<f64>) -> f64 {
    match (rng.below(10), previous) {
        (0, _) => 0.0,
        (1, Some(p)) => p,
        (2, Some(p)) => p * (1.0 + 1e-9),
        (k, _) => {
            let m = 10f64.powf(rng.range(-6.0, 6.0));
            if k == 3 {
                -m
            } else {
                m
            }
        }
    }
}

/// The rational numbers `num/den` that R S holds (exact rotations), or floats.
enum Coefficients {
    Exact(Vec<Vec<(i128, i128)>>),
    Float(Vec<Vec<f64>>),
}

/// A random quadratic system as a model text.
pub fn system(rng: &mut Rng) -> String {
    let n = 1 + rng.below(5);
    // s = 1, 2 or 1/2 (masses 1, 4, 1/4) as num/den.
    let s: Vec<(i128, i128)> = (0..n).map(|_| *rng.pick(&[(1, 1), (2, 1), (1, 2)])).collect();
    let mut blocks = Vec::new();
    let damped = rng.chance(0.35);
    let mut k = 0;
    let mut previous = None;
    while k < n {
        let w2 = frequency(rng, previous);
        previous = Some(w2);
        if k + 1 < n && rng.chance(0.2) {
            let g = 10f64.powf(rng.range(-2.0, 2.0));
            blocks.push(Block::Gyro { w2, g });
            k += 2;
        } else {
            let c = if !damped || rng.chance(0.3) {
                0.0
            } else if w2 > 0.0 && rng.chance(0.2) {
                2.0 * w2.sqrt()
            } else {
                10f64.powf(rng.range(-3.0, 3.0))
            };
            blocks.push(Block::Mode { w2, c });
            k += 1;
        }
    }
    let coefficients = if rng.chance(0.5) {
        let mut r: Vec<Vec<(i128, i128)>> = (0..n).map(|i| (0..n).map(|j| (i128::from(i == j), 1)).collect()).collect();
        for _ in 0..rng.below(n + 1) {
            let (a, b, h) = *rng.pick(&[(3, 4, 5), (5, 12, 13), (8, 15, 17)]);
            let (i, j) = (rng.below(n), rng.below(n));
            if i == j {
                continue;
            }
            let sign = if rng.chance(0.5) { 1 } else { -1 };
            // Rows i and j turned: each entry over the same denominator.
            for col in 0..n {
                let (x, dx) = r[i][col];
                let (y, dy) = r[j][col];
                let l = dx / gcd(dx, dy) * dy;
                let d = l * h;
                let (x, y) = (x * (l / dx), y * (l / dy));
                r[i][col] = (a * x - sign * b * y, d);
                r[j][col] = (sign * b * x + a * y, d);
            }
        }
        Coefficients::Exact(
            r.iter().map(|row| row.iter().zip(&s).map(|(&(x, d), &(sn, sd))| (x * sn, d * sd)).collect()).collect(),
        )
    } else {
        let mut r: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect()).collect();
        for _ in 0..rng.below(n + 1) {
            let (i, j) = (rng.below(n), rng.below(n));
            if i == j {
                continue;
            }
            let (sin, cos) = rng.range(0.0, std::f64::consts::TAU).sin_cos();
            for col in 0..n {
                let (x, y) = (r[i][col], r[j][col]);
                r[i][col] = cos * x - sin * y;
                r[j][col] = sin * x + cos * y;
            }
        }
        Coefficients::Float(
            r.iter().map(|row| row.iter().zip(&s).map(|(x, &(sn, sd))| x * sn as f64 / sd as f64).collect()).collect(),
        )
    };
    // κ(S): the largest s over the smallest.
    let value = |&(a, b): &(i128, i128)| a as f64 / b as f64;
    let kappa = s.iter().map(value).fold(0.0, f64::max) / s.iter().map(value).fold(f64::INFINITY, f64::min);
    write(n, &s, &blocks, &coefficients, kappa)
}

/// The model text of a system.
fn write(n: usize, s: &[(i128, i128)], blocks: &[Block], r: &Coefficients, kappa: f64) -> String {
    let q: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
    let modal = |k: usize, prime: &str| -> String {
        let terms: Vec<String> = (0..n)
            .filter_map(|i| match r {
                Coefficients::Exact(m) => {
                    (m[k][i].0 != 0).then(|| format!("({}/{})*{}{prime}", m[k][i].0, m[k][i].1, q[i]))
                }
                Coefficients::Float(m) => (m[k][i] != 0.0).then(|| format!("({:?})*{}{prime}", m[k][i], q[i])),
            })
            .collect();
        format!("({})", if terms.is_empty() { "0".to_string() } else { terms.join(" + ") })
    };
    let mut text = String::from("# A quadratic system with known modes (lagrange-fuzz linearize).\n");
    for b in blocks {
        match b {
            Block::Mode { w2, c } => text.push_str(&format!("# mode {w2:?} {c:?}\n")),
            Block::Gyro { w2, g } => text.push_str(&format!("# gyro {w2:?} {g:?}\n")),
        }
    }
    text.push_str(&format!("# kappa {kappa:?}\n"));
    let kinetic: Vec<String> = (0..n).map(|i| format!("{}/{}*{}'^2", s[i].0 * s[i].0, s[i].1 * s[i].1, q[i])).collect();
    let mut potential = Vec::new();
    let mut gyro = Vec::new();
    let mut damping = Vec::new();
    let mut k = 0;
    for b in blocks {
        match *b {
            Block::Mode { w2, c } => {
                potential.push(format!("({w2:?})*{}^2", modal(k, "")));
                if c != 0.0 {
                    damping.push(format!("({c:?})*{}^2", modal(k, "'")));
                }
                k += 1;
            }
            Block::Gyro { w2, g } => {
                potential.push(format!("({w2:?})*({}^2 + {}^2)", modal(k, ""), modal(k + 1, "")));
                gyro.push(format!(
                    "({g:?})/2*({}*{} - {}*{})",
                    modal(k, ""),
                    modal(k + 1, "'"),
                    modal(k + 1, ""),
                    modal(k, "'")
                ));
                k += 2;
            }
        }
    }
    let quoted: Vec<String> = q.iter().map(|c| format!("\"{c}\"")).collect();
    text.push_str(&format!("coordinates = [{}]\n", quoted.join(", ")));
    let mut lagrangian = format!("1/2*({}) - 1/2*({})", kinetic.join(" + "), potential.join(" + "));
    for g in gyro {
        lagrangian.push_str(&format!(" + {g}"));
    }
    text.push_str(&format!("lagrangian = \"{lagrangian}\"\n"));
    if !damping.is_empty() {
        text.push_str(&format!("dissipation = \"1/2*({})\"\n", damping.join(" + ")));
    }
    text.push_str("[initial]\n");
    for c in &q {
        text.push_str(&format!("{c} = 0\n"));
    }
    text
}

/// The blocks and κ(S) the comments of `text` give.
fn known(text: &str) -> Option<(Vec<Block>, f64)> {
    let mut blocks = Vec::new();
    let mut kappa = None;
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| words.get(i).and_then(|w| w.parse::<f64>().ok());
        match words.get(..2) {
            Some(["#", "mode"]) => blocks.push(Block::Mode { w2: num(2)?, c: num(3)? }),
            Some(["#", "gyro"]) => blocks.push(Block::Gyro { w2: num(2)?, g: num(3)? }),
            Some(["#", "kappa"]) => kappa = num(2),
            _ => {}
        }
    }
    Some((blocks, kappa?))
}

/// Loads and linearizes `text` and checks the spectrum and the verdict
/// against the modes its comments state.
pub fn check_linearization(text: &str) -> Outcome {
    let Some((blocks, kappa)) = known(text) else {
        return Outcome::fine("no modes stated");
    };
    let d = match Model::parse(text, &[]).and_then(Derivation::new) {
        Ok(d) => d,
        Err(e) => {
            return Outcome::problem(FindingKind::Invariant, format!("a quadratic system is refused: {}", e.message))
        }
    };
    let config = LinearizeConfig { keep_unstable: true, ..LinearizeConfig::default() };
    let lin = match mech::linearize(&d, &config) {
        Ok(l) => l,
        Err(e) => {
            return Outcome::problem(FindingKind::Invariant, format!("linearize refuses a quadratic system: {e}"))
        }
    };
    let n2 = 2 * d.q().len();
    if lin.eigenvalues.len() != n2 {
        return Outcome::problem(FindingKind::Invariant, format!("{} eigenvalues, not {n2}", lin.eigenvalues.len()));
    }
    if lin.eigenvalues.iter().any(|e| !e.0.is_finite() || !e.1.is_finite()) {
        return Outcome::problem(FindingKind::Invariant, format!("eigenvalues not finite: {:?}", lin.eigenvalues));
    }
    // The size of A (its largest entry is below κ(S) times the blocks' size).
    let size = blocks.iter().map(|b| b.size()).fold(1.0, f64::max) * kappa;
    let backward = f64::EPSILON * n2 as f64 * size;
    let mut expected: Vec<((f64, f64), f64, f64)> = Vec::new();
    for b in &blocks {
        let ev = b.eigenvalues();
        for (k, &l) in ev.iter().enumerate() {
            let sep =
                ev.iter().enumerate().filter(|&(j, _)| j != k).map(|(_, &m)| dist(l, m)).fold(f64::INFINITY, f64::min);
            let spread = 2.0 * (1.0 + l.0 * l.0 + l.1 * l.1);
            let tol = SAFETY * (kappa * backward * spread / sep).min((kappa * backward * spread).sqrt());
            expected.push((l, tol, tol.max(AXIS * size)));
        }
    }
    // Two passes, the tightest first, each to its nearest unused computed
    // eigenvalue: as computed, then with a real part within the axis band
    // read as zero (so that a zero snapped from a small real part does not
    // take the place of an exact zero).
    expected.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut used = vec![false; n2];
    let mut matched = vec![false; expected.len()];
    for snapped in [false, true] {
        for (k, &(l, tol, band)) in expected.iter().enumerate() {
            if matched[k] {
                continue;
            }
            let distance = |c: (f64, f64)| {
                let re = if snapped && c.0 == 0.0 && l.0.abs() <= band { 0.0 } else { c.0 - l.0 };
                re.hypot(c.1 - l.1)
            };
            let best = (0..n2)
                .filter(|&j| !used[j])
                .min_by(|&a, &b| distance(lin.eigenvalues[a]).total_cmp(&distance(lin.eigenvalues[b])));
            if let Some(j) = best.filter(|&j| distance(lin.eigenvalues[j]) <= tol) {
                used[j] = true;
                matched[k] = true;
            }
        }
    }
    if let Some(k) = matched.iter().position(|m| !m) {
        let (l, tol, _) = expected[k];
        return Outcome::problem(
            FindingKind::Invariant,
            format!("the eigenvalue {} ± {tol:.1e} is not among those computed: {:?}", show(l), lin.eigenvalues),
        );
    }
    // The verdicts the known real parts allow.
    let options: Vec<(bool, bool, bool)> = expected
        .iter()
        .map(|&((re, _), _, band)| {
            let near = re.abs() <= band;
            (re > 0.0, re == 0.0 || near, re < 0.0)
        })
        .collect();
    let can_unstable = options.iter().any(|o| o.0);
    let must_unstable = options.iter().any(|o| o.0 && !o.1);
    let can_stable = options.iter().all(|o| o.2);
    let can_marginal = !must_unstable && options.iter().any(|o| o.1);
    let allowed = match lin.stability {
        Stability::Unstable => can_unstable,
        Stability::Stable => can_stable,
        Stability::Marginal => can_marginal,
    };
    if !allowed {
        let exact: Vec<String> = blocks.iter().flat_map(|b| b.eigenvalues()).map(show).collect();
        return Outcome::problem(
            FindingKind::Invariant,
            format!("the verdict is {}, but the eigenvalues are {}", lin.stability.word(), exact.join(", ")),
        );
    }
    Outcome::fine(format!("{} {}", lin.stability.word(), blocks.len()))
}

fn gcd(a: i128, b: i128) -> i128 {
    if b == 0 {
        a.abs()
    } else {
        gcd(b, a % b)
    }
}

fn dist(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0).hypot(a.1 - b.1)
}

fn show(l: (f64, f64)) -> String {
    format!("{:e}{:+e}i", l.0, l.1)
}

/// Linearize on quadratic systems with known spectra.
#[derive(Default)]
pub struct LinearizeTarget;

impl Target for LinearizeTarget {
    fn name(&self) -> &'static str {
        "linearize"
    }

    fn input(&mut self, rng: &mut Rng) -> String {
        system(rng)
    }

    fn check(&mut self, input: &str) -> Outcome {
        check_linearization(input)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_spectra_solve_their_polynomials() {
        for b in [
            Block::Mode { w2: 4.0, c: 0.0 },
            Block::Mode { w2: -9.0, c: 1.0 },
            Block::Mode { w2: 1e-6, c: 3.0 },
            Block::Mode { w2: 2.0, c: 0.5 },
        ] {
            let Block::Mode { w2, c } = b else { unreachable!() };
            for (re, im) in b.eigenvalues() {
                // s² + c s + ω² at s = re + i im.
                let (r2, i2) = (re * re - im * im + c * re + w2, 2.0 * re * im + c * im);
                assert!(r2.hypot(i2) < 1e-12 * (1.0 + w2.abs()), "{b:?}: {re} {im}");
            }
        }
        for b in [Block::Gyro { w2: 1.0, g: 0.5 }, Block::Gyro { w2: -1.0, g: 0.5 }, Block::Gyro { w2: -1.0, g: 3.0 }] {
            let Block::Gyro { w2, g } = b else { unreachable!() };
            for (re, im) in b.eigenvalues() {
                // (s² + ω²)² + γ² s² = 0: the product of s² ± iγ s + ω².
                let s2 = (re * re - im * im, 2.0 * re * im);
                let a = (s2.0 + w2, s2.1);
                let v = (a.0 * a.0 - a.1 * a.1 + g * g * s2.0, 2.0 * a.0 * a.1 + g * g * s2.1);
                assert!(v.0.hypot(v.1) < 1e-12, "{b:?}: {re} {im}");
            }
        }
    }

    #[test]
    fn a_generated_system_states_its_modes_and_a_wrong_one_is_caught() {
        let mut rng = Rng::new(11);
        let text = system(&mut rng);
        let (blocks, _) = known(&text).expect("the modes are stated");
        assert!(!blocks.is_empty());
        assert!(Model::parse(&text, &[]).is_ok(), "{text}");
        let pendulum = "# mode 4.0 0.0\n# kappa 1.0\ncoordinates = [\"q1\"]\nlagrangian = \"q1'^2/2 - 4*q1^2/2\"\n";
        assert!(check_linearization(pendulum).problem.is_none(), "{:?}", check_linearization(pendulum));
        let wrong = pendulum.replace("# mode 4.0", "# mode 9.0");
        assert!(check_linearization(&wrong).problem.is_some());
    }

    #[test]
    fn a_small_real_part_does_not_take_the_place_of_an_exact_zero() {
        // Zeros (free coordinates) beside −0.0318 (a damped free one), inside the
        // band where a real part may be read as zero: computed exactly, each must
        // still find its own.
        let text = "# A quadratic system with known modes (lagrange-fuzz linearize).\n\
# mode 285774.5005304711 0.0\n\
# mode 0.02977566436209067 0.0\n\
# mode 0.6728322416838243 1.640527039318553\n\
# mode 0.0 0.03177174852980577\n\
# mode 0.0 0.0\n\
# kappa 4.0\n\
coordinates = [\"q1\", \"q2\", \"q3\", \"q4\", \"q5\"]\n\
lagrangian = \"1/2*(4/1*q1'^2 + 1/4*q2'^2 + 1/1*q3'^2 + 4/1*q4'^2 + 1/4*q5'^2) - 1/2*((285774.5005304711)*((2/1)*q1)^2 + (0.02977566436209067)*((1/2)*q2)^2 + (0.6728322416838243)*((1/1)*q3)^2 + (0.0)*((2/1)*q4)^2 + (0.0)*((1/2)*q5)^2)\"\n\
dissipation = \"1/2*((1.640527039318553)*((1/1)*q3')^2 + (0.03177174852980577)*((2/1)*q4')^2)\"\n\
[initial]\n\
q1 = 0\n\
q2 = 0\n\
q3 = 0\n\
q4 = 0\n\
q5 = 0\n";
        let outcome = check_linearization(text);
        assert!(outcome.problem.is_none(), "{outcome:?}");
    }
}
