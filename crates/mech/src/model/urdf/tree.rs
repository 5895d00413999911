//! A URDF robot's link tree as lagrange bodies: one body per moving joint,
//! fixed joints merged into the body they hang from, every placement and
//! inertia as numbers in the body's frame.
//!
//! Entry: [`plan`]. A lagrange body turns about an axis of its parent's frame
//! and has no fixed rotation of its own, while a URDF joint places its child at
//! an origin with a fixed rotation R0 (roll, pitch, yaw) and then moves it along
//! or about an axis of that rotated frame. Each link therefore keeps the fixed
//! rotation C from its body's frame to its own (C = I at the root): for a joint
//! from a link with (C, t) in body b, at origin (p, R0) with axis a, the child's
//! body turns about n = C·R0·a (in b's axes, since R0·Rot(a, q) = Rot(R0·a, q)·R0)
//! from the reference point t + C·p, and the child link sits in it with C' = C·R0.
//! A fixed joint adds no body: the child link sits in b with t' = t + C·p,
//! C' = C·R0. Inertials are turned into the body's frame and summed about its
//! reference point (the joint's origin): mass, centre of mass, and
//! Σ R I_c Rᵀ + m(|c|²·1 − c cᵀ).
//!
//! A floating joint gives six coordinates: the translation of the child's
//! origin and roll, pitch, yaw (the sequence "xyz": about x, the new y, the
//! newest z), both in the parent body's axes at the joint's origin; they are the
//! URDF joint frame's own where C·R0 = I (a floating joint at the root with no
//! rotation in its origin, the usual case).

use super::xml::{JointKind, Robot};
use crate::error::ModelError;
use std::collections::HashSet;

type Mat3 = [[f64; 3]; 3];
const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Entries of a composed rotation this close to 0 or ±1 are taken as exactly
/// that: a quarter turn written as 1.5707963267948966 gives cos = 6e-17, and an
/// axis that is exactly a frame axis keeps the derivation's expressions short.
/// The change is below the rounding of the trigonometry that made it.
const SNAP: f64 = 1e-14;

/// How a body moves relative to its parent body.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Motion {
    /// One angle (a coordinate index) about a unit axis in the parent's axes.
    Turn { coord: usize, axis: [f64; 3] },
    /// One slide along a unit axis in the parent's axes.
    Slide { coord: usize, axis: [f64; 3] },
    /// x, y, z, roll, pitch, yaw.
    Free { coords: [usize; 6] },
}

/// One body of the model.
#[derive(Debug, Clone)]
pub(crate) struct PlanBody {
    /// The body's name (the moving link's, as an identifier).
    pub(crate) name: String,
    /// The moving link, as the URDF names it.
    pub(crate) link: String,
    /// The joint that moves it and its type.
    pub(crate) joint: String,
    pub(crate) kind: JointKind,
    pub(crate) parent: Option<usize>,
    /// The joint's origin in the parent body's frame (from its reference point).
    pub(crate) offset: [f64; 3],
    pub(crate) motion: Motion,
    pub(crate) mass: f64,
    /// The centre of mass in the body's frame.
    pub(crate) center_of_mass: [f64; 3],
    /// The inertia tensor about the reference point, body axes.
    pub(crate) inertia: Mat3,
    /// The fixed rotation from the body's frame to the moving link's (columns:
    /// the link's axes in the body's).
    pub(crate) frame: Mat3,
    /// Links welded onto it by fixed joints.
    pub(crate) merged: Vec<String>,
    /// What the joint says that does not enter the model (limits, mimic, ...).
    pub(crate) ignored: Vec<String>,
}

/// A coordinate and the joint it belongs to.
#[derive(Debug, Clone)]
pub(crate) struct PlanCoordinate {
    pub(crate) name: String,
    pub(crate) joint: String,
}

/// The robot as bodies.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    pub(crate) robot: String,
    pub(crate) coordinates: Vec<PlanCoordinate>,
    pub(crate) bodies: Vec<PlanBody>,
    /// The root link and the links welded to it: they do not move.
    pub(crate) grounded: Vec<String>,
    /// The tags left out of the whole file.
    pub(crate) ignored: Vec<String>,
}

/// Where a link sits: in which body (None: the world), at which point and with
/// which fixed rotation of that body's frame.
#[derive(Debug, Clone, Copy)]
struct Place {
    body: Option<usize>,
    offset: [f64; 3],
    frame: Mat3,
}

