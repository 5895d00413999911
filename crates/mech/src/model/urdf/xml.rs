//! A URDF file's XML read into plain data: links with their inertial tags and
//! joints with their origin, axis and the names of their parent and child
//! links, each with the byte span of the element or attribute it came from.
//!
//! Entry: [`read`]. The XML is parsed by `roxmltree` (its positions give every
//! error a place); what the file says is checked here as far as it concerns one
//! element: numbers, a known joint type, an axis with a direction, a physical
//! inertia. What concerns the whole tree (names that exist, one parent per
//! link, no cycle) is `tree.rs`'s. Tags that carry no mechanics (visual,
//! collision, limits, dynamics, mimic, transmissions, gazebo, ...) are
//! recorded as notes, to be written as comments.

use crate::error::ModelError;
use std::ops::Range;

/// A placement `<origin xyz rpy>`: a translation, then a fixed rotation by
/// roll, pitch, yaw about the fixed x, y, z axes (R = Rz(yaw)·Ry(pitch)·Rx(roll)).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Pose {
    pub(crate) xyz: [f64; 3],
    pub(crate) rpy: [f64; 3],
}

/// A link's `<inertial>`: mass, the centre of mass and the axes of the inertia
/// tensor (`origin`), and the tensor about the centre of mass in those axes.
#[derive(Debug, Clone)]
pub(crate) struct Inertial {
    pub(crate) mass: f64,
    pub(crate) origin: Pose,
    pub(crate) tensor: [[f64; 3]; 3],
}

/// A `<link>`.
#[derive(Debug, Clone)]
pub(crate) struct Link {
    pub(crate) name: String,
    /// The element.
    pub(crate) span: Range<usize>,
    pub(crate) inertial: Option<Inertial>,
}

/// The joint types a URDF may name that lagrange reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum JointKind {
    /// One angle about the axis, within limits.
    Revolute,
    /// One angle about the axis, without limits.
    Continuous,
    /// One slide along the axis.
    Prismatic,
    /// No coordinate: the child is welded to the parent.
    Fixed,
    /// Six coordinates: three translations and three angles.
    Floating,
}

impl JointKind {
    pub(crate) fn word(self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
            JointKind::Fixed => "fixed",
            JointKind::Floating => "floating",
        }
    }
}

/// A `<joint>`.
#[derive(Debug, Clone)]
pub(crate) struct Joint {
    pub(crate) name: String,
    /// The element.
    pub(crate) span: Range<usize>,
    pub(crate) kind: JointKind,
    /// The parent link's name and where it is written.
    pub(crate) parent: (String, Range<usize>),
    /// The child link's name and where it is written.
    pub(crate) child: (String, Range<usize>),
    pub(crate) origin: Pose,
    /// The axis in the joint's frame, of length 1 (default x).
    pub(crate) axis: [f64; 3],
    /// What the joint says that carries no mechanics here (limits, mimic, ...), as phrases.
    pub(crate) ignored: Vec<String>,
}

/// A URDF file, read.
#[derive(Debug, Clone)]
pub(crate) struct Robot {
    pub(crate) name: String,
    pub(crate) links: Vec<Link>,
    pub(crate) joints: Vec<Joint>,
    /// Which tags were left out (visual, collision, transmission, ...), each once, in file order.
    pub(crate) ignored: Vec<String>,
}

/// Reads a URDF file's text.
pub(crate) fn read(text: &str) -> Result<Robot, ModelError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let pos = e.pos();
        let at = byte_offset(text, pos.row, pos.col);
        ModelError::at(at..(at + 1).min(text.len()).max(at), format!("this is not well-formed XML: {e}"))
            .with_help("a URDF file is XML: <robot name=\"...\"> with <link> and <joint> elements")
    })?;
    let root = doc.root_element();
    if !root.has_tag_name("robot") {
        return Err(ModelError::at(
            root.range(),
            format!("the root element is <{}>, not <robot>", root.tag_name().name()),
        )
        .with_help("a URDF file is <robot name=\"...\"> with <link> and <joint> elements"));
    }
    let name = root.attribute("name").unwrap_or("robot").to_string();
    let mut robot = Robot { name, links: Vec::new(), joints: Vec::new(), ignored: Vec::new() };
    for node in root.children().filter(|n| n.is_element()) {
        match node.tag_name().name() {
            "link" => robot.links.push(read_link(node, &mut robot.ignored)?),
            "joint" => robot.joints.push(read_joint(node)?),
            other => note(&mut robot.ignored, other),
        }
    }
    if robot.links.is_empty() {
        return Err(
            ModelError::at(root.range(), "the robot has no <link>").with_help("a URDF robot is links joined by joints")
        );
    }
    Ok(robot)
}

fn note(list: &mut Vec<String>, tag: &str) {
    let tag = format!("<{tag}>");
    if !list.contains(&tag) {
        list.push(tag);
    }
}

