//! The FMI 2.0 FMU of `lagrange export --to fmu`: one archive for Model
//! Exchange and Co-Simulation that FMPy, OpenModelica, Dymola or Simulink load.
//!
//! [`sources`] writes its two texts: the C source (the file [`to_c`](super::to_c)
//! writes, then the wrapper `fmi2.c`, which implements the standard's
//! functions over it and steps Co-Simulation with an embedded Dormand–Prince
//! 5(4)) and `modelDescription.xml`, whose value references follow the
//! wrapper's layout:
//!
//! | value references | variables |
//! |---|---|
//! | 0 … 2n−1 | the continuous states q, then q' (start: `[initial]`) |
//! | 2n … 4n−1 | their derivatives `der(q)` = q', `der(q')` = q'' |
//! | then P | the parameters, tunable (start: the model file's values) |
//! | then m | the inputs; unset, an input takes its expression in t |
//! | then 1 or 2 | the outputs h (the energy function) and E (T + U₀) |
//! | then 1 | `solver.tolerance`, Co-Simulation's relative and absolute tolerance |
//!
//! [`package`] compiles the source with the system's C compiler for this host
//! and zips the three files. A model with `[[constraints]]` is exported with
//! its constraints at acceleration level: the projection a run does after each
//! step is not in the FMU (Model Exchange would need it as events), so its
//! constraints drift as any index-reduced system's do.

use super::to_c;
use crate::derive::Derivation;
use crate::error::ModelError;
use sym::emit::{literal, Language};

/// The default of `solver.tolerance` (and of the model description's
/// DefaultExperiment tolerance, which FMPy passes to Co-Simulation).
pub const DEFAULT_TOLERANCE: f64 = 1e-8;

/// The wrapper appended to the model's C file.
const WRAPPER: &str = include_str!("fmi2.c");

/// The texts an FMU is made of.
#[derive(Debug, Clone)]
pub struct Sources {
    /// The model identifier: the C source's and the binary's name.
    pub identifier: String,
    /// The GUID the description and the binary share (a digest of both).
    pub guid: String,
    /// `modelDescription.xml`.
    pub model_description: String,
    /// `sources/IDENTIFIER.c`: the model's C file and the FMI wrapper.
    pub source: String,
}

/// A model identifier from a file name: a C identifier (FMI's rule for
/// `modelIdentifier`), other characters as `_`.
pub fn identifier(stem: &str) -> String {
    let mut id: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if !id.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
        id.insert(0, '_');
    }
    id
}

/// The FMU's source and model description (see the module comment), with
/// lagrange's `version` in both.
pub fn sources(d: &Derivation, version: &str, identifier: &str) -> Result<Sources, ModelError> {
    let model = d.model();
    let n = d.q.len();
    let c = to_c(d, version)?;
    let start = start_state(d);
    let names = d.coordinate_names();
    let taken = |name: &str| {
        names.contains(&name)
            || model.parameters.iter().any(|p| p.name == name)
            || model.inputs.iter().any(|u| u.name == name)
    };
    let output_name = |name: &str| if taken(name) { format!("output.{name}") } else { name.to_string() };
    let env = |name: &str| model.parameter(name);

    let mut variables = Vec::new();
    let states: Vec<String> = names.iter().map(|name| fmi_name("coordinate", name)).collect();
    for (i, (name, state)) in names.iter().zip(&states).enumerate() {
        variables.push(Variable::state(state, &format!("coordinate {name}"), start[i]));
    }
    for (i, (name, state)) in names.iter().zip(&states).enumerate() {
        variables.push(Variable::state(&format!("{state}'"), &format!("velocity of {name}"), start[n + i]));
    }
    for (i, state) in states.iter().enumerate() {
        variables.push(Variable::derivative(&format!("der({state})"), i + 1));
    }
    for (i, state) in states.iter().enumerate() {
        variables.push(Variable::derivative(&format!("der({state}')"), n + i + 1));
    }
    for p in &model.parameters {
        variables.push(Variable::parameter(&fmi_name("parameter", &p.name), "parameter", p.value));
    }
    for u in &model.inputs {
        let expression = d.pool().display(u.value.expr).to_string();
        // The start an importer may show or set: the expression at t = 0.
        let at_zero = d.pool().eval(u.value.expr, &|name: &str| if name == "t" { Some(0.0) } else { env(name) });
        let value = at_zero.ok().filter(|v| v.is_finite()).unwrap_or(0.0);
        variables.push(Variable {
            name: fmi_name("input", &u.name),
            description: format!("input {} (while never set: {expression})", u.name),
            attributes: "causality=\"input\" variability=\"continuous\"".into(),
            real: format!("<Real start=\"{}\"/>", number(value)),
        });
    }
    let outputs_start = variables.len();
    variables.push(Variable::output(&output_name("h"), "the energy function h = Σ q' ∂L/∂q' − L"));
    if d.energy.is_some() {
        variables.push(Variable::output(&output_name("E"), "the energy T + U₀"));
    }
    let outputs = outputs_start..variables.len();
    variables.push(Variable::parameter(
        "solver.tolerance",
        "relative and absolute tolerance of the Co-Simulation integrator",
        DEFAULT_TOLERANCE,
    ));

    let body = description(d, version, identifier, &variables, 2 * n, outputs.clone());
    let guid = guid(&[&c, &body]);
    let model_description = body.replace("@GUID@", &guid);
    let start: Vec<String> = start.iter().map(|&v| literal(Language::C, v)).collect();
    let wrapper = WRAPPER
        .replace("@GUID@", &guid)
        .replace("@HAS_ENERGY@", if d.energy.is_some() { "1" } else { "0" })
        .replace("@TOLERANCE@", &literal(Language::C, DEFAULT_TOLERANCE));
    let source = format!(
        "{c}\n/* ---- The FMI 2.0 wrapper (FMU {identifier}, GUID {guid}). ---- */\n\n\
         /* The continuous states' start values: [initial] of the model file. */\n\
         #define FMU_START_STATE {{{}}}\n\n{wrapper}",
        start.join(", ")
    );
    Ok(Sources { identifier: identifier.to_string(), guid, model_description, source })
}