/// Plans the bodies of a robot; `floating_base` gives the root link six coordinates.
pub(crate) fn plan(robot: &Robot, floating_base: bool) -> Result<Plan, ModelError> {
    let n_links = robot.links.len();
    let link_index = |name: &str| robot.links.iter().position(|l| l.name == name);
    for (k, l) in robot.links.iter().enumerate() {
        if robot.links[..k].iter().any(|e| e.name == l.name) {
            return Err(ModelError::at(l.span.clone(), format!("a second link is named '{}'", l.name)));
        }
    }
    // Each link's parent joint.
    let mut parent_joint: Vec<Option<usize>> = vec![None; n_links];
    for (k, j) in robot.joints.iter().enumerate() {
        if robot.joints[..k].iter().any(|e| e.name == j.name) {
            return Err(ModelError::at(j.span.clone(), format!("a second joint is named '{}'", j.name)));
        }
        for (name, span) in [&j.parent, &j.child] {
            if link_index(name).is_none() {
                return Err(ModelError::at(
                    span.clone(),
                    format!("joint '{}' names the link '{name}', which the file does not have", j.name),
                )
                .with_help(known_links(robot)));
            }
        }
        let c = link_index(&j.child.0).unwrap_or_default();
        if let Some(other) = parent_joint[c] {
            return Err(ModelError::at(
                j.child.1.clone(),
                format!(
                    "link '{}' is the child of joints '{}' and '{}': the links do not form a tree",
                    j.child.0, robot.joints[other].name, j.name
                ),
            )
            .with_help("a URDF robot is a tree: each link hangs from at most one joint (closed loops are not URDF)"));
        }
        parent_joint[c] = Some(k);
    }
    let roots: Vec<usize> = (0..n_links).filter(|&l| parent_joint[l].is_none()).collect();
    let Some(&root) = roots.first() else {
        return Err(cycle(robot, &parent_joint, 0));
    };
    if let Some(&second) = roots.get(1) {
        return Err(ModelError::at(
            robot.links[second].span.clone(),
            format!(
                "links '{}' and '{}' both hang from no joint: the robot is not one tree",
                robot.links[root].name, robot.links[second].name
            ),
        )
        .with_help("join every link but the root to a parent link by a <joint>"));
    }

    // Depth first from the root, children in file order.
    let mut place: Vec<Option<Place>> = vec![None; n_links];
    place[root] = Some(Place { body: None, offset: [0.0; 3], frame: IDENTITY });
    let mut names = Names::default();
    let mut coordinates = Vec::new();
    let mut bodies: Vec<PlanBody> = Vec::new();
    let mut moving_link: Vec<usize> = Vec::new();
    if floating_base {
        let base = &robot.links[root];
        let coords = free_coordinates(&mut names, &mut coordinates, &base.name, "floating base");
        bodies.push(PlanBody {
            name: names.take(&base.name, "link"),
            link: base.name.clone(),
            joint: "floating base".into(),
            kind: JointKind::Floating,
            parent: None,
            offset: [0.0; 3],
            motion: Motion::Free { coords },
            mass: 0.0,
            center_of_mass: [0.0; 3],
            inertia: [[0.0; 3]; 3],
            frame: IDENTITY,
            merged: Vec::new(),
            ignored: Vec::new(),
        });
        moving_link.push(root);
        place[root] = Some(Place { body: Some(0), offset: [0.0; 3], frame: IDENTITY });
    }
    let mut stack = vec![root];
    let mut order = Vec::new();
    while let Some(l) = stack.pop() {
        order.push(l);
        let here = place[l].expect("a link is placed before its children");
        let children: Vec<usize> =
            (0..robot.joints.len()).filter(|&k| robot.joints[k].parent.0 == robot.links[l].name).collect();
        for &k in children.iter().rev() {
            let j = &robot.joints[k];
            let c = link_index(&j.child.0).unwrap_or_default();
            let r0 = rpy(j.origin.rpy);
            let frame = snap(mul(here.frame, r0));
            let offset = add(here.offset, apply(here.frame, j.origin.xyz));
            let motion = match j.kind {
                JointKind::Fixed => {
                    place[c] = Some(Place { body: here.body, offset, frame });
                    if let Some(b) = here.body {
                        bodies[b].merged.push(robot.links[c].name.clone());
                    }
                    stack.push(c);
                    continue;
                }
                JointKind::Revolute | JointKind::Continuous => {
                    let coord = coordinates.len();
                    coordinates.push(PlanCoordinate { name: names.take(&j.name, "joint"), joint: j.name.clone() });
                    Motion::Turn { coord, axis: snap_vec(apply(frame, j.axis)) }
                }
                JointKind::Prismatic => {
                    let coord = coordinates.len();
                    coordinates.push(PlanCoordinate { name: names.take(&j.name, "joint"), joint: j.name.clone() });
                    Motion::Slide { coord, axis: snap_vec(apply(frame, j.axis)) }
                }
                JointKind::Floating => {
                    Motion::Free { coords: free_coordinates(&mut names, &mut coordinates, &j.name, &j.name) }
                }
            };
            place[c] = Some(Place { body: Some(bodies.len()), offset: [0.0; 3], frame });
            moving_link.push(c);
            bodies.push(PlanBody {
                name: names.take(&robot.links[c].name, "link"),
                link: robot.links[c].name.clone(),
                joint: j.name.clone(),
                kind: j.kind,
                parent: here.body,
                offset,
                motion,
                mass: 0.0,
                center_of_mass: [0.0; 3],
                inertia: [[0.0; 3]; 3],
                frame,
                merged: Vec::new(),
                ignored: j.ignored.clone(),
            });
            stack.push(c);
        }
    }
    if order.len() < n_links {
        let lost = (0..n_links).find(|l| place[*l].is_none()).unwrap_or_default();
        return Err(cycle(robot, &parent_joint, lost));
    }
    if coordinates.is_empty() {
        // A model without coordinates has nothing to derive or run: say so here,
        // at the URDF, rather than let every command refuse the written model.
        let root_link = &robot.links[root];
        let joints = if robot.joints.is_empty() { "no joint" } else { "only fixed joints" };
        return Err(ModelError::at(
            root_link.span.clone(),
            format!(
                "the robot has {joints}: every link is welded to the root link '{}', so nothing moves and the model would have no coordinates",
                root_link.name
            ),
        )
        .with_help(
            "a robot that moves as a whole (a quadrotor, a satellite) needs a floating base: six coordinates for its root link; otherwise give it a revolute, continuous or prismatic joint",
        ));
    }

    // Inertials, summed per body about its reference point.
    let mut grounded = Vec::new();
    let mut moments = vec![[0.0; 3]; bodies.len()];
    for (l, link) in robot.links.iter().enumerate() {
        let Some(p) = place[l] else { continue };
        let Some(b) = p.body else {
            grounded.push(link.name.clone());
            continue;
        };
        let Some(i) = &link.inertial else { continue };
        let c = add(p.offset, apply(p.frame, i.origin.xyz));
        let r = mul(p.frame, rpy(i.origin.rpy));
        let turned = mul(mul(r, i.tensor), transpose(r));
        let c2 = c.iter().map(|x| x * x).sum::<f64>();
        let body = &mut bodies[b];
        for a in 0..3 {
            for e in 0..3 {
                let shift = if a == e { c2 } else { 0.0 } - c[a] * c[e];
                body.inertia[a][e] += turned[a][e] + i.mass * shift;
            }
            moments[b][a] += i.mass * c[a];
        }
        body.mass += i.mass;
    }
    for (b, body) in bodies.iter_mut().enumerate() {
        if body.mass.is_nan() || body.mass <= 0.0 {
            let link = &robot.links[moving_link[b]];
            let why = if link.inertial.is_some() { "its mass is 0" } else { "it has no <inertial>" };
            return Err(ModelError::at(
                link.span.clone(),
                format!("link '{}' moves (joint '{}' is {}) but {why}", link.name, body.joint, body.kind.word()),
            )
            .with_help("give the link <inertial> with a mass > 0 and an <inertia>; a link without one can hang on a fixed joint only"));
        }
        body.center_of_mass = moments[b].map(|m| m / body.mass);
        for a in 0..3 {
            for e in 0..a {
                let mean = 0.5 * (body.inertia[a][e] + body.inertia[e][a]);
                body.inertia[a][e] = mean;
                body.inertia[e][a] = mean;
            }
        }
    }
    Ok(Plan { robot: robot.name.clone(), coordinates, bodies, grounded, ignored: robot.ignored.clone() })
}

