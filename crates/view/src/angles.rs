//! Which coordinates are angles, so that q and q + 2π are the same
//! configuration and plots may wrap them to (−π, π].

use mech::{Derivation, Orbit};

/// Whether each coordinate is an angle, so that q and q + 2π are the same
/// configuration: a rigid body's Euler angle, the angle of an orbit's plane
/// polar coordinates, or a coordinate that the Lagrangian and the particles'
/// positions contain, and only inside sin, cos and tan. A coordinate they do
/// not contain at all (a cyclic x) is not one.
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
            if model.bodies.iter().any(|b| b.angles.contains(&i)) || orbit_angle.as_deref() == Some(*name) {
                return true;
            }
            let mut seen = false;
            exprs.iter().all(|&e| only_in_trig(pool, e, name, false, &mut seen)) && seen
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