/// The byte offset of a 1-based row and column (in characters).
fn byte_offset(text: &str, row: u32, col: u32) -> usize {
    let line_start =
        if row <= 1 { 0 } else { text.match_indices('\n').nth(row as usize - 2).map_or(text.len(), |(i, _)| i + 1) };
    let line = &text[line_start..];
    line_start + line.char_indices().nth(col.saturating_sub(1) as usize).map_or(line.len(), |(i, _)| i)
}

/// A required attribute.
fn required<'a>(node: roxmltree::Node<'a, '_>, attr: &str) -> Result<(&'a str, Range<usize>), ModelError> {
    match node.attribute_node(attr) {
        Some(a) => Ok((a.value(), a.range_value())),
        None => Err(ModelError::at(tag_span(node), format!("<{}> has no `{attr}` attribute", node.tag_name().name()))),
    }
}

/// The opening tag's name, for pointing at an element.
fn tag_span(node: roxmltree::Node<'_, '_>) -> Range<usize> {
    let start = node.range().start;
    start..start + 1 + node.tag_name().name().len()
}

/// An attribute of numbers: `count` of them, finite.
fn numbers<const N: usize>(
    node: roxmltree::Node<'_, '_>,
    attr: &str,
    default: Option<[f64; N]>,
) -> Result<[f64; N], ModelError> {
    let Some(a) = node.attribute_node(attr) else {
        return default.ok_or_else(|| {
            ModelError::at(tag_span(node), format!("<{}> has no `{attr}` attribute", node.tag_name().name()))
        });
    };
    let span = a.range_value();
    let words: Vec<&str> = a.value().split_whitespace().collect();
    let what = if N == 1 { "a number".to_string() } else { format!("{N} numbers separated by spaces") };
    if words.len() != N {
        return Err(ModelError::at(
            span,
            format!("`{attr}` is \"{}\": expected {what}, found {}", a.value(), words.len()),
        ));
    }
    let mut out = [0.0; N];
    for (k, w) in words.iter().enumerate() {
        match w.parse::<f64>() {
            Ok(x) if x.is_finite() => out[k] = x,
            _ => {
                return Err(ModelError::at(
                    span,
                    format!("`{attr}` is \"{}\": '{w}' is not a finite number", a.value()),
                )
                .with_help(format!("expected {what}")))
            }
        }
    }
    Ok(out)
}

fn read_pose(node: roxmltree::Node<'_, '_>) -> Result<Pose, ModelError> {
    match child(node, "origin")? {
        None => Ok(Pose::default()),
        Some(o) => Ok(Pose { xyz: numbers(o, "xyz", Some([0.0; 3]))?, rpy: numbers(o, "rpy", Some([0.0; 3]))? }),
    }
}

/// The one child element of a name (two are an error).
fn child<'a, 'i>(node: roxmltree::Node<'a, 'i>, name: &str) -> Result<Option<roxmltree::Node<'a, 'i>>, ModelError> {
    let mut found = node.children().filter(|n| n.is_element() && n.has_tag_name(name));
    let first = found.next();
    if let Some(second) = found.next() {
        return Err(ModelError::at(tag_span(second), format!("<{}> has a second <{name}>", node.tag_name().name())));
    }
    Ok(first)
}

fn read_link(node: roxmltree::Node<'_, '_>, ignored: &mut Vec<String>) -> Result<Link, ModelError> {
    let (name, _) = required(node, "name")?;
    let mut inertial = None;
    for c in node.children().filter(|n| n.is_element()) {
        if c.tag_name().name() != "inertial" {
            note(ignored, c.tag_name().name());
        }
    }
    if let Some(i) = child(node, "inertial")? {
        let origin = read_pose(i)?;
        let mass_node =
            child(i, "mass")?.ok_or_else(|| ModelError::at(tag_span(i), "<inertial> has no <mass value=\"...\"/>"))?;
        let [mass] = numbers::<1>(mass_node, "value", None)?;
        if mass < 0.0 {
            let (_, span) = required(mass_node, "value")?;
            return Err(ModelError::at(span, format!("the mass is {mass}: expected a number ≥ 0")));
        }
        let t = child(i, "inertia")?.ok_or_else(|| {
            ModelError::at(tag_span(i), "<inertial> has no <inertia ixx=\"...\" ixy ixz iyy iyz izz/>")
        })?;
        let mut v = [0.0; 6];
        for (k, key) in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"].iter().enumerate() {
            [v[k]] = numbers::<1>(t, key, None)?;
        }
        let tensor = [[v[0], v[1], v[2]], [v[1], v[3], v[4]], [v[2], v[4], v[5]]];
        crate::model::check::physical(&tensor).map_err(|why| {
            ModelError::at(tag_span(t), format!("this inertia is not a rigid body's: {why}")).with_help(
                "about the centre of mass, principal moments are ≥ 0 and each is at most the sum of the other two",
            )
        })?;
        inertial = Some(Inertial { mass, origin, tensor });
    }
    Ok(Link { name: name.to_string(), span: tag_span(node), inertial })
}

