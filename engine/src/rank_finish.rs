//! The end of a run over ranks: rank 0 merges the ranks' tallies of their tents (module
//! `rank_tally`) into `summary.json` (with the state hash of the gathered elements, energies,
//! Newton counts, the partition's traffic), writes `history.csv` from the merged tallies and
//! history sums, and `crack_tips.csv` and
//! `interface.csv` from their crack-tracking crossings and probe samples (neither file depends
//! on the order they come in).

use std::path::{Path, PathBuf};
use std::time::Instant;

use sdg_distributed::{Gathered, RankReport};
use sdg_mesh::Front;
use sdg_solver::element::FrontSolution;
use sdg_solver::norms::{FrontEnergy, front_energy, slice_errors};
use sdg_solver::patch::{Initial, PatchSolver};

use crate::error::EngineError;
use crate::output::write_output;
use crate::problem::Problem;
use crate::rank_outputs::{self, history_csv, merged};
use crate::rank_prior::Prior;
use crate::rank_setup::PartitionKind;
use crate::rank_tally::Tally;
use crate::solve::context::initial_state;
use crate::solve::outputs::{crack_tips, lefm, write_crack_tips, write_probes};
use crate::solve::summary::state_hash;
use crate::solve::tent::momentum_residual;
use crate::solve::{
    CheckpointSummary, DistributedSummary, EnergySummary, ErrorSummary, InterfaceSummary,
    RankSummary, RunSummary, Timings,
};

/// How a run over ranks ended, for [`finish`]: on the `partition` with the `gathered`
/// results since the (re)start after the `prior`, the snapshots rank 0 wrote (time in s, file
/// name), its wall time since the (re)start (s), and the checkpoints written (count, seconds).
pub(crate) struct End<'a> {
    pub(crate) partition: PartitionKind,
    pub(crate) gathered: &'a Gathered,
    pub(crate) snapshots: Vec<(f64, String)>,
    pub(crate) prior: &'a Prior,
    pub(crate) wall_time_s: f64,
    pub(crate) checkpoints: (u64, f64),
    /// `summary.json`'s `mode`.
    pub(crate) mode: &'static str,
    /// Threads that solved each rank's tents.
    pub(crate) threads: usize,
}

/// The energy of the initial front of `problem` (scaled units), integrated on `threads`
/// threads.
pub(crate) fn initial_energy(problem: &Problem, threads: usize) -> FrontEnergy {
    let mesh = &problem.mesh;
    let solver = PatchSolver::new(
        problem.system.clone(),
        problem.loaded.config.solver.order,
        0,
    );
    let initial_front = Front::flat(mesh.vertices().len(), 0.0);
    let empty = FrontSolution::new(mesh.triangles().len(), solver.basis().len(), solver.width());
    energy_on(problem, &initial_front, &empty, threads)
}

/// Writes the outputs of a run over ranks that ended as `end` and its `summary.json` into
/// `dir`, with the `estimate` made before. Returns the summary and the folder.
pub(crate) fn finish(
    problem: &Problem,
    dir: &Path,
    end: End<'_>,
    estimate: crate::estimate::Estimate,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let config = &problem.loaded.config;
    let finishing = Instant::now();
    let gathered = end.gathered;
    let (front, solution) = (&gathered.front, &gathered.solution);
    let outputs: Vec<&[f64]> = gathered.reports.iter().map(|r| &r.outputs[..]).collect();
    let times = crate::solve::book::history_times(config.time.span());
    let (sums, tally, rests) = merged(&outputs, &times)?;
    let ranks = gathered.reports.len();
    let wall_time_s = end.prior.wall_time_s + end.wall_time_s;
    tracing::info!(patches = tally.tents(), wall_time_s, "solve finished");
    let initial_energy = initial_energy(problem, ranks);
    let energy = energy_on(problem, front, solution, ranks);
    let mut summary = summarize(
        problem,
        (front, solution),
        (end.prior, &tally),
        &gathered.reports,
        (initial_energy, &energy),
        estimate,
    );
    summary.wall_time_s = wall_time_s;
    summary.mode = end.mode;
    summary.threads = ranks * end.threads;
    summary.patches_per_second = tally.tents() as f64 / end.wall_time_s.max(f64::MIN_POSITIVE);
    summary.distributed = Some(distributed_summary(end.partition, gathered));
    summary.snapshots = end.snapshots;
    summary.checkpoint = end.prior.summary(end.checkpoints.0, end.checkpoints.1);
    let mut records = end.prior.records.clone();
    for rest in rests {
        records.append(rank_outputs::records(rest)?.0);
    }
    let history = history_csv(
        problem,
        end.prior,
        &tally,
        &sums,
        (&initial_energy, front, Some(&energy)),
    )?;
    let (crack_csv, crack) = crack_tips(problem, &problem.mesh, &records.crossings, &[]).unzip();
    summary.lefm = lefm(problem, crack_csv.as_deref(), &history);
    summary.crack = crack;
    let mut written = vec![write_output(dir, "history.csv", history.as_bytes()).map(drop)];
    if config.output.png {
        crate::plot::write_history_png(dir, &history);
        draw_snapshots(dir, &summary.snapshots);
    }
    if let Some(csv) = crack_csv {
        written.push(write_crack_tips(problem, dir, &csv));
    }
    written.push(write_probes(problem, dir, &mut records.samples));
    crate::solve::finish::write_summary(dir, written, summary, finishing)
}