fn free_coordinates(names: &mut Names, out: &mut Vec<PlanCoordinate>, base: &str, joint: &str) -> [usize; 6] {
    let mut coords = [0; 6];
    for (k, suffix) in ["x", "y", "z", "roll", "pitch", "yaw"].iter().enumerate() {
        coords[k] = out.len();
        out.push(PlanCoordinate { name: names.take(&format!("{base}_{suffix}"), "joint"), joint: joint.into() });
    }
    coords
}

fn known_links(robot: &Robot) -> String {
    let names: Vec<&str> = robot.links.iter().take(12).map(|l| l.name.as_str()).collect();
    let more = if robot.links.len() > 12 { ", ..." } else { "" };
    format!("its links are: {}{more}", names.join(", "))
}

/// The error for a link that is its own ancestor, at one of the cycle's joints.
fn cycle(robot: &Robot, parent_joint: &[Option<usize>], start: usize) -> ModelError {
    let mut seen = vec![false; robot.links.len()];
    let mut l = start;
    while !seen[l] {
        seen[l] = true;
        let Some(j) = parent_joint[l] else { break };
        l = robot.links.iter().position(|x| x.name == robot.joints[j].parent.0).unwrap_or_default();
    }
    // `l` is on the cycle: list it from there.
    let mut path = vec![robot.links[l].name.clone()];
    let mut at = l;
    let mut first_joint = None;
    while let Some(j) = parent_joint[at] {
        first_joint.get_or_insert(j);
        at = robot.links.iter().position(|x| x.name == robot.joints[j].parent.0).unwrap_or_default();
        path.push(robot.links[at].name.clone());
        if at == l || path.len() > robot.links.len() {
            break;
        }
    }
    let joint = &robot.joints[first_joint.unwrap_or_default()];
    ModelError::at(
        joint.span.clone(),
        format!("the joints form a cycle: {} (each the parent of the one before)", path.join(" ← ")),
    )
    .with_help("a URDF robot is a tree with one root link; closed loops are not URDF")
}

