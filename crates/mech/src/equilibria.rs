//! Equilibria found from a start, and trusted: Newton's method from the start
//! lands on the nearest point where the motion stands still, which may be an
//! unstable one (a bead on a spinning hoop started at θ = 0.5 lands on the top
//! of its effective potential, θ = 0). When it does, or when it finds nothing,
//! [`search`] starts Newton again from points around the start and around the
//! landing point (along each coordinate and along the unstable directions, at
//! [`SCAN`] distances), keeps the distinct equilibria within [`NEAR`] of the
//! start, and chooses the stable one nearest the start; every equilibrium it
//! met is reported with its stability, so the reader sees both.
//!
//! The search knows nothing of mechanics: an analysis supplies a [`Landscape`]
//! (its Newton solve and its stability test), `modes` on ∇U = 0 and
//! `linearize` on q'' = 0.

use crate::report::Ordered;
use serde::Serialize;

/// Distances from the start (and from an unstable landing point) at which the
/// search starts Newton again, in the coordinates' own units: a quarter, half
/// and whole unit, about one radian for an angle.
pub const SCAN: [f64; 3] = [0.25, 0.5, 1.0];
/// An equilibrium counts as near the start when no coordinate differs by more
/// than this: twice the farthest restart, so a restart may walk downhill a
/// little beyond where it began.
pub const NEAR: f64 = 2.0;
/// Most coordinates scanned one by one (2·3 restarts each); beyond that only
/// the unstable directions are followed.
const MAX_SCAN_AXES: usize = 8;
/// Two equilibria are the same when they differ by less than this fraction of
/// (1 + their size) in every coordinate (Newton's round-off is far below).
const SAME_POINT: f64 = 1e-7;

/// Whether small motions about a point stay small.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stability {
    /// Every small motion stays bounded (`modes`: every Ω² ≥ 0) or dies away
    /// (`linearize`: every eigenvalue has Re < 0).
    Stable,
    /// No eigenvalue has Re > 0 but some lie on the imaginary axis: the
    /// linearization neither grows nor decays there (`linearize` only).
    Marginal,
    /// Some small motion grows exponentially.
    Unstable,
}

impl Stability {
    /// The word used in reports.
    pub fn word(self) -> &'static str {
        match self {
            Stability::Stable => "stable",
            Stability::Marginal => "marginal",
            Stability::Unstable => "unstable",
        }
    }
}

/// A point Newton's method converged to.
#[derive(Debug, Clone)]
pub struct Solved {
    /// The point.
    pub x: Vec<f64>,
    /// Newton iterations taken.
    pub iterations: usize,
    /// The residual's norm there.
    pub residual: f64,
}

/// What an analysis says about a point.
#[derive(Debug, Clone)]
pub struct Assessment {
    /// Its stability.
    pub stability: Stability,
    /// Directions (in the unknowns) along which a displacement grows, if known.
    pub unstable_directions: Vec<Vec<f64>>,
}

/// The two things the search needs from an analysis.
pub trait Landscape {
    /// Newton's method from `x0`; the error says why it found nothing.
    fn solve(&mut self, x0: &[f64]) -> Result<Solved, String>;
    /// The stability at an equilibrium.
    fn assess(&mut self, x: &[f64]) -> Assessment;
}

/// One equilibrium the search met.
#[derive(Debug, Clone)]
pub struct Equilibrium {
    /// The point (the unknowns of the search).
    pub x: Vec<f64>,
    /// Its stability.
    pub stability: Stability,
    /// Newton iterations of the run that found it.
    pub iterations: usize,
    /// The residual's norm there.
    pub residual: f64,
    /// Along which a displacement grows.
    pub unstable_directions: Vec<Vec<f64>>,
}

/// An equilibrium the search met, as the JSON reports list it.
#[derive(Debug, Clone, Serialize)]
pub struct EquilibriumReport {
    /// The coordinates solved for.
    pub at: Ordered<f64>,
    /// stable, marginal or unstable.
    pub stability: Stability,
    /// Whether this is the one analysed.
    pub chosen: bool,
    /// Whether Newton's method from the start reached it.
    pub landing: bool,
}

impl EquilibriumReport {
    /// The list, named by `names` (the unknowns of the search).
    pub fn list(names: &[String], found: &[Equilibrium], chosen: usize, landing: Option<usize>) -> Vec<Self> {
        found
            .iter()
            .enumerate()
            .map(|(i, e)| EquilibriumReport {
                at: Ordered(names.iter().cloned().zip(e.x.iter().copied()).collect()),
                stability: e.stability,
                chosen: i == chosen,
                landing: landing == Some(i),
            })
            .collect()
    }
}

/// The outcome of [`search`].
#[derive(Debug, Clone)]
pub struct Search {
    /// The distinct equilibria met, the landing point of Newton from the start first.
    pub found: Vec<Equilibrium>,
    /// The one chosen for the analysis (an index into `found`).
    pub chosen: usize,
    /// The index of Newton's landing point from the start, when it converged.
    pub landing: Option<usize>,
}

