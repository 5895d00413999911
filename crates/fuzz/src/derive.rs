//! Target (c): derive on valid models, checked against the [`Oracle`]. Enter
//! with [`check_derivation`] (one model text) or [`DeriveTarget`] (models from
//! [`crate::generate`]).
//!
//! For a model that loads: derive never panics and its errors point inside
//! the text; a singular mass matrix is one the oracle finds singular too; the
//! report serializes and every expression in it parses back to the same value.
//! At random points where the oracle's values are finite and moderate: L, the
//! momenta, M (entry by entry against a symmetric one), the equations `E = M q'' − f`, the energy
//! function, T + U₀, H(q, p), q'(q, p) and Hamilton's equations agree with the
//! oracle; M and f are finite. Over the points: the cyclic coordinates are those
//! with ∂L/∂q = 0, H is conserved exactly when ∂L/∂t, R, Q and the constraints'
//! time terms vanish, and H is the energy exactly when h = T + U₀.

use crate::generate;
use crate::oracle::{Oracle, Point};
use crate::rng::Rng;
use crate::run::{FindingKind, Outcome, Target};
use crate::spans::{check_model_error, signature_of};
use mech::{Derivation, DeriveReport, Model};
use sym::{ExprId, Limits, ParseOptions, Pool};

/// Random points tried per model; those where the oracle is not finite and
/// moderate are skipped.
const POINTS: usize = 8;
/// Values beyond this are not compared: rounding in long sums of large terms
/// would dominate.
const MODERATE: f64 = 1e4;
/// Relative tolerance of a comparison, against 1 + |a| + |b| + the largest
/// of the oracle's values at the point (terms of that size may cancel).
const RTOL: f64 = 1e-7;

/// Loads, derives and checks the model `text` against the oracle.
pub fn check_derivation(text: &str) -> Outcome {
    let model = match Model::parse(text, &[]) {
        Ok(model) => model,
        Err(err) => return error_outcome(text, &err, "load error"),
    };
    check_model(text, model)
}

/// Derives and checks a loaded model; `text` is its source (for spans).
pub(crate) fn check_model(text: &str, model: Model) -> Outcome {
    // Inputs take their values, as in every run.
    let model = model.with_inputs_applied();
    let oracle = Oracle::new(&model);
    let d = match Derivation::new(model) {
        Ok(d) => d,
        Err(err) => {
            let outcome = error_outcome(text, &err, "derive error");
            if outcome.problem.is_none() && err.kind == mech::ModelErrorKind::SingularMassMatrix {
                if let Some(o) = &oracle {
                    if let Some(problem) = regular_mass_matrix(o, text) {
                        return problem;
                    }
                }
            }
            return outcome;
        }
    };
    if let Some(problem) = report_reads_back(&d) {
        return problem;
    }
    let o = match (oracle, d.kinetic(), d.potential()) {
        (Some(o), _, _) => o,
        (None, Some(tt), Some(uu)) => {
            let forces = (!d.model().loads.is_empty()).then(|| d.forces().to_vec());
            Oracle::with_energies(d.model(), d.pool().clone(), tt, uu, forces)
        }
        (None, _, _) => return Outcome::fine("derived (bodies without T and U)"),
    };
    let mut rng = Rng::new(hash(text));
    let mut compared = 0;
    for _ in 0..POINTS {
        let Some(point) = o.point(&mut rng) else { continue };
        match compare_at(&d, &o, &point) {
            Ok(true) => compared += 1,
            Ok(false) => {}
            Err(problem) => return problem,
        }
    }
    let mut flags = Flags::new(d.q().len());
    for _ in 0..POINTS {
        if let Some(point) = o.probe_point(&mut rng) {
            record_verdicts(&o, &point, &mut flags);
        }
    }
    if compared < 2 {
        return Outcome::fine("derived (no moderate points)");
    }
    if let Some(problem) = check_flags(&d, &o, &flags) {
        return problem;
    }
    Outcome::fine(format!(
        "derived: H {}, cyclic {}, conserved {}, energy {:?}",
        d.hamiltonian().is_some(),
        d.cyclic().len(),
        d.hamiltonian_conserved(),
        d.hamiltonian_is_energy()
    ))
}

/// The outcome of an error: a span finding, or a fine outcome named by the error.
fn error_outcome(text: &str, err: &mech::ModelError, what: &str) -> Outcome {
    match check_model_error(text, err) {
        Err(why) => Outcome::problem(FindingKind::Span, format!("{what}: {why}")),
        Ok(()) => Outcome::fine(format!("{what}: {}", signature_of(&err.message))),
    }
}

