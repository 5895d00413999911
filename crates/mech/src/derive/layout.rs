//! The input layout of every compiled expression of a derivation:
//! `[q (n), q' (n), t, parameters (in file order)]`.
//!
//! Kernels, recorders, stop conditions and analyses all evaluate expressions
//! over this one vector; [`Layout`] names its parts so that none of them
//! rebuilds it by hand.

use crate::model::Parameter;
use std::ops::Range;
use sym::{ExprId, Pool};

/// Where q, q', t and the parameters sit in an input vector, with their symbols.
#[derive(Debug, Clone)]
pub struct Layout {
    n: usize,
    symbols: Vec<ExprId>,
    values: Vec<f64>,
}

impl Layout {
    /// The layout of `n = q.len()` coordinates and the given parameters (their
    /// symbols are made in `pool` if no expression named them).
    pub(crate) fn new(pool: &mut Pool, q: &[ExprId], qd: &[ExprId], t: ExprId, parameters: &[Parameter]) -> Layout {
        let n = q.len();
        debug_assert_eq!(qd.len(), n);
        let mut symbols = Vec::with_capacity(2 * n + 1 + parameters.len());
        symbols.extend(q);
        symbols.extend(qd);
        symbols.push(t);
        symbols.extend(parameters.iter().map(|p| pool.symbol(&p.name)));
        let mut values = vec![0.0; 2 * n + 1];
        values.extend(parameters.iter().map(|p| p.value));
        Layout { n, symbols, values }
    }

    /// The number of coordinates n.
    pub fn n_coords(&self) -> usize {
        self.n
    }

    /// The length of an input vector.
    pub fn len(&self) -> usize {
        self.symbols.len()
    }

    /// Whether the vector is empty (never: t is always there).
    pub fn is_empty(&self) -> bool {
        self.symbols.is_empty()
    }

    /// The symbols, in input order: tapes compile over these.
    pub fn symbols(&self) -> &[ExprId] {
        &self.symbols
    }

    /// Where the coordinates are.
    pub fn q(&self) -> Range<usize> {
        0..self.n
    }

    /// Where the velocities are.
    pub fn qd(&self) -> Range<usize> {
        self.n..2 * self.n
    }

    /// Where the time is.
    pub fn t(&self) -> usize {
        2 * self.n
    }

    /// Where the parameters are.
    pub fn parameters(&self) -> Range<usize> {
        2 * self.n + 1..self.symbols.len()
    }

    /// An input vector with the parameters' values and zeros for (q, q', t).
    pub fn values(&self) -> Vec<f64> {
        self.values.clone()
    }

    /// Writes (q, q', t) into an input vector, leaving the parameters as they are.
    pub fn set_state(&self, inputs: &mut [f64], t: f64, q: &[f64], qd: &[f64]) {
        inputs[self.q()].copy_from_slice(q);
        inputs[self.qd()].copy_from_slice(qd);
        inputs[self.t()] = t;
    }
}
