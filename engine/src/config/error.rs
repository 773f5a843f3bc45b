//! A configuration error: where it came from, which key, and why.

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
