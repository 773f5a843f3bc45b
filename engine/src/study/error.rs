//! A study error: the study file, the key and why.

/// A bad study: refused before any case runs (exit code 2).
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{file}: {}{reason}", key.as_ref().map(|k| format!("{k}: ")).unwrap_or_default())]
pub struct StudyError {
    /// The study file.
    pub file: String,
    /// The study key (`base`, `metrics`, `axes."adapt.min_edge"`), when the error is one key's.
    pub key: Option<String>,
    /// What is wrong.
    pub reason: String,
}
