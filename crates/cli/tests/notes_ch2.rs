//! `lagrange derive` against the worked examples of the lecture notes.
//!
//! Each test runs the real binary as `lagrange derive examples/X.toml --format json`
//! and compares the `lagrange.derive/1` output with the results printed in the notes'
//! chapter 2 (and, from chapter 3, the Kepler problem, the two coupled oscillators, the
//! triatomic molecule and the spring chain). Line numbers in the comments refer to
//! `shared/reference/000_aa8c78fda05aa840.txt`.
//!
//! Expressions are compared numerically at fixed-seed random sample points, so any
//! algebraically equal form passes. Equations are compared in the contract's
//! normalization `E_q = d/dt ∂L/∂q' − ∂L/∂q + ∂R/∂q' − Q_q`; where the notes print an
//! equation divided by a factor, `equation_scaled` checks that printed form as well.
//! Where the notes print no Hamilton equations, `hamilton_from_h` checks `hamilton`
//! against finite differences of `hamiltonian`.
//!
//! The second half runs the broken models of `tests/bad/`: each must exit with code 2
//! (never panic) and name the file, with `line:col` where the error has a place.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

use serde_json::Value;

use crate::common::{is_close, json, repo_root, run, Run};

/// Random sample points per comparison (coordinates, velocities, accelerations,
/// momenta, `t`, and the parameters scaled by a random factor in [0.6, 1.4]).
const SAMPLES: usize = 8;
/// Relative tolerance of a comparison of two expressions (with an absolute floor of the same size).
const RTOL: f64 = 1e-9;
/// Relative tolerance of a comparison with a finite-difference derivative.
const FD_RTOL: f64 = 1e-6;
/// The tolerances are relative to the value expected, or to this where it is smaller.
const FLOOR: f64 = 1.0;

// ------------------------------------------------------------------ running the binary

/// `lagrange derive PATH --format json`, which must succeed; the parsed output.
fn derive_json(path: &str) -> Value {
    let json = json(&["derive", path, "--format", "json"]);
    assert_eq!(json["format"], "lagrange.derive/1", "{path}: format");
    json
}

// ------------------------------------------------------------------ numeric comparison

/// A tiny fixed-seed linear congruential generator (Knuth's MMIX constants).
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

/// Which names an expression may use: each space is the previous one's names plus more.
#[derive(Clone, Copy, Debug)]
enum Space {
    /// Parameters, `t`, coordinates `q`.
    Config,
    /// Also velocities `q'`.
    Velocity,
    /// Also accelerations `q''`.
    Acceleration,
    /// Parameters, `t`, coordinates `q` and momenta `p_q` (no velocities).
    Phase,
}

/// One random point: the values of every name, split by the space they belong to.
struct Sample {
    config: HashMap<String, f64>,
    velocity: HashMap<String, f64>,
    acceleration: HashMap<String, f64>,
    phase: HashMap<String, f64>,
}

impl Sample {
    fn env(&self, space: Space) -> &HashMap<String, f64> {
        match space {
            Space::Config => &self.config,
            Space::Velocity => &self.velocity,
            Space::Acceleration => &self.acceleration,
            Space::Phase => &self.phase,
        }
    }
}

fn eval(pool: &mut sym::Pool, what: &str, src: &str, env: &HashMap<String, f64>) -> f64 {
    let expr = pool.parse(src).unwrap_or_else(|err| panic!("{what}: cannot parse {src:?}: {err:?}"));
    pool.eval(expr, &|name: &str| env.get(name).copied())
        .unwrap_or_else(|err| panic!("{what}: cannot evaluate {src:?} at {env:?}: {err:?}"))
}

/// Checks `actual == expected` at random points where `vars` (name, lo, hi) are drawn
/// uniformly and every other name is looked up in `params`.
#[track_caller]
fn check_expr_eq(what: &str, actual: &str, expected: &str, vars: &[(&str, f64, f64)], params: &HashMap<String, f64>) {
    let mut pool = sym::Pool::default();
    let mut rng = Rng(0x5eed_1a9a_4e5e_ed01);
    for _ in 0..SAMPLES {
        let mut env = params.clone();
        for &(name, lo, hi) in vars {
            env.insert(name.to_string(), rng.uniform(lo, hi));
        }
        let a = eval(&mut pool, what, actual, &env);
        let e = eval(&mut pool, what, expected, &env);
        assert!(e.is_finite(), "{what}: expected {expected:?} is not finite at {env:?}");
        assert!(
            is_close(a, e, RTOL, FLOOR),
            "{what}: got {actual:?} = {a}, the notes give {expected:?} = {e} at {env:?}"
        );
    }
}

// ------------------------------------------------------------------ one derived example

/// The derivation of one example and random sample points for its names.
struct Case {
    file: String,
    json: Value,
    pool: sym::Pool,
    coords: Vec<String>,
    samples: Vec<Sample>,
}

impl Case {
    /// Derives `examples/FILE`; `ranges` overrides the sampling interval of coordinates
    /// (default `[-1.5, 1.5]`), e.g. to keep a radius positive.
    fn new(file: &str, ranges: &[(&str, f64, f64)]) -> Case {
        let json = derive_json(&format!("examples/{file}"));
        let coords: Vec<String> = json["coordinates"]
            .as_array()
            .unwrap_or_else(|| panic!("{file}: `coordinates` is not an array"))
            .iter()
            .map(|q| q.as_str().expect("coordinate names are strings").to_string())
            .collect();
        // Sorted, so that the random draws go to the same names on every run.
        let mut params = BTreeMap::new();
        for (name, value) in
            json["parameters"].as_object().unwrap_or_else(|| panic!("{file}: `parameters` is not an object"))
        {
            let value = value.as_f64().unwrap_or_else(|| panic!("{file}: parameter {name} is not a number"));
            params.insert(name.clone(), value);
        }
        let mut rng = Rng(0x1a9_2a17_9e0c_ba5e);
        let mut samples = Vec::new();
        for _ in 0..SAMPLES {
            // Parameters vary too (keeping their sign), so that a model whose parameters
            // are all 1 still tells m from m^2.
            let mut config: HashMap<String, f64> =
                params.iter().map(|(name, value)| (name.clone(), value * rng.uniform(0.6, 1.4))).collect();
            config.insert("t".to_string(), rng.uniform(0.0, 3.0));
            for q in &coords {
                let (lo, hi) = ranges.iter().find(|r| r.0 == q).map(|r| (r.1, r.2)).unwrap_or((-1.5, 1.5));
                config.insert(q.clone(), rng.uniform(lo, hi));
            }
            let mut velocity = config.clone();
            let mut phase = config.clone();
            for q in &coords {
                velocity.insert(format!("{q}'"), rng.uniform(-1.5, 1.5));
                phase.insert(format!("p_{q}"), rng.uniform(-2.0, 2.0));
            }
            let mut acceleration = velocity.clone();
            for q in &coords {
                acceleration.insert(format!("{q}''"), rng.uniform(-2.0, 2.0));
            }
            samples.push(Sample { config, velocity, acceleration, phase });
        }
        Case { file: file.to_string(), json, pool: sym::Pool::default(), coords, samples }
    }