/// A stable hash of the text (FNV-1a), the seed of its points.
fn hash(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

/// What the points say about one quantity that may vanish identically.
#[derive(Clone, Copy, Default)]
struct Vanishing {
    /// Points where it vanished against terms of ordinary size.
    zero: usize,
    /// Points where it did not vanish.
    nonzero: usize,
}

impl Vanishing {
    fn record(&mut self, v: Option<Zero>) {
        match v {
            Some(Zero::Yes) => self.zero += 1,
            Some(Zero::No) => self.nonzero += 1,
            None => {}
        }
    }

    /// Shown to be zero: zero at every compared point, and at least two.
    fn zero(self, valid: usize) -> bool {
        self.nonzero == 0 && self.zero == valid && valid >= 2
    }

    /// Shown not to be zero.
    fn nonzero(self) -> bool {
        self.nonzero > 0
    }
}

/// What the points say about the derivation's yes/no answers.
struct Flags {
    /// Points compared.
    valid: usize,
    /// ∂L/∂q per coordinate.
    dl_dq: Vec<Vanishing>,
    /// ∂L/∂t, R and Q together (any of them not zero: H is not conserved).
    rate: Vanishing,
    /// h − (T + U₀).
    energy_gap: Vanishing,
}

impl Flags {
    fn new(n: usize) -> Flags {
        Flags {
            valid: 0,
            dl_dq: vec![Vanishing::default(); n],
            rate: Vanishing::default(),
            energy_gap: Vanishing::default(),
        }
    }
}

/// Whether an expression vanishes at a point.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Zero {
    Yes,
    No,
}

/// Whether `e` of the oracle's pool vanishes at `point` against the size of
/// its terms (the expression with every sum's terms made positive): not zero
/// when |e| > 10⁻⁷ of that size; zero when below 10⁻¹⁰ of it and every term is of
/// ordinary size; unknown (None) when the size is below 10⁻⁶ or a term is
/// below 10⁻⁸ of it (`x'^1000` underflows: no point tells it from zero).
fn vanishes(o: &Oracle, e: ExprId, point: &Point) -> Option<Zero> {
    let v = o.eval(&o.pool, e, point).ok().filter(|v| v.is_finite())?;
    let mut memo = Default::default();
    let size = magnitude(o, e, point, &mut memo).filter(|m| m.is_finite())?;
    if v.abs() > 1e-7 * size {
        return Some(Zero::No);
    }
    // Between the two bounds is the derivation's own tolerance (10⁻¹⁰ of the
    // terms): a difference of 10⁻⁹ (a position with exp(-(3 + t)^2) in it) may
    // be called zero or not, and neither answer is a finding.
    if v.abs() > 1e-10 * size {
        return None;
    }
    let tiny_term = o.pool.terms(e).into_iter().any(|t| {
        let m = magnitude(o, t, point, &mut memo).unwrap_or(0.0);
        m > 0.0 && m < 1e-8 * size
    });
    (size >= 1e-6 && !tiny_term).then_some(Zero::Yes)
}

/// The scale of the rounding error of evaluating `e` at `point`, in units of
/// the unit roundoff, to first order: a number or function value is its own
/// scale; a sum adds its terms' scales (so a sum that cancels keeps the size of
/// its terms); a product sums each factor's scale times the others' values; a
/// power bⁿ is |n|·|b|ⁿ⁻¹ times b's scale. Memoized as (value, scale).
fn magnitude(o: &Oracle, e: ExprId, point: &Point, memo: &mut Memo) -> Option<f64> {
    scaled(o, e, point, memo).map(|(_, scale)| scale)
}

/// Values and rounding scales of subexpressions at one point.
type Memo = std::collections::HashMap<ExprId, (f64, f64)>;

