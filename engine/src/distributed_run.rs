//! `sdg run --ranks N` and `sdg run --mpi`: one front split over N ranks, each a thread of
//! this process connected to the others by the in-process transport
//! (`sdg_distributed::Loopback`), or each an MPI process (`MpiTransport`, cargo feature `mpi`),
//! with the same tents, elements and interface states as a run on threads.
//!
//! Each rank pitches and solves the tents at the vertices it owns
//! ([`sdg_distributed::solve_rank_observed`]), writing its pieces of the snapshots and summing
//! the history's energies as it goes (module `rank_outputs`); at the end the elements are
//! gathered on rank 0 ([`sdg_distributed::gathering`]), each from the rank owning its
//! triangle's first corner (an interface face from the owner of its edge's first end), and rank
//! 0 writes `summary.json` with the state hash and energy totals summed in the serial order of
//! the tents, and `history.csv`.
//!
//! What cannot be honoured yet is refused as bad input (exit 2), naming the key and why:
//! mesh-changing events (`[adapt]`, `[fracture]`), deterministic rounds, checkpoints and
//! restarts, `--trace`, interface probes and the spacetime mesh.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use sdg_distributed::{
    Causality, Gathered, LoopbackOptions, Options, Partition, Physics, RankReport, SolvedPatch,
};
use sdg_mesh::Front;
use sdg_solver::element::FrontSolution;
use sdg_solver::norms::{FrontEnergy, front_energy, slice_errors};
use sdg_solver::patch::{Initial, Newton, PatchReport, PatchSolver};

use crate::error::EngineError;
use crate::job::RunOptions;
use crate::output::write_output;
use crate::problem::Problem;
use crate::rank_outputs::{RankOutputs, history_csv};
use crate::solve::context::initial_state;
use crate::solve::start::Start;
use crate::solve::summary::state_hash;
use crate::solve::tent::momentum_residual;
use crate::solve::{
    CheckpointSummary, DistributedSummary, EnergySummary, ErrorSummary, InterfaceSummary,
    RunSummary, Timings,
};

/// How the vertices are split among the ranks (`--partition`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PartitionKind {
    /// Recursive coordinate bisection weighted by star size: balanced, short cuts.
    #[default]
    Coordinate,
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
            Self::Stripes => "stripes",
            Self::Random => "random",
        }
    }
}

/// What `sdg run --ranks` asks beyond [`RunOptions`].
#[derive(Clone, Copy, Debug)]
pub struct RankOptions {
    /// Ranks, at least 1.
    pub ranks: usize,
    /// How the vertices are split among them.
    pub partition: PartitionKind,
}

/// The seed of `--partition random`: the same owners on every run.
const RANDOM_SEED: u64 = 1;

/// Longest a rank waits for an update while it has vertices left, before it reports a stall.
const IDLE_LIMIT: Duration = Duration::from_secs(120);

