//! The error of invalid law parameters.

/// Why law parameters are invalid: the parameter's name and the reason.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{key}: {reason}")]
pub struct LawError {
    /// The parameter, e.g. `friction`, `r_s` or `defect_mean`.
    pub key: &'static str,
    /// What is wrong.
    pub reason: String,
}