fn scaled(o: &Oracle, e: ExprId, point: &Point, memo: &mut Memo) -> Option<(f64, f64)> {
    if let Some(&m) = memo.get(&e) {
        return Some(m);
    }
    let pool = &o.pool;
    let value = o.eval(pool, e, point).ok()?;
    let scale = match pool.node(e) {
        sym::Node::Add(terms) => {
            let mut total = 0.0;
            for &t in terms.iter() {
                total += scaled(o, t, point, memo)?.1;
            }
            total
        }
        sym::Node::Mul(factors) => {
            let parts: Vec<(f64, f64)> = factors.iter().map(|&f| scaled(o, f, point, memo)).collect::<Option<_>>()?;
            let mut total = 0.0;
            for (i, (_, scale)) in parts.iter().enumerate() {
                let others: f64 = parts.iter().enumerate().filter(|&(j, _)| j != i).map(|(_, p)| p.0.abs()).product();
                total += scale * others;
            }
            total
        }
        sym::Node::Pow(base, exp) if pool.as_number(*exp).is_some() => {
            let n = pool.as_number(*exp)?.to_f64();
            let (b, scale) = scaled(o, *base, point, memo)?;
            n.abs() * b.abs().powf(n - 1.0) * scale
        }
        _ => value.abs(),
    };
    let m = (value, scale.max(value.abs()));
    memo.insert(e, m);
    Some(m)
}

/// What one probe point says about the quantities behind the yes/no answers.
fn record_verdicts(o: &Oracle, point: &Point, flags: &mut Flags) {
    flags.valid += 1;
    for (i, &dl) in o.dl_dq.iter().enumerate() {
        flags.dl_dq[i].record(vanishes(o, dl, point));
    }
    if let Some(gap) = o.energy_gap {
        flags.energy_gap.record(vanishes(o, gap, point));
    }
    // H is conserved when ∂L/∂t, R, Q and the time terms of the constraints
    // (the work of their forces) all vanish.
    let mut rate = vec![vanishes(o, o.dl_dt, point), vanishes(o, o.dissipation, point)];
    rate.extend(o.forces.iter().map(|&f| vanishes(o, f, point)));
    rate.extend(o.constraints.iter().map(|c| vanishes(o, c.1, point)));
    flags.rate.record(if rate.contains(&Some(Zero::No)) {
        Some(Zero::No)
    } else if rate.iter().all(|r| *r == Some(Zero::Yes)) {
        Some(Zero::Yes)
    } else {
        None
    });
}