/// `sdg run` over `ranks.ranks` in-process ranks: solves `problem` to the end time and writes
/// `summary.json`, `history.csv` and the snapshots into the output folder. Returns the
/// summary and the folder. Errors: what the ranks cannot do yet, and bad `options` (a restart,
/// a trace, a wall-time limit), as [`EngineError::Input`] (exit 2); a failed rank as
/// [`EngineError::Runtime`] (exit 1).
pub fn solve_ranks(
    problem: &Problem,
    options: &RunOptions,
    ranks: &RankOptions,
) -> Result<(RunSummary, PathBuf), EngineError> {
    refuse(problem, options, ranks)?;
    let config = &problem.loaded.config;
    let Start {
        state, max_star, ..
    } = Start::new(problem)?;
    let estimate = state.estimate(problem, max_star, ranks.ranks, false);
    if options.progress {
        crate::progress::note(format_args!("estimate: {}", estimate.describe()));
    }
    if !options.force {
        estimate.check(problem)?;
    }
    let dir = options.output_dir(problem)?;
    prepare_folder(&dir)?;
    let mesh = &problem.mesh;
    let partition = partition_for(mesh, ranks.partition, ranks.ranks)?;
    let (physics, causality) = (physics(problem), causality(problem));
    let _span = tracing::info_span!("solve", config = %problem.loaded.file.display()).entered();
    tracing::info!(
        ranks = ranks.ranks,
        partition = ranks.partition.name(),
        order = config.solver.order,
        vertices = mesh.vertices().len(),
        "solve over ranks started"
    );
    let started = Instant::now();
    let delays = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let mut outputs: Vec<RankOutputs> = (0..ranks.ranks as u32)
        .map(|rank| RankOutputs::new(problem, &partition, rank, &dir))
        .collect();
    let failed = |e| EngineError::Runtime(format!("the run over ranks failed: {e}"));
    let run = (causality, physics, delays);
    let mut solved = sdg_distributed::solve_threads_observed(
        mesh,
        &partition,
        run,
        &mut outputs,
        &Options {
            seed: 0,
            idle_limit: IDLE_LIMIT,
        },
    )
    .map_err(failed)?;
    let wall_time_s = started.elapsed().as_secs_f64();
    let mut snapshots = Vec::new();
    for (rank, outputs) in solved.iter_mut().zip(outputs) {
        let (values, written) = outputs.finish()?;
        rank.report.outputs = values;
        if rank.view.rank() == 0 {
            snapshots = written;
        }
    }
    let gathered = sdg_distributed::gather_threads(mesh, &solved).map_err(failed)?;
    finish(
        problem,
        &dir,
        (ranks.partition, &gathered, snapshots),
        wall_time_s,
        estimate,
    )
}

/// `sdg run --mpi` on this MPI process (one rank per process of `mpirun`): the ranks split the
/// front as [`solve_ranks`] does, with `sdg_distributed::MpiTransport`, and gather the results
/// on rank 0, which writes the outputs. Returns the summary and the folder on rank 0, `None`
/// on the others. Errors as [`solve_ranks`]; what is refused, every rank refuses alike, before
/// MPI starts.
#[cfg(feature = "mpi")]
pub fn solve_mpi(
    problem: &Problem,
    options: &RunOptions,
    partition: PartitionKind,
) -> Result<Option<(RunSummary, PathBuf)>, EngineError> {
    use sdg_distributed::{LocalView, MpiOptions, MpiTransport, Transport};
    refuse(
        problem,
        options,
        &RankOptions {
            ranks: 1,
            partition,
        },
    )?;
    let dir = options.output_dir(problem)?;
    let mut transport = MpiTransport::start(MpiOptions::default())
        .map_err(|e| EngineError::Runtime(format!("starting MPI: {e}")))?;
    let (rank, ranks) = (transport.rank(), transport.ranks());
    let failed = |e: sdg_distributed::PitchingError| {
        EngineError::Runtime(format!("the run over {ranks} MPI ranks failed: {e}"))
    };
    let Start {
        state, max_star, ..
    } = Start::new(problem)?;
    let estimate = state.estimate(problem, max_star, ranks, false);
    if options.progress && rank == 0 {
        crate::progress::note(format_args!("estimate: {}", estimate.describe()));
    }
    if !options.force {
        estimate.check(problem)?;
    }
    if rank == 0 {
        prepare_folder(&dir)?;
    }
    let mesh = &problem.mesh;
    let partition_of = partition_for(mesh, partition, ranks)?;
    let (physics, causality) = (physics(problem), causality(problem));
    let view = LocalView::new(mesh, &partition_of, rank).map_err(|e| failed(e.into()))?;
    let pitcher = sdg_mesh::Pitcher::new(
        view.mesh(),
        causality.c_max,
        causality.safety,
        causality.t_end,
    )
    .map_err(|e| failed(e.into()))?;
    let front = Front::flat(view.mesh().vertices().len(), 0.0);
    let solution = physics.initial_solution(&view);
    let run = Options {
        seed: u64::from(rank),
        idle_limit: IDLE_LIMIT,
    };
    // Every rank set up before any sends (a barrier), and done before any gathers.
    transport
        .sum(&[0])
        .map_err(|e| failed(sdg_distributed::PitchingError::Transport { rank, source: e }))?;
    let started = Instant::now();
    let mut outputs = RankOutputs::new(problem, &partition_of, rank, &dir);
    let mut report = sdg_distributed::solve_rank_observed(
        (&view, &pitcher, &front, &solution),
        physics,
        &mut transport,
        &mut outputs,
        &run,
    )
    .map_err(failed)?;
    let (values, snapshots) = outputs.finish()?;
    report.outputs = values;
    transport
        .sum(&[0])
        .map_err(|e| failed(sdg_distributed::PitchingError::Transport { rank, source: e }))?;
    let wall_time_s = started.elapsed().as_secs_f64();
    let gathered = sdg_distributed::gather(
        mesh,
        &view,
        (&front, &solution, &report),
        &mut transport,
        IDLE_LIMIT,
    )
    .map_err(failed)?;
    match gathered {
        Some(gathered) => finish(
            problem,
            &dir,
            (partition, &gathered, snapshots),
            wall_time_s,
            estimate,
        )
        .map(Some),
        None => Ok(None),
    }
}

