//! The grid of a sweep: its axes (`a=0:1:5,g=9.78;9.81`), which coordinates,
//! velocities or parameters they set, the runs they make in order, and the
//! shards that split them between machines.

use super::{SweepError, MAX_RUNS};
use crate::model::Model;

/// What an axis of the grid sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// The initial value of coordinate `k`.
    Coordinate(usize),
    /// The initial velocity of coordinate `k`.
    Velocity(usize),
    /// Parameter `k` (in the model's order).
    Parameter(usize),
}

/// One axis: `count` evenly spaced values from `start` to `stop`, both
/// included (`a=0:1:5`), or the values listed (`g=9.78;9.81;9.83`).
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The name as written (`a`, `a'`, `g`).
    pub name: String,
    /// First value.
    pub start: f64,
    /// Last value (equal to `start` when `count` is 1).
    pub stop: f64,
    /// Number of values, at least 1.
    pub count: usize,
    /// The values, where they were listed rather than spaced evenly.
    pub values: Option<Vec<f64>>,
}

impl Axis {
    /// The `k`-th value.
    pub fn value(&self, k: usize) -> f64 {
        if let Some(values) = &self.values {
            return values[k];
        }
        if self.count <= 1 {
            self.start
        } else if k + 1 == self.count {
            self.stop
        } else {
            self.start + (self.stop - self.start) * (k as f64 / (self.count - 1) as f64)
        }
    }

    /// Whether the values are evenly spaced (a range, or a list that is one to
    /// round-off): a heat map's cells need it.
    pub fn is_even(&self) -> bool {
        let Some(values) = &self.values else { return true };
        let even = Axis { values: None, ..self.clone() };
        let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        values.iter().enumerate().all(|(k, v)| (v - even.value(k)).abs() <= 1e-12 * scale)
    }
}

/// Parses `name=start:stop:count` or `name=v1;v2;...`, comma separated,
/// without a model: the axes of a grid as text describes them (used again to
/// read a merged CSV's provenance).
pub fn parse_axes(spec: &str) -> Result<Vec<Axis>, SweepError> {
    let mut axes: Vec<Axis> = Vec::new();
    for item in spec.split(',').map(str::trim) {
        if item.is_empty() {
            if spec.trim().is_empty() {
                return Err(SweepError::EmptyGrid);
            }
            return Err(SweepError::AxisSyntax { item: spec.trim().to_string() });
        }
        let syntax = || SweepError::AxisSyntax { item: item.to_string() };
        let (name, range) = item.split_once('=').ok_or_else(syntax)?;
        let name = name.trim();
        if name.is_empty() || range.trim().is_empty() {
            return Err(syntax());
        }
        let number = |what: &'static str, text: &str| {
            text.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| SweepError::AxisNumber {
                name: name.to_string(),
                what,
                text: text.to_string(),
            })
        };
        let axis = if range.contains(':') {
            let parts: Vec<&str> = range.split(':').map(str::trim).collect();
            if parts.len() != 3 {
                return Err(syntax());
            }
            let start = number("start", parts[0])?;
            let stop = number("stop", parts[1])?;
            let count = parts[2]
                .parse::<usize>()
                .ok()
                .filter(|&c| c >= 1)
                .ok_or_else(|| SweepError::AxisCount { name: name.to_string(), text: parts[2].to_string() })?;
            Axis { name: name.to_string(), start, stop: if count == 1 { start } else { stop }, count, values: None }
        } else {
            let values =
                range.split(';').map(|v| number("value", v.trim())).collect::<Result<Vec<f64>, SweepError>>()?;
            Axis {
                name: name.to_string(),
                start: values[0],
                stop: values[values.len() - 1],
                count: values.len(),
                values: Some(values),
            }
        };
        if axes.iter().any(|a| a.name == name) {
            return Err(SweepError::DuplicateAxis { name: name.to_string() });
        }
        axes.push(axis);
    }
    let runs = axes.iter().fold(1u128, |acc, a| acc.saturating_mul(a.count as u128));
    if runs > MAX_RUNS as u128 {
        return Err(SweepError::TooLarge { runs, max: MAX_RUNS });
    }
    Ok(axes)
}