/// The states' start values: `[initial]` at the parameters' values, 0 where
/// the file gives none (an importer sets them).
fn start_state(d: &Derivation) -> Vec<f64> {
    let model = d.model();
    let n = d.q.len();
    let mut start = vec![0.0; 2 * n];
    let env = |name: &str| model.parameter(name);
    for iv in &model.initial {
        if let Ok(v) = model.pool.eval(iv.value.expr, &env) {
            if v.is_finite() {
                start[usize::from(iv.order) * n + iv.coord] = v;
            }
        }
    }
    start
}

/// One `ScalarVariable` of the model description.
struct Variable {
    name: String,
    description: String,
    attributes: String,
    real: String,
}

impl Variable {
    fn state(name: &str, description: &str, start: f64) -> Variable {
        Variable {
            name: name.into(),
            description: description.into(),
            attributes: "causality=\"local\" variability=\"continuous\" initial=\"exact\"".into(),
            real: format!("<Real start=\"{}\"/>", number(start)),
        }
    }

    /// The derivative of the state at `index` (1-based, in the list of variables).
    fn derivative(name: &str, index: usize) -> Variable {
        Variable {
            name: name.into(),
            description: String::new(),
            attributes: "causality=\"local\" variability=\"continuous\"".into(),
            real: format!("<Real derivative=\"{index}\"/>"),
        }
    }

    fn parameter(name: &str, description: &str, start: f64) -> Variable {
        Variable {
            name: name.into(),
            description: description.into(),
            attributes: "causality=\"parameter\" variability=\"tunable\" initial=\"exact\"".into(),
            real: format!("<Real start=\"{}\"/>", number(start)),
        }
    }

    fn output(name: &str, description: &str) -> Variable {
        Variable {
            name: name.into(),
            description: description.into(),
            attributes: "causality=\"output\" variability=\"continuous\" initial=\"calculated\"".into(),
            real: "<Real/>".into(),
        }
    }
}

/// The FMU's name for the model's symbol `name`, a `kind` of symbol
/// ("coordinate", "parameter", "input"): the name itself, but for `time`, which
/// FMI tools take for the clock (FMPy's results and input signals have a column
/// `time`, and the coordinate's would be lost in it), so it is `coordinate.time`.
fn fmi_name(kind: &str, name: &str) -> String {
    if name == "time" {
        format!("{kind}.{name}")
    } else {
        name.to_string()
    }
}