/// Compares the derivation with the oracle at one point; false when the
/// point was skipped (an oracle value not finite or not moderate).
fn compare_at(d: &Derivation, o: &Oracle, point: &Point) -> Result<bool, Outcome> {
    let n = d.q().len();
    let op = &o.pool;
    // The oracle's values; the point is skipped unless all are finite and moderate.
    let mut oracle_values = Vec::new();
    let mut ov = |e: ExprId| -> Option<f64> {
        let v = o.eval(op, e, point).ok().filter(|v| v.is_finite() && v.abs() < MODERATE)?;
        oracle_values.push(v);
        Some(v)
    };
    let collect = |f: &mut dyn FnMut(ExprId) -> Option<f64>, es: &[ExprId]| -> Option<Vec<f64>> {
        es.iter().map(|&e| f(e)).collect()
    };
    let Some(l) = ov(o.lagrangian) else { return Ok(false) };
    let Some(p) = collect(&mut ov, &o.momenta) else { return Ok(false) };
    let mut m = Vec::with_capacity(n);
    for row in &o.mass_matrix {
        let Some(r) = collect(&mut ov, row) else { return Ok(false) };
        m.push(r);
    }
    let Some(residual) = collect(&mut ov, &o.residual) else { return Ok(false) };
    // ∂L/∂q, ∂L/∂t, R and Q are only tested for zero, but must be finite too.
    let Some(_) = collect(&mut ov, &o.dl_dq) else { return Ok(false) };
    let Some(rates) = collect(&mut ov, &o.momentum_rates) else { return Ok(false) };
    let Some(h) = ov(o.energy_function) else { return Ok(false) };
    let Some(_) = ov(o.dl_dt) else { return Ok(false) };
    let Some(_) = ov(o.dissipation) else { return Ok(false) };
    let Some(_) = collect(&mut ov, &o.forces) else { return Ok(false) };
    let energy = match o.energy {
        Some(e) => match ov(e) {
            Some(v) => Some(v),
            None => return Ok(false),
        },
        None => None,
    };
    let mut rows = Vec::new();
    for (row, time_term) in &o.constraints {
        let Some(a) = collect(&mut ov, row) else { return Ok(false) };
        let Some(_) = ov(*time_term) else { return Ok(false) };
        rows.push(a);
    }
    let scale = oracle_values.iter().fold(0.0f64, |s, v| s.max(v.abs()));

    let dp = d.pool();
    let mismatch = |what: String, ours: f64, want: f64| {
        Outcome::problem(FindingKind::Invariant, format!("{what} is {ours} but the oracle's is {want} at {point:?}"))
    };
    let value = |e: ExprId| o.eval(dp, e, point);
    // The oracle's value is finite here, so ours must be too (M and f included).
    let check = |what: &dyn Fn() -> String, e: ExprId, want: f64| -> Result<(), Outcome> {
        match value(e) {
            Ok(v) if (v - want).abs() <= RTOL * (1.0 + v.abs() + want.abs() + scale) => Ok(()),
            Ok(v) => Err(mismatch(what(), v, want)),
            Err(err) => Err(Outcome::problem(FindingKind::Invariant, format!("{} does not evaluate: {err}", what()))),
        }
    };
    let names = d.coordinate_names();
    check(&|| "L".into(), d.lagrangian(), l)?;
    for i in 0..n {
        check(&|| format!("p_{}", names[i]), d.momenta()[i], p[i])?;
        for j in 0..n {
            check(&|| format!("M[{i}][{j}]"), d.mass_matrix()[i][j], m[i][j])?;
        }
        check(&|| format!("the equation of {}", names[i]), d.equations()[i], residual[i])?;
        // E = M q'' − f, from M and f themselves.
        let f = value(d.forcing()[i]).map_err(|e| Outcome::problem(FindingKind::Invariant, e))?;
        let mut m_qdd = 0.0;
        for j in 0..n {
            m_qdd += value(d.mass_matrix()[i][j]).unwrap_or(f64::NAN) * point.qdd[j];
        }
        if !f.is_finite() {
            return Err(mismatch(format!("f[{i}] (where the oracle is finite)"), f, residual[i] - m_qdd));
        }
        let e = m_qdd - f;
        if (e - residual[i]).abs() > RTOL * (1.0 + e.abs() + residual[i].abs() + scale) {
            return Err(mismatch(format!("M q'' − f of {}", names[i]), e, residual[i]));
        }
    }
    check(&|| "the energy function".into(), d.energy_function(), h)?;
    if let (Some(ours), Some(want)) = (d.energy(), energy) {
        check(&|| "the energy T + U₀".into(), ours, want)?;
    }
    // H and q'(q, p) hold M⁻¹(p − b), and ṗ its derivatives: only compared
    // where M is well conditioned (near a body's gimbal lock, sin β → 0, the
    // rounding of M⁻¹ grows past any tolerance) and p is not b up to rounding
    // (a tiny M beside O(1) terms linear in q' leaves no digits of M q' in p).
    let carried = (0..n).all(|i| {
        let m_qd: f64 = (0..n).map(|j| m[i][j] * point.qd[j]).sum();
        p[i].abs() <= 1e6 * m_qd.abs()
    });
    let regular = hadamard_ratio(m.clone()) > 1e-4 && carried;
    if let (Some(hamiltonian), true) = (d.hamiltonian(), regular) {
        check(&|| "H(q, p)".into(), hamiltonian, h)?;
        let velocities = d.velocities().unwrap_or_default();
        for i in 0..n.min(velocities.len()) {
            check(&|| format!("q' of {} in (q, p)", names[i]), velocities[i], point.qd[i])?;
        }
        for (i, &(dq, dpdt)) in d.hamilton().unwrap_or_default().iter().enumerate() {
            check(&|| format!("dq/dt of {}", names[i]), dq, point.qd[i])?;
            check(&|| format!("dp/dt of {}", names[i]), dpdt, rates[i])?;
        }
    }
    for (k, a) in rows.iter().enumerate() {
        let c = &d.constraints().list[k];
        for i in 0..n {
            check(&|| format!("A[{}][{}]", c.name, names[i]), c.jacobian[i], a[i])?;
        }
    }
    Ok(true)
}

