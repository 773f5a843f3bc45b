//! How a run over ranks is split and what every rank solves with: the partition of the
//! vertices (`--partition`), the physics of the patches and the causality of the tents.

use sdg_distributed::{Causality, Partition, Physics};
use sdg_solver::patch::{Initial, Newton};

use crate::error::EngineError;
use crate::problem::Problem;

/// How the vertices are split among the ranks (`--partition`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PartitionKind {
    /// Recursive coordinate bisection weighted by star size: balanced, short cuts.
    #[default]
    Coordinate,
    /// METIS's k-way partition of the vertex graph weighted by star size: fewest cut edges.
    Metis,
    /// Stripes along x of equal weight.
    Stripes,
    /// Seeded random owners (nearly every vertex on a rank boundary): for tests.
    Random,
}

impl PartitionKind {
    /// The name `--partition` and `summary.json` use.
    pub fn name(self) -> &'static str {
        match self {
            Self::Coordinate => "coordinate",
            Self::Metis => "metis",
            Self::Stripes => "stripes",
            Self::Random => "random",
        }
    }
}

/// The seed of `--partition random`: the same owners on every run.
const RANDOM_SEED: u64 = 1;

/// The partition of `mesh` over `ranks` ranks of `kind`; one that cannot be made (more ranks
/// than vertices) is bad input.
pub fn partition_for(
    mesh: &sdg_mesh::Mesh,
    kind: PartitionKind,
    ranks: usize,
) -> Result<Partition, EngineError> {
    match kind {
        PartitionKind::Coordinate => Partition::coordinate(mesh, ranks),
        PartitionKind::Metis => Partition::metis(mesh, ranks),
        PartitionKind::Stripes => Partition::striped(mesh, ranks),
        PartitionKind::Random => Partition::random(mesh, ranks, RANDOM_SEED),
    }
    .map_err(|e| EngineError::Input(format!("{ranks} ranks, --partition {}: {e}", kind.name())))
}

/// What every rank solves the patches of `problem` with.
pub fn physics(problem: &Problem) -> Physics<'_> {
    let config = &problem.loaded.config;
    Physics {
        system: &problem.system,
        order: config.solver.order,
        boundary: &problem.boundary,
        initial: problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave),
        interfaces: &problem.interfaces,
        newton: Newton {
            tol: config.solver.newton_tol,
            max_iter: config.solver.newton_max_iter,
        },
    }
}

/// What every rank pitches the tents of `problem` with.
pub fn causality(problem: &Problem) -> Causality {
    let config = &problem.loaded.config;
    Causality {
        c_max: problem.material.max_wave_speed(),
        safety: config.pitch.safety,
        t_end: config.time.span(),
    }
}
