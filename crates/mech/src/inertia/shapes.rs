//! The standard shapes of a body file and their moments of inertia about their
//! own centre of mass, in the part's own axes (where every one is diagonal).
//!
//! Enter with [`Shape::from_name`], [`Shape::size_names`] (what `size` lists)
//! and [`Shape::principal_moments`]. Every shape with a symmetry axis has it
//! along the part's z axis; `orientation` turns the part as a whole.

use sym::{ExprId, Pool};

/// A shape with a closed-form inertia tensor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// A point mass.
    Point,
    /// A thin rod of length L along the part's z axis.
    Rod,
    /// A solid rectangular box with edges a, b, c along the part's x, y, z.
    Box,
    /// A solid sphere of radius R.
    Sphere,
    /// A thin spherical shell of radius R.
    Shell,
    /// A solid circular cylinder of radius R and height h, axis along z.
    Cylinder,
    /// A solid circular cone of base radius R and height h, axis along z,
    /// apex up (+z); its centre of mass is on the axis h/4 above the base.
    Cone,
    /// A thin circular disk of radius R in the part's xy plane.
    Disk,
    /// A thin circular ring (hoop) of radius R in the part's xy plane.
    Ring,
    /// A solid ellipsoid with semi-axes a, b, c along the part's x, y, z.
    Ellipsoid,
}

impl Shape {
    /// Every shape, in the order the documentation lists them.
    pub const ALL: [Shape; 10] = [
        Shape::Point,
        Shape::Rod,
        Shape::Box,
        Shape::Sphere,
        Shape::Shell,
        Shape::Cylinder,
        Shape::Cone,
        Shape::Disk,
        Shape::Ring,
        Shape::Ellipsoid,
    ];