/// Draws each snapshot of `snapshots` (time in s, file name) written as pieces
/// (`snapshot_NNNN.pvtu`) that has no picture yet into `snapshot_NNNN.png` from its pieces, as
/// the run on threads draws it when it writes the snapshot. A picture that cannot be drawn does
/// not end the run: a warning names it.
fn draw_snapshots(dir: &Path, snapshots: &[(f64, String)]) {
    for (time, name) in snapshots {
        let Some(stem) = name.strip_suffix(".pvtu") else {
            continue;
        };
        if dir.join(format!("{stem}.png")).exists() {
            continue;
        }
        if let Err(e) = crate::output::snapshot::draw_pieces_png(dir, name, *time) {
            tracing::warn!("{stem}.png: {e}");
        }
    }
}

/// The energy on `front` with the elements of `solution` (initial data where there is none),
/// scaled units, integrated on `threads` threads.
fn energy_on(
    problem: &Problem,
    front: &Front,
    solution: &FrontSolution,
    threads: usize,
) -> FrontEnergy {
    let solver = PatchSolver::new(
        problem.system.clone(),
        problem.loaded.config.solver.order,
        0,
    );
    let initial = problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave);
    front_energy(
        &problem.mesh,
        front,
        solution,
        solver.basis(),
        &problem.system,
        threads,
        |x| initial_state(problem, initial, x),
    )
}

/// The summary of a run that left `front` and `solution` (with the energy `e` on it) after
/// the tents of `tally` from the `energy0` of the initial front, with the `estimate` made
/// before; the wall time is the caller's to fill in. (The ranks stop at a patch with a
/// non-finite value, so the tally holds none.)
fn summarize(
    problem: &Problem,
    (front, solution): (&Front, &FrontSolution),
    (prior, tally): (&Prior, &Tally),
    ranks: &[RankReport],
    (energy0, e): (FrontEnergy, &FrontEnergy),
    estimate: crate::estimate::Estimate,
) -> RunSummary {
    let config = &problem.loaded.config;
    let mesh = &problem.mesh;
    let system = &problem.system;
    let rho = problem.material.density();
    let t_end = config.time.span();
    let solver = PatchSolver::new(system.clone(), config.solver.order, 0);
    let (basis, width) = (solver.basis(), solver.width());
    let threads = ranks.len();
    let totals = tally.totals(&prior.totals);
    let c_max = problem.material.max_wave_speed();
    let slope = (prior.max_slope_ratio / c_max).max(tally.slope());
    let (nonlinear, newton, newton_max) = tally.newton();
    let (nonlinear, newton) = (prior.nonlinear + nonlinear, prior.newton + newton);
    let newton_max = prior.newton_max.max(newton_max);
    let (elements, dofs) = tally.elements_and_dofs();
    let (elements, dofs) = (prior.elements + elements, prior.dofs + dofs);
    let [assembly_s, solve_s, evaluation_s] = tally.timings();
    let timings = Timings {
        assembly_s,
        solve_s,
        evaluation_s,
        waiting_s: ranks.iter().map(|r| r.waited.as_secs_f64()).sum(),
        ..Timings::default()
    };
    let count = prior.patches + tally.tents();
    let error = problem.exact.as_ref().map(|w| {
        let e = slice_errors(mesh, solution, basis, system, t_end, w);
        ErrorSummary {
            velocity_l2_rel: e.velocity,
            stress_l2_rel: e.stress,
        }
    });
    let (min_edge, max_edge) = mesh.edge_length_range();
    RunSummary {
        command: "run",
        config_file: problem.loaded.file.clone(),
        overrides: problem.loaded.overrides.clone(),
        vertices: mesh.vertices().len(),
        triangles: mesh.triangles().len(),
        order: config.solver.order,
        patches: count,
        elements,
        dofs_per_patch: dofs as f64 / count.max(1) as f64,
        final_time: config.time.clock(front.min_time()),
        max_slope_ratio: c_max * slope,
        max_momentum_residual: momentum_residual(&totals),
        mode: "asynchronous",
        state_hash: state_hash(front, solution, basis.len() * width),
        wall_time_s: 0.0,
        patches_per_second: 0.0,
        threads,
        ranks: threads,
        distributed: None,
        peak_memory_bytes: crate::estimate::peak_resident_bytes(),
        estimate,
        energy: EnergySummary::new(rho, energy0.total, e, &totals),
        interface: InterfaceSummary {
            nonlinear_patches: nonlinear,
            newton_iterations_mean: newton as f64 / nonlinear.max(1) as f64,
            newton_iterations_max: newton_max,
        },
        loading: problem.loading,
        lefm: None,
        crack: None,
        fracture: None,
        error,
        snapshots: Vec::new(),
        refinements: 0,
        rejected_patches: 0,
        unresolved_patches: 0,
        unresolved_max: 0.0,
        coarsenings: 0,
        events: 0,
        rounds: 0,
        min_edge,
        max_edge,
        checkpoint: CheckpointSummary::default(),
        timings,
    }
}

/// `distributed` of `summary.json`.
fn distributed_summary(partition: PartitionKind, gathered: &Gathered) -> DistributedSummary {
    let reports = &gathered.reports;
    let tents: u64 = gathered.tents_by_rank.iter().sum();
    let per_tent = |x: u64| x as f64 / tents.max(1) as f64;
    DistributedSummary {
        partition: partition.name(),
        boundary_vertices: reports.iter().map(|r| r.boundary_vertices).sum(),
        updates_per_tent: per_tent(reports.iter().map(|r| r.updates_sent).sum()),
        bytes_per_tent: per_tent(reports.iter().map(|r| r.update_bytes).sum()),
        waited_s: reports.iter().map(|r| r.waited.as_secs_f64()).sum(),
        per_rank: (reports.iter().zip(&gathered.tents_by_rank))
            .map(|(r, &tents)| RankSummary {
                tents,
                boundary_vertices: r.boundary_vertices,
                updates_sent: r.updates_sent,
                update_bytes: r.update_bytes,
                waited_s: r.waited.as_secs_f64(),
            })
            .collect(),
    }
}
