//! [`PlotKeeper`]: a bounded, decimated copy of a run for its figure, gathered
//! row by row as the run streams, in constant memory however long the run:
//! past [`MAX_PLOT_POINTS`] rows every other row is dropped and the stride
//! doubles. Made for a model ([`PlotKeeper::of`]) it also knows which
//! coordinates are angles and keeps the positions of 2-D particles, for their
//! paths in the plane. [`PlotKeeper::into_plot`] names the series for
//! [`super::svg`] and keeps the invariants the derivation says are conserved.

use super::{Path, PlotData, Series};
use mech::{Derivation, Mechanism, PointKind, RunReport};

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
    /// Whether each coordinate is an angle (drawn wrapped).
    angles: Vec<bool>,
    /// The particles' paths, when every point of the model is a particle in the plane.
    paths: Option<Paths>,
}

/// The positions of a model's particles in the plane, as the run goes.
struct Paths {
    mechanism: Mechanism,
    names: Vec<String>,
    /// Where the points are at the current row: x, y of each.
    at: Vec<f64>,
    /// x then y of each particle, one column per coordinate of a position.
    columns: Vec<Vec<f64>>,
}

impl Paths {
    /// The paths of `d`'s particles, when it has particles only and they move in the plane.
    fn of(d: &Derivation) -> Option<Paths> {
        let mechanism = Mechanism::new(d);
        let points = mechanism.points();
        if points.is_empty() || mechanism.dimension() != 2 || points.iter().any(|p| p.kind != PointKind::Particle) {
            return None;
        }
        let names = points.iter().map(|p| p.name.clone()).collect();
        let n = 2 * points.len();
        Some(Paths { mechanism, names, at: vec![0.0; n], columns: vec![Vec::new(); n] })
    }
}

impl PlotKeeper {
    /// An empty copy of a run of `n` coordinates, none of them known to be an
    /// angle, without particle paths.
    pub fn new(n: usize) -> PlotKeeper {
        PlotKeeper {
            n,
            stride: 1,
            seen: 0,
            t: Vec::new(),
            q: vec![Vec::new(); n],
            qd: vec![Vec::new(); n],
            inv: Vec::new(),
            angles: vec![false; n],
            paths: None,
        }
    }

    /// An empty copy of a run of `d`: its angles are drawn wrapped, and the
    /// paths of its particles are kept when they move in the plane.
    pub fn of(d: &Derivation) -> PlotKeeper {
        let mut keeper = PlotKeeper::new(d.coordinate_names().len());
        keeper.angles = crate::angles::angles(d);
        keeper.paths = Paths::of(d);
        keeper
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
        if let Some(paths) = &mut self.paths {
            paths.mechanism.place(t, q, qd, &mut paths.at);
            for (column, &x) in paths.columns.iter_mut().zip(&paths.at) {
                column.push(x);
            }
        }
        if self.t.len() >= MAX_PLOT_POINTS {
            let halve = |v: &mut Vec<f64>| {
                let kept: Vec<f64> = v.iter().step_by(2).copied().collect();
                *v = kept;
            };
            halve(&mut self.t);
            self.q.iter_mut().chain(self.qd.iter_mut()).chain(self.inv.iter_mut()).for_each(halve);
            if let Some(paths) = &mut self.paths {
                paths.columns.iter_mut().for_each(halve);
            }
            self.stride *= 2;
        }
    }