    fn n(&self) -> usize {
        self.coords.len()
    }

    /// The string at `json[path[0]][path[1]]...`.
    fn str_at(&self, path: &[&str]) -> String {
        let mut value = &self.json;
        for key in path {
            value = &value[*key];
        }
        value.as_str().unwrap_or_else(|| panic!("{}: {path:?} is not a string but {value}", self.file)).to_string()
    }

    fn value(&mut self, what: &str, src: &str, sample: usize, space: Space) -> f64 {
        let env = self.samples[sample].env(space);
        eval(&mut self.pool, what, src, env)
    }

    /// `actual == expected` at every sample point of `space`.
    #[track_caller]
    fn check(&mut self, what: &str, actual: &str, expected: &str, space: Space) {
        let what = format!("{}: {what}", self.file);
        for s in 0..self.samples.len() {
            let a = self.value(&what, actual, s, space);
            let e = self.value(&what, expected, s, space);
            assert!(e.is_finite(), "{what}: expected {expected:?} is not finite at sample {s}");
            assert!(
                is_close(a, e, RTOL, FLOOR),
                "{what}: got {actual:?} = {a}, the notes give {expected:?} = {e} at {:?}",
                self.samples[s].env(space)
            );
        }
    }

    /// The Lagrangian, as a function of (q, q', t).
    #[track_caller]
    fn lagrangian(&mut self, expected: &str) {
        let actual = self.str_at(&["lagrangian"]);
        self.check("lagrangian", &actual, expected, Space::Velocity);
    }

    /// The momenta p_q = ∂L/∂q', one entry per coordinate, in (q, q', t).
    #[track_caller]
    fn momenta(&mut self, expected: &[(&str, &str)]) {
        assert_eq!(expected.len(), self.n(), "{}: one momentum per coordinate", self.file);
        for &(q, p) in expected {
            let actual = self.str_at(&["momenta", q]);
            self.check(&format!("momentum p_{q}"), &actual, p, Space::Velocity);
        }
    }

    /// The rows of `mass_matrix` (functions of q, t) and `forcing` (of q, q', t).
    fn mass_forcing(&self) -> (Vec<Vec<String>>, Vec<String>) {
        let n = self.n();
        let rows = self.json["mass_matrix"]
            .as_array()
            .unwrap_or_else(|| panic!("{}: `mass_matrix` is not an array", self.file));
        assert_eq!(rows.len(), n, "{}: mass_matrix rows", self.file);
        let mass: Vec<Vec<String>> = rows
            .iter()
            .map(|row| {
                let row = row.as_array().expect("mass_matrix rows are arrays");
                assert_eq!(row.len(), n, "{}: mass_matrix columns", self.file);
                row.iter().map(|m| m.as_str().expect("mass_matrix entries are strings").to_string()).collect()
            })
            .collect();
        let forcing: Vec<String> = self.json["forcing"]
            .as_array()
            .unwrap_or_else(|| panic!("{}: `forcing` is not an array", self.file))
            .iter()
            .map(|f| f.as_str().expect("forcing entries are strings").to_string())
            .collect();
        assert_eq!(forcing.len(), n, "{}: forcing length", self.file);
        (mass, forcing)
    }

    /// `equations[q]` equals the expected E_q, and so does row q of `M·q'' − f`.
    #[track_caller]
    fn equations(&mut self, expected: &[(&str, &str)]) {
        let n = self.n();
        assert_eq!(expected.len(), n, "{}: one equation per coordinate", self.file);
        for &(q, e) in expected {
            let actual = self.str_at(&["equations", q]);
            self.check(&format!("equation E_{q}"), &actual, e, Space::Acceleration);
        }
        let (mass, forcing) = self.mass_forcing();
        let coords = self.coords.clone();
        for s in 0..self.samples.len() {
            for &(q, e) in expected {
                let i = coords
                    .iter()
                    .position(|c| c == q)
                    .unwrap_or_else(|| panic!("{}: {q} is not a coordinate", self.file));
                let what = format!("{}: row {q} of M*q'' - f", self.file);
                let mut row = -self.value(&what, &forcing[i], s, Space::Velocity);
                for (j, qj) in coords.iter().enumerate() {
                    let m_ij = self.value(&what, &mass[i][j], s, Space::Config);
                    row += m_ij * self.samples[s].acceleration[&format!("{qj}''")];
                }
                let want = self.value(&what, e, s, Space::Acceleration);
                assert!(
                    is_close(row, want, RTOL, FLOOR),
                    "{what}: M*q'' - f = {row}, the notes' E_{q} = {e:?} = {want} at {:?}",
                    self.samples[s].acceleration
                );
            }
        }
    }

    /// The notes' printed form of the equation of q: `factor * E_q == expected`.
    #[track_caller]
    fn equation_scaled(&mut self, q: &str, factor: &str, expected: &str) {
        let actual = self.str_at(&["equations", q]);
        let scaled = format!("({actual})*({factor})");
        self.check(&format!("equation E_{q} times {factor}"), &scaled, expected, Space::Acceleration);
    }

    /// `mass_matrix` entry by entry (functions of q, t).
    #[track_caller]
    fn mass_matrix(&mut self, expected: &[&[&str]]) {
        let (mass, _) = self.mass_forcing();
        let coords = self.coords.clone();
        for (i, row) in expected.iter().enumerate() {
            for (j, e) in row.iter().enumerate() {
                let what = format!("mass_matrix[{}][{}]", coords[i], coords[j]);
                self.check(&what, &mass[i][j], e, Space::Config);
            }
        }
    }

    /// `forcing` entry by entry (functions of q, q', t).
    #[track_caller]
    fn forcing(&mut self, expected: &[&str]) {
        let (_, forcing) = self.mass_forcing();
        let coords = self.coords.clone();
        for (i, e) in expected.iter().enumerate() {
            let what = format!("forcing[{}]", coords[i]);
            self.check(&what, &forcing[i], e, Space::Velocity);
        }
    }

    /// The Hamiltonian as a function of (q, p, t).
    #[track_caller]
    fn hamiltonian(&mut self, expected: &str) {
        let actual = self.str_at(&["hamiltonian"]);
        self.check("hamiltonian", &actual, expected, Space::Phase);
    }