/// Writes the outputs of a run over ranks that ended with `gathered` after `wall_time_s` on
/// the `partition`, with the `snapshots` (time in s, file name) rank 0 wrote, and its
/// `summary.json` into `dir`. Returns the summary and the folder.
fn finish(
    problem: &Problem,
    dir: &Path,
    (partition, gathered, snapshots): (PartitionKind, &Gathered, Vec<(f64, String)>),
    wall_time_s: f64,
    estimate: crate::estimate::Estimate,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let config = &problem.loaded.config;
    let mesh = &problem.mesh;
    let finishing = Instant::now();
    let (front, solution) = (&gathered.front, &gathered.solution);
    let serial = gathered.in_serial_order();
    let patches: Vec<SolvedPatch> = serial.iter().map(|(_, p)| *p).collect();
    let ranks = gathered.reports.len();
    tracing::info!(patches = patches.len(), wall_time_s, "solve finished");
    let initial_energy = {
        let initial_front = Front::flat(mesh.vertices().len(), 0.0);
        let empty = FrontSolution::new(
            mesh.triangles().len(),
            solution.basis_len(),
            solution.width(),
        );
        energy_on(problem, &initial_front, &empty, ranks)
    };
    let energy = energy_on(problem, front, solution, ranks);
    let mut summary = summarize(
        problem,
        (front, solution),
        &patches,
        &gathered.reports,
        (initial_energy, &energy),
        estimate,
    )?;
    summary.wall_time_s = wall_time_s;
    summary.patches_per_second = patches.len() as f64 / wall_time_s.max(f64::MIN_POSITIVE);
    summary.distributed = Some(distributed_summary(partition, gathered));
    summary.snapshots = snapshots;
    let outputs: Vec<&[f64]> = gathered.reports.iter().map(|r| &r.outputs[..]).collect();
    let history = history_csv(
        problem,
        &serial,
        &outputs,
        (&initial_energy, front, &energy),
    )?;
    let written = vec![write_output(dir, "history.csv", history.as_bytes()).map(drop)];
    if config.output.png {
        crate::plot::write_history_png(dir, &history);
    }
    crate::solve::finish::write_summary(dir, written, summary, finishing)
}

