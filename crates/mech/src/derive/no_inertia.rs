//! Which coordinates have no inertia at a point, and why: the null space of the
//! mass matrix M(q) there, and the parameters at 0 that empty it (a mass, a
//! moment, a length). The refusals of every command that solves `M q'' = f` at
//! a start name the cause with it: `m = 0` is a model without inertia, not a
//! singular coordinate.
//!
//! Entry point: [`Derivation::no_inertia_at`]. A numeric test at one point,
//! used to explain a refusal, never to claim a result.

use crate::derive::Derivation;
use nalgebra::DMatrix;
use sym::ExprId;

/// The smallest singular value of M, relative to its largest, taken for zero:
/// below it the accelerations of the null direction are round-off.
const SINGULAR: f64 = 1e-12;

/// Coordinates without inertia at a point.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NoInertia {
    /// The coordinates whose velocities (a combination of them when several)
    /// cost no kinetic energy there.
    pub coordinates: Vec<String>,
    /// Parameters at 0 without which those coordinates would have inertia.
    pub zero_parameters: Vec<String>,
}

impl NoInertia {
    /// The sentence: what has no inertia and, when known, why.
    pub fn message(&self, at: &str) -> String {
        let who = match self.coordinates.as_slice() {
            [one] => format!("the coordinate {one} has no inertia at {at}"),
            many => format!("a combination of the coordinates {} has no inertia at {at}", many.join(", ")),
        };
        match self.zero_parameters.as_slice() {
            [] => format!("{who}: the mass matrix M is singular there, so the accelerations are undetermined"),
            zeros => {
                let list: Vec<String> = zeros.iter().map(|p| format!("{p} = 0")).collect();
                format!(
                    "{who} because {}: the mass matrix M is singular, so the accelerations are undetermined",
                    list.join(" and ")
                )
            }
        }
    }

    /// What to do about it.
    pub fn help(&self) -> String {
        match self.zero_parameters.as_slice() {
            [] => "the coordinates are singular there (like polar angles at the pole): start away from it, or choose other coordinates".into(),
            zeros => format!(
                "a mass, moment or length of 0 leaves nothing to accelerate: give {} a value other than 0",
                zeros.join(" and ")
            ),
        }
    }
}

impl Derivation {
    /// The coordinates among `among` (indices) without inertia at q (t = 0,
    /// parameters from `parameter`), if M restricted to them is singular there
    /// and finite; with the parameters at 0 that cause it (setting one to 1
    /// with the others at 0 set to 1
    /// too gives an idle coordinate's diagonal entry of M a value, and does not without it).
    pub fn no_inertia_at(
        &self,
        among: &[usize],
        q: &[f64],
        parameter: &dyn Fn(&str) -> Option<f64>,
    ) -> Option<NoInertia> {
        let names: Vec<&str> = self.model.coordinates.iter().map(|c| c.name.as_str()).collect();
        // M's entry e with the parameters in `ones` set to 1.
        let value = |e: ExprId, ones: &[&str]| {
            let env = |name: &str| {
                if ones.contains(&name) {
                    return Some(1.0);
                }
                if name == "t" {
                    return Some(0.0);
                }
                match names.iter().position(|&c| c == name) {
                    Some(k) => Some(q[k]),
                    None => parameter(name),
                }
            };
            self.pool().eval(e, &env).unwrap_or(f64::NAN)
        };
        let n = among.len();
        if n == 0 {
            return None;
        }
        let m = DMatrix::from_fn(n, n, |i, j| value(self.mass_matrix[among[i]][among[j]], &[]));
        if !m.iter().all(|v| v.is_finite()) {
            return None;
        }
        let idle: Vec<usize> = if m.amax() == 0.0 {
            (0..n).collect()
        } else {
            let svd = m.svd(false, true);
            let k = svd.singular_values.imin();
            if svd.singular_values[k] > SINGULAR * svd.singular_values.amax() {
                return None;
            }
            let null = svd.v_t?.row(k).transpose();
            let top = null.amax();
            (0..n).filter(|&i| null[i].abs() > 0.1 * top).collect()
        };
        // A parameter at 0 is a cause when setting every parameter at 0 to 1
        // gives an idle coordinate inertia, and setting all but it does not.
        let zeros: Vec<&str> =
            self.model.parameters.iter().filter(|p| parameter(&p.name) == Some(0.0)).map(|p| p.name.as_str()).collect();
        let has_inertia = |ones: &[&str]| {
            idle.iter().any(|&i| {
                let v = value(self.mass_matrix[among[i]][among[i]], ones);
                v.is_finite() && v != 0.0
            })
        };
        let zero_parameters = if has_inertia(&zeros) {
            zeros
                .iter()
                .filter(|p| {
                    let others: Vec<&str> = zeros.iter().copied().filter(|o| o != *p).collect();
                    !has_inertia(&others)
                })
                .map(|p| p.to_string())
                .collect()
        } else {
            Vec::new()
        };
        Some(NoInertia { coordinates: idle.iter().map(|&i| names[among[i]].to_string()).collect(), zero_parameters })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;

    #[track_caller]
    fn check(model: &str, set: &[(&str, f64)], at: &[f64], expect: Option<(&[&str], &[&str])>) {
        let overrides: Vec<(String, f64)> = set.iter().map(|(n, v)| (n.to_string(), *v)).collect();
        let model = Model::parse(model, &overrides).unwrap();
        let d = Derivation::new(model).unwrap();
        let all: Vec<usize> = (0..d.q.len()).collect();
        let got = d.no_inertia_at(&all, at, &|n| d.model.parameter(n));
        let want = expect.map(|(c, p)| NoInertia {
            coordinates: c.iter().map(|s| s.to_string()).collect(),
            zero_parameters: p.iter().map(|s| s.to_string()).collect(),
        });
        assert_eq!(got, want);
    }

    const PENDULUM: &str = r#"
        coordinates = ["ph"]
        [parameters]
        m = 1.0
        l = 1.0
        [[particles]]
        mass = "m"
        position = ["l*sin(ph)", "-l*cos(ph)"]
    "#;

    const POLAR: &str = r#"
        coordinates = ["r", "th"]
        [parameters]
        m = 1.0
        [[particles]]
        mass = "m"
        position = ["r*cos(th)", "r*sin(th)"]
    "#;

    #[test]
    fn names_the_parameter_at_zero_or_the_coordinate() {
        check(PENDULUM, &[], &[1.0], None);
        check(PENDULUM, &[("m", 0.0)], &[1.0], Some((&["ph"], &["m"])));
        check(PENDULUM, &[("l", 0.0)], &[1.0], Some((&["ph"], &["l"])));
        check(PENDULUM, &[("m", 0.0), ("l", 0.0)], &[1.0], Some((&["ph"], &["m", "l"])));
        // A coordinate singularity: no parameter is to blame.
        check(POLAR, &[], &[0.0, 1.0], Some((&["th"], &[])));
        check(POLAR, &[], &[2.0, 1.0], None);
        check(POLAR, &[("m", 0.0)], &[2.0, 1.0], Some((&["r", "th"], &["m"])));
    }
}