/// The yes/no answers of the derivation against what the points showed: a
/// "zero" answer (cyclic, conserved, H is the energy) is wrong where the
/// quantity did not vanish, a "not zero" answer where it vanished at every point.
fn check_flags(d: &Derivation, o: &Oracle, flags: &Flags) -> Option<Outcome> {
    let valid = flags.valid;
    let contradicts = |says_zero: bool, seen: Vanishing| if says_zero { seen.nonzero() } else { seen.zero(valid) };
    let names = d.coordinate_names();
    for (i, name) in names.iter().enumerate() {
        let cyclic = d.cyclic().contains(&i);
        // "Could not decide" (said as a reason) claims nothing either way.
        let undecided = d
            .verdicts()
            .cyclic
            .iter()
            .any(|r| matches!(r, mech::CyclicReason::Undecided { coordinate } if coordinate == name));
        if !undecided && contradicts(cyclic, flags.dl_dq[i]) {
            let (is, seen) = if cyclic { ("", "not zero") } else { ("not ", "zero") };
            let message = format!("{name} is {is}cyclic, but ∂L/∂{name} is {seen} at the points");
            return Some(Outcome::problem(FindingKind::Invariant, message));
        }
    }
    if contradicts(d.hamiltonian_conserved(), flags.rate) {
        let message = format!(
            "hamiltonian_conserved is {}, but ∂L/∂t, R, Q and the constraints' time terms {} at the points",
            d.hamiltonian_conserved(),
            if d.hamiltonian_conserved() { "do not all vanish" } else { "all vanish" }
        );
        return Some(Outcome::problem(FindingKind::Invariant, message));
    }
    let wrong = match (d.hamiltonian_is_energy(), o.energy_gap) {
        (None, None) => false,
        // An honest "could not decide" (a body tree's h − (T + U₀) is rarely
        // proven zero by rewriting): no claim to contradict.
        (None, Some(_)) if d.verdicts().energy.contains(&mech::EnergyReason::EnergyUndecided) => false,
        (Some(is_energy), Some(_)) => contradicts(is_energy, flags.energy_gap),
        _ => true,
    };
    if wrong {
        let message = format!(
            "hamiltonian_is_energy is {:?}, but h − (T + U₀) {}",
            d.hamiltonian_is_energy(),
            if o.energy_gap.is_none() {
                "is not defined (no T and U)"
            } else if flags.energy_gap.nonzero() {
                "is not zero at the points"
            } else {
                "is zero at the points"
            }
        );
        return Some(Outcome::problem(FindingKind::Invariant, message));
    }
    None
}

/// A finding when derive called M singular but the oracle's M is well
/// conditioned at every point where it is finite (at least two).
fn regular_mass_matrix(o: &Oracle, text: &str) -> Option<Outcome> {
    let mut rng = Rng::new(hash(text));
    let mut regular = 0;
    for _ in 0..POINTS {
        let Some(point) = o.point(&mut rng) else { continue };
        let m: Option<Vec<Vec<f64>>> = o
            .mass_matrix
            .iter()
            .map(|row| row.iter().map(|&e| o.eval(&o.pool, e, &point).ok().filter(|v| v.is_finite())).collect())
            .collect();
        let Some(m) = m else { continue };
        if hadamard_ratio(m) < 1e-6 {
            return None;
        }
        regular += 1;
    }
    (regular >= 2).then(|| {
        Outcome::problem(FindingKind::Invariant, "derive calls M singular, but ∂²L/∂q'∂q' is regular at every point")
    })
}

/// |det M| / Π ‖row‖: 1 for orthogonal rows, 0 for a singular matrix.
fn hadamard_ratio(mut m: Vec<Vec<f64>>) -> f64 {
    let n = m.len();
    let norms: f64 = m.iter().map(|r| r.iter().map(|x| x * x).sum::<f64>().sqrt()).product();
    if norms == 0.0 {
        return 0.0;
    }
    let mut det = 1.0;
    for c in 0..n {
        let Some(pivot) = (c..n).max_by(|&a, &b| m[a][c].abs().total_cmp(&m[b][c].abs())) else { return 0.0 };
        if m[pivot][c] == 0.0 {
            return 0.0;
        }
        m.swap(c, pivot);
        det *= m[c][c];
        for r in c + 1..n {
            let factor = m[r][c] / m[c][c];
            for k in c..n {
                m[r][k] -= factor * m[c][k];
            }
        }
    }
    det.abs() / norms
}

