//! The complete configuration of a run: one section per table.

use serde::{Deserialize, Serialize};

use super::conditions::{BoundaryConfig, ExactConfig};
use super::fracture::FractureConfig;
use super::interface::InterfaceConfig;
use super::loading::LoadingConfig;
use super::material::MaterialConfig;
use super::mesh::MeshConfig;
use super::settings::{
    AdaptConfig, CheckpointConfig, LimitsConfig, OutputConfig, PitchConfig, SchedulerConfig,
    SolverConfig, TimeConfig,
};

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
    /// tag of the mesh must be named by one entry. Read apart from the other keys
    /// ([`Config::parse`], [`super::LoadedConfig::load`]) so that errors name the key inside an
    /// entry.
    #[serde(default, skip_deserializing, skip_serializing_if = "Vec::is_empty")]
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
