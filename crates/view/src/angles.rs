//! Which coordinates are angles, so that q and q + 2π are the same
//! configuration and plots may wrap them to (−π, π].

use mech::{Derivation, Orbit};

/// Whether each coordinate is an angle, so that q and q + 2π are the same
/// configuration: a rigid body's Euler angle, the angle of an orbit's plane
/// polar coordinates, or a coordinate that the Lagrangian and the particles'
/// positions contain, and only inside sin, cos and tan. A coordinate they do
/// not contain at all (cyclic) is one when its own inertia ∂²L/∂q'² changes
/// with the configuration, as an azimuth's does (the spherical pendulum's φ,
/// m l² sin²θ); a cyclic x of constant inertia is not one.
pub fn angles(d: &Derivation) -> Vec<bool> {
    let pool = d.pool();
    let model = d.model();
    let names = d.coordinate_names();
    let mut exprs = vec![d.lagrangian()];
    exprs.extend(model.particles.iter().flat_map(|p| p.position.iter().copied()));
    let orbit_angle = Orbit::new(d).ok().map(|o| o.names[1].clone());
    names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            if model.bodies.iter().any(|b| b.orientation.angles().contains(&i)) || orbit_angle.as_deref() == Some(*name)
            {
                return true;
            }
            let mut seen = false;
            let only_trig = exprs.iter().all(|&e| only_in_trig(pool, e, name, false, &mut seen));
            if seen {
                return only_trig;
            }
            let inertia = d.mass_matrix().get(i).and_then(|row| row.get(i));
            inertia.is_some_and(|&m| {
                pool.symbols(m).iter().any(|s| s.order == 0 && names.contains(&pool.name_str(s.name)))
            })
        })
        .collect()
}

/// Whether coordinate `name` occurs in `e` only inside a trigonometric
/// function; `seen` is set where it occurs at all.
fn only_in_trig(pool: &sym::Pool, e: sym::ExprId, name: &str, inside: bool, seen: &mut bool) -> bool {
    use sym::{Func, Node};
    let all = |xs: &[sym::ExprId], inside: bool, seen: &mut bool| {
        xs.iter().all(|&x| only_in_trig(pool, x, name, inside, seen))
    };
    match pool.node(e) {
        Node::Sym(s) if s.order == 0 && pool.name_str(s.name) == name => {
            *seen = true;
            inside
        }
        Node::Sym(_) | Node::Num(_) | Node::Pi => true,
        Node::Add(xs) | Node::Mul(xs) => all(xs, inside, seen),
        Node::Pow(a, b) | Node::Atan2(a, b) => all(&[*a, *b], inside, seen),
        Node::Func(f, a) => all(&[*a], inside || matches!(f, Func::Sin | Func::Cos | Func::Tan), seen),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn angles_of(text: &str) -> Vec<bool> {
        angles(&Derivation::new(mech::Model::parse(text, &[]).unwrap()).unwrap())
    }

    #[test]
    fn a_cyclic_azimuth_is_an_angle_and_a_cyclic_line_is_not() {
        let spherical = "name = \"s\"\ncoordinates = [\"th\", \"ph\"]\nkinetic = \"m*l^2/2*(th'^2 + sin(th)^2*ph'^2)\"\npotential = \"-m*g*l*cos(th)\"\n[parameters]\nm = 1.0\nl = 1.0\ng = 9.81\n";
        assert_eq!(angles_of(spherical), [true, true]);
        let cart = "name = \"c\"\ncoordinates = [\"x\", \"a\"]\nkinetic = \"M/2*x'^2 + m/2*(x'^2 + 2*l*x'*a'*cos(a) + l^2*a'^2)\"\npotential = \"-m*g*l*cos(a)\"\n[parameters]\nM = 2.0\nm = 1.0\nl = 1.0\ng = 9.81\n";
        assert_eq!(angles_of(cart), [false, true]);
    }
}