/// Names made identifiers, each once.
#[derive(Default)]
struct Names {
    taken: HashSet<String>,
}

impl Names {
    /// `raw` as a name lagrange accepts for a coordinate or a body, and not
    /// taken yet (nor `g`, the gravity parameter).
    fn take(&mut self, raw: &str, what: &str) -> String {
        let mut name: String = raw.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
        if !name.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
            name = format!("{what}_{name}");
        }
        let acceptable = |n: &str| {
            let s = toml::Spanned::new(0..0, n.to_string());
            crate::source::check_identifier(&s, what).is_ok()
                && crate::source::check_not_generated(&s, what, true).is_ok()
                && n != "g"
        };
        if !acceptable(&name) {
            name = format!("{what}_{name}");
        }
        let base = name.clone();
        let mut k = 2;
        while self.taken.contains(&name) || !acceptable(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        self.taken.insert(name.clone());
        name
    }
}

/// R = Rz(yaw)·Ry(pitch)·Rx(roll), URDF's fixed-axis roll, pitch, yaw.
fn rpy([r, p, y]: [f64; 3]) -> Mat3 {
    let (sr, cr) = r.sin_cos();
    let (sp, cp) = p.sin_cos();
    let (sy, cy) = y.sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

fn mul(a: Mat3, b: Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}

fn transpose(a: Mat3) -> Mat3 {
    let mut out = a;
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = a[j][i];
        }
    }
    out
}

