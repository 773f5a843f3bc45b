//! How a run over ranks is split and what every rank solves with: the partition of the
//! vertices (`--partition`), the physics of the patches and the causality of the tents.

use sdg_distributed::{Causality, Partition, Physics};
use sdg_solver::patch::{Initial, Newton};

use crate::error::EngineError;
use crate::problem::Problem;

/// How the vertices are split among the ranks (`--partition`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PartitionKind {
    /// Recursive coordinate bisection weighted by work ([`partition_for`]): balanced, short cuts.
    #[default]
    Coordinate,
    /// METIS's k-way partition of the vertex graph weighted by work: fewest cut edges.
    Metis,
    /// Stripes along x of equal work.
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

/// The partition of `problem`'s mesh over `ranks` ranks of `kind`, each vertex weighted by its
/// work (its tents to the end time times its star size); one that cannot be made (more ranks
/// than vertices) is bad input.
pub fn partition_for(
    problem: &Problem,
    kind: PartitionKind,
    ranks: usize,
) -> Result<Partition, EngineError> {
    let mesh = &problem.mesh;
    let failed = |e: &dyn std::fmt::Display| {
        EngineError::Input(format!("{ranks} ranks, --partition {}: {e}", kind.name()))
    };
    let weights = || work_weights(problem).map_err(|e| failed(&e));
    match kind {
        PartitionKind::Coordinate => Partition::coordinate_weighted(mesh, ranks, &weights()?),
        PartitionKind::Metis => Partition::metis_weighted(mesh, ranks, &weights()?),
        PartitionKind::Stripes => Partition::striped_weighted(mesh, ranks, &weights()?),
        PartitionKind::Random => Partition::random(mesh, ranks, RANDOM_SEED),
    }
    .map_err(|e| failed(&e))
}

/// Most tents per vertex (on average) that [`work_weights`] pitches.
const WEIGHT_TENTS_PER_VERTEX: u64 = 32;

/// Mean vertex weight of [`work_weights`]: fine enough to split a mean vertex into 1%, small
/// enough that METIS's 32-bit sums hold 20 million vertices.
const MEAN_WEIGHT: f64 = 100.0;

/// Every vertex's work to the end time: its tents ([`crate::estimate::tents_per_vertex`] on
/// the initial mesh, least time first, at most [`WEIGHT_TENTS_PER_VERTEX`] tents a vertex on
/// average and [`crate::estimate::SAMPLE_TENTS`] in all, then extrapolated) times its star
/// size (a tent's patch elements), scaled to a mean of [`MEAN_WEIGHT`], at least 1. Tents per
/// vertex differ over a mesh (the left half of the 48 x 48 `plane_wave` pitches 9% more than
/// the right), so star sizes alone leave a rank with more work than the others. A function of the mesh and the pitcher only (no wall-time
/// limit), so that every rank computes the same partition.
fn work_weights(problem: &Problem) -> Result<Vec<u64>, sdg_mesh::PitchError> {
    let mesh = &problem.mesh;
    let c = causality(problem);
    let pitcher = sdg_mesh::Pitcher::new(mesh, c.c_max, c.safety, c.t_end)?;
    let n = mesh.vertices().len();
    let most = WEIGHT_TENTS_PER_VERTEX
        .saturating_mul(n as u64)
        .min(crate::estimate::SAMPLE_TENTS);
    let (tents, _, _) = crate::estimate::tents_per_vertex(mesh, &pitcher, most, f64::INFINITY);
    let work: Vec<f64> = (tents.iter().enumerate())
        .map(|(v, t)| t * mesh.vertex_triangles(v as u32).len() as f64)
        .collect();
    let mean = work.iter().sum::<f64>() / n.max(1) as f64;
    let scale = if mean > 0.0 { MEAN_WEIGHT / mean } else { 0.0 };
    Ok(work
        .iter()
        .map(|w| ((w * scale).round() as u64).max(1))
        .collect())
}

/// What every rank solves the patches of `problem` with, sampling the interface at the
/// points `probes` (m) and cutting no face by snapshot planes (`cut_times` empty).
pub fn physics<'a>(problem: &'a Problem, probes: &'a [[f64; 2]]) -> Physics<'a> {
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
        probes,
        cut_times: &[],
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::LoadedConfig;

    fn problem(name: &str, overrides: &[&str]) -> Problem {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../configs")
            .join(name);
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Problem::setup(LoadedConfig::load(&file, &overrides).expect("valid config"))
            .expect("valid problem")
    }

    /// The heaviest rank's work over the mean: work per vertex as `work_weights` estimates it,
    /// unrounded.
    fn work_imbalance(problem: &Problem, partition: &Partition) -> f64 {
        let mesh = &problem.mesh;
        let c = causality(problem);
        let pitcher = sdg_mesh::Pitcher::new(mesh, c.c_max, c.safety, c.t_end).unwrap();
        let (tents, _, _) =
            crate::estimate::tents_per_vertex(mesh, &pitcher, u64::MAX, f64::INFINITY);
        let mut sums = vec![0.0; partition.ranks()];
        for (v, t) in tents.iter().enumerate() {
            sums[partition.owner(v as u32) as usize] +=
                t * mesh.vertex_triangles(v as u32).len() as f64;
        }
        let total: f64 = sums.iter().sum();
        sums.iter().copied().fold(0.0, f64::max) * sums.len() as f64 / total
    }

    /// On the 48 x 48 `plane_wave` the left half pitches 9% more tents than the right, so star
    /// sizes leave the heaviest rank 2 to 5% over the mean; weighing the stars by their tents
    /// leaves at most 0.3% (coordinate, METIS and stripes; 2, 3, 4 and 8 ranks).
    #[test]
    fn work_weights_balance_the_tents_that_star_sizes_do_not() {
        let problem = problem("plane_wave.toml", &["mesh.nx=48", "mesh.ny=48"]);
        for ranks in [2, 3, 4, 8] {
            let stars = work_imbalance(
                &problem,
                &Partition::coordinate(&problem.mesh, ranks).unwrap(),
            );
            assert!(stars > 1.02, "{ranks} ranks: star sizes alone {stars}");
            for kind in [
                PartitionKind::Coordinate,
                PartitionKind::Metis,
                PartitionKind::Stripes,
            ] {
                let work = work_imbalance(&problem, &partition_for(&problem, kind, ranks).unwrap());
                assert!(work < 1.003, "{ranks} ranks, {}: {work}", kind.name());
            }
        }
    }

    /// The weights are the same on every call (every rank computes the partition alone).
    #[test]
    fn work_weights_depend_on_the_mesh_alone() {
        let problem = problem("crack_branching.toml", &[]);
        let first = work_weights(&problem).unwrap();
        assert_eq!(first, work_weights(&problem).unwrap());
        assert!(first.iter().all(|&w| w >= 1));
        let mean = first.iter().sum::<u64>() as f64 / first.len() as f64;
        assert!((mean - MEAN_WEIGHT).abs() < 1.0, "{mean}");
    }
}