/// A finding when the report does not serialize or one of its expressions
/// does not read back to the value it printed.
fn report_reads_back(d: &Derivation) -> Option<Outcome> {
    let report = DeriveReport::new(d);
    if let Err(err) = serde_json::to_string(&report) {
        return Some(Outcome::problem(FindingKind::RoundTrip, format!("the report does not serialize: {err}")));
    }
    let mut exprs: Vec<ExprId> = vec![d.lagrangian(), d.energy_function()];
    exprs.extend(d.momenta());
    exprs.extend(d.forcing());
    exprs.extend(d.mass_matrix().iter().flatten());
    exprs.extend(d.hamiltonian());
    exprs.extend(d.equations());
    exprs.extend([d.kinetic(), d.potential(), d.energy(), d.dissipation()].into_iter().flatten());
    exprs.extend(d.velocities().unwrap_or_default());
    exprs.extend(d.hamilton().unwrap_or_default().iter().flat_map(|&(dq, dp)| [dq, dp]));
    exprs.extend(d.conserved().iter().map(|c| c.expr));
    for c in &d.constraints().list {
        exprs.extend(&c.jacobian);
        exprs.extend([c.expr, c.time_term]);
    }
    let pool = d.pool();
    // Round trips are about the printer, not the parser's bounds on input.
    let limits = Limits { max_exponent: u64::MAX, max_len: usize::MAX, ..Limits::default() };
    let unlimited = ParseOptions::default().with_limits(limits);
    let mut fresh = Pool::default();
    let env = |name: &str| -> Option<f64> {
        // Any fixed values: the two readings must agree wherever they are evaluated.
        let h = hash(name) % 1000;
        Some(0.3 + h as f64 / 997.0)
    };
    for e in exprs {
        let text = pool.display(e).to_string();
        let back = match fresh.parse_with(&text, &unlimited) {
            Ok(back) => back,
            Err(err) => {
                return Some(Outcome::problem(
                    FindingKind::RoundTrip,
                    format!("the report's {text:?} fails to parse: {err}"),
                ))
            }
        };
        let (a, b) = (pool.eval(e, &env), fresh.eval(back, &env));
        if let (Ok(a), Ok(b)) = (a, b) {
            let same = (a.is_nan() && b.is_nan()) || a == b || (a - b).abs() <= 1e-9 * (1.0 + a.abs());
            if !same {
                return Some(Outcome::problem(
                    FindingKind::RoundTrip,
                    format!("the report's {text:?} reads back with the value {b}, not {a}"),
                ));
            }
        }
    }
    None
}

/// Derive on models of the grammar of [`generate`].
#[derive(Default)]
pub struct DeriveTarget;

impl Target for DeriveTarget {
    fn name(&self) -> &'static str {
        "derive"
    }

    fn input(&mut self, rng: &mut Rng) -> String {
        generate::model(rng)
    }

    fn check(&mut self, input: &str) -> Outcome {
        check_derivation(input)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `vanishes` says about `e(oracle)` at the probe points of `text`.
    fn verdicts(text: &str, e: impl Fn(&Oracle) -> ExprId) -> Vec<Option<Zero>> {
        let o = Oracle::new(&Model::parse(text, &[]).unwrap()).unwrap();
        let mut rng = Rng::new(1);
        (0..POINTS).filter_map(|_| o.probe_point(&mut rng)).map(|p| vanishes(&o, e(&o), &p)).collect()
    }

    #[test]
    fn zero_is_told_from_tiny_and_from_large_cancelling_terms() {
        let model =
            |top: &str, tables: &str| format!("coordinates = [\"r\"]\n{top}\n[parameters]\nm = 1.0\nw = 1.0\n{tables}");
        // A bead on a rotating wire: ∂L/∂t is a sum of terms that cancel.
        let wire = model("", "[[particles]]\nmass = \"m\"\nposition = [\"r*cos(w*t)\", \"r*sin(w*t)\"]\n");
        assert!(verdicts(&wire, |o| o.dl_dt).iter().all(|v| *v == Some(Zero::Yes)));
        // h − T for T = (r'^-2 − 2)^127 is large and does not cancel.
        let steep = model("kinetic = \"m*(r'^-2 - 2)^127\"", "");
        assert!(verdicts(&steep, |o| o.energy_gap.unwrap()).contains(&Some(Zero::No)));
        // h − T for T = r'^1000 underflows: no point can tell it from zero.
        let tiny = model("kinetic = \"m*r'^1000/2\"", "");
        assert!(!verdicts(&tiny, |o| o.energy_gap.unwrap()).contains(&Some(Zero::Yes)));
    }

    #[test]
    fn an_example_agrees_with_the_oracle_and_a_wrong_flag_would_be_caught() {
        let text = std::fs::read_to_string(crate::Corpus::repo_root().join("examples/double_pendulum.toml")).unwrap();
        let outcome = check_derivation(&text);
        assert!(outcome.problem.is_none(), "{:?}", outcome.problem);
        assert!(outcome.signature.starts_with("derived: H true"), "{}", outcome.signature);
        assert!(hadamard_ratio(vec![vec![1.0, 2.0], vec![2.0, 4.0]]) < 1e-12);
        assert!((hadamard_ratio(vec![vec![2.0, 0.0], vec![0.0, 3.0]]) - 1.0).abs() < 1e-12);
    }
}