/// `modelDescription.xml` with `@GUID@` for the GUID: the variables in
/// value-reference order, `derivatives` of them after the 2n states.
fn description(
    d: &Derivation,
    version: &str,
    identifier: &str,
    variables: &[Variable],
    states: usize,
    outputs: std::ops::Range<usize>,
) -> String {
    let model = d.model();
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let mut about = format!("equations of motion of {} written by lagrange {version}", model.name);
    if !d.constraints().list.is_empty() {
        about.push_str(
            "; the constraints are held at acceleration level only (no projection): they drift as any index-reduced system's do",
        );
    }
    x.push_str(&format!(
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{}\" guid=\"@GUID@\" description=\"{}\"\n  \
         generationTool=\"lagrange {}\" variableNamingConvention=\"flat\" numberOfEventIndicators=\"0\">\n",
        xml(&model.name),
        xml(&about),
        xml(version)
    ));
    x.push_str(&format!(
        "  <ModelExchange modelIdentifier=\"{identifier}\" canNotUseMemoryManagementFunctions=\"true\"/>\n  \
         <CoSimulation modelIdentifier=\"{identifier}\" canHandleVariableCommunicationStepSize=\"true\" canNotUseMemoryManagementFunctions=\"true\"/>\n"
    ));
    x.push_str(
        "  <LogCategories>\n    <Category name=\"logError\"/>\n    <Category name=\"logAll\"/>\n  </LogCategories>\n",
    );
    x.push_str(&format!(
        "  <DefaultExperiment startTime=\"0\" tolerance=\"{}\"/>\n  <ModelVariables>\n",
        number(DEFAULT_TOLERANCE)
    ));
    for (vr, v) in variables.iter().enumerate() {
        let description =
            if v.description.is_empty() { String::new() } else { format!(" description=\"{}\"", xml(&v.description)) };
        x.push_str(&format!(
            "    <!-- {} -->\n    <ScalarVariable name=\"{}\" valueReference=\"{vr}\"{description} {}>\n      {}\n    </ScalarVariable>\n",
            vr + 1,
            xml(&v.name),
            v.attributes,
            v.real
        ));
    }
    x.push_str("  </ModelVariables>\n  <ModelStructure>\n    <Outputs>\n");
    for i in outputs.clone() {
        x.push_str(&format!("      <Unknown index=\"{}\"/>\n", i + 1));
    }
    x.push_str("    </Outputs>\n    <Derivatives>\n");
    let derivatives = states..2 * states;
    for i in derivatives.clone() {
        x.push_str(&format!("      <Unknown index=\"{}\"/>\n", i + 1));
    }
    x.push_str("    </Derivatives>\n    <InitialUnknowns>\n");
    for i in derivatives.chain(outputs) {
        x.push_str(&format!("      <Unknown index=\"{}\"/>\n", i + 1));
    }
    x.push_str("    </InitialUnknowns>\n  </ModelStructure>\n</fmiModelDescription>\n");
    x
}

/// A finite number as an `xs:double`, by its shortest round-trip digits.
fn number(v: f64) -> String {
    format!("{v:?}")
}

/// Text as XML attribute content.
fn xml(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            c if (c as u32) < 0x20 => out.push_str(&format!("&#{};", c as u32)),
            c => out.push(c),
        }
    }
    out
}

/// A GUID in the standard's form from a digest of the texts: the same model
/// exported twice gets the same GUID, a changed one a new GUID.
fn guid(texts: &[&str]) -> String {
    use std::hash::{Hash, Hasher};
    let mut halves = [0u64; 2];
    for (salt, half) in halves.iter_mut().enumerate() {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        salt.hash(&mut h);
        texts.hash(&mut h);
        *half = h.finish();
    }
    let hex = format!("{:016x}{:016x}", halves[0], halves[1]);
    format!("{{{}-{}-{}-{}-{}}}", &hex[..8], &hex[8..12], &hex[12..16], &hex[16..20], &hex[20..])
}

