//! What a call asks for besides the model's text, as the page sends it (JSON):
//! the CLI's `--set`, `--until`, `--rtol`, `--atol`, `--samples`, `--method`,
//! `--check-minimum`, `--points`, and the files a model names (body files),
//! which the page supplies since it has no file system.

use serde::Deserialize;
use std::collections::BTreeMap;

/// The options of every entry point; absent fields take the CLI's defaults.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Options {
    /// Parameter overrides (`--set name=value`).
    pub set: BTreeMap<String, f64>,
    /// End time of a run (`--until`; default 10).
    pub until: Option<f64>,
    /// Relative tolerance (`--rtol`).
    pub rtol: Option<f64>,
    /// Absolute tolerance (`--atol`; default `rtol`·10⁻³ when `rtol` is given).
    pub atol: Option<f64>,
    /// Rows of a run, both ends included (`--samples`).
    pub samples: Option<usize>,
    /// The integrator's name (`--method`).
    pub method: Option<String>,
    /// `extremal --check-minimum`.
    pub check_minimum: bool,
    /// `extremal --points` (default 201).
    pub points: Option<usize>,
    /// Files the model may name (body files), by their paths relative to
    /// one root (the page's: the examples folder).
    pub files: BTreeMap<String, String>,
    /// The model's folder among `files` ("" for the root): the names a model
    /// gives are relative to it, as the CLI reads them beside the model file.
    pub folder: String,
}

impl Options {
    /// Reads the options; empty text means the defaults.
    pub fn parse(text: &str) -> Result<Options, String> {
        if text.trim().is_empty() {
            return Ok(Options::default());
        }
        serde_json::from_str(text).map_err(|e| format!("bad options: {e}"))
    }

    /// The text of the file a model in [`Options::folder`] names `name`.
    pub fn file(&self, name: &str) -> Option<&String> {
        let mut path: Vec<&str> = Vec::new();
        for part in self.folder.split('/').chain(name.split('/')) {
            match part {
                "" | "." => {}
                ".." => {
                    path.pop()?;
                }
                part => path.push(part),
            }
        }
        self.files.get(&path.join("/"))
    }

    /// The overrides as `mech` takes them.
    pub fn overrides(&self) -> Vec<(String, f64)> {
        self.set.iter().map(|(k, v)| (k.clone(), *v)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_named_file_is_found_relative_to_the_models_folder() {
        let o = Options::parse(r#"{"folder": "tops", "files": {"tops/a.toml": "A", "b.toml": "B"}}"#).unwrap();
        assert_eq!(o.file("a.toml").map(String::as_str), Some("A"));
        assert_eq!(o.file("./a.toml").map(String::as_str), Some("A"));
        assert_eq!(o.file("../b.toml").map(String::as_str), Some("B"));
        assert_eq!(o.file("b.toml"), None);
        assert_eq!(o.file("../../b.toml"), None);
        assert!(Options::parse(r#"{"sett": {}}"#).is_err());
        assert_eq!(Options::parse("").unwrap().until, None);
    }
}