/// A number with 6 significant digits, trailing zeros dropped (for messages).
pub(crate) fn short(v: f64) -> String {
    if v == 0.0 || (v.abs() >= 1e-4 && v.abs() < 1e6) {
        let s = format!("{:.6}", v);
        let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        if s == "-0" {
            "0".into()
        } else {
            s
        }
    } else {
        format!("{v:.5e}")
    }
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

fn same(a: &[f64], b: &[f64]) -> bool {
    let size = a.iter().chain(b).fold(0.0f64, |m, v| m.max(v.abs()));
    distance(a, b) <= SAME_POINT * (1.0 + size)
}

/// Finds the equilibria near `start`. With `prefer_stable`, an unstable
/// landing point (or none) sends the search around it and the stable
/// equilibrium nearest the start is chosen; without, Newton's landing point is
/// chosen when there is one (the others are still listed). The error is
/// Newton's own from the start, when nothing was found at all.
pub fn search(land: &mut dyn Landscape, start: &[f64], prefer_stable: bool) -> Result<Search, String> {
    let mut found: Vec<Equilibrium> = Vec::new();
    let add = |land: &mut dyn Landscape, found: &mut Vec<Equilibrium>, s: Solved| -> usize {
        if let Some(i) = found.iter().position(|f| same(&f.x, &s.x)) {
            return i;
        }
        let a = land.assess(&s.x);
        found.push(Equilibrium {
            x: s.x,
            stability: a.stability,
            iterations: s.iterations,
            residual: s.residual,
            unstable_directions: a.unstable_directions,
        });
        found.len() - 1
    };
    let first = land.solve(start);
    let (landing, first_error) = match first {
        Ok(s) => (Some(add(land, &mut found, s)), None),
        Err(e) => (None, Some(e)),
    };
    if let Some(i) = landing {
        if found[i].stability != Stability::Unstable {
            return Ok(Search { found, chosen: i, landing });
        }
    }
    // Restarts around the start and around the landing point.
    let n = start.len();
    let mut centres = vec![start.to_vec()];
    let mut directions: Vec<Vec<f64>> = Vec::new();
    if let Some(i) = landing {
        centres.push(found[i].x.clone());
        for v in &found[i].unstable_directions {
            let big = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            if big > 0.0 && v.iter().all(|x| x.is_finite()) {
                directions.push(v.iter().map(|x| x / big).collect());
            }
        }
    }
    if n <= MAX_SCAN_AXES {
        for k in 0..n {
            let mut e = vec![0.0; n];
            e[k] = 1.0;
            directions.push(e);
        }
    }
    for &d in &SCAN {
        for centre in &centres {
            for v in &directions {
                for sign in [1.0, -1.0] {
                    let x0: Vec<f64> = centre.iter().zip(v).map(|(c, v)| c + sign * d * v).collect();
                    if let Ok(s) = land.solve(&x0) {
                        if s.x.iter().all(|v| v.is_finite()) && distance(&s.x, start) <= NEAR {
                            add(land, &mut found, s);
                        }
                    }
                }
            }
        }
    }
    if found.is_empty() {
        return Err(first_error.unwrap_or_else(|| "no equilibrium found".into()));
    }
    let nearest = |keep: &dyn Fn(&Equilibrium) -> bool| -> Option<usize> {
        (0..found.len())
            .filter(|&i| keep(&found[i]))
            .min_by(|&a, &b| distance(&found[a].x, start).total_cmp(&distance(&found[b].x, start)))
    };
    let chosen = match (prefer_stable, landing) {
        (false, Some(i)) => i,
        _ => nearest(&|f| f.stability != Stability::Unstable).or(landing).or_else(|| nearest(&|_| true)).unwrap_or(0),
    };
    Ok(Search { found, chosen, landing })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// U = −w²/2 sin²x − g cos x (the spinning hoop's effective potential):
    /// equilibria at 0 (unstable for w² > g) and ±acos(g/w²) (stable).
    struct Hoop {
        w2: f64,
        g: f64,
    }

    impl Landscape for Hoop {
        fn solve(&mut self, x0: &[f64]) -> Result<Solved, String> {
            let (w2, g) = (self.w2, self.g);
            let sol = num::newton(
                |x, f, j| {
                    let (s, c) = x[0].sin_cos();
                    f[0] = s * (g - w2 * c);
                    j[0] = c * (g - w2 * c) + w2 * s * s;
                },
                x0,
                &num::NewtonConfig::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
            Ok(Solved { x: sol.x, iterations: sol.iterations, residual: sol.residual })
        }
        fn assess(&mut self, x: &[f64]) -> Assessment {
            let c = x[0].cos();
            let curvature = c * (self.g - self.w2 * c) + self.w2 * x[0].sin().powi(2);
            if curvature > 0.0 {
                Assessment { stability: Stability::Stable, unstable_directions: vec![] }
            } else {
                Assessment { stability: Stability::Unstable, unstable_directions: vec![vec![1.0]] }
            }
        }
    }

    #[test]
    fn an_unstable_landing_point_sends_the_search_to_the_stable_one_nearby() {
        let mut hoop = Hoop { w2: 25.0, g: 9.81 };
        let s = search(&mut hoop, &[0.5], true).unwrap();
        let landing = s.landing.expect("Newton converges from 0.5");
        assert!(s.found[landing].x[0].abs() < 1e-12, "Newton from 0.5 lands on the top, θ = 0");
        assert_eq!(s.found[landing].stability, Stability::Unstable);
        let chosen = &s.found[s.chosen];
        assert_eq!(chosen.stability, Stability::Stable);
        assert!((chosen.x[0] - (9.81f64 / 25.0).acos()).abs() < 1e-12, "{:?}", chosen.x);
        // Without the preference the landing point is kept, and the other listed.
        let s = search(&mut hoop, &[0.5], false).unwrap();
        assert_eq!(s.chosen, s.landing.unwrap());
        assert!(s.found.iter().any(|f| f.stability == Stability::Stable));
    }

    #[test]
    fn a_stable_landing_point_ends_the_search() {
        let mut hoop = Hoop { w2: 4.0, g: 9.81 };
        let s = search(&mut hoop, &[0.5], true).unwrap();
        assert_eq!(s.found.len(), 1);
        assert!(s.found[0].x[0].abs() < 1e-12);
        assert_eq!(s.found[0].stability, Stability::Stable);
    }
}