fn read_joint(node: roxmltree::Node<'_, '_>) -> Result<Joint, ModelError> {
    let (name, _) = required(node, "name")?;
    let (kind_text, kind_span) = required(node, "type")?;
    let kind = match kind_text {
        "revolute" => JointKind::Revolute,
        "continuous" => JointKind::Continuous,
        "prismatic" => JointKind::Prismatic,
        "fixed" => JointKind::Fixed,
        "floating" => JointKind::Floating,
        "planar" => {
            return Err(ModelError::at(kind_span, format!("joint '{name}' is planar, which lagrange does not import"))
                .with_help("a planar joint is two slides and a turn: write it as two prismatic joints and a revolute joint, with a link of some mass between each"))
        }
        other => {
            return Err(ModelError::at(kind_span, format!("joint '{name}' has the unknown type '{other}'"))
                .with_help("a URDF joint is revolute, continuous, prismatic, fixed or floating"))
        }
    };
    let link = |tag: &str| -> Result<(String, Range<usize>), ModelError> {
        let c = child(node, tag)?
            .ok_or_else(|| ModelError::at(tag_span(node), format!("joint '{name}' has no <{tag} link=\"...\"/>")))?;
        let (l, span) = required(c, "link")?;
        Ok((l.to_string(), span))
    };
    let parent = link("parent")?;
    let child_link = link("child")?;
    let origin = read_pose(node)?;
    let mut axis = [1.0, 0.0, 0.0];
    if let Some(a) = child(node, "axis")? {
        let v = numbers::<3>(a, "xyz", Some(axis))?;
        // Scaled by the largest component first, so that no square overflows.
        let scale = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let moves = matches!(kind, JointKind::Revolute | JointKind::Continuous | JointKind::Prismatic);
        if moves && scale == 0.0 {
            let span = a.attribute_node("xyz").map_or(tag_span(a), |x| x.range_value());
            return Err(ModelError::at(span, format!("the axis of joint '{name}' has no direction (its length is 0)"))
                .with_help("give the axis as three numbers not all 0, e.g. xyz=\"0 0 1\""));
        }
        if scale > 0.0 {
            let u = v.map(|x| x / scale);
            let n = u.iter().map(|x| x * x).sum::<f64>().sqrt();
            axis = u.map(|x| x / n);
        }
    }
    let mut ignored = Vec::new();
    for c in node.children().filter(|n| n.is_element()) {
        let tag = c.tag_name().name();
        if matches!(tag, "parent" | "child" | "origin" | "axis") {
            continue;
        }
        let attrs: Vec<String> = c.attributes().map(|a| format!("{}={}", a.name(), a.value())).collect();
        ignored.push(if attrs.is_empty() { format!("<{tag}>") } else { format!("<{tag} {}>", attrs.join(" ")) });
    }
    Ok(Joint { name: name.to_string(), span: tag_span(node), kind, parent, child: child_link, origin, axis, ignored })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[track_caller]
    fn check_error(text: &str, at: &str, message: &str) {
        let err = read(text).expect_err("the file should be refused");
        let span = err.span.clone().expect("a place");
        assert!(text[span.start..].starts_with(at), "error at {:?}, expected at {at:?}: {}", &text[span], err.message);
        assert!(err.message.contains(message), "{}", err.message);
    }

    #[test]
    fn refusals_point_at_their_place() {
        check_error("<robot><link name=\"a\"", "", "not well-formed XML");
        check_error("<model/>", "<model", "not <robot>");
        check_error(r#"<robot><link name="a"/><joint name="j" type="ball"/></robot>"#, "ball", "unknown type 'ball'");
        check_error(
            r#"<robot><link name="a"><inertial><mass value="-1"/></inertial></link></robot>"#,
            "-1",
            "expected a number ≥ 0",
        );
        check_error(
            r#"<robot><link name="a"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="3"/></inertial></link></robot>"#,
            "<inertia",
            "exceeds the sum",
        );
        check_error(
            r#"<robot><link name="a"/><joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0"/></joint></robot>"#,
            "0 0\"",
            "expected 3 numbers",
        );
        check_error(
            r#"<robot><link name="a"/><joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 0"/></joint></robot>"#,
            "0 0 0",
            "no direction",
        );
        check_error(
            r#"<robot><link name="a"/><joint name="j" type="fixed"><parent link="a"/></joint></robot>"#,
            "<joint",
            "no <child",
        );
    }

    #[test]
    fn error_places_count_characters_per_line() {
        let text = "ab\nçd<x";
        assert_eq!(byte_offset(text, 2, 3), text.find("<x").unwrap());
        assert_eq!(byte_offset(text, 1, 1), 0);
    }
}
