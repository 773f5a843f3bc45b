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
//! the tents, and `history.csv`. The ranks run in phases between checkpoints (module
//! `rank_run`), which are the threaded run's checkpoint files (module `rank_checkpoint`): a
//! run over ranks restarts from either kind, on any number of ranks, and a run on threads from
//! a checkpoint of one over ranks.
//!
//! What cannot be honoured yet is refused as bad input (exit 2), naming the key and why:
//! mesh-changing events (`[adapt]`, `[fracture]`), deterministic rounds, `--trace`, interface
//! probes and the spacetime mesh.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use sdg_distributed::{
    Causality, Gathered, LoopbackOptions, Partition, Physics, RankReport, SolvedPatch, Transport,
};
use sdg_mesh::Front;
use sdg_solver::element::FrontSolution;
use sdg_solver::norms::{FrontEnergy, front_energy, slice_errors};
use sdg_solver::patch::{Initial, Newton, PatchReport, PatchSolver};

use crate::error::EngineError;
use crate::job::RunOptions;
use crate::output::write_output;
use crate::problem::Problem;
use crate::rank_checkpoint::Prior;
use crate::rank_outputs::{history_csv, merged_sums};
use crate::rank_run::{Failure, OTHER_RANK_STOPPED, Shared, pause_request, run_rank};
use crate::solve::Control;
use crate::solve::checkpoint::{self, Folder};
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

/// `sdg run` over `ranks.ranks` in-process ranks: solves `problem` to the end time and writes
/// `summary.json`, `history.csv` and the snapshots into the output folder, and checkpoints as
/// configured or asked (module `rank_checkpoint`). Returns the summary and the folder.
/// Errors: what the ranks cannot do yet, and bad `options` (a trace), as
/// [`EngineError::Input`] (exit 2); a failed rank as [`EngineError::Runtime`] (exit 1); a stop
/// request as [`EngineError::Checkpointed`] (exit 3) once the checkpoint is written.
pub fn solve_ranks(
    problem: &Problem,
    options: &RunOptions,
    ranks: &RankOptions,
) -> Result<(RunSummary, PathBuf), EngineError> {
    refuse(problem, options, ranks)?;
    let set_up = SetUp::new(problem, options, ranks.ranks, true)?;
    let partition = partition_for(&problem.mesh, ranks.partition, ranks.ranks)?;
    let _span = tracing::info_span!("solve", config = %problem.loaded.file.display()).entered();
    tracing::info!(
        ranks = ranks.ranks,
        partition = ranks.partition.name(),
        order = problem.loaded.config.solver.order,
        vertices = problem.mesh.vertices().len(),
        "solve over ranks started"
    );
    let shared = set_up.shared(problem, (&partition, ranks.partition));
    let delays = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let ends = sdg_distributed::Loopback::connect(ranks.ranks, delays);
    let results: Vec<Result<Option<(RunSummary, PathBuf)>, Failure>> = std::thread::scope(|s| {
        let shared = &shared;
        let handles: Vec<_> = (ends.into_iter())
            .map(|mut end| {
                s.spawn(move || {
                    let rank = end.rank();
                    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        run_rank(shared, &mut end)
                    }))
                    .unwrap_or_else(|_| {
                        Err(Failure::Own(EngineError::Runtime(format!(
                            "rank {rank}: internal error (a bug, please report it)"
                        ))))
                    });
                    if matches!(result, Err(Failure::Own(ref e)) if e.exit_code() != 3) {
                        for r in (0..end.ranks() as u32).filter(|&r| r != rank) {
                            let _ = end.send(r, sdg_distributed::Message::Abort);
                        }
                    }
                    result
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(Failure::Own(EngineError::Runtime(
                        "a rank thread panicked".into(),
                    )))
                })
            })
            .collect()
    });
    let mut own: Vec<EngineError> = Vec::new();
    let (mut aborted, mut done) = (None, None);
    for result in results {
        match result {
            Ok(Some(d)) => done = Some(d),
            Ok(None) => {}
            Err(Failure::Own(e)) => own.push(e),
            Err(e) => aborted = aborted.or(Some(e.into_error())),
        }
    }
    // A failure before a stop, and a stop with the reason of the rank that was asked.
    let told = |e: &EngineError| match e {
        EngineError::Checkpointed { reason, .. } => reason != OTHER_RANK_STOPPED,
        _ => true,
    };
    own.sort_by_key(|e| (e.exit_code() == 3, !told(e)));
    match (own.into_iter().next().or(aborted), done) {
        (Some(e), _) => Err(e),
        (None, Some(done)) => Ok(done),
        (None, None) => Err(EngineError::Runtime("rank 0 returned no summary".into())),
    }
}

