//! URDF robots as model files: `lagrange import robot.urdf` writes the model,
//! and a model file may name a URDF file with `urdf = "robot.urdf"` to take its
//! coordinates and bodies from it.
//!
//! Entry: [`urdf_to_model`], the URDF's text in and a model file's text out.
//! A model naming a URDF is read by `urdf/named.rs` from `Model::parse_with`.
//! Three steps, one file each: `urdf/xml.rs` reads the XML (roxmltree, so every
//! error has its place in the URDF file), `urdf/tree.rs` turns the link tree
//! into bodies (fixed rotations carried into axes and inertias, fixed joints
//! merged), and `urdf/write.rs` writes the model, commented.

pub(crate) mod named;
mod tree;
mod write;
mod xml;

use crate::error::ModelError;

/// How to read a URDF robot.
#[derive(Debug, Clone, Default)]
pub struct UrdfConfig {
    /// Give the root link six coordinates (x, y, z, roll, pitch, yaw): a robot
    /// whose URDF does not attach it to the world by a floating joint, such as
    /// a humanoid. Without it the root link is fixed to the world.
    pub floating_base: bool,
}

/// The model file of a URDF robot. `urdf` is the URDF file's text and
/// `source` its name, for the header comment; errors point into `urdf`.
pub fn urdf_to_model(urdf: &str, source: &str, config: &UrdfConfig) -> Result<String, ModelError> {
    if urdf.len() > crate::source::MAX_FILE_BYTES {
        return Err(ModelError::whole(format!(
            "the URDF file is {} bytes; the limit is {}",
            urdf.len(),
            crate::source::MAX_FILE_BYTES
        )));
    }
    let robot = xml::read(urdf)?;
    let plan = tree::plan(&robot, config.floating_base)?;
    Ok(write::model_text(&plan, source))
}