/// The partition of `mesh` over `ranks` ranks of `kind`; one that cannot be made (more ranks
/// than vertices) is bad input.
fn partition_for(
    mesh: &sdg_mesh::Mesh,
    kind: PartitionKind,
    ranks: usize,
) -> Result<Partition, EngineError> {
    match kind {
        PartitionKind::Coordinate => Partition::coordinate(mesh, ranks),
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

/// What a run over ranks cannot do yet, as bad input naming the key or option and why.
fn refuse(problem: &Problem, options: &RunOptions, ranks: &RankOptions) -> Result<(), EngineError> {
    let config = &problem.loaded.config;
    let file = problem.loaded.file.display();
    let events = "mesh-changing events do not run over ranks yet";
    let refusals = [
        (ranks.ranks == 0).then(|| "--ranks: must be at least 1".to_string()),
        config.adapt.enabled.then(|| {
            format!("{file}: adapt.enabled: {events}; run on threads (without --ranks or --mpi)")
        }),
        config.fracture.is_some().then(|| {
            format!("{file}: [fracture]: {events}; run on threads (without --ranks or --mpi)")
        }),
        (options.deterministic || config.scheduler.deterministic).then(|| {
            format!(
                "{}: deterministic rounds do not run over ranks; without events the \
                 asynchronous run over ranks is already the same for any rank count and timing",
                if options.deterministic {
                    "--deterministic".to_string()
                } else {
                    format!("{file}: scheduler.deterministic")
                }
            )
        }),
        options
            .restart
            .is_some()
            .then(|| "--restart: a run over ranks writes and reads no checkpoints yet".into()),
        options.max_wall_time_s.is_some().then(|| {
            "--max-wall-time: a run over ranks cannot checkpoint and stop yet".to_string()
        }),
        options
            .trace
            .is_some()
            .then(|| "--trace: a run over ranks records no trace yet".to_string()),
        config.checkpoint.every_sim_s.is_some().then(|| {
            format!("{file}: checkpoint.every_sim_s: a run over ranks writes no checkpoints yet")
        }),
        config.checkpoint.at_end.then(|| {
            format!("{file}: checkpoint.at_end: a run over ranks writes no checkpoints yet")
        }),
        (!config.output.interface_probes.is_empty()).then(|| {
            format!(
                "{file}: output.interface_probes: a run over ranks records no probes yet; set \
                 it to []"
            )
        }),
        config.output.spacetime_mesh.then(|| {
            format!("{file}: output.spacetime_mesh: a run over ranks does not write it yet")
        }),
    ];
    if let Some(reason) = refusals.into_iter().flatten().next() {
        return Err(EngineError::Input(reason));
    }
    // What is not done, without being asked for by a key of its own.
    if problem.interfaces.any_cohesive() {
        tracing::warn!(
            "crack_tips.csv and the summary's crack block are not written by a run over ranks yet"
        );
    }
    if config.output.png && !config.output.snapshot_times.is_empty() {
        tracing::warn!(
            "snapshots over ranks are written as pieces (snapshot_NNNN_R.vtu) and not drawn: no \
             snapshot_NNNN.png"
        );
    }
    if config.checkpoint.every_wall_s.is_finite() {
        tracing::info!(
            every_wall_s = config.checkpoint.every_wall_s,
            "a run over ranks writes no checkpoints: checkpoint.every_wall_s does not apply"
        );
    }
    Ok(())
}

/// Removes an earlier run's `summary.json` and snapshot files from `dir`.
fn prepare_folder(dir: &Path) -> Result<(), EngineError> {
    match std::fs::remove_file(dir.join("summary.json")) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(EngineError::io(dir.join("summary.json"), e));
        }
        _ => {}
    }
    crate::output::snapshot::remove_earlier(dir)?;
    Ok(())
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
/// `patches` (in serial order) from the `energy0` of the initial front, with the `estimate`
/// made before; the wall time is the caller's to fill in.
fn summarize(
    problem: &Problem,
    (front, solution): (&Front, &FrontSolution),
    patches: &[SolvedPatch],
    ranks: &[RankReport],
    (energy0, e): (FrontEnergy, &FrontEnergy),
    estimate: crate::estimate::Estimate,
) -> Result<RunSummary, EngineError> {
    let config = &problem.loaded.config;
    let mesh = &problem.mesh;
    let system = &problem.system;
    let rho = problem.material.density();
    let t_end = config.time.span();
    let solver = PatchSolver::new(system.clone(), config.solver.order, 0);
    let (basis, width) = (solver.basis(), solver.width());
    let threads = ranks.len();
    let mut totals = PatchReport::default();
    let (mut slope, mut nonlinear, mut newton, mut newton_max) = (0.0_f64, 0_u64, 0_u64, 0);
    let (mut elements, mut dofs) = (0_u64, 0_u64);
    let mut timings = Timings::default();
    for p in patches {
        let r = &p.report;
        if let Some((name, value)) = non_finite(r) {
            return Err(EngineError::Runtime(format!(
                "a patch over ranks has {name} = {value} (a non-finite value)"
            )));
        }
        elements += r.elements as u64;
        dofs += r.dofs as u64;
        timings.assembly_s += r.assembly_s;
        timings.solve_s += r.solve_s;
        timings.evaluation_s += r.evaluation_s;
        totals.accumulate(r);
        if r.newton_iterations > 0 {
            nonlinear += 1;
            newton += r.newton_iterations as u64;
            newton_max = newton_max.max(r.newton_iterations);
        }
        slope = slope.max(p.slope);
    }
    timings.waiting_s = ranks.iter().map(|r| r.waited.as_secs_f64()).sum();
    let count = patches.len() as u64;
    let (initial_j, work) = (rho * energy0.total, rho * totals.boundary_work);
    let (dissipation, interface_work) = (rho * totals.dissipation, rho * totals.interface_work);
    let final_j = rho * e.total;
    let error = problem.exact.as_ref().map(|w| {
        let e = slice_errors(mesh, solution, basis, system, t_end, w);
        ErrorSummary {
            velocity_l2_rel: e.velocity,
            stress_l2_rel: e.stress,
        }
    });
    let (min_edge, max_edge) = mesh.edge_length_range();
    Ok(RunSummary {
        command: "run",
        config_file: problem.loaded.file.clone(),
        vertices: mesh.vertices().len(),
        triangles: mesh.triangles().len(),
        order: config.solver.order,
        patches: count,
        elements,
        dofs_per_patch: dofs as f64 / count.max(1) as f64,
        final_time: config.time.clock(front.min_time()),
        max_slope_ratio: problem.material.max_wave_speed() * slope,
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
        energy: EnergySummary {
            initial: initial_j,
            final_kinetic: rho * e.kinetic,
            final_strain: rho * e.strain,
            r#final: final_j,
            boundary_work: work,
            dissipation,
            interface_work,
            friction_dissipation: rho * totals.friction_dissipation,
            fracture_energy: rho * totals.fracture_work,
            balance_residual_rel: (initial_j + work - final_j - dissipation - interface_work)
                / (initial_j + work.abs()).max(f64::MIN_POSITIVE),
        },
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
    })
}

/// The first non-finite value of a patch report, named as the engine's guard names it.
fn non_finite(r: &PatchReport) -> Option<(&'static str, f64)> {
    [
        ("energy_in", r.energy_in),
        ("energy_out", r.energy_out),
        ("boundary_work", r.boundary_work),
        ("interface_work", r.interface_work),
        ("dissipation", r.dissipation),
    ]
    .into_iter()
    .find(|(_, v)| !v.is_finite())
}

/// `distributed` of `summary.json`.
fn distributed_summary(partition: PartitionKind, gathered: &Gathered) -> DistributedSummary {
    let reports = &gathered.reports;
    let per_tent = |x: u64| x as f64 / gathered.tents.len().max(1) as f64;
    DistributedSummary {
        partition: partition.name(),
        boundary_vertices: reports.iter().map(|r| r.boundary_vertices).sum(),
        updates_per_tent: per_tent(reports.iter().map(|r| r.updates_sent).sum()),
        bytes_per_tent: per_tent(reports.iter().map(|r| r.update_bytes).sum()),
        waited_s: reports.iter().map(|r| r.waited.as_secs_f64()).sum(),
    }
}
