//! Reading a configuration: the file, the command line's overrides, and validation.

use std::path::{Path, PathBuf};

use super::error::ConfigError;
use super::overrides::{apply_override, attribute, attribute_added};
use super::schema::Config;

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