    /// The name used in body files.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Point => "point",
            Shape::Rod => "rod",
            Shape::Box => "box",
            Shape::Sphere => "sphere",
            Shape::Shell => "shell",
            Shape::Cylinder => "cylinder",
            Shape::Cone => "cone",
            Shape::Disk => "disk",
            Shape::Ring => "ring",
            Shape::Ellipsoid => "ellipsoid",
        }
    }

    /// The shape with this name, if any.
    pub fn from_name(name: &str) -> Option<Shape> {
        Shape::ALL.into_iter().find(|s| s.name() == name)
    }

    /// What the entries of `size` are, in order (empty: the shape takes no size).
    pub fn size_names(self) -> &'static [&'static str] {
        match self {
            Shape::Point => &[],
            Shape::Rod => &["length L along the part's z axis"],
            Shape::Box => &["edge a along x", "edge b along y", "edge c along z"],
            Shape::Sphere | Shape::Shell => &["radius R"],
            Shape::Cylinder | Shape::Cone => &["radius R", "height h along the part's z axis"],
            Shape::Disk | Shape::Ring => &["radius R (in the part's xy plane)"],
            Shape::Ellipsoid => &["semi-axis a along x", "semi-axis b along y", "semi-axis c along z"],
        }
    }

    /// A one-line description of the shape and its moments, for the text output.
    pub fn describe(self) -> &'static str {
        match self {
            Shape::Point => "point mass",
            Shape::Rod => "thin rod of length L along z: I_x = I_y = M L^2/12, I_z = 0",
            Shape::Box => "solid box, edges a, b, c along x, y, z: I_x = M (b^2 + c^2)/12, and cyclically",
            Shape::Sphere => "solid sphere of radius R: I = 2/5 M R^2",
            Shape::Shell => "thin spherical shell of radius R: I = 2/3 M R^2",
            Shape::Cylinder => "solid cylinder, axis z: I_z = M R^2/2, I_x = I_y = M (3 R^2 + h^2)/12",
            Shape::Cone => "solid cone, axis z, about its CM (h/4 above the base): I_z = 3/10 M R^2, I_x = I_y = 3/80 M (4 R^2 + h^2)",
            Shape::Disk => "thin disk in the xy plane: I_z = M R^2/2, I_x = I_y = M R^2/4",
            Shape::Ring => "thin ring in the xy plane: I_z = M R^2, I_x = I_y = M R^2/2",
            Shape::Ellipsoid => "solid ellipsoid, semi-axes a, b, c along x, y, z: I_x = M (b^2 + c^2)/5, and cyclically",
        }
    }

    /// The moments (I_x, I_y, I_z) about the part's centre of mass in the
    /// part's own axes, for mass `m` and the `size` entries (as many as
    /// [`Shape::size_names`] lists).
    pub fn principal_moments(self, pool: &mut Pool, m: ExprId, size: &[ExprId]) -> [ExprId; 3] {
        debug_assert_eq!(size.len(), self.size_names().len());
        // c * m * (sum of the squares of the listed sizes, each with its weight).
        let moment = |pool: &mut Pool, c: (i64, i64), terms: &[(i64, usize)]| {
            let sq: Vec<ExprId> = terms
                .iter()
                .map(|&(w, k)| {
                    let s2 = pool.powi(size[k], 2);
                    let w = pool.int(w);
                    pool.mul2(w, s2)
                })
                .collect();
            let sum = pool.add(&sq);
            let c = pool.rational(c.0, c.1);
            pool.mul(&[c, m, sum])
        };
        match self {
            Shape::Point => [pool.zero(); 3],
            Shape::Rod => {
                let i = moment(pool, (1, 12), &[(1, 0)]);
                [i, i, pool.zero()]
            }
            Shape::Box => [
                moment(pool, (1, 12), &[(1, 1), (1, 2)]),
                moment(pool, (1, 12), &[(1, 0), (1, 2)]),
                moment(pool, (1, 12), &[(1, 0), (1, 1)]),
            ],
            Shape::Sphere => [moment(pool, (2, 5), &[(1, 0)]); 3],
            Shape::Shell => [moment(pool, (2, 3), &[(1, 0)]); 3],
            Shape::Cylinder => {
                let across = moment(pool, (1, 12), &[(3, 0), (1, 1)]);
                [across, across, moment(pool, (1, 2), &[(1, 0)])]
            }
            Shape::Cone => {
                let across = moment(pool, (3, 80), &[(4, 0), (1, 1)]);
                [across, across, moment(pool, (3, 10), &[(1, 0)])]
            }
            Shape::Disk => {
                let across = moment(pool, (1, 4), &[(1, 0)]);
                [across, across, moment(pool, (1, 2), &[(1, 0)])]
            }
            Shape::Ring => {
                let across = moment(pool, (1, 2), &[(1, 0)]);
                [across, across, moment(pool, (1, 1), &[(1, 0)])]
            }
            Shape::Ellipsoid => [
                moment(pool, (1, 5), &[(1, 1), (1, 2)]),
                moment(pool, (1, 5), &[(1, 0), (1, 2)]),
                moment(pool, (1, 5), &[(1, 0), (1, 1)]),
            ],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The moments of `shape` with mass M and the given size names, printed.
    #[track_caller]
    fn check(shape: &str, size: &[&str], expect: [&str; 3]) {
        let mut pool = Pool::default();
        let m = pool.symbol("M");
        let size: Vec<ExprId> = size.iter().map(|s| pool.parse(s).unwrap()).collect();
        let got = Shape::from_name(shape).unwrap().principal_moments(&mut pool, m, &size);
        let got: Vec<String> = got.iter().map(|&e| pool.display(e).to_string()).collect();
        assert_eq!(got, expect, "{shape}");
    }

    #[test]
    fn standard_moments() {
        check("point", &[], ["0", "0", "0"]);
        check("rod", &["L"], ["L^2*M/12", "L^2*M/12", "0"]);
        check("sphere", &["R"], ["2*M*R^2/5", "2*M*R^2/5", "2*M*R^2/5"]);
        check("shell", &["R"], ["2*M*R^2/3", "2*M*R^2/3", "2*M*R^2/3"]);
        check("disk", &["R"], ["M*R^2/4", "M*R^2/4", "M*R^2/2"]);
        check("ring", &["R"], ["M*R^2/2", "M*R^2/2", "M*R^2"]);
    }

    #[test]
    fn names_round_trip() {
        for s in Shape::ALL {
            assert_eq!(Shape::from_name(s.name()), Some(s));
        }
        assert_eq!(Shape::from_name("cube"), None);
    }
}