    /// The Legendre transform: H(q, p(q, q'), t) == Σ p q' − L for every model.
    #[track_caller]
    fn legendre(&mut self) {
        let lagrangian = self.str_at(&["lagrangian"]);
        let hamiltonian = self.str_at(&["hamiltonian"]);
        let momenta: Vec<String> = self.coords.clone().iter().map(|q| self.str_at(&["momenta", q.as_str()])).collect();
        let coords = self.coords.clone();
        let what = format!("{}: H(q, p(q, q')) = sum p q' - L", self.file);
        for s in 0..self.samples.len() {
            let mut phase = self.samples[s].config.clone();
            let mut sum = -self.value(&what, &lagrangian, s, Space::Velocity);
            for (q, p) in coords.iter().zip(&momenta) {
                let p_value = self.value(&what, p, s, Space::Velocity);
                sum += p_value * self.samples[s].velocity[&format!("{q}'")];
                phase.insert(format!("p_{q}"), p_value);
            }
            let h = eval(&mut self.pool, &what, &hamiltonian, &phase);
            assert!(is_close(h, sum, RTOL, FLOOR), "{what}: H = {h}, sum p q' - L = {sum} at {phase:?}");
        }
    }

    /// `hamilton` as the notes print it: (q, dq, dp) in (q, p, t).
    #[track_caller]
    fn hamilton(&mut self, expected: &[(&str, &str, &str)]) {
        assert_eq!(expected.len(), self.n(), "{}: one pair per coordinate", self.file);
        for &(q, dq, dp) in expected {
            let actual_dq = self.str_at(&["hamilton", q, "dq"]);
            let actual_dp = self.str_at(&["hamilton", q, "dp"]);
            self.check(&format!("hamilton {q} dq"), &actual_dq, dq, Space::Phase);
            self.check(&format!("hamilton {q} dp"), &actual_dp, dp, Space::Phase);
        }
    }

    /// `hamilton` against finite differences of `hamiltonian`: dq = ∂H/∂p and
    /// dp = −∂H/∂q + extra, with `extra` (per coordinate, in (q, p, t)) the
    /// non-conservative part −∂R/∂q' + Q; coordinates not listed have none.
    #[track_caller]
    fn hamilton_from_h(&mut self, extra: &[(&str, &str)]) {
        let hamiltonian = self.str_at(&["hamiltonian"]);
        let coords = self.coords.clone();
        for s in 0..self.samples.len() {
            let point = self.samples[s].phase.clone();
            for q in &coords {
                let what = format!("{}: hamilton {q}", self.file);
                let dq = self.str_at(&["hamilton", q.as_str(), "dq"]);
                let dp = self.str_at(&["hamilton", q.as_str(), "dp"]);
                let dq_value = eval(&mut self.pool, &what, &dq, &point);
                let dp_value = eval(&mut self.pool, &what, &dp, &point);
                let dh_dp = self.derivative(&what, &hamiltonian, &point, &format!("p_{q}"));
                let mut want_dp = -self.derivative(&what, &hamiltonian, &point, q);
                if let Some((_, e)) = extra.iter().find(|(c, _)| *c == q.as_str()) {
                    want_dp += eval(&mut self.pool, &what, e, &point);
                }
                assert!(
                    is_close(dq_value, dh_dp, FD_RTOL, FLOOR),
                    "{what}: dq = {dq:?} = {dq_value}, dH/dp = {dh_dp} at {point:?}"
                );
                assert!(
                    is_close(dp_value, want_dp, FD_RTOL, FLOOR),
                    "{what}: dp = {dp:?} = {dp_value}, -dH/dq (+ extra) = {want_dp} at {point:?}"
                );
            }
        }
    }

    /// ∂src/∂name at `point` by the five-point central difference.
    fn derivative(&mut self, what: &str, src: &str, point: &HashMap<String, f64>, name: &str) -> f64 {
        let x = point[name];
        let h = 1e-3 * (1.0 + x.abs());
        let mut at = |dx: f64| {
            let mut env = point.clone();
            env.insert(name.to_string(), x + dx);
            eval(&mut self.pool, what, src, &env)
        };
        (-at(2.0 * h) + 8.0 * at(h) - 8.0 * at(-h) + at(-2.0 * h)) / (12.0 * h)
    }

    /// `hamiltonian_is_energy` (null when the model gives only a Lagrangian) and
    /// `hamiltonian_conserved`.
    #[track_caller]
    fn verdicts(&self, is_energy: Option<bool>, conserved: bool) {
        let actual = &self.json["hamiltonian_is_energy"];
        match is_energy {
            Some(b) => assert_eq!(actual, &Value::Bool(b), "{}: hamiltonian_is_energy", self.file),
            None => assert!(actual.is_null(), "{}: hamiltonian_is_energy is {actual}, not null", self.file),
        }
        assert_eq!(self.json["hamiltonian_conserved"], Value::Bool(conserved), "{}: hamiltonian_conserved", self.file);
    }

    /// `energy` = T + U in (q, q', t), or null.
    #[track_caller]
    fn energy(&mut self, expected: Option<&str>) {
        match expected {
            Some(e) => {
                let actual = self.str_at(&["energy"]);
                self.check("energy", &actual, e, Space::Velocity);
            }
            None => {
                assert!(self.json["energy"].is_null(), "{}: energy is {}, not null", self.file, self.json["energy"])
            }
        }
    }

    /// `dissipation` (Rayleigh's R) in (q, q', t), or null.
    #[track_caller]
    fn dissipation(&mut self, expected: Option<&str>) {
        match expected {
            Some(e) => {
                let actual = self.str_at(&["dissipation"]);
                self.check("dissipation", &actual, e, Space::Velocity);
            }
            None => assert!(
                self.json["dissipation"].is_null(),
                "{}: dissipation is {}, not null",
                self.file,
                self.json["dissipation"]
            ),
        }
    }