fn apply(a: Mat3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn snap_entry(x: f64) -> f64 {
    if x.abs() < SNAP {
        0.0
    } else if (x.abs() - 1.0).abs() < SNAP {
        x.signum()
    } else {
        x
    }
}

fn snap(a: Mat3) -> Mat3 {
    a.map(|row| row.map(snap_entry))
}

fn snap_vec(v: [f64; 3]) -> [f64; 3] {
    v.map(snap_entry)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planned(text: &str) -> Result<Plan, ModelError> {
        plan(&super::super::xml::read(text)?, false)
    }

    const INERTIAL: &str =
        r#"<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#;

    fn joint(name: &str, kind: &str, parent: &str, child: &str) -> String {
        format!(r#"<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/></joint>"#)
    }

    #[track_caller]
    fn check_error(links: &[&str], joints: &[String], at: &str, message: &str) {
        let mut text = String::from("<robot name=\"r\">");
        for l in links {
            text.push_str(&format!(r#"<link name="{l}">{INERTIAL}</link>"#));
        }
        for j in joints {
            text.push_str(j);
        }
        text.push_str("</robot>");
        let err = planned(&text).expect_err("refused");
        let span = err.span.clone().expect("a place");
        assert!(text[span.start..].starts_with(at), "at {:?}, expected {at:?}: {}", &text[span.start..], err.message);
        assert!(err.message.contains(message), "{}", err.message);
    }

    /// A robot with nothing that moves is refused at its root link, not written
    /// as a model without coordinates; with a floating base it moves as a whole.
    #[test]
    fn a_robot_without_moving_joints_is_refused_unless_its_base_floats() {
        let only_fixed = [joint("weld", "fixed", "base", "arm")];
        check_error(&["base", "arm"], &only_fixed, "<link name=\"base\"", "only fixed joints");
        check_error(&["base"], &[], "<link name=\"base\"", "the robot has no joint");
        let text = format!(r#"<robot name="r"><link name="base">{INERTIAL}</link></robot>"#);
        let floating = plan(&super::super::xml::read(&text).expect("the XML"), true).expect("a floating base moves");
        assert_eq!(floating.coordinates.len(), 6);
    }

    #[test]
    fn tree_refusals_point_at_the_joint_or_link() {
        check_error(&["a", "b"], &[joint("j", "revolute", "a", "c")], "c\"", "names the link 'c'");
        check_error(
            &["a", "b", "c"],
            &[joint("j", "revolute", "a", "b"), joint("k", "revolute", "c", "b")],
            "b\"/></joint></robot>",
            "the child of joints 'j' and 'k'",
        );
        check_error(
            &["a", "b", "c"],
            &[joint("j", "revolute", "a", "b"), joint("k", "revolute", "c", "a"), joint("l", "revolute", "b", "c")],
            "<joint",
            "cycle",
        );
        check_error(
            &["w", "a", "b"],
            &[joint("j", "revolute", "a", "b"), joint("k", "revolute", "b", "a")],
            "<joint name=\"k\"",
            "cycle",
        );
        check_error(&["a", "b", "c"], &[joint("j", "revolute", "a", "b")], "<link name=\"c\"", "not one tree");
        check_error(&["a", "a"], &[], "<link name=\"a\"", "second link");
    }

    #[test]
    fn a_moving_link_without_inertial_is_refused_at_the_link() {
        let text = format!(r#"<robot><link name="a"/><link name="b"/>{}</robot>"#, joint("j", "revolute", "a", "b"));
        let err = planned(&text).expect_err("refused");
        assert_eq!(&text[err.span.clone().unwrap()], "<link", "{}", err.message);
        assert!(
            err.message.contains("link 'b' moves (joint 'j' is revolute) but it has no <inertial>"),
            "{}",
            err.message
        );
        // Welded to a link with mass, it is fine.
        let text = format!(
            r#"<robot><link name="a"/><link name="b"/><link name="c">{INERTIAL}</link>{}{}</robot>"#,
            joint("j", "revolute", "a", "b"),
            joint("k", "fixed", "b", "c")
        );
        let p = planned(&text).unwrap();
        assert_eq!(p.bodies.len(), 1);
        assert_eq!(p.bodies[0].merged, ["c"]);
    }

    #[test]
    fn fixed_rotations_carry_to_the_axes_and_inertia() {
        // A quarter turn about z at the joint: the x axis becomes y, and the
        // link's inertia diag(1, 2, 3) about its centre of mass at x = 1 (link
        // axes) is diag(2, 1, 3) plus m(|c|² − ccᵀ) with c = (0, 1, 0).
        let text = r#"<robot><link name="a"/><link name="b"><inertial><origin xyz="1 0 0"/><mass value="2"/>
            <inertia ixx="1" ixy="0" ixz="0" iyy="2" iyz="0" izz="3"/></inertial></link>
            <joint name="j" type="revolute"><origin xyz="0 0 1" rpy="0 0 1.5707963267948966"/>
            <axis xyz="1 0 0"/><parent link="a"/><child link="b"/></joint></robot>"#;
        let p = planned(text).unwrap();
        let b = &p.bodies[0];
        let Motion::Turn { axis, .. } = b.motion else { panic!("a turn") };
        assert_eq!(axis, [0.0, 1.0, 0.0]);
        assert_eq!(b.offset, [0.0, 0.0, 1.0]);
        assert_eq!(b.center_of_mass, [0.0, 1.0, 0.0]);
        assert_eq!(b.inertia, [[4.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 5.0]]);
    }

    #[test]
    fn names_become_identifiers_once() {
        let mut n = Names::default();
        assert_eq!(n.take("shoulder-pan joint", "joint"), "shoulder_pan_joint");
        assert_eq!(n.take("shoulder_pan_joint", "joint"), "shoulder_pan_joint_2");
        assert_eq!(n.take("1", "joint"), "joint_1");
        assert_eq!(n.take("t", "joint"), "joint_t");
        assert_eq!(n.take("g", "joint"), "joint_g");
        assert_eq!(n.take("p_x", "joint"), "joint_p_x");
    }
}