/// `sdg run --mpi` on this MPI process (one rank per process of `mpirun`): the ranks split the
/// front as [`solve_ranks`] does, with `sdg_distributed::MpiTransport`, and gather the results
/// on rank 0, which writes the outputs. Returns the summary and the folder on rank 0, `None`
/// on the others. Errors as [`solve_ranks`]; what is refused, every rank refuses alike, before
/// MPI starts. A rank that fails by itself reports its error and ends every rank with exit
/// code 1 (`MPI_Abort`), so that none waits for it.
#[cfg(feature = "mpi")]
pub fn solve_mpi(
    problem: &Problem,
    options: &RunOptions,
    partition: PartitionKind,
) -> Result<Option<(RunSummary, PathBuf)>, EngineError> {
    use sdg_distributed::{MpiOptions, MpiTransport, Transport};
    refuse(
        problem,
        options,
        &RankOptions {
            ranks: 1,
            partition,
        },
    )?;
    let mut transport = MpiTransport::start(MpiOptions::default())
        .map_err(|e| EngineError::Runtime(format!("starting MPI: {e}")))?;
    let (rank, ranks) = (transport.rank(), transport.ranks());
    let result = (|| {
        let set_up = SetUp::new(problem, options, ranks, rank == 0)?;
        let partition_of = partition_for(&problem.mesh, partition, ranks)?;
        let shared = set_up.shared(problem, (&partition_of, partition));
        // Every rank set up before any sends (a barrier).
        transport.sum(&[0]).map_err(|e| {
            Failure::Own(EngineError::Runtime(format!(
                "the run over {ranks} MPI ranks failed: rank {rank}: {e}"
            )))
        })?;
        run_rank(&shared, &mut transport)
    })();
    match result {
        Ok(done) => Ok(done),
        // Every rank has the checkpoint on disk: end at once, before `mpirun`, which got the
        // signal too, kills the processes (1 s after its SIGTERM by default).
        Err(Failure::Own(e @ EngineError::Checkpointed { .. })) => {
            crate::progress::note(format_args!("stopped: rank {rank}: {e}"));
            transport.abort(e.exit_code().into())
        }
        Err(Failure::Own(e)) => {
            crate::progress::note(format_args!("error: rank {rank}: {e}"));
            transport.abort(1)
        }
        Err(f) => Err(f.into_error()),
    }
}

/// What every rank sets up before it solves: the estimate, the folders, the checkpoint read
/// back and the pause request.
struct SetUp {
    estimate: crate::estimate::Estimate,
    dir: PathBuf,
    folder: Folder,
    prior: Prior,
    restored: Option<(Front, FrontSolution)>,
    control: std::sync::Arc<Control>,
    request: sdg_distributed::PauseRequest,
}

