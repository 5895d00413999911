//! [`PlotKeeper`]: a bounded, decimated copy of a run for its figure, gathered
//! row by row as the run streams, in constant memory however long the run:
//! past [`MAX_PLOT_POINTS`] rows every other row is dropped and the stride
//! doubles. [`PlotKeeper::into_plot`] names the series for [`super::svg`].

use super::{PlotData, Series};
use mech::RunReport;

/// The most points kept for the plot; beyond it every other point is dropped.
const MAX_PLOT_POINTS: usize = 8192;

/// A bounded, decimated copy of the run for the plot: constant memory however
/// long the run.
pub struct PlotKeeper {
    n: usize,
    stride: usize,
    seen: usize,
    t: Vec<f64>,
    q: Vec<Vec<f64>>,
    qd: Vec<Vec<f64>>,
    inv: Vec<Vec<f64>>,
}

impl PlotKeeper {
    /// An empty copy of a run of `n` coordinates.
    pub fn new(n: usize) -> PlotKeeper {
        PlotKeeper {
            n,
            stride: 1,
            seen: 0,
            t: Vec::new(),
            q: vec![Vec::new(); n],
            qd: vec![Vec::new(); n],
            inv: Vec::new(),
        }
    }

    /// Takes one row: the time, the coordinates, the velocities and the invariants.
    pub fn push(&mut self, t: f64, q: &[f64], qd: &[f64], inv: &[f64]) {
        if self.inv.is_empty() {
            self.inv = vec![Vec::new(); inv.len()];
        }
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(self.stride) {
            return;
        }
        self.t.push(t);
        for i in 0..self.n {
            self.q[i].push(q[i]);
            self.qd[i].push(qd[i]);
        }
        for (k, v) in inv.iter().enumerate() {
            self.inv[k].push(*v);
        }
        if self.t.len() >= MAX_PLOT_POINTS {
            let halve = |v: &mut Vec<f64>| {
                let kept: Vec<f64> = v.iter().step_by(2).copied().collect();
                *v = kept;
            };
            halve(&mut self.t);
            self.q.iter_mut().chain(self.qd.iter_mut()).chain(self.inv.iter_mut()).for_each(halve);
            self.stride *= 2;
        }
    }

    /// The figure's data: the rows kept, named after the coordinates and the
    /// invariants, titled `title`, with the run's method, step and steps below.
    pub fn into_plot(self, title: &str, r: &RunReport, names: &[String], inv_names: &[String]) -> PlotData {
        let series = |vals: Vec<Vec<f64>>, suffix: &str| -> Vec<Series> {
            vals.into_iter()
                .zip(names)
                .map(|(values, name)| Series { name: format!("{name}{suffix}"), values })
                .collect()
        };
        let step = match r.dt {
            Some(h) => format!("dt {h:.2e}"),
            None => format!("rtol {:.0e}", r.rtol),
        };
        PlotData {
            title: title.to_string(),
            subtitle: format!("{}, {}, {} steps", r.method.name(), step, r.steps),
            time: self.t,
            coordinates: series(self.q, ""),
            velocities: series(self.qd, "'"),
            invariants: self
                .inv
                .into_iter()
                .zip(inv_names)
                .map(|(values, name)| Series { name: name.clone(), values })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ops::ControlFlow;

    #[test]
    fn a_long_run_is_kept_in_bounded_memory() {
        let rows = 5 * MAX_PLOT_POINTS + 3;
        let mut keeper = PlotKeeper::new(2);
        for k in 0..rows {
            let t = k as f64;
            keeper.push(t, &[t, -t], &[1.0, -1.0], &[0.5]);
        }
        assert!(keeper.t.len() < MAX_PLOT_POINTS, "{} points kept", keeper.t.len());
        assert!(keeper.t.len() > MAX_PLOT_POINTS / 4, "{} points kept", keeper.t.len());
        // Every kept row is whole and evenly spaced from the first.
        assert_eq!(keeper.t[0], 0.0);
        let stride = keeper.stride as f64;
        assert!(keeper.t.iter().enumerate().all(|(k, &t)| t == k as f64 * stride));
        assert_eq!(keeper.q[1], keeper.t.iter().map(|t| -t).collect::<Vec<_>>());
        assert_eq!(keeper.inv[0].len(), keeper.t.len());
    }

    #[test]
    fn the_plot_is_named_after_the_run() {
        let text = "name = \"drop\"\ncoordinates = [\"y\"]\n[[particles]]\nmass = \"1\"\nposition = [\"y\"]\n[initial]\ny = 0.0\n\"y'\" = 1.0\n";
        let d = mech::Derivation::new(mech::Model::parse(text, &[]).unwrap()).unwrap();
        let config = mech::RunConfig { until: 1.0, output: num::Output::Samples(5), ..Default::default() };
        let mut keeper = PlotKeeper::new(1);
        let r = mech::simulate(&d, &config, |row| {
            keeper.push(row.t, row.q, row.qd, row.invariants);
            ControlFlow::Continue(())
        })
        .unwrap();
        let invariants: Vec<String> = mech::invariants_of(&d).into_iter().map(|i| i.name).collect();
        assert!(!invariants.is_empty(), "a free particle conserves its energy");
        let data = keeper.into_plot("drop", &r, &["y".into()], &invariants);
        assert_eq!(data.time, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        assert_eq!(data.coordinates[0].name, "y");
        assert_eq!(data.velocities[0].name, "y'");
        assert_eq!(data.invariants.iter().map(|s| s.name.clone()).collect::<Vec<_>>(), invariants);
        assert!(data.invariants.iter().all(|s| s.values.len() == 5));
        assert_eq!(data.subtitle, format!("{}, rtol 1e-9, {} steps", r.method.name(), r.steps));
    }
}