/// Why [`package`] made no FMU.
#[derive(Debug, thiserror::Error)]
pub enum PackageError {
    /// This host is not one FMI 2.0 names a binary folder for.
    #[error("FMI 2.0 has no binary folder for this platform ({0}); the FMU is built for linux64 and darwin64")]
    Platform(String),
    /// The C compiler failed (its messages).
    #[error("the C compiler {compiler} failed on the FMU's source:\n{messages}")]
    Compile {
        /// The compiler run.
        compiler: String,
        /// What it printed.
        messages: String,
    },
    /// A file could not be written or read.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// The FMU archive: `modelDescription.xml`, `sources/ID.c` and the binary
/// `binaries/PLATFORM/ID.so` (`.dylib` on macOS) that `compiler` builds from
/// the source for this host (`-std=c99 -O2 -shared -fPIC`).
#[cfg(not(target_arch = "wasm32"))]
pub fn package(sources: &Sources, compiler: &std::path::Path) -> Result<Vec<u8>, PackageError> {
    use std::io::Write;
    let (platform, extension) = match (std::env::consts::OS, std::env::consts::ARCH) {
        ("linux", "x86_64" | "aarch64") => ("linux64", "so"),
        ("macos", _) => ("darwin64", "dylib"),
        (os, arch) => return Err(PackageError::Platform(format!("{os} {arch}"))),
    };
    let id = &sources.identifier;
    let dir = std::env::temp_dir().join(format!(
        "lagrange-fmu-{}-{}",
        std::process::id(),
        sources.guid.trim_matches(['{', '}'])
    ));
    std::fs::create_dir_all(&dir)?;
    let result = (|| {
        let c = dir.join(format!("{id}.c"));
        let binary = dir.join(format!("{id}.{extension}"));
        std::fs::write(&c, &sources.source)?;
        let run = std::process::Command::new(compiler)
            .args(["-std=c99", "-O2", "-shared", "-fPIC", "-o"])
            .arg(&binary)
            .arg(&c)
            .arg("-lm")
            .output()?;
        if !run.status.success() {
            return Err(PackageError::Compile {
                compiler: compiler.display().to_string(),
                messages: String::from_utf8_lossy(&run.stderr).into_owned(),
            });
        }
        let binary = std::fs::read(&binary)?;
        let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored)
            .unix_permissions(0o644);
        let zipped = |e: zip::result::ZipError| PackageError::Io(std::io::Error::other(e));
        zip.start_file("modelDescription.xml", options).map_err(zipped)?;
        zip.write_all(sources.model_description.as_bytes())?;
        zip.start_file(format!("sources/{id}.c"), options).map_err(zipped)?;
        zip.write_all(sources.source.as_bytes())?;
        zip.start_file(format!("binaries/{platform}/{id}.{extension}"), options.unix_permissions(0o755))
            .map_err(zipped)?;
        zip.write_all(&binary)?;
        Ok(zip.finish().map_err(zipped)?.into_inner())
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_are_c_identifiers() {
        assert_eq!(identifier("double_pendulum"), "double_pendulum");
        assert_eq!(identifier("cart-pendulum.v2"), "cart_pendulum_v2");
        assert_eq!(identifier("3body"), "_3body");
    }

    #[test]
    fn the_guid_is_a_digest_in_the_standard_s_form() {
        let a = guid(&["model", "description"]);
        assert_eq!(a, guid(&["model", "description"]));
        assert_ne!(a, guid(&["model", "description!"]));
        assert_eq!(a.len(), 38);
        assert!(a.starts_with('{') && a.ends_with('}'));
        assert_eq!(a.matches('-').count(), 4);
    }

    /// A symbol named `time` would be taken for the clock by FMI tools.
    #[test]
    fn a_symbol_named_time_is_not_the_fmus_time() {
        let d = crate::test_models::derive(
            "coordinates = [\"time\", \"y\"]\nlagrangian = \"m/2*(time'^2 + y'^2) - time^2 - time*y\"\n\
             [parameters]\nm = 1.0\n[initial]\ntime = 0.5\n",
        );
        let description = sources(&d, "0", "clock").expect("the FMU's sources").model_description;
        for name in
            ["coordinate.time", "coordinate.time'", "der(coordinate.time)", "der(coordinate.time')", "y", "der(y)"]
        {
            assert!(description.contains(&format!("name=\"{name}\"")), "no variable {name}:\n{description}");
        }
        assert!(!description.contains("name=\"time\""), "{description}");
        let d = crate::test_models::derive(
            "coordinates = [\"x\"]\nlagrangian = \"x'^2/2 - time*x^2/2\"\n[parameters]\ntime = 2.0\n[initial]\nx = 1.0\n",
        );
        let description = sources(&d, "0", "clock").expect("the FMU's sources").model_description;
        assert!(description.contains("name=\"parameter.time\""), "{description}");
        assert!(!description.contains("name=\"time\""), "{description}");
    }

    #[test]
    fn attribute_text_is_escaped() {
        assert_eq!(xml("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
    }
}