    /// The figure's data: the rows kept, named after the coordinates and the
    /// invariants, titled `title`, with the run's method, step and steps below.
    /// Of the invariants only those the derivation says are conserved
    /// (`r.invariants[k].conserved`) are kept: the drift of the others is not
    /// an error.
    pub fn into_plot(self, title: &str, r: &RunReport, names: &[String], inv_names: &[String]) -> PlotData {
        let angles = self.angles;
        let series = |vals: Vec<Vec<f64>>, suffix: &str, wrapped: bool| -> Vec<Series> {
            vals.into_iter()
                .zip(names)
                .zip(&angles)
                .map(|((values, name), &angle)| Series {
                    name: format!("{name}{suffix}"),
                    values,
                    angle: wrapped && angle,
                })
                .collect()
        };
        let step = match r.dt {
            Some(h) => format!("dt {h:.2e}"),
            None => format!("rtol {:.0e}", r.rtol),
        };
        let paths = match self.paths {
            Some(p) => {
                let mut columns = p.columns.into_iter();
                p.names
                    .into_iter()
                    .map(|name| Path {
                        name,
                        x: columns.next().unwrap_or_default(),
                        y: columns.next().unwrap_or_default(),
                    })
                    .collect()
            }
            None => Vec::new(),
        };
        PlotData {
            title: title.to_string(),
            subtitle: format!("{}, {}, {} steps", r.method.name(), step, r.steps),
            time: self.t,
            coordinates: series(self.q, "", true),
            velocities: series(self.qd, "'", false),
            invariants: self
                .inv
                .into_iter()
                .zip(inv_names)
                .enumerate()
                .filter(|(k, _)| r.invariants.get(*k).is_some_and(|audit| audit.conserved))
                .map(|(_, (values, name))| Series { name: name.clone(), values, angle: false })
                .collect(),
            paths,
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

    /// The plot data of `file` in examples/, run to `until`.
    fn example(file: &str, until: f64) -> PlotData {
        let path = format!("{}/../../examples/{file}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        let d = mech::Derivation::new(mech::Model::parse(&text, &[]).unwrap()).unwrap();
        let config = mech::RunConfig { until, output: num::Output::Samples(400), ..Default::default() };
        let mut keeper = PlotKeeper::of(&d);
        let r = mech::simulate(&d, &config, |row| {
            keeper.push(row.t, row.q, row.qd, row.invariants);
            ControlFlow::Continue(())
        })
        .unwrap();
        let names: Vec<String> = d.coordinate_names().iter().map(|s| s.to_string()).collect();
        let invariants: Vec<String> = mech::invariants_of(&d).into_iter().map(|i| i.name).collect();
        keeper.into_plot(&d.model().name, &r, &names, &invariants)
    }

    #[test]
    fn particles_in_the_plane_get_their_paths() {
        let data = example("double_pendulum.toml", 5.0);
        let names: Vec<&str> = data.paths.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["particle 1", "particle 2"]);
        // The first bob swings on a rod of length lA = 1 about the origin.
        let p = &data.paths[0];
        assert!(p.x.iter().zip(&p.y).all(|(x, y)| (x.hypot(*y) - 1.0).abs() < 1e-6));
        assert!(data.paths.iter().all(|p| p.x.len() == data.time.len() && p.y.len() == data.time.len()));
        assert!(data.coordinates.iter().all(|q| q.angle) && data.velocities.iter().all(|v| !v.angle));
        assert!(super::super::svg(&data).unwrap().contains("Paths in the plane"));

        // Kepler's orbit is drawn from r and θ, not from particles: no path panel.
        let data = example("kepler.toml", 5.0);
        assert!(data.paths.is_empty());
        assert!(!super::super::svg(&data).unwrap().contains("in the plane"));
        assert_eq!(data.coordinates.iter().map(|q| q.angle).collect::<Vec<_>>(), [false, true]);
    }

    #[test]
    fn only_conserved_quantities_drift() {
        let data = example("double_pendulum.toml", 1.0);
        assert_eq!(data.invariants.iter().map(|s| s.name.as_str()).collect::<Vec<_>>(), ["H"]);
        assert!(super::super::svg(&data).unwrap().contains("Drift of conserved quantities"));

        // The drive feeds energy in: H is not conserved, and nothing else is.
        let data = example("driven_oscillator.toml", 1.0);
        assert!(data.invariants.is_empty(), "{:?}", data.invariants.iter().map(|s| &s.name).collect::<Vec<_>>());
        assert!(!super::super::svg(&data).unwrap().contains("Drift"));
    }
}
