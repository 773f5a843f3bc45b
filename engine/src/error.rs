//! Errors of a run, split by who must act: the user (bad input, exit code 2) or the operator
//! (a failure while running, exit code 1).

use std::path::PathBuf;

use crate::config::ConfigError;

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The mesh cannot be read or is not a valid triangulation.
    #[error("{0}")]
    Mesh(String),
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The run failed after it started.
    #[error("{0}")]
    Runtime(String),
}

impl EngineError {
    /// Process exit code: 2 for invalid input (config, mesh), 1 for a runtime failure.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Config(_) | Self::Mesh(_) => 2,
            Self::Io { .. } | Self::Runtime(_) => 1,
        }
    }

    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}