    /// `cyclic` as a set, and for each cyclic q an entry of `conserved` equal to p_q
    /// (the entry may be written in q, q', t or with the name p_q itself).
    #[track_caller]
    fn cyclic(&mut self, expected: &[&str]) {
        let actual: BTreeSet<String> = self.json["cyclic"]
            .as_array()
            .unwrap_or_else(|| panic!("{}: `cyclic` is not an array", self.file))
            .iter()
            .map(|q| q.as_str().expect("cyclic names are strings").to_string())
            .collect();
        let want: BTreeSet<String> = expected.iter().map(|q| q.to_string()).collect();
        assert_eq!(actual, want, "{}: cyclic coordinates", self.file);

        let conserved: Vec<(String, String)> = self.json["conserved"]
            .as_array()
            .unwrap_or_else(|| panic!("{}: `conserved` is not an array", self.file))
            .iter()
            .map(|c| {
                let name = c["name"].as_str().unwrap_or("").to_string();
                let expr = c["expr"].as_str().expect("conserved expr is a string").to_string();
                (name, expr)
            })
            .collect();
        let coords = self.coords.clone();
        let momenta: Vec<String> = coords.iter().map(|c| self.str_at(&["momenta", c.as_str()])).collect();
        for &q in expected {
            let what = format!("{}: conserved momentum of cyclic {q}", self.file);
            let mut found = false;
            for (_, expr) in &conserved {
                let mut equal = true;
                for s in 0..self.samples.len() {
                    let mut env = self.samples[s].velocity.clone();
                    for (c, p) in coords.iter().zip(&momenta) {
                        let p_value = eval(&mut self.pool, &what, p, &self.samples[s].velocity);
                        env.insert(format!("p_{c}"), p_value);
                    }
                    let want = env[&format!("p_{q}")];
                    let got = match self.pool.parse(expr) {
                        Ok(e) => self.pool.eval(e, &|name: &str| env.get(name).copied()).ok(),
                        Err(_) => None,
                    };
                    if !got.is_some_and(|v| is_close(v, want, RTOL, FLOOR)) {
                        equal = false;
                        break;
                    }
                }
                if equal {
                    found = true;
                    break;
                }
            }
            assert!(found, "{what}: no entry of `conserved` equals p_{q}: {conserved:?}");
        }
    }
}

// ------------------------------------------------------------------ chapter 2

/// Sec. 2.2.1 b), example (i), lines 640-660: L = m/2 x'^2 (1 + tan^2 al) - m g (h - x tan al),
/// ∂L/∂x' = m x'(1 + tan^2 al), d/dt ∂L/∂x' = m x''/cos^2 al, ∂L/∂x = m g tan al,
/// hence x'' = g sin al cos al.
#[test]
fn inclined_plane() {
    let mut c = Case::new("inclined_plane.toml", &[]);
    c.lagrangian("m/2*x'^2*(1 + tan(al)^2) - m*g*(h - x*tan(al))");
    c.momenta(&[("x", "m*x'*(1 + tan(al)^2)")]);
    c.equations(&[("x", "m*x''/cos(al)^2 - m*g*tan(al)")]);
    c.equation_scaled("x", "cos(al)^2/m", "x'' - g*sin(al)*cos(al)");
    c.hamiltonian("p_x^2*cos(al)^2/(2*m) + m*g*(h - x*tan(al))");
    c.energy(Some("m/2*x'^2*(1 + tan(al)^2) + m*g*(h - x*tan(al))"));
    c.verdicts(Some(true), true);
    c.cyclic(&[]);
    c.dissipation(None);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.2.1 b), example (iv), lines 664-681: L = m/2 l^2 ph'^2 + m g l cos ph,
/// m l^2 ph'' + m g l sin ph = 0, i.e. ph'' + (g/l) sin ph = 0; Sec. 2.4.1 line 1003:
/// p = m l^2 ph'; Sec. 2.4.2 d) (ii), lines 1156-1162: H = m/2 l^2 ph'^2 - m g l cos ph = E = const.
#[test]
fn planar_pendulum() {
    let mut c = Case::new("pendulum.toml", &[]);
    c.lagrangian("m/2*l^2*ph'^2 + m*g*l*cos(ph)");
    c.momenta(&[("ph", "m*l^2*ph'")]);
    c.equations(&[("ph", "m*l^2*ph'' + m*g*l*sin(ph)")]);
    c.equation_scaled("ph", "1/(m*l^2)", "ph'' + g/l*sin(ph)");
    c.hamiltonian("p_ph^2/(2*m*l^2) - m*g*l*cos(ph)");
    c.energy(Some("m/2*l^2*ph'^2 - m*g*l*cos(ph)"));
    c.verdicts(Some(true), true);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.2.1 b), cycloidal pendulum, lines 687-718: x = R(al - sin al), y = R(1 + cos al),
/// L = m R^2 al'^2 (1 - cos al) - m g R (1 + cos al), ∂L/∂al' = 2 m R^2 al'(1 - cos al),
/// d/dt ∂L/∂al' = 2 m R^2 (al''(1 - cos al) + al'^2 sin al),
/// ∂L/∂al = m R^2 al'^2 sin al + m g R sin al, and
/// 2 al''(1 - cos al) + al'^2 sin al - (g/R) sin al = 0.
/// The mass matrix vanishes at al = 0, so al is sampled in [0.4, 2.8].
#[test]
fn cycloidal_pendulum() {
    let mut c = Case::new("cycloidal_pendulum.toml", &[("al", 0.4, 2.8)]);
    c.lagrangian("m*R^2*al'^2*(1 - cos(al)) - m*g*R*(1 + cos(al))");
    c.momenta(&[("al", "2*m*R^2*al'*(1 - cos(al))")]);
    c.equations(&[("al", "2*m*R^2*(al''*(1 - cos(al)) + al'^2*sin(al)) - (m*R^2*al'^2*sin(al) + m*g*R*sin(al))")]);
    c.equation_scaled("al", "1/(m*R^2)", "2*al''*(1 - cos(al)) + al'^2*sin(al) - g/R*sin(al)");
    c.hamiltonian("p_al^2/(4*m*R^2*(1 - cos(al))) + m*g*R*(1 + cos(al))");
    c.energy(Some("m*R^2*al'^2*(1 - cos(al)) + m*g*R*(1 + cos(al))"));
    c.verdicts(Some(true), true);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.2.2 b), lines 829-846: the double pendulum's Lagrangian