impl SetUp {
    /// The set-up of a run of `problem` with `options` over `ranks` ranks; `first` prepares
    /// the folders (rank 0, or the process of the in-process ranks).
    fn new(
        problem: &Problem,
        options: &RunOptions,
        ranks: usize,
        first: bool,
    ) -> Result<Self, EngineError> {
        let config = &problem.loaded.config;
        let Start {
            state, max_star, ..
        } = Start::new(problem)?;
        let estimate = state.estimate(problem, max_star, ranks, false);
        let restored = match &options.restart {
            Some(path) => Some(checkpoint::restore(path, config)?),
            None => None,
        };
        let estimate = match &restored {
            Some((_, r)) => estimate.remaining(&r.frontier.front.snapshot(), config.time.span()),
            None => estimate,
        };
        if options.progress && first {
            crate::progress::note(format_args!("estimate: {}", estimate.describe()));
        }
        if !options.force {
            estimate.check(problem)?;
        }
        let dir = options.output_dir(problem)?;
        let folder = Folder::new(config, &dir);
        if first {
            folder.check_unmixed(options.restart.as_deref())?;
            prepare_folder(&dir, restored.is_some())?;
        }
        let (prior, restored) = match restored {
            Some(r) => {
                let (prior, front, solution) = Prior::restored(problem, r, &folder)?;
                (prior, Some((front, solution)))
            }
            None => (Prior::fresh(), None),
        };
        let control = options.control.clone().unwrap_or_default();
        let request = pause_request(problem, options, control.clone());
        Ok(Self {
            estimate,
            dir,
            folder,
            prior,
            restored,
            control,
            request,
        })
    }

    /// What the ranks of the run share, on `partition`.
    fn shared<'a>(
        &'a self,
        problem: &'a Problem,
        partition: (&'a Partition, PartitionKind),
    ) -> Shared<'a> {
        Shared {
            problem,
            partition,
            dir: &self.dir,
            folder: &self.folder,
            prior: &self.prior,
            restored: self.restored.as_ref().map(|(f, s)| (f, s)),
            control: &self.control,
            request: self.request.clone(),
            estimate: &self.estimate,
            started: Instant::now(),
        }
    }
}

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
    let serial = gathered.in_serial_order();
    let patches: Vec<SolvedPatch> = serial.iter().map(|(_, p)| *p).collect();
    let ranks = gathered.reports.len();
    let wall_time_s = end.prior.wall_time_s + end.wall_time_s;
    tracing::info!(patches = patches.len(), wall_time_s, "solve finished");
    let initial_energy = initial_energy(problem, ranks);
    let energy = energy_on(problem, front, solution, ranks);
    let mut summary = summarize(
        problem,
        (front, solution),
        (end.prior, &patches),
        &gathered.reports,
        (initial_energy, &energy),
        estimate,
    )?;
    summary.wall_time_s = wall_time_s;
    summary.patches_per_second = patches.len() as f64 / end.wall_time_s.max(f64::MIN_POSITIVE);
    summary.distributed = Some(distributed_summary(end.partition, gathered));
    summary.snapshots = end.snapshots;
    summary.checkpoint = end.prior.summary(end.checkpoints.0, end.checkpoints.1);
    let outputs: Vec<&[f64]> = gathered.reports.iter().map(|r| &r.outputs[..]).collect();
    let times = crate::solve::book::history_times(config.time.span()).len();
    let (sums, _) = merged_sums(&outputs, times)?;
    let history = history_csv(
        problem,
        end.prior,
        &serial,
        &sums,
        (&initial_energy, front, Some(&energy)),
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
            .trace
            .is_some()
            .then(|| "--trace: a run over ranks records no trace yet".to_string()),
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
    Ok(())
}

/// Removes an earlier run's `summary.json` and, unless `restarted`, its snapshot files from
/// `dir`.
fn prepare_folder(dir: &Path, restarted: bool) -> Result<(), EngineError> {
    match std::fs::remove_file(dir.join("summary.json")) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(EngineError::io(dir.join("summary.json"), e));
        }
        _ => {}
    }
    if !restarted {
        crate::output::snapshot::remove_earlier(dir)?;
    }
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
    (prior, patches): (&Prior, &[SolvedPatch]),
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
    let mut totals = prior.totals;
    let c_max = problem.material.max_wave_speed();
    let mut slope = prior.max_slope_ratio / c_max;
    let (mut nonlinear, mut newton) = (prior.nonlinear, prior.newton);
    let mut newton_max = prior.newton_max;
    let (mut elements, mut dofs) = (prior.elements, prior.dofs);
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
    let count = prior.patches + patches.len() as u64;
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
