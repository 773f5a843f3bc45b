//! The command line's side of `sdg run --ranks N` and `sdg run --mpi`.

use std::path::Path;

use sdg_engine::{EngineError, PartitionKind, Problem, RunOptions, RunSummary};

/// `--partition`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum PartitionArg {
    /// Recursive coordinate bisection weighted by work (tents times star size).
    Coordinate,
    /// METIS's k-way partition of the vertex graph weighted by work (fewest cut edges).
    Metis,
    /// Stripes along x of equal work.
    Stripes,
    /// Seeded random owners (for tests: nearly every vertex on a rank boundary).
    Random,
}

impl PartitionArg {
    /// The engine's partition kind.
    pub(crate) fn kind(self) -> PartitionKind {
        match self {
            Self::Coordinate => PartitionKind::Coordinate,
            Self::Metis => PartitionKind::Metis,
            Self::Stripes => PartitionKind::Stripes,
            Self::Random => PartitionKind::Random,
        }
    }
}

/// The number of processes of the MPI job this process is part of, as the launcher tells it
/// (OpenMPI's `mpirun`, or a PMI launcher such as Slurm's `srun`); `None` outside one.
pub(crate) fn mpi_processes() -> Option<usize> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"]
        .iter()
        .find_map(|name| std::env::var(name).ok()?.parse().ok())
}

/// `sdg run --mpi` on this process: the summary and output folder on rank 0, `None` on the
/// other ranks.
#[cfg(feature = "mpi")]
pub(crate) fn solve_mpi(
    problem: &Problem,
    options: &RunOptions,
    partition: PartitionKind,
) -> Result<Option<(RunSummary, std::path::PathBuf)>, EngineError> {
    sdg_engine::solve_mpi(problem, options, partition)
}

/// `sdg run --mpi` in a build without the cargo feature `mpi`: bad input, saying how to build.
#[cfg(not(feature = "mpi"))]
pub(crate) fn solve_mpi(
    _: &Problem,
    _: &RunOptions,
    _: PartitionKind,
) -> Result<Option<(RunSummary, std::path::PathBuf)>, EngineError> {
    Err(EngineError::Input(
        "--mpi: this sdg was built without MPI; build it with the cargo feature mpi (cargo \
         build --release --features mpi, which needs OpenMPI and libclang) and start it with \
         mpirun -n N sdg run CONFIG --mpi"
            .into(),
    ))
}

/// The line of totals of a run over ranks that wrote `summary` into `dir`.
pub(crate) fn totals(summary: &RunSummary, partition: PartitionKind, dir: &Path) -> String {
    format!(
        "{} patches (order {}) to t = {:e} s in {:.3} s on {} ranks of {} threads ({} \
         partition); energy balance residual {:.1e}; outputs in {}",
        summary.patches,
        summary.order,
        summary.final_time,
        summary.wall_time_s,
        summary.ranks,
        summary.threads / summary.ranks.max(1),
        partition.name(),
        summary.energy.balance_residual_rel,
        dir.display()
    )
}