/// The axes as text that [`parse_axes`] reads back.
pub fn format_axes(axes: &[Axis]) -> String {
    let axis = |a: &Axis| match &a.values {
        Some(values) => {
            format!("{}={}", a.name, values.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(";"))
        }
        None => format!("{}={:?}:{:?}:{}", a.name, a.start, a.stop, a.count),
    };
    axes.iter().map(axis).collect::<Vec<_>>().join(",")
}

/// A grid of runs: the cartesian product of its axes, the first axis varying
/// slowest (run index `((i0·n1) + i1)·n2 + i2 …`).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// The axes, in the order given.
    pub axes: Vec<Axis>,
    /// What each axis sets.
    pub targets: Vec<Target>,
}

impl Grid {
    /// Parses a `--grid` text and resolves its names against a model.
    pub fn parse(spec: &str, model: &Model) -> Result<Grid, SweepError> {
        let axes = parse_axes(spec)?;
        let mut targets = Vec::with_capacity(axes.len());
        for axis in &axes {
            let name = axis.name.as_str();
            let base = name.strip_suffix('\'').unwrap_or(name);
            let coord = model.coordinates.iter().position(|c| c.name == base);
            let target = match coord {
                Some(k) if base.len() == name.len() => Some(Target::Coordinate(k)),
                Some(k) => Some(Target::Velocity(k)),
                None => model.parameters.iter().position(|p| p.name == name).map(Target::Parameter),
            };
            let known = || {
                let mut names: Vec<String> = Vec::new();
                for c in &model.coordinates {
                    names.push(c.name.clone());
                    names.push(format!("{}'", c.name));
                }
                names.extend(model.parameters.iter().map(|p| p.name.clone()));
                names.join(", ")
            };
            targets.push(target.ok_or_else(|| SweepError::UnknownName { name: name.to_string(), known: known() })?);
        }
        Ok(Grid { axes, targets })
    }

    /// The number of runs.
    pub fn len(&self) -> usize {
        self.axes.iter().map(|a| a.count).product()
    }

    /// True when the grid has no run (never, for a parsed grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The input values of run `run`, one per axis.
    pub fn point(&self, run: usize) -> Vec<f64> {
        let mut rest = run;
        let mut values = vec![0.0; self.axes.len()];
        for (k, axis) in self.axes.iter().enumerate().rev() {
            values[k] = axis.value(rest % axis.count);
            rest /= axis.count;
        }
        values
    }
}

/// The `index`-th of `count` slices of a sweep: the runs `r` with `r % count == index`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which slice, `0..count`.
    pub index: usize,
    /// How many slices.
    pub count: usize,
}

impl Default for Shard {
    fn default() -> Self {
        Shard { index: 0, count: 1 }
    }
}

impl Shard {
    /// Parses `i/n`.
    pub fn parse(text: &str) -> Result<Shard, SweepError> {
        let err = || SweepError::ShardSyntax { text: text.to_string() };
        let (i, n) = text.split_once('/').ok_or_else(err)?;
        let index: usize = i.trim().parse().map_err(|_| err())?;
        let count: usize = n.trim().parse().map_err(|_| err())?;
        if count == 0 || index >= count {
            return Err(err());
        }
        Ok(Shard { index, count })
    }

    /// The run indices of this shard among `total`, ascending.
    pub fn runs(self, total: usize) -> impl Iterator<Item = usize> {
        (self.index..total).step_by(self.count)
    }

    /// The number of this shard's runs among `total`.
    pub fn len(self, total: usize) -> usize {
        total.saturating_sub(self.index).div_ceil(self.count)
    }

    /// The grid index of this shard's `k`-th run.
    pub fn nth(self, k: usize) -> usize {
        self.index + k * self.count
    }

    /// Whether the sweep is split at all.
    pub fn is_whole(self) -> bool {
        self.count == 1
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}
