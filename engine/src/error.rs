//! Errors of a run, split by who must act: the user (bad input, exit code 2) or the operator
//! (a failure while running, exit code 1).

use std::path::PathBuf;

use crate::config::ConfigError;
use crate::study::StudyError;

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The study file is invalid, or a case's config is.
    #[error(transparent)]
    Study(#[from] StudyError),
    /// The mesh file of `config` (its `mesh.path`) cannot be read or is not a valid
    /// triangulation.
    #[error("{}: mesh.path: {source}", config.display())]
    Mesh {
        /// The config file that names the mesh.
        config: PathBuf,
        /// What the mesh reader found, with the mesh file and line.
        source: sdg_mesh::GmshError,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// An output file (or the folder it goes in) could not be written: a full disk, a
    /// read-only file system, a folder removed under the running job. A file written before is
    /// left as it was (writes go through a temporary file and a rename).
    #[error("{}: cannot write: {source}", path.display())]
    Write {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// An input file other than the config and its mesh (a VTU file to plot) cannot be read,
    /// is not in a supported format or lacks what was asked for; the message names the file.
    #[error("{0}")]
    Input(String),
    /// The run failed after it started.
    #[error("{0}")]
    Runtime(String),
    /// A picture could not be drawn (data that cannot be plotted, an image too small).
    #[error("plot: {0}")]
    Plot(String),
    /// The run stopped before the end time after writing a checkpoint (a signal, the wall-time
    /// limit): `sdg run --restart` goes on from it.
    #[error(
        "{reason}: stopped at t = {time:e} s with checkpoint {}; resume with --restart",
        checkpoint.display()
    )]
    Checkpointed {
        /// Why the run stopped.
        reason: String,
        /// The front's least time, s.
        time: f64,
        /// The checkpoint file.
        checkpoint: PathBuf,
    },
    /// Cases of a study failed (each reported with the end of its log as it ended).
    #[error("{message}")]
    CasesFailed {
        /// Which cases and how.
        message: String,
        /// The exit code: that of the only case run (`sdg study --case K`), else 1.
        code: u8,
    },
}

impl EngineError {
    /// Process exit code: 2 for invalid input (config, study, mesh, input file, a checkpoint
    /// that cannot be restarted from), 1 for a runtime failure, 3 for a run checkpointed and
    /// stopped ("resubmit me"); a study's failed cases: that of `sdg study --case K`'s case.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Config(_) | Self::Study(_) | Self::Mesh { .. } | Self::Input(_) => 2,
            Self::Io { .. } | Self::Write { .. } | Self::Runtime(_) | Self::Plot(_) => 1,
            Self::Checkpointed { .. } => 3,
            Self::CasesFailed { code, .. } => *code,
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

/// A scheduler failure as an engine error.
pub(crate) fn scheduler_error(e: sdg_scheduler::RunError<EngineError>) -> EngineError {
    match e {
        sdg_scheduler::RunError::Work(e) => e,
        stalled => EngineError::Runtime(stalled.to_string()),
    }
}
