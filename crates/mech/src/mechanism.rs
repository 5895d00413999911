//! The mechanism as a picture: where the things a model is made of are, as
//! functions of (q, t), for drawing it move (`lagrange report`).
//!
//! What is drawn, by what the model gives:
//! - **particles** at their positions x_i(q, t), and **rigid bodies** at their
//!   reference points (and centres of mass, where those differ) with their body
//!   axes (in 3-D);
//! - a model without particles or bodies whose first two coordinates are the
//!   plane polar coordinates of an orbit (`r` and an angle, as `lagrange
//!   orbit` reads them): one point at (r cos θ, r sin θ);
//! - any other model: one point per coordinate on a line, the coordinate read
//!   as a displacement from its place (coupled oscillators, the triatomic
//!   molecule's longitudinal motion), with springs between coordinates that the
//!   potential couples.
//!
//! Rods are not declared in model files: [`rods`] finds them in the motion,
//! between the fixed origin and a point or two consecutive points whose
//! distance does not change along the run.

use crate::{Derivation, Orbit};
use sym::{ExprId, Tape};

/// What a drawn point is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointKind {
    /// A particle of `[[particles]]`.
    Particle,
    /// A rigid body's reference point.
    Body,
    /// The point of a model given by T and U alone (see the module documentation).
    Coordinate,
}

impl PointKind {
    /// The kind's name in reports (`particle`, `body`, `coordinate`).
    pub fn name(self) -> &'static str {
        match self {
            PointKind::Particle => "particle",
            PointKind::Body => "body",
            PointKind::Coordinate => "coordinate",
        }
    }
}

/// One drawn point.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// `particle 1`, the body's name, or the coordinate's.
    pub name: String,
    /// What it is.
    pub kind: PointKind,
    /// Its mass (1 where the model gives none), for the size it is drawn at.
    pub mass: f64,
}

/// A rigid body's axes, drawn at one of the points.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyAxes {
    /// The body's name.
    pub name: String,
    /// The index of its reference point in [`Mechanism::points`].
    pub point: usize,
}

/// How the points follow from the coordinates.
#[derive(Debug, Clone)]
enum Placement {
    /// Positions compiled from the model's expressions over `[q, q', t, parameters]`,
    /// followed by the nine entries of each body's axes (3-D).
    Compiled { tape: Box<Tape>, inputs: Vec<f64>, values: Vec<f64> },
    /// (r cos θ, r sin θ) of coordinates `r` and `angle`.
    Polar { r: usize, angle: usize },
    /// Coordinate k at (k·spacing + q_k, 0).
    Line { spacing: f64 },
}

/// The points of a model and how to place them. See the module documentation.
#[derive(Debug, Clone)]
pub struct Mechanism {
    points: Vec<Point>,
    bodies: Vec<BodyAxes>,
    dimension: usize,
    placement: Placement,
    springs: Vec<(usize, usize)>,
    layout: crate::Layout,
}

impl Mechanism {
    /// The mechanism of a derivation.
    pub fn new(d: &Derivation) -> Mechanism {
        let model = d.model();
        let pool = d.pool();
        let value = |e: ExprId| pool.eval(e, &|name| model.parameter(name)).unwrap_or(1.0);
        let layout = d.layout().clone();
        if !model.particles.is_empty() || !model.bodies.is_empty() {
            let dimension =
                model.particles.iter().map(|p| p.position.len()).chain(model.bodies.iter().map(|b| b.dimension)).max();
            let dimension = dimension.unwrap_or(3);
            let mut points = Vec::new();
            let mut exprs = Vec::new();
            let zero = pool.zero();
            for (i, p) in model.particles.iter().enumerate() {
                points.push(Point {
                    name: format!("particle {}", i + 1),
                    kind: PointKind::Particle,
                    mass: value(p.mass),
                });
                exprs.extend((0..dimension).map(|k| p.position.get(k).copied().unwrap_or(zero)));
            }
            let mut bodies = Vec::new();
            for (b, motion) in model.bodies.iter().zip(d.bodies()) {
                if dimension == 3 {
                    bodies.push(BodyAxes { name: b.name.clone(), point: points.len() });
                }
                points.push(Point { name: b.name.clone(), kind: PointKind::Body, mass: value(b.mass) });
                exprs.extend(motion.position[..dimension].iter().copied());
                if motion.center != motion.position {
                    let name = format!("{} (centre of mass)", b.name);
                    points.push(Point { name, kind: PointKind::Body, mass: value(b.mass) });
                    exprs.extend(motion.center[..dimension].iter().copied());
                }
            }
            if dimension == 3 {
                for motion in d.bodies() {
                    exprs.extend(motion.axes.iter().flatten().copied());
                }
            }
            if let Ok(tape) = Tape::compile(pool, &exprs, layout.symbols()) {
                let placement = Placement::Compiled {
                    tape: Box::new(tape),
                    inputs: layout.values(),
                    values: vec![0.0; exprs.len()],
                };
                return Mechanism { points, bodies, dimension, placement, springs: Vec::new(), layout };
            }
        }
        let names = d.coordinate_names();
        if let Ok(orbit) = Orbit::new(d) {
            let [r, angle] = orbit.names.clone().map(|n| names.iter().position(|c| *c == n).unwrap_or(0));
            let point = Point { name: names[r].to_string(), kind: PointKind::Coordinate, mass: 1.0 };
            let placement = Placement::Polar { r, angle };
            return Mechanism {
                points: vec![point],
                bodies: Vec::new(),
                dimension: 2,
                placement,
                springs: Vec::new(),
                layout,
            };
        }
        let points =
            names.iter().map(|n| Point { name: n.to_string(), kind: PointKind::Coordinate, mass: 1.0 }).collect();
        let springs = coupled_neighbours(d);
        Mechanism {
            points,
            bodies: Vec::new(),
            dimension: 2,
            placement: Placement::Line { spacing: 1.0 },
            springs,
            layout,
        }
    }

