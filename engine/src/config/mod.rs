//! The TOML run configuration: schema, command-line overrides and load-time validation.
//!
//! Every key is documented in `docs/config.md`. Units are SI. Unknown keys, wrong types and
//! unphysical values are rejected with an error naming the file and the key.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

mod conditions;
mod fracture;
mod loading;
mod material;
mod mesh;
mod overrides;
mod settings;
mod validate;

pub use conditions::{
    BoundaryConfig, BoundaryKind, ExactConfig, ExactKind, HistoryConfig, HistoryKind,
    InterfaceConfig, LawName, ProfileName, WaveName,
};
pub use fracture::FractureConfig;
pub use loading::{LoadScales, LoadingConfig};
pub use material::{MaterialConfig, PlaneName};
pub(crate) use mesh::rectangle_key;
pub use mesh::{DiagonalName, MeshConfig, MeshKind, SegmentConfig};
pub use settings::{
    AdaptConfig, CheckpointConfig, LimitsConfig, OutputConfig, PitchConfig, SchedulerConfig,
    SolverConfig, TimeConfig, VtuFormat, ZoneConfig,
};

pub use overrides::attribute;
use overrides::{apply_override, attribute_added};

/// A configuration error: where it came from, which key, and why.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{file}: {}{reason}", key.as_ref().map(|k| format!("{k}: ")).unwrap_or_default())]
pub struct ConfigError {
    /// The config file, or `--set KEY=VALUE` for an override.
    pub file: String,
    /// Dotted key path, when the error belongs to one key.
    pub key: Option<String>,
    /// What is wrong.
    pub reason: String,
}

/// The complete configuration of a run.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The space mesh at the initial time.
    pub mesh: MeshConfig,
    /// The bulk material.
    pub material: MaterialConfig,
    /// Time span.
    pub time: TimeConfig,
    /// Tent pitching.
    #[serde(default)]
    pub pitch: PitchConfig,
    /// Outputs.
    #[serde(default)]
    pub output: OutputConfig,
    /// The patch solver.
    #[serde(default)]
    pub solver: SolverConfig,
    /// Parallel execution.
    #[serde(default)]
    pub scheduler: SchedulerConfig,
    /// Adaptive refinement of the front.
    #[serde(default)]
    pub adapt: AdaptConfig,
    /// The most a run may cost: checked against its estimate before any work.
    #[serde(default)]
    pub limits: LimitsConfig,
    /// When the run saves its state for a restart.
    #[serde(default)]
    pub checkpoint: CheckpointConfig,
    /// Boundary conditions, one entry per group of sides (`[[boundary]]`). Every boundary tag
    /// of the mesh must be named by one entry.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub boundary: Vec<BoundaryConfig>,
    /// Interface laws, one entry per group of interface tags (`[[interface]]`). Every interface
    /// tag of the mesh must be named by one entry.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub interface: Vec<InterfaceConfig>,
    /// A mode-I load given by its load ratio: transmitting conditions on its sides.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loading: Option<LoadingConfig>,
    /// Crack propagation from the tips of existing cracks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fracture: Option<FractureConfig>,
    /// An exact solution: initial data, `exact` boundaries and the error at the end time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exact: Option<ExactConfig>,
}

/// A loaded, validated configuration and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedConfig {
    /// The validated configuration with overrides applied.
    pub config: Config,
    /// The config file.
    pub file: PathBuf,
}

impl LoadedConfig {
    /// Reads `file`, applies `overrides` (`key.path=value`, in order) and validates.
    pub fn load(file: &Path, overrides: &[String]) -> Result<Self, ConfigError> {
        let source = file.display().to_string();
        let text = std::fs::read_to_string(file).map_err(|e| ConfigError {
            file: source.clone(),
            key: None,
            reason: format!("cannot read: {e}"),
        })?;
        let config = Config::parse(&text, &source, overrides)?;
        Ok(Self {
            config,
            file: file.to_path_buf(),
        })
    }

    /// Resolves a path given in the config relative to the config file's folder.
    pub fn resolve(&self, path: &Path) -> PathBuf {
        match self.file.parent() {
            Some(dir) if path.is_relative() => dir.join(path),
            _ => path.to_path_buf(),
        }
    }
}

impl Config {
    /// Parses TOML `text` (named `source` in errors), applies `overrides` and validates.
    pub fn parse(text: &str, source: &str, overrides: &[String]) -> Result<Self, ConfigError> {
        let table: toml::Table = toml::from_str(text).map_err(|e| ConfigError {
            file: source.to_string(),
            key: None,
            reason: format!("invalid TOML: {}", e.message())
                .trim_end()
                .to_string()
                + &line_of(text, e.span()),
        })?;
        let mut root = toml::Value::Table(table);
        let mut added = Vec::new();
        for spec in overrides {
            if let Some(path) = apply_override(&mut root, spec)? {
                added.push((spec.as_str(), path));
            }
        }
        let config: Config = serde_path_to_error::deserialize(root).map_err(|e| {
            let path = e.path().to_string();
            let error = ConfigError {
                file: source.to_string(),
                key: (path != ".").then_some(path),
                reason: e.into_inner().message().to_string(),
            };
            attribute_added(attribute(error, overrides), &added)
        })?;
        config.validate().map_err(|(key, reason)| {
            let error = ConfigError {
                file: source.to_string(),
                key: Some(key),
                reason,
            };
            attribute_added(attribute(error, overrides), &added)
        })?;
        Ok(config)
    }
}

/// ` (line N)` for a TOML error span, or nothing.
fn line_of(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    span.map(|s| {
        let line = text[..s.start.min(text.len())].matches('\n').count() + 1;
        format!(" (line {line})")
    })
    .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) const BASE: &str = r#"
[mesh]
kind = "rectangle"
width = 0.016
height = 0.01
nx = 16
ny = 10

[material]
young = 3.24e9
poisson = 0.35
density = 1190.0
plane = "strain"

[time]
end = 1e-6
"#;

    pub(super) fn parse(text: &str, overrides: &[&str]) -> Result<Config, ConfigError> {
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Config::parse(text, "test.toml", &o)
    }

    /// Two interface segments and a contact law on one of them.
    pub(super) const INTERFACES: &str = r#"
[[mesh.interface]]
from = [0.0, 0.005]
to = [0.004, 0.005]
tag = "crack"

[[mesh.interface]]
from = [0.008, 0.0]
to = [0.008, 0.004]
tag = "joint"

[[interface]]
tags = ["crack"]
law = "contact"
friction = 0.25
r_c = -1e-6
r_s = 0.0
s_c = 0.0
s_s = 6e5

[[interface]]
tags = ["joint"]
law = "free"
"#;

    #[test]
    fn syntax_errors_give_the_line() {
        let e = parse(&format!("{BASE}\n[time\n"), &[]).unwrap_err();
        assert!(e.reason.contains("line 18"), "{e}");
        assert_eq!(e.to_string().split(':').next(), Some("test.toml"));
    }
}
