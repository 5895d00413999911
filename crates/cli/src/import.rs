//! `lagrange import`: a URDF robot written as a model file (one body per
//! moving joint, fixed joints merged, what has no mechanics left out with a
//! comment). The conversion is `mech::urdf_to_model`; this module reads the
//! URDF and writes the model, to `-o FILE` or stdout.

use crate::diagnostics::Failure;
use std::path::PathBuf;

/// Options of `import`.
#[derive(clap::Args)]
pub struct Args {
    /// The URDF file (XML): links with <inertial>, joints revolute, continuous, prismatic, fixed or floating.
    pub urdf: PathBuf,
    /// Write the model file here (default: stdout).
    #[arg(short = 'o', long = "out", value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    /// Give the root link six coordinates (x, y, z, roll, pitch, yaw): a robot not fixed to the world, such as a humanoid.
    #[arg(long)]
    pub floating_base: bool,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    let path = &args.urdf;
    let source = crate::read_source(path)?;
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    let config = mech::UrdfConfig { floating_base: args.floating_base };
    let text = mech::urdf_to_model(&source, &name, &config).map_err(|e| Failure::model(path, &source, e))?;
    match &args.out {
        None => crate::write_stdout(&text),
        Some(out) => {
            crate::files::refuse_overwrite(&[path], &[Some(out)]).map_err(Failure::usage)?;
            crate::files::write_whole(out, text.as_bytes())
                .map_err(|e| Failure::run(format!("cannot write the model {}: {e}", out.display())))
        }
    }
}