/// L = (mA + mB)/2 lA^2 q1'^2 + mB/2 lB^2 q2'^2 + mB lA lB q1' q2' cos(q1 - q2)
///     + (mA + mB) g lA cos q1 + mB g lB cos q2 (q1 = a, q2 = b);
/// Sec. 2.4.2 d) (iii), lines 1166-1178: p_1, p_2 and H = T + U = E = const.
/// The notes print no equations of motion here; the expected E_q are
/// d/dt ∂L/∂q' - ∂L/∂q of the notes' L worked out by hand.
#[test]
fn double_pendulum() {
    let mut c = Case::new("double_pendulum.toml", &[("a", -3.0, 3.0), ("b", -3.0, 3.0)]);
    c.lagrangian(
        "(mA + mB)/2*lA^2*a'^2 + mB/2*lB^2*b'^2 + mB*lA*lB*a'*b'*cos(a - b) \
         + (mA + mB)*g*lA*cos(a) + mB*g*lB*cos(b)",
    );
    c.momenta(&[("a", "(mA + mB)*lA^2*a' + mB*lA*lB*b'*cos(a - b)"), ("b", "mB*lB^2*b' + mB*lA*lB*a'*cos(a - b)")]);
    c.equations(&[
        (
            "a",
            "(mA + mB)*lA^2*a'' + mB*lA*lB*b''*cos(a - b) + mB*lA*lB*b'^2*sin(a - b) \
             + (mA + mB)*g*lA*sin(a)",
        ),
        ("b", "mB*lB^2*b'' + mB*lA*lB*a''*cos(a - b) - mB*lA*lB*a'^2*sin(a - b) + mB*g*lB*sin(b)"),
    ]);
    c.mass_matrix(&[&["(mA + mB)*lA^2", "mB*lA*lB*cos(a - b)"], &["mB*lA*lB*cos(a - b)", "mB*lB^2"]]);
    // H = p^T M^-1 p / 2 + U with the 2x2 mass matrix above inverted by hand.
    c.hamiltonian(
        "(mB*lB^2*p_a^2 - 2*mB*lA*lB*cos(a - b)*p_a*p_b + (mA + mB)*lA^2*p_b^2) \
         / (2*((mA + mB)*lA^2*mB*lB^2 - (mB*lA*lB*cos(a - b))^2)) \
         - (mA + mB)*g*lA*cos(a) - mB*g*lB*cos(b)",
    );
    c.energy(Some(
        "(mA + mB)/2*lA^2*a'^2 + mB/2*lB^2*b'^2 + mB*lA*lB*a'*b'*cos(a - b) \
         - (mA + mB)*g*lA*cos(a) - mB*g*lB*cos(b)",
    ));
    c.verdicts(Some(true), true);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.4.1, example 2, lines 1013-1057: particle in a cone, q1 = r, q2 = ph,
/// L = m/2 (r'^2/sin^2 al + r^2 ph'^2) - m g r cot al, p_ph = m r^2 ph' = l_z const (ph cyclic),
/// d/dt ∂L/∂r' = m r''/sin^2 al, ∂L/∂r = m r ph'^2 - m g cot al, and
/// r'' - r ph'^2 sin^2 al + g sin al cos al = 0.
/// The notes give no equation for ph; E_ph is d/dt p_ph.
#[test]
fn particle_in_a_cone() {
    let mut c = Case::new("cone.toml", &[("r", 0.3, 2.0)]);
    c.lagrangian("m/2*(r'^2/sin(al)^2 + r^2*ph'^2) - m*g*r*cos(al)/sin(al)");
    c.momenta(&[("r", "m*r'/sin(al)^2"), ("ph", "m*r^2*ph'")]);
    c.equations(&[("r", "m*r''/sin(al)^2 - (m*r*ph'^2 - m*g*cos(al)/sin(al))"), ("ph", "m*r^2*ph'' + 2*m*r*r'*ph'")]);
    c.equation_scaled("r", "sin(al)^2/m", "r'' - r*ph'^2*sin(al)^2 + g*sin(al)*cos(al)");
    c.hamiltonian("p_r^2*sin(al)^2/(2*m) + p_ph^2/(2*m*r^2) + m*g*r*cos(al)/sin(al)");
    c.energy(Some("m/2*(r'^2/sin(al)^2 + r^2*ph'^2) + m*g*r*cos(al)/sin(al)"));
    c.verdicts(Some(true), true);
    c.cyclic(&["ph"]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.4.2 d) (iv), U = 0, lines 1182-1198: L = T = m/2 (r'^2 + r^2 om^2) = E,
/// H = m/2 (r'^2 - r^2 om^2) != E, dH/dt = -∂L/∂t = 0 so H = const,
/// m r'' - m om^2 r = 0.
#[test]
fn bead_on_rotating_wire() {
    let mut c = Case::new("rotating_wire.toml", &[]);
    c.lagrangian("m/2*(r'^2 + r^2*om^2)");
    c.momenta(&[("r", "m*r'")]);
    c.equations(&[("r", "m*r'' - m*om^2*r")]);
    c.equation_scaled("r", "1/m", "r'' - om^2*r");
    c.hamiltonian("p_r^2/(2*m) - m/2*r^2*om^2");
    c.energy(Some("m/2*(r'^2 + r^2*om^2)"));
    c.verdicts(Some(false), true);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.4.2 d) (iv), U = m g r sin(om t), lines 1214-1227:
/// L = m/2 (r'^2 + r^2 om^2) - m g r sin(om t), ∂L/∂t != 0,
/// H = m/2 (r'^2 - r^2 om^2) + m g r sin(om t) != E = m/2 (r'^2 + r^2 om^2) + m g r sin(om t);
/// none is conserved.
#[test]
fn bead_on_rotating_wire_with_gravity() {
    let mut c = Case::new("rotating_wire_gravity.toml", &[]);
    c.lagrangian("m/2*(r'^2 + r^2*om^2) - m*g*r*sin(om*t)");
    c.momenta(&[("r", "m*r'")]);
    c.equations(&[("r", "m*r'' - m*om^2*r + m*g*sin(om*t)")]);
    c.hamiltonian("p_r^2/(2*m) - m/2*r^2*om^2 + m*g*r*sin(om*t)");
    c.energy(Some("m/2*(r'^2 + r^2*om^2) + m*g*r*sin(om*t)"));
    c.verdicts(Some(false), false);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.4.2 d) (v), lines 1229-1236: F = F0 t, U = -F0 x t, L = m/2 x'^2 + F0 x t,
/// H = m/2 x'^2 - F0 x t = T + U = E(t), not conserved (∂L/∂t = F0 x = -dH/dt).
#[test]
fn time_dependent_force() {
    let mut c = Case::new("time_dependent_force.toml", &[]);
    c.lagrangian("m/2*x'^2 + F0*x*t");
    c.momenta(&[("x", "m*x'")]);
    c.equations(&[("x", "m*x'' - F0*t")]);
    c.hamiltonian("p_x^2/(2*m) - F0*x*t");
    c.energy(Some("m/2*x'^2 - F0*x*t"));
    c.verdicts(Some(true), false);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.4.2 d) (i), lines 1149-1154, and Sec. 2.5 (ii), lines 1281-1296:
/// L = m/2 (x'^2 - om^2 x^2), p = m x', H(x, p) = p^2/(2m) + m/2 om^2 x^2 = E = const,
/// p' = -m om^2 x, x' = p/m, x'' + om^2 x = 0.
#[test]
fn harmonic_oscillator() {
    let mut c = Case::new("oscillator.toml", &[]);
    c.lagrangian("m/2*(x'^2 - om^2*x^2)");
    c.momenta(&[("x", "m*x'")]);
    c.equations(&[("x", "m*x'' + m*om^2*x")]);
    c.equation_scaled("x", "1/m", "x'' + om^2*x");
    c.hamiltonian("p_x^2/(2*m) + m/2*om^2*x^2");
    c.hamilton(&[("x", "p_x/m", "-m*om^2*x")]);
    c.energy(Some("m/2*(x'^2 + om^2*x^2)"));
    c.verdicts(Some(true), true);
    c.cyclic(&[]);
    c.dissipation(None);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// The oscillator of Sec. 2.5 (ii) with Rayleigh's R = be/2 x'^2 of Sec. 2.6.2,
/// lines 1413-1436: d/dt ∂L/∂x' - ∂L/∂x + ∂R/∂x' = 0, i.e. m x'' + m om^2 x + be x' = 0;
/// dp/dt = -∂H/∂x - ∂R/∂x' = -m om^2 x - be p/m. H is T + U but not conserved.
#[test]
fn damped_oscillator() {
    let mut c = Case::new("damped_oscillator.toml", &[]);
    c.lagrangian("m/2*(x'^2 - om^2*x^2)");
    c.momenta(&[("x", "m*x'")]);
    c.equations(&[("x", "m*x'' + m*om^2*x + be*x'")]);
    c.hamiltonian("p_x^2/(2*m) + m/2*om^2*x^2");
    c.hamilton(&[("x", "p_x/m", "-m*om^2*x - be*p_x/m")]);
    c.energy(Some("m/2*(x'^2 + om^2*x^2)"));
    c.dissipation(Some("be/2*x'^2"));
    c.verdicts(Some(true), false);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[("x", "-be*p_x/m")]);
}

/// Sec. 2.5 (vi), lines 1313-1334, with U(r) = -k exp(-r/a)/r:
/// p_r = m r', p_ph = m r^2 ph' (ph cyclic), m r'' - m r ph'^2 + ∂U/∂r = 0,
/// r^2 ph'' + 2 r r' ph' = 0, H = p_r^2/(2m) + p_ph^2/(2 m r^2) + U(r),
/// p_r' = p_ph^2/(m r^3) - ∂U/∂r, p_ph' = 0, r' = p_r/m, ph' = p_ph/(m r^2).
#[test]
fn central_force_polar() {
    let u = "(-k*exp(-r/a)/r)";
    let du = "(k*exp(-r/a)*(1/r^2 + 1/(a*r)))";
    let lagrangian = format!("m/2*(r'^2 + r^2*ph'^2) - {u}");
    let e_r = format!("m*r'' - m*r*ph'^2 + {du}");
    let hamiltonian = format!("p_r^2/(2*m) + p_ph^2/(2*m*r^2) + {u}");
    let dp_r = format!("p_ph^2/(m*r^3) - {du}");
    let energy = format!("m/2*(r'^2 + r^2*ph'^2) + {u}");
    let mut c = Case::new("central_force.toml", &[("r", 0.3, 3.0)]);
    c.lagrangian(&lagrangian);
    c.momenta(&[("r", "m*r'"), ("ph", "m*r^2*ph'")]);
    c.equations(&[("r", &e_r), ("ph", "m*(r^2*ph'' + 2*r*r'*ph')")]);
    c.equation_scaled("ph", "1/m", "r^2*ph'' + 2*r*r'*ph'");
    c.hamiltonian(&hamiltonian);
    c.hamilton(&[("r", "p_r/m", &dp_r), ("ph", "p_ph/(m*r^2)", "0")]);
    c.energy(Some(&energy));
    c.verdicts(Some(true), true);
    c.cyclic(&["ph"]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.6.1 b), lines 1376-1410, with phi = -E0 x and A = B0/2 (-y, x, 0):
/// L = m/2 v^2 - Q phi + Q v.A, p_i = m x_i' + Q A_i,
/// H = (p - Q A)^2/(2m) + Q phi = E; the Lagrange equations are Newton's with the
/// Lorentz force m x'' = Q (E + v x B).
#[test]
fn charged_particle_in_fields() {
    let mut c = Case::new("charged_particle.toml", &[]);
    c.lagrangian("m*(x'^2 + y'^2 + z'^2)/2 + Q*E0*x + Q*B0*(x*y' - y*x')/2");
    c.momenta(&[("x", "m*x' - Q*B0*y/2"), ("y", "m*y' + Q*B0*x/2"), ("z", "m*z'")]);
    c.equations(&[("x", "m*x'' - Q*(E0 + y'*B0)"), ("y", "m*y'' - Q*(-x'*B0)"), ("z", "m*z''")]);
    c.hamiltonian("((p_x + Q*B0*y/2)^2 + (p_y - Q*B0*x/2)^2 + p_z^2)/(2*m) - Q*E0*x");
    c.energy(Some("m*(x'^2 + y'^2 + z'^2)/2 - Q*E0*x"));
    c.verdicts(Some(true), true);
    c.cyclic(&["z"]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 2.6.2, lines 1438-1446: L = m/2 z'^2 - m g z, R = be/2 z'^2 (the notes' beta),
/// m z'' + m g + be z' = 0.
#[test]
fn free_fall_with_air_resistance() {
    let mut c = Case::new("air_resistance.toml", &[]);
    c.lagrangian("m/2*z'^2 - m*g*z");
    c.momenta(&[("z", "m*z'")]);
    c.equations(&[("z", "m*z'' + m*g + be*z'")]);
    c.hamiltonian("p_z^2/(2*m) + m*g*z");
    c.hamilton(&[("z", "p_z/m", "-m*g - be*p_z/m")]);
    c.energy(Some("m/2*z'^2 + m*g*z"));
    c.dissipation(Some("be/2*z'^2"));
    c.verdicts(Some(true), false);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[("z", "-be*p_z/m")]);
}

// ------------------------------------------------------------------ chapter 3

/// Sec. 3.1.3, lines 1562-1592, with k = G mu M: L = mu/2 (r'^2 + r^2 th'^2) + k/r,
/// p_r = mu r', p_th = mu r^2 th' = l (th cyclic), mu r'' = mu r th'^2 - k/r^2 (eq. 3.1),
/// H = p_r^2/(2 mu) + l^2/(2 mu r^2) - k/r = E = const; Hamilton's equations as in
/// Sec. 2.5 (vi), lines 1318-1323, with U = -k/r. The model gives only `lagrangian`,
/// so `energy` and `hamiltonian_is_energy` are null.
#[test]
fn kepler_problem() {
    let mut c = Case::new("kepler.toml", &[("r", 0.3, 3.0)]);
    c.lagrangian("mu/2*(r'^2 + r^2*th'^2) + k/r");
    c.momenta(&[("r", "mu*r'"), ("th", "mu*r^2*th'")]);
    c.equations(&[("r", "mu*r'' - mu*r*th'^2 + k/r^2"), ("th", "mu*r^2*th'' + 2*mu*r*r'*th'")]);
    c.hamiltonian("p_r^2/(2*mu) + p_th^2/(2*mu*r^2) - k/r");
    c.hamilton(&[("r", "p_r/mu", "p_th^2/(mu*r^3) - k/r^2"), ("th", "p_th/(mu*r^2)", "0")]);
    c.energy(None);
    c.verdicts(None, true);
    c.cyclic(&["th"]);
    c.dissipation(None);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 3.3.1, lines 2113-2129: L = m1/2 q1'^2 + m2/2 q2'^2 - (k1 q1^2 + k2 q2^2 + k12 (q1 - q2)^2)/2,
/// q1'' + k1/m1 q1 + k12/m1 (q1 - q2) = 0 and q2'' + k2/m2 q2 + k12/m2 (q2 - q1) = 0;
/// Sec. 3.3.3 example (i), lines 2312-2315: T = diag(m1, m2),
/// U = [[k1 + k12, -k12], [-k12, k2 + k12]], so M = T and f = -U q.
#[test]
fn two_coupled_oscillators() {
    let mut c = Case::new("coupled_oscillators.toml", &[]);
    c.lagrangian("m1/2*q1'^2 + m2/2*q2'^2 - (k1*q1^2 + k2*q2^2 + k12*(q1 - q2)^2)/2");
    c.momenta(&[("q1", "m1*q1'"), ("q2", "m2*q2'")]);
    c.equations(&[("q1", "m1*q1'' + k1*q1 + k12*(q1 - q2)"), ("q2", "m2*q2'' + k2*q2 + k12*(q2 - q1)")]);
    c.equation_scaled("q1", "1/m1", "q1'' + k1/m1*q1 + k12/m1*(q1 - q2)");
    c.equation_scaled("q2", "1/m2", "q2'' + k2/m2*q2 + k12/m2*(q2 - q1)");
    c.mass_matrix(&[&["m1", "0"], &["0", "m2"]]);
    c.forcing(&["-((k1 + k12)*q1 - k12*q2)", "-(-k12*q1 + (k2 + k12)*q2)"]);
    c.hamiltonian("p_q1^2/(2*m1) + p_q2^2/(2*m2) + (k1*q1^2 + k2*q2^2 + k12*(q1 - q2)^2)/2");
    c.energy(Some("m1/2*q1'^2 + m2/2*q2'^2 + (k1*q1^2 + k2*q2^2 + k12*(q1 - q2)^2)/2"));
    c.verdicts(Some(true), true);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// Sec. 3.3.3 example (2), lines 2324-2338: T = diag(m, M, m),
/// U = k [[1, -1, 0], [-1, 2, -1], [0, -1, 1]], T q'' + U q = 0.
#[test]
fn linear_triatomic_molecule() {
    let mut c = Case::new("triatomic.toml", &[]);
    c.lagrangian("m/2*(q1'^2 + q3'^2) + M/2*q2'^2 - (k/2*(q1 - q2)^2 + k/2*(q3 - q2)^2)");
    c.momenta(&[("q1", "m*q1'"), ("q2", "M*q2'"), ("q3", "m*q3'")]);
    c.equations(&[
        ("q1", "m*q1'' + k*q1 - k*q2"),
        ("q2", "M*q2'' - k*q1 + 2*k*q2 - k*q3"),
        ("q3", "m*q3'' - k*q2 + k*q3"),
    ]);
    c.mass_matrix(&[&["m", "0", "0"], &["0", "M", "0"], &["0", "0", "m"]]);
    c.forcing(&["-(k*q1 - k*q2)", "-(-k*q1 + 2*k*q2 - k*q3)", "-(-k*q2 + k*q3)"]);
    c.hamiltonian("p_q1^2/(2*m) + p_q3^2/(2*m) + p_q2^2/(2*M) + k/2*(q1 - q2)^2 + k/2*(q3 - q2)^2");
    c.energy(Some("m/2*(q1'^2 + q3'^2) + M/2*q2'^2 + k/2*(q1 - q2)^2 + k/2*(q3 - q2)^2"));
    c.verdicts(Some(true), true);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

/// The 50-mass chain of Sec. 3.3.2's general form (bench/README.md): T = diag(m1..m50),
/// E_i = m_i x_i'' + k_i (x_i - x_{i-1}) - k_{i+1} (x_{i+1} - x_i) with x_0 = x_51 = 0.
#[test]
fn chain_of_fifty_masses() {
    let n = 50;
    let x = |i: usize| if i == 0 || i == n + 1 { "0".to_string() } else { format!("x{i}") };
    let mut c = Case::new("chain50.toml", &[]);
    let springs: Vec<String> = (1..=n + 1).map(|j| format!("k{j}*({} - {})^2/2", x(j), x(j - 1))).collect();
    let potential = format!("({})", springs.join(" + "));
    let kinetic: Vec<String> = (1..=n).map(|i| format!("m{i}*x{i}'^2/2")).collect();
    c.lagrangian(&format!("{} - {potential}", kinetic.join(" + ")));
    let momenta: Vec<(String, String)> = (1..=n).map(|i| (format!("x{i}"), format!("m{i}*x{i}'"))).collect();
    let momenta: Vec<(&str, &str)> = momenta.iter().map(|(q, p)| (q.as_str(), p.as_str())).collect();
    c.momenta(&momenta);
    let equations: Vec<(String, String)> = (1..=n)
        .map(|i| {
            let e = format!("m{i}*x{i}'' + k{i}*(x{i} - {}) - k{}*({} - x{i})", x(i - 1), i + 1, x(i + 1));
            (format!("x{i}"), e)
        })
        .collect();
    let equations: Vec<(&str, &str)> = equations.iter().map(|(q, e)| (q.as_str(), e.as_str())).collect();
    c.equations(&equations);
    let p_terms: Vec<String> = (1..=n).map(|i| format!("p_x{i}^2/(2*m{i})")).collect();
    c.hamiltonian(&format!("{} + {potential}", p_terms.join(" + ")));
    c.energy(None);
    c.verdicts(None, true);
    c.cyclic(&[]);
    c.legendre();
    c.hamilton_from_h(&[]);
}

// ------------------------------------------------------------------ every example

fn example_files() -> Vec<String> {
    let dir = repo_root().join("examples");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|err| panic!("cannot read {}: {err}", dir.display()))
        .map(|entry| entry.expect("directory entry").file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".toml"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no examples/*.toml");
    files
}

/// Every model under `examples/` derives, and its JSON has the contract's shape.
#[test]
fn every_example_derives() {
    for file in example_files() {
        let json = derive_json(&format!("examples/{file}"));
        let coords = json["coordinates"].as_array().expect("coordinates");
        let n = coords.len();
        assert!(n > 0, "{file}: no coordinates");
        for key in ["name", "lagrangian", "hamiltonian"] {
            assert!(json[key].is_string(), "{file}: `{key}` is not a string");
        }
        for q in coords {
            let q = q.as_str().expect("coordinate names are strings");
            assert!(json["momenta"][q].is_string(), "{file}: momenta[{q}]");
            assert!(json["equations"][q].is_string(), "{file}: equations[{q}]");
            assert!(json["hamilton"][q]["dq"].is_string(), "{file}: hamilton[{q}].dq");
            assert!(json["hamilton"][q]["dp"].is_string(), "{file}: hamilton[{q}].dp");
        }
        assert_eq!(json["mass_matrix"].as_array().map(Vec::len), Some(n), "{file}: mass_matrix");
        assert_eq!(json["forcing"].as_array().map(Vec::len), Some(n), "{file}: forcing");
        assert!(json["cyclic"].is_array(), "{file}: cyclic");
        assert!(json["conserved"].is_array(), "{file}: conserved");
        assert!(json["hamiltonian_conserved"].is_boolean(), "{file}: hamiltonian_conserved");
        assert!(json["parameters"].is_object(), "{file}: parameters");
    }
}

/// Every model under `examples/` also prints as text and as LaTeX.
#[test]
fn every_example_prints_text_and_latex() {
    for file in example_files() {
        for format in ["text", "latex"] {
            let path = format!("examples/{file}");
            let run = run(&["derive", &path, "--format", format]);
            assert_eq!(run.code, Some(0), "derive {path} --format {format}\nstderr:\n{}", run.stderr);
            assert!(!run.stdout.trim().is_empty(), "derive {path} --format {format}: empty output");
        }
    }
}

// ------------------------------------------------------------------ bad input

/// `lagrange derive tests/bad/FILE --format json`: exit code 2, no panic, the file named.
#[track_caller]
fn derive_bad(file: &str) -> Run {
    let path = format!("crates/cli/tests/bad/{file}");
    let run = run(&["derive", &path, "--format", "json"]);
    assert!(!run.stderr.contains("panicked"), "{file}: lagrange panicked\nstderr:\n{}", run.stderr);
    assert_eq!(
        run.code,
        Some(2),
        "{file}: exit code (2 = bad input; 101 = panic; None = killed by a signal)\nstderr:\n{}",
        run.stderr
    );
    assert!(run.stderr.contains(file), "{file}: stderr does not name the file\nstderr:\n{}", run.stderr);
    run
}

/// Every `FILE:LINE:COL` in `text`.
fn locations(text: &str, file: &str) -> Vec<(usize, usize)> {
    fn number(s: &str) -> Option<(usize, &str)> {
        let end = s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
        let value = s[..end].parse().ok()?;
        Some((value, &s[end..]))
    }
    text.match_indices(file)
        .filter_map(|(at, _)| {
            let rest = text[at + file.len()..].strip_prefix(':')?;
            let (line, rest) = number(rest)?;
            let (col, _) = number(rest.strip_prefix(':')?)?;
            Some((line, col))
        })
        .collect()
}

/// stderr has `FILE:LINE:COL`, on `line` when given (and at `col` when given).
#[track_caller]
fn assert_located(run: &Run, file: &str, line: Option<usize>, col: Option<usize>) {
    let found = locations(&run.stderr, file);
    assert!(
        found.iter().any(|&(l, c)| line.is_none_or(|want| l == want) && col.is_none_or(|want| c == want)),
        "{file}: stderr has no {file}:{}:{} location\nstderr:\n{}",
        line.map_or("LINE".to_string(), |l| l.to_string()),
        col.map_or("COL".to_string(), |c| c.to_string()),
        run.stderr
    );
}

#[test]
fn bad_malformed_toml() {
    let run = derive_bad("malformed_toml.toml");
    assert_located(&run, "malformed_toml.toml", None, None);
}

#[test]
fn bad_unknown_name() {
    // Line 4 is `lagrangian = "m*x'^2/2 - k*y^2/2"`; `y` is its 28th character.
    let run = derive_bad("unknown_name.toml");
    assert_located(&run, "unknown_name.toml", Some(4), Some(28));
}

#[test]
fn bad_syntax_error() {
    let run = derive_bad("syntax_error.toml");
    assert_located(&run, "syntax_error.toml", Some(4), None);
}

#[test]
fn bad_duplicate_coordinate() {
    let run = derive_bad("duplicate_coordinate.toml");
    assert_located(&run, "duplicate_coordinate.toml", Some(3), None);
}

#[test]
fn bad_parameter_shadows_coordinate() {
    // Line 9 is `x = 2.0` in [parameters].
    let run = derive_bad("parameter_shadows_coordinate.toml");
    assert_located(&run, "parameter_shadows_coordinate.toml", Some(9), None);
}

#[test]
fn bad_singular_mass_matrix() {
    derive_bad("singular_mass_matrix.toml");
}

#[test]
fn bad_body_file_missing() {
    // Line 13 is `inertia = "top_body.toml"`, a body file that is not there.
    let run = derive_bad("body_file_missing.toml");
    assert_located(&run, "body_file_missing.toml", Some(13), None);
}

#[test]
fn bad_deep_nesting() {
    let run = derive_bad("deep_nesting.toml");
    assert_located(&run, "deep_nesting.toml", Some(4), None);
}

/// Huge powers are refused where they are written (the parser's exponent
/// limit), never expanded, unrolled or evaluated into a hang.
#[test]
fn bad_huge_exponents() {
    for file in ["huge_exponent.toml", "huge_constant_power.toml"] {
        let run = derive_bad(file);
        assert!(run.stderr.contains("exponent"), "{file}: stderr does not say what is wrong\n{}", run.stderr);
        assert_located(&run, file, None, None);
    }
}

/// Whatever is under `tests/bad/` fails cleanly, including files added later.
#[test]
fn every_bad_model_exits_2() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|err| panic!("cannot read {}: {err}", dir.display()))
        .map(|entry| entry.expect("directory entry").file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 8, "tests/bad has {} models", files.len());
    for file in files {
        derive_bad(&file);
    }
}

/// The comparison helper itself: equal forms pass, different ones do not.
#[test]
fn check_expr_eq_accepts_equal_forms() {
    let params: HashMap<String, f64> = [("m".to_string(), 2.0), ("l".to_string(), 0.5)].into();
    check_expr_eq("double angle", "m*l^2*sin(2*x)", "2*m*l^2*sin(x)*cos(x)", &[("x", -3.0, 3.0)], &params);
    check_expr_eq("rational", "1/2*x'^2", "x'^2/2", &[("x'", -2.0, 2.0)], &params);
    let differs =
        std::panic::catch_unwind(|| check_expr_eq("differs", "sin(x)", "cos(x)", &[("x", -3.0, 3.0)], &HashMap::new()));
    assert!(differs.is_err(), "sin(x) == cos(x) must fail");
}
