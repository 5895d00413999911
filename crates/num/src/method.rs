//! The catalogue of methods ([`Method`]): names for `--method NAME`, one-line
//! descriptions for `--list-methods`, and properties (order, adaptive,
//! symplectic). Every solver names itself by it; the factory that builds any of
//! them ([`Method::build`]) is in `build.rs`, so that this catalogue imports no
//! solver.

use std::fmt;
use std::str::FromStr;

use crate::error::SolveError;

/// An integration method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Dormand–Prince 5(4), adaptive explicit Runge–Kutta ([`crate::Dopri5`]).
    Dopri5,
    /// DOP853, adaptive explicit Runge–Kutta of order 8 ([`crate::Dop853`]).
    Dop853,
    /// Störmer–Verlet, symplectic, order 2, fixed step ([`crate::Composition`]).
    Verlet,
    /// Yoshida's triple jump of Verlet, symplectic, order 4.
    Yoshida4,
    /// Kahan–Li 9-stage composition of Verlet, symplectic, order 6.
    KahanLi6,
    /// Kahan–Li 15-stage composition of Verlet, symplectic, order 8.
    KahanLi8,
    /// Gauss–Legendre collocation, 1 stage (implicit midpoint), symplectic, order 2 ([`crate::Gauss`]).
    Gauss2,
    /// Gauss–Legendre collocation, 2 stages, symplectic, order 4.
    Gauss4,
    /// Gauss–Legendre collocation, 3 stages, symplectic, order 6.
    Gauss6,
    /// Radau IIA, 3 stages, order 5, adaptive, for stiff problems ([`crate::Radau5`]).
    Radau5,
    /// Adaptive Taylor series, order from the tolerance ([`crate::Taylor`]); needs a system
    /// with [`crate::OdeSystem::taylor_series`].
    Taylor,
}

impl Method {
    /// Every method, in the order `--list-methods` shows them.
    pub const ALL: [Method; 11] = [
        Method::Dopri5,
        Method::Dop853,
        Method::Verlet,
        Method::Yoshida4,
        Method::KahanLi6,
        Method::KahanLi8,
        Method::Gauss2,
        Method::Gauss4,
        Method::Gauss6,
        Method::Radau5,
        Method::Taylor,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dopri5 => "dopri5",
            Method::Dop853 => "dop853",
            Method::Verlet => "verlet",
            Method::Yoshida4 => "yoshida4",
            Method::KahanLi6 => "kahanli6",
            Method::KahanLi8 => "kahanli8",
            Method::Gauss2 => "gauss2",
            Method::Gauss4 => "gauss4",
            Method::Gauss6 => "gauss6",
            Method::Radau5 => "radau5",
            Method::Taylor => "taylor",
        }
    }

    /// A one-line description.
    pub fn description(self) -> &'static str {
        match self {
            Method::Dopri5 => "Dormand-Prince 5(4), adaptive explicit Runge-Kutta (general purpose)",
            Method::Dop853 => {
                "Dormand-Prince 8(5,3), adaptive explicit Runge-Kutta (the default with constraints, abs or many coordinates)"
            }
            Method::Verlet => "Stormer-Verlet, symplectic, order 2, fixed step (separable H)",
            Method::Yoshida4 => "Yoshida triple-jump composition, symplectic, order 4, fixed step (separable H)",
            Method::KahanLi6 => "Kahan-Li 9-stage composition, symplectic, order 6, fixed step (separable H)",
            Method::KahanLi8 => "Kahan-Li 15-stage composition, symplectic, order 8, fixed step (separable H)",
            Method::Gauss2 => "implicit midpoint (Gauss-Legendre 1 stage), symplectic, order 2, fixed step",
            Method::Gauss4 => "Gauss-Legendre 2 stages, symplectic, order 4, fixed step",
            Method::Gauss6 => "Gauss-Legendre 3 stages, symplectic, order 6, fixed step",
            Method::Radau5 => "Radau IIA 3 stages, order 5, adaptive, implicit (stiff problems)",
            Method::Taylor => "Taylor series, order from rtol (13 at 1e-10), adaptive (the default)",
        }
    }

    /// What `rtol` and `atol` control with this method, in one sentence.
    ///
    /// The adaptive methods bound each step's local error; the fixed-step
    /// methods only take their step from the tolerance (the local error at the
    /// start, and the drift of H over pilot runs where H is conserved), so the
    /// tolerance bounds neither their trajectory's error nor, beyond the pilot
    /// runs, H's drift: the audit at the end of a run measures the latter.
    pub fn tolerance_controls(self) -> &'static str {
        match self {
            Method::Taylor => {
                "each step's truncation error, per component (atol + rtol*|y_i|), estimated from the series' last two terms"
            }
            Method::Dopri5 | Method::Dop853 | Method::Radau5 => {
                "each step's local error estimate, per component (atol + rtol*|y_i|); rejected steps are retried shorter"
            }
            _ => {
                "the fixed step only: chosen so that the first step's local error meets it and, where H is conserved, so that H drifts by at most 10*rtol over pilot runs; not the trajectory's error"
            }
        }
    }

    /// The classical order of accuracy (the Taylor method's at its default rtol of
    /// 1e-9; [`crate::taylor_order`] gives it for any tolerance).
    pub fn order(self) -> u32 {
        match self {
            Method::Taylor => 12,
            Method::Dopri5 | Method::Radau5 => 5,
            Method::Dop853 | Method::KahanLi8 => 8,
            Method::Verlet | Method::Gauss2 => 2,
            Method::Yoshida4 | Method::Gauss4 => 4,
            Method::KahanLi6 | Method::Gauss6 => 6,
        }
    }

    /// Whether the method adapts its step to `rtol`/`atol` (otherwise it takes a fixed
    /// step `dt`, chosen by [`select_step`] when not given).
    pub fn is_adaptive(self) -> bool {
        matches!(self, Method::Dopri5 | Method::Dop853 | Method::Radau5 | Method::Taylor)
    }

    /// Whether the method is symplectic (for Hamiltonian systems: no energy drift).
    pub fn is_symplectic(self) -> bool {
        !self.is_adaptive()
    }

    /// Whether the method needs a [`SeparableSystem`] (the explicit compositions).
    pub fn needs_separable(self) -> bool {
        matches!(self, Method::Verlet | Method::Yoshida4 | Method::KahanLi6 | Method::KahanLi8)
    }

    /// The names of all methods, comma separated.
    pub fn known_names() -> String {
        Method::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ")
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = SolveError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.trim().to_ascii_lowercase();
        Method::ALL
            .into_iter()
            .find(|m| m.name() == lower)
            .ok_or_else(|| SolveError::UnknownMethod { name: s.to_string(), known: Method::known_names() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>().unwrap(), m);
            assert!(!m.description().is_empty());
        }
        assert!(matches!("rk4".parse::<Method>(), Err(SolveError::UnknownMethod { .. })));
    }
}