    /// The drawn points.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// The rigid bodies whose axes are drawn.
    pub fn bodies(&self) -> &[BodyAxes] {
        &self.bodies
    }

    /// 2 (positions are (x, y)) or 3.
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// Pairs of points joined by springs (from the potential's couplings).
    pub fn springs(&self) -> &[(usize, usize)] {
        &self.springs
    }

    /// Where the points are at (t, q, q'): `dimension()` numbers per point, into `out`.
    pub fn place(&mut self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) {
        match &mut self.placement {
            Placement::Compiled { tape, inputs, values } => {
                self.layout.set_state(inputs, t, q, qd);
                tape.eval(inputs, values);
                let n = out.len();
                out.copy_from_slice(&values[..n]);
            }
            Placement::Polar { r, angle } => {
                out[0] = q[*r] * q[*angle].cos();
                out[1] = q[*r] * q[*angle].sin();
            }
            Placement::Line { spacing } => {
                for (k, &x) in q.iter().enumerate() {
                    out[2 * k] = k as f64 * *spacing + x;
                    out[2 * k + 1] = 0.0;
                }
            }
        }
    }

    /// The body axes e1, e2, e3 of body `b` at (t, q, q'), in space components
    /// (the rows of its rotation, through its tree).
    pub fn axes(&mut self, b: usize, t: f64, q: &[f64], qd: &[f64]) -> [[f64; 3]; 3] {
        let Placement::Compiled { tape, inputs, values } = &mut self.placement else {
            return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        };
        self.layout.set_state(inputs, t, q, qd);
        tape.eval(inputs, values);
        let start = values.len() - 9 * self.bodies.len() + 9 * b;
        std::array::from_fn(|i| std::array::from_fn(|j| values[start + 3 * i + j]))
    }
}

/// Consecutive coordinates k, k+1 that the potential couples (∂²L/∂q_k∂q_{k+1} ≠ 0
/// as an expression), for the springs of a line of coordinates.
fn coupled_neighbours(d: &Derivation) -> Vec<(usize, usize)> {
    let pool = d.pool();
    let forcing = &d.forcing;
    let mut pairs = Vec::new();
    for k in 0..forcing.len().saturating_sub(1) {
        let symbols = pool.symbols(forcing[k]);
        let next = &d.model().coordinates[k + 1].name;
        if symbols.iter().any(|s| s.order == 0 && pool.name_str(s.name) == next) {
            pairs.push((k, k + 1));
        }
    }
    pairs
}

/// Rods: the fixed origin (−1) and a point, or two consecutive points, whose
/// distance is the same in every frame (to 1e-9 of its size) and not zero.
/// `frames` holds `dimension` numbers per point per frame.
pub fn rods(frames: &[Vec<f64>], n_points: usize, dimension: usize) -> Vec<(isize, isize)> {
    let at = |f: &Vec<f64>, i: isize| -> Vec<f64> {
        if i < 0 {
            vec![0.0; dimension]
        } else {
            f[i as usize * dimension..(i as usize + 1) * dimension].to_vec()
        }
    };
    let constant = |i: isize, j: isize| -> bool {
        let lengths: Vec<f64> = frames
            .iter()
            .map(|f| {
                let (a, b) = (at(f, i), at(f, j));
                a.iter().zip(&b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
            })
            .collect();
        let Some(&first) = lengths.first() else { return false };
        first > 1e-12 && lengths.iter().all(|l| (l - first).abs() <= 1e-9 * first.max(1.0))
    };
    let mut rods = Vec::new();
    if frames.len() < 2 {
        return rods;
    }
    for i in 0..n_points as isize {
        if constant(-1, i) {
            rods.push((-1, i));
        } else if i > 0 && constant(i - 1, i) {
            rods.push((i - 1, i));
        }
        if i > 0 && constant(-1, i) && constant(i - 1, i) {
            rods.push((i - 1, i));
        }
    }
    rods
}
