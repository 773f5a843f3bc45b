//! `sdg`: adaptive spacetime discontinuous Galerkin simulation of dynamic fracture.
//!
//! Exit codes: 0 success; 2 invalid arguments, configuration, mesh or checkpoint, or an
//! estimated cost above `[limits]`; 1 runtime failure (a panic included, or an output file
//! that cannot be written); 3 checkpointed and stopped by SIGTERM, SIGINT, SIGHUP or the
//! wall-time limit: resubmit with `--restart`.
//!
//! Output that cannot be written is dropped: a closed or broken stdout or stderr (EPIPE, a pipe
//! whose reader is gone) or a terminal that went away neither ends a command nor changes its
//! exit code, and signals keep working.

use std::io::{IsTerminal, Write};
use std::num::NonZeroUsize;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use std::sync::Arc;

use sdg_engine::{Control, EngineError, LoadedConfig, PartitionKind, Problem, RunOptions};

/// `sdg --version`: the version, and `(features: mpi)` in a build with the cargo feature `mpi`
/// (job scripts check it before they start ranks: examples/slurm/mpi.sbatch).
const VERSION: &str = if cfg!(feature = "mpi") {
    concat!(env!("CARGO_PKG_VERSION"), " (features: mpi)")
} else {
    env!("CARGO_PKG_VERSION")
};

/// Adaptive spacetime DG simulation of dynamic fracture on tent-pitched meshes.
#[derive(Debug, Parser)]
#[command(name = "sdg", version = VERSION, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Solve the configured problem to the end time.
    Run(RunArgs),
    /// Pitch tents to the end time without solving; write the summary and spacetime mesh.
    Mesh(JobArgs),
    /// Check a configuration and its mesh, print the estimated cost of the run, then exit.
    Validate(ValidateArgs),
    /// Draw a field of a VTU file (a snapshot, or any triangle grid) as PNG, or the crack tips of
    /// one or more runs.
    Plot(PlotArgs),
    /// Predict the speedup on more workers by replaying a trace of `sdg run --trace`.
    Scaling(ScalingArgs),
    /// Run a study: a base config over the product of axes of config values, each case an
    /// `sdg run`; then gather their metrics into study.csv, study.json and study.png.
    Study(StudyArgs),
}

// `study`: a study file, where its cases go and how they run.
#[derive(Debug, Args)]
struct StudyArgs {
    /// The study file (TOML: `base`, `metrics`, `[axes]`, `[set]`).
    study: PathBuf,
    /// Output folder [default: out/studies/STEM, STEM the study file's name without .toml].
    #[arg(long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Cases run at once.
    #[arg(long, value_name = "J", default_value = "1")]
    jobs: NonZeroUsize,
    /// Worker threads of each case [default: the available cores over --jobs; 1 with --slurm].
    #[arg(long, value_name = "N")]
    threads: Option<NonZeroUsize>,
    /// Run only case K (from 0, as `--dry-run` lists them; a Slurm array task id) and gather
    /// nothing; the exit code is that case's.
    #[arg(long, value_name = "K", conflicts_with_all = ["slurm", "collect", "dry_run"])]
    case: Option<usize>,
    /// Write DIR/study.slurm, a Slurm array job whose task K runs case K; submit nothing.
    #[arg(long, conflicts_with_all = ["collect", "dry_run"])]
    slurm: bool,
    /// Run nothing: gather the finished cases into study.csv, study.json and study.png.
    #[arg(long, conflicts_with = "dry_run")]
    collect: bool,
    /// Run nothing: list the cases, their overrides and their state.
    #[arg(long)]
    dry_run: bool,
    /// Print nothing but errors (failed cases included).
    #[arg(long)]
    quiet: bool,
}

// `scaling`: a trace and the worker counts to replay it on.
#[derive(Debug, Args)]
struct ScalingArgs {
    /// A trace written by `sdg run --trace FILE`.
    trace: PathBuf,
    /// Worker counts, comma-separated.
    #[arg(
        long,
        value_name = "N,...",
        value_delimiter = ',',
        default_value = "1,2,4,8,16,32,64,128,256"
    )]
    workers: Vec<NonZeroUsize>,
    /// Claiming a tent, us (`cargo bench --bench scheduler` on this machine: 0.27).
    #[arg(long, value_name = "US", default_value_t = 0.27)]
    overhead_us: f64,
    /// Draw the predicted speedup into this PNG file.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Replay over N ranks, each with the worker counts of --workers (needs --config and
    /// --latency-us; a trace without mesh-changing events).
    #[arg(long, value_name = "N", requires_all = ["rank_config", "latency_us"])]
    ranks: Option<NonZeroUsize>,
    /// With --ranks: the traced run's config, whose mesh is partitioned.
    #[arg(
        long = "config",
        id = "rank_config",
        value_name = "FILE",
        requires = "ranks"
    )]
    config: Option<PathBuf>,
    /// With --ranks: the traced run's overrides (repeatable, applied in order).
    #[arg(long = "set", value_name = "KEY=VALUE", requires = "ranks")]
    set: Vec<String>,
    /// With --ranks: how the vertices are split among them [default: coordinate].
    #[arg(long, value_enum, requires = "ranks")]
    partition: Option<PartitionArg>,
    /// With --ranks: the delay of an update message between ranks, us.
    #[arg(long, value_name = "US", requires = "ranks")]
    latency_us: Option<f64>,
}

// What every command that reads a config takes: all that `validate` takes.
#[derive(Debug, Args)]
struct ConfigArgs {
    /// TOML configuration file.
    config: PathBuf,
    /// Override a config key, e.g. `--set mesh.nx=64` (repeatable, applied in order).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
}

// `validate`: a config, and the threads the estimated wall time is for.
#[derive(Debug, Args)]
struct ValidateArgs {
    #[command(flatten)]
    config: ConfigArgs,
    /// Worker threads of the estimated run (default: all available cores).
    #[arg(long, value_name = "N")]
    threads: Option<NonZeroUsize>,
}

// The options of the commands that pitch tents, `run` and `mesh`.
#[derive(Debug, Args)]
struct JobArgs {
    #[command(flatten)]
    config: ConfigArgs,
    /// Output folder (overrides `output.dir`).
    #[arg(long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Worker threads (default: all available cores).
    #[arg(long, value_name = "N")]
    threads: Option<NonZeroUsize>,
    /// Results independent of thread count and timing (sets `scheduler.deterministic`).
    #[arg(long)]
    deterministic: bool,
    /// Log level on stderr: error, warn, info, debug or trace.
    #[arg(long, value_name = "LEVEL", default_value = "warn")]
    log_level: tracing::Level,
    /// Log format: text, or json (one object per line, for job scripts).
    #[arg(long, value_enum, default_value_t = LogFormat::Text)]
    log_format: LogFormat,
    /// Run even when the estimated cost exceeds `[limits]`.
    #[arg(long)]
    force: bool,
}

// `run`: a job that can checkpoint, stop and restart.
#[derive(Debug, Args)]
struct RunArgs {
    #[command(flatten)]
    job: JobArgs,
    /// Go on from the checkpoint FILE, or the newest valid one in the folder (the
    /// configuration and overrides must be those of the run that wrote it).
    #[arg(long, value_name = "PATH")]
    restart: Option<PathBuf>,
    /// Checkpoint and stop with exit code 3 after this much wall time, s.
    #[arg(long, value_name = "SECONDS")]
    max_wall_time: Option<f64>,
    /// Record every tent and event (vertex, dependencies, cost) in this CSV file, for
    /// `sdg scaling`.
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Split the front over N ranks, threads of this process (no mesh-changing events): the
    /// same state hash as a run on threads. With --threads T, each rank solves its tents on T
    /// threads (default 1).
    #[arg(long, value_name = "N")]
    ranks: Option<NonZeroUsize>,
    /// One rank per MPI process: start with `mpirun -n N sdg run CONFIG --mpi` (a build with
    /// the cargo feature `mpi`); with --threads T each rank solves its tents on T threads
    /// (default 1).
    #[arg(long, conflicts_with = "ranks")]
    mpi: bool,
    /// How the vertices are split among the ranks (with --ranks or --mpi) [default:
    /// coordinate].
    #[arg(long, value_enum)]
    partition: Option<PartitionArg>,
}

#[derive(Debug, Args)]
struct PlotArgs {
    /// A VTU file (ASCII, base64 binary or appended, uncompressed or zlib); or one or more
    /// runs' crack_tips.csv, whose tips are drawn together, each named by its run's folder; or,
    /// with --lefm, run folders.
    #[arg(required = true, value_name = "FILE")]
    inputs: Vec<PathBuf>,
    /// The seed's figures 2.6 to 2.10 from run folders of the mode-I problem (configs with
    /// a loading section), one curve per run, into the folder --out.
    #[arg(long, conflicts_with_all = ["field", "edges"])]
    lefm: bool,
    /// Point or cell field: NAME (vectors: magnitude), NAME_x, NAME_xy, or von_mises
    /// [default: velocity, i.e. its magnitude].
    #[arg(long, value_name = "NAME")]
    field: Option<String>,
    /// PNG file [default: the VTU path with extension png; required for crack_tips.csv].
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Overlay the mesh edges.
    #[arg(long)]
    edges: bool,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum LogFormat {
    Text,
    Json,
}

/// Writes a line to stdout, or drops it if stdout cannot be written (`println!` panics then).
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::write_line(&mut std::io::stdout(), format_args!($($arg)*))
    };
}

/// Writes a line to stderr, or drops it if stderr cannot be written (`eprintln!` panics then).
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::write_line(&mut std::io::stderr(), format_args!($($arg)*))
    };
}

/// Writes `line` and a newline to `out`, ignoring errors: a run is never ended, nor a thread
/// of it, by output that cannot be written.
fn write_line(out: &mut impl Write, line: std::fmt::Arguments) {
    let _ = writeln!(out, "{line}");
}

/// The log's writer: stderr, dropping what cannot be written. (tracing-subscriber reports a
/// failed write with `eprintln!`, which panics on a broken stderr, in whatever thread logged.)
#[derive(Debug)]
struct LogWriter;

impl Write for LogWriter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let _ = std::io::stderr().write_all(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

// After the macros, which they use.
mod ranks;
mod signals;

use ranks::PartitionArg;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let (level, format) = match &cli.command {
        Command::Run(RunArgs { job, .. }) | Command::Mesh(job) => (job.log_level, job.log_format),
        // No log options: warnings as text, should there be any.
        Command::Validate(_) | Command::Plot(_) | Command::Scaling(_) | Command::Study(_) => {
            (tracing::Level::WARN, LogFormat::Text)
        }
    };
    let logs = tracing_subscriber::fmt()
        .with_max_level(level)
        .with_ansi(std::io::stderr().is_terminal())
        .with_writer(|| LogWriter)
        .log_internal_errors(false);
    match format {
        LogFormat::Text => logs.init(),
        LogFormat::Json => logs.json().init(),
    }
    // A panic is a bug: its message (printed by the panic hook, with the place) and exit 1,
    // like any failure while running. Panics of worker threads end the run the same way
    // (`sdg_scheduler::RunError::Panic`).
    let result = std::panic::catch_unwind(|| match &cli.command {
        Command::Run(job) => run(job),
        Command::Mesh(job) => mesh(job),
        Command::Validate(args) => validate(args),
        Command::Plot(args) => plot(args),
        Command::Scaling(args) => scaling(args),
        Command::Study(args) => study(args),
    });
    match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e @ EngineError::Checkpointed { .. })) => {
            note!("stopped: {e}");
            ExitCode::from(e.exit_code())
        }
        Ok(Err(e)) => {
            note!("error: {e}");
            ExitCode::from(e.exit_code())
        }
        Err(_) => {
            note!("error: internal error (a bug, please report it with the message above)");
            ExitCode::from(1)
        }
    }
}

/// Loads the config with its overrides and sets the problem up. The checks against the mesh
/// (boundary sides, interface tags, probes) name the override that set their key, as the checks
/// of the config alone do.
fn setup(args: &ConfigArgs) -> Result<Problem, EngineError> {
    let loaded = LoadedConfig::load(&args.config, &args.set)?;
    Problem::setup(loaded).map_err(|e| match e {
        EngineError::Config(e) => sdg_engine::config::attribute(e, &args.set).into(),
        e => e,
    })
}

fn options(job: &JobArgs) -> RunOptions {
    RunOptions {
        output_dir: job.output.clone(),
        threads: job.threads.map(NonZeroUsize::get),
        deterministic: job.deterministic,
        progress: !job.config.quiet,
        force: job.force,
        ..RunOptions::default()
    }
}

fn validate(args: &ValidateArgs) -> Result<(), EngineError> {
    let problem = setup(&args.config)?;
    let options = RunOptions {
        threads: args.threads.map(NonZeroUsize::get),
        ..RunOptions::default()
    };
    let estimate = sdg_engine::estimate_job(&problem, &options)?;
    // What `sdg run` would refuse, `validate` refuses too, after saying why.
    let check = estimate.check(&problem);
    if !args.config.quiet {
        let m = &problem.material;
        say!(
            "{}: {} ({} vertices, {} triangles)\n\
             wave speeds: c_d = {:.6e} m/s, c_s = {:.6e} m/s, c_R = {:.6e} m/s\n\
             estimate: {}",
            args.config.config.display(),
            match &check {
                Ok(()) => "valid",
                Err(e) if e.key.is_some() => "valid input, over its [limits]",
                Err(_) => "valid input, beyond this machine's memory on these threads",
            },
            problem.mesh.vertices().len(),
            problem.mesh.triangles().len(),
            m.c_d(),
            m.c_s(),
            m.c_r(),
            estimate.describe()
        );
    }
    check?;
    Ok(())
}

fn mesh(job: &JobArgs) -> Result<(), EngineError> {
    let (summary, dir) = sdg_engine::mesh_job(&setup(&job.config)?, &options(job))?;
    if !job.config.quiet {
        say!(
            "{} tents, {} tetrahedra to t = {:e} s, max slope ratio {:.4} (safety {}), \
             {:.3} s; outputs in {}",
            summary.tents,
            summary.tetrahedra,
            summary.final_time,
            summary.max_slope_ratio,
            summary.safety,
            summary.wall_time_s,
            dir.display()
        );
    }
    Ok(())
}

fn run(args: &RunArgs) -> Result<(), EngineError> {
    if args.mpi {
        return run_over_ranks(args, None);
    }
    if let Some(processes) = ranks::mpi_processes().filter(|&n| n > 1) {
        return Err(EngineError::Input(format!(
            "started as one of {processes} MPI processes without --mpi: each would run the \
             whole job; add --mpi (with a build with the cargo feature mpi: cargo build \
             --release --features mpi)"
        )));
    }
    if let Some(ranks) = args.ranks {
        return run_over_ranks(args, Some(ranks.get()));
    }
    if args.partition.is_some() {
        return Err(EngineError::Input(
            "--partition: splits the front among ranks: give --ranks N or --mpi too".into(),
        ));
    }
    // Before anything else: a signal during set-up is a request like any other.
    let control = Arc::new(Control::default());
    signals::listen_to_signals(control.clone())?;
    stop_with_study(&control)?;
    let job = &args.job;
    let problem = setup(&job.config)?;
    check_max_wall_time(args.max_wall_time)?;
    let options = RunOptions {
        restart: args.restart.clone(),
        max_wall_time_s: args.max_wall_time,
        trace: args.trace.clone(),
        control: Some(control),
        ..options(job)
    };
    let (summary, dir) = sdg_engine::solve_job(&problem, &options)?;
    if !job.config.quiet {
        let error = summary.error.map_or(String::new(), |e| {
            format!(
                ", error: velocity {:.3e}, stress {:.3e}",
                e.velocity_l2_rel, e.stress_l2_rel
            )
        });
        say!(
            "{} patches (order {}, {:.0} dofs each) to t = {:e} s in {:.3} s on {} \
             threads ({}){error}; energy balance residual {:.1e}; outputs in {}",
            summary.patches,
            summary.order,
            summary.dofs_per_patch,
            summary.final_time,
            summary.wall_time_s,
            summary.threads,
            summary.mode,
            summary.energy.balance_residual_rel,
            dir.display()
        );
        if let Some(f) = &summary.fracture {
            let fork = f.macro_branching.as_ref().map_or(String::new(), |m| {
                let arms: Vec<String> = (m.arms.iter().zip(&m.open_arms))
                    .map(|(a, open)| format!("{a:.3e} ({open:.3e} open)"))
                    .collect();
                let from_tip = m.distance.map_or(String::new(), |d| {
                    format!(", {d:.3e} m from the initial tip")
                });
                format!(
                    "; first macro branching at t = {:.6e} s at ({:.4e}, {:.4e}) m{from_tip}, \
                     arms {} m",
                    m.time,
                    m.point[0],
                    m.point[1],
                    arms.join(", ")
                )
            });
            say!(
                "cracks: {} nucleations, {} extensions, {} branchings, {} branches{fork}",
                f.nucleations,
                f.extensions,
                f.branchings,
                f.branches
            );
        }
    }
    Ok(())
}

/// `--max-wall-time`: a positive number of seconds, if given.
fn check_max_wall_time(seconds: Option<f64>) -> Result<(), EngineError> {
    match seconds.filter(|s| !(s.is_finite() && *s > 0.0)) {
        Some(s) => Err(EngineError::Input(format!(
            "--max-wall-time: must be a positive number of seconds, got {s}"
        ))),
        None => Ok(()),
    }
}

/// `sdg run --ranks N` (`ranks`) or, without, `sdg run --mpi`: the front split over ranks.
/// Signals are requests as on threads: SIGTERM, SIGINT and SIGHUP checkpoint and stop every
/// rank (exit 3), SIGUSR1 checkpoints; under `mpirun` each process listens to its own.
fn run_over_ranks(args: &RunArgs, ranks: Option<usize>) -> Result<(), EngineError> {
    let control = Arc::new(Control::default());
    signals::listen_to_signals(control.clone())?;
    stop_with_study(&control)?;
    let job = &args.job;
    let problem = setup(&job.config)?;
    check_max_wall_time(args.max_wall_time)?;
    let options = RunOptions {
        restart: args.restart.clone(),
        max_wall_time_s: args.max_wall_time,
        trace: args.trace.clone(),
        control: Some(control),
        ..options(job)
    };
    let partition = args
        .partition
        .map_or_else(Default::default, PartitionArg::kind);
    let done = match ranks {
        Some(ranks) => {
            let ranks = sdg_engine::RankOptions { ranks, partition };
            Some(sdg_engine::solve_ranks(&problem, &options, &ranks)?)
        }
        None => ranks::solve_mpi(&problem, &options, partition)?,
    };
    if let Some((summary, dir)) = done.filter(|_| !job.config.quiet) {
        say!("{}", ranks::totals(&summary, partition, &dir));
    }
    Ok(())
}

/// A case of `sdg study` ([`sdg_engine::study::STUDY_ENV`] set) reads its standard input, a
/// pipe from the study: a [`sdg_engine::study::CHECKPOINT_BYTE`] asks for a checkpoint, the
/// pipe's end (the study asked its cases to stop, or is gone, even by SIGKILL) for a checkpoint
/// and a stop (exit 3), as SIGTERM does. So no run outlives its study, and none is lost.
fn stop_with_study(control: &Arc<Control>) -> Result<(), EngineError> {
    use std::io::Read;
    if std::env::var_os(sdg_engine::study::STUDY_ENV).is_none() {
        return Ok(());
    }
    let control = control.clone();
    std::thread::Builder::new()
        .name("study watch".into())
        .spawn(move || {
            let mut input = std::io::stdin().lock();
            let mut byte = [0u8; 1];
            loop {
                match input.read(&mut byte) {
                    Ok(1) if byte[0] == sdg_engine::study::CHECKPOINT_BYTE => {
                        control.checkpoint();
                    }
                    Ok(1) => {}
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    _ => break,
                }
            }
            control.stop("the study that started this run stopped or is gone");
        })
        .map_err(|e| EngineError::Runtime(format!("watching the study: {e}")))?;
    Ok(())
}

fn study(args: &StudyArgs) -> Result<(), EngineError> {
    use sdg_engine::study::{self, CaseStatus, RunPlan};
    let plan = study::Study::load(&args.study)?;
    let cases = plan.prepare()?;
    let out =
        (args.output.clone()).unwrap_or_else(|| PathBuf::from("out/studies").join(plan.stem()));
    let program = std::env::current_exe()
        .map_err(|e| EngineError::Runtime(format!("cannot find the sdg binary: {e}")))?;
    if args.dry_run {
        let common = &cases[0].overrides[..plan.set.len()];
        say!(
            "{}: {} cases of {} in {}{}",
            args.study.display(),
            cases.len(),
            plan.base.display(),
            out.display(),
            match common.is_empty() {
                true => String::new(),
                false => format!(", each with --set {}", common.join(" --set ")),
            }
        );
        for case in &cases {
            let dir = study::case_dir(&out, case.index, cases.len());
            let status = study::case_status(case, &dir)?;
            say!(
                "{:>4}  {:<10}  {}{}",
                case.index,
                status.name(),
                case.label(&plan.axes),
                with_keys(case)
            );
        }
        return Ok(());
    }
    if args.slurm {
        let threads = args.threads.map_or(1, NonZeroUsize::get);
        let script = study::write_slurm(&plan, cases.len(), &program, &out, threads)?;
        if !args.quiet {
            say!(
                "{}: {} cases, task K runs case K. Submit with
  sbatch {}
then gather                  them with
  sdg study {} --collect --output {}",
                script.display(),
                cases.len(),
                script.display(),
                args.study.display(),
                out.display()
            );
        }
        return Ok(());
    }
    if !args.collect {
        let selected: Vec<usize> = match args.case {
            Some(k) if k >= cases.len() => {
                return Err(EngineError::Input(format!(
                    "--case {k}: {} has {} cases, 0 to {}",
                    args.study.display(),
                    cases.len(),
                    cases.len() - 1
                )));
            }
            Some(k) => vec![k],
            None => (0..cases.len()).collect(),
        };
        sdg_engine::output::check_writable(&out, &format!("--output {}", out.display()))?;
        let threads = args.threads.map_or_else(
            || {
                let cores = std::thread::available_parallelism().map_or(1, NonZeroUsize::get);
                (cores / args.jobs.get()).max(1)
            },
            NonZeroUsize::get,
        );
        let progress = !args.quiet && args.case.is_none();
        let estimate_s = first_case_estimate(&plan, &cases[selected[0]], threads, progress)?;
        let stop = Arc::new(study::Stop::default());
        signals::listen_to_signals(stop.clone())?;
        let run_plan = RunPlan {
            program,
            out: out.clone(),
            jobs: args.jobs.get(),
            threads,
            progress,
            estimate_s,
            stop: stop.clone(),
        };
        let tally = study::run_cases(&plan, &cases, &selected, &run_plan)?;
        if args.case.is_some() {
            return match (tally.failed.first(), tally.stopped.first()) {
                (Some(&(k, code)), _) => Err(EngineError::CasesFailed {
                    message: format!("case {k} failed: sdg run exited {code}"),
                    code: u8::try_from(code).unwrap_or(1),
                }),
                (None, Some(k)) => Err(EngineError::CasesFailed {
                    message: format!(
                        "case {k} checkpointed and stopped: run the same command again to go on"
                    ),
                    code: 3,
                }),
                (None, None) => Ok(()),
            };
        }
        if !tally.stopped.is_empty() || stop.requested() {
            // Gather what finished, then say how to go on.
            study::collect(&plan, &cases, &out)?;
            let list: Vec<String> = tally.stopped.iter().map(usize::to_string).collect();
            return Err(EngineError::CasesFailed {
                message: format!(
                    "stopped: {} case(s) checkpointed ({}){}; run the same command again to go \
                     on from their checkpoints; the finished cases are gathered in {}",
                    list.len(),
                    list.join(", "),
                    match tally.failed.len() {
                        0 => String::new(),
                        n => format!(", {n} failed"),
                    },
                    out.join("study.csv").display()
                ),
                code: 3,
            });
        }
        if !tally.failed.is_empty() {
            // Gather what finished, then fail.
            study::collect(&plan, &cases, &out)?;
            let list: Vec<String> = (tally.failed.iter())
                .map(|(k, code)| format!("{k} (exit {code})"))
                .collect();
            return Err(EngineError::CasesFailed {
                message: format!(
                    "{} of {} cases failed: {}; the others are gathered in {}",
                    list.len(),
                    cases.len(),
                    list.join(", "),
                    out.join("study.csv").display()
                ),
                code: 1,
            });
        }
    }
    let collected = study::collect(&plan, &cases, &out)?;
    if !args.quiet {
        let done = collected.count(|s| *s == CaseStatus::Done);
        say!(
            "{done} of {} cases finished; {}, study.json and study.png in {}",
            cases.len(),
            "study.csv",
            out.display()
        );
    }
    Ok(())
}

/// Sets up the problem of `case` (checking its mesh, boundaries and probes, as `sdg validate`
/// does: a base config that does not set up is refused before anything runs) and, when
/// `estimate`, returns the estimated wall time of its run on `threads` threads, s.
fn first_case_estimate(
    plan: &sdg_engine::Study,
    case: &sdg_engine::study::Case,
    threads: usize,
    estimate: bool,
) -> Result<Option<f64>, EngineError> {
    let loaded = LoadedConfig::load(&plan.base, &case.overrides)?;
    let refused = |e: EngineError| match e.exit_code() {
        2 => EngineError::Study(sdg_engine::StudyError {
            file: plan.file.display().to_string(),
            key: Some("base".into()),
            reason: format!("case {}: {e}", case.index),
        }),
        _ => e,
    };
    let problem = Problem::setup(loaded).map_err(refused)?;
    if !estimate {
        return Ok(None);
    }
    let options = RunOptions {
        threads: Some(threads),
        ..RunOptions::default()
    };
    Ok(sdg_engine::estimate_job(&problem, &options)
        .ok()
        .map(|e| e.wall_time_s))
}

fn scaling(args: &ScalingArgs) -> Result<(), EngineError> {
    if !(args.overhead_us.is_finite() && args.overhead_us >= 0.0) {
        return Err(EngineError::Input(format!(
            "--overhead-us: must be a time >= 0 in us, got {}",
            args.overhead_us
        )));
    }
    let workers: Vec<usize> = args.workers.iter().map(|w| w.get()).collect();
    let overhead_s = args.overhead_us * 1e-6;
    let model = rank_model(args)?;
    let scaling = sdg_engine::trace::scaling_job(
        &args.trace,
        &workers,
        overhead_s,
        model.as_ref(),
        args.out.as_deref(),
    )?;
    let entries = sdg_engine::trace::read(&args.trace)?;
    let one = scaling.one_s;
    match (&model, sdg_engine::trace::rounds(&entries)) {
        (Some(model), _) => say!(
            "model: {} ranks ({} partition), {} us per update between ranks, the asynchronous \
             protocol's tents; {:.2}% of the dependencies cross ranks; workers are per rank",
            model.ranks,
            args.partition
                .map_or(PartitionKind::default(), PartitionArg::kind)
                .name(),
            args.latency_us.unwrap_or_default(),
            100.0 * scaling.cross_rank.unwrap_or(0.0)
        ),
        (None, 0) => say!(
            "model: the asynchronous scheduler (a trace without rounds; its {} refinements, \
             coarsenings and crack extensions run beside the tents that hold none of their vertices)",
            sdg_engine::trace::regions(&entries)
        ),
        (None, n) => say!("model: the deterministic scheduler's {n} rounds"),
    }
    print_predictions(&scaling.predictions, one);
    let critical = scaling.critical_s;
    if model.is_some() {
        say!(
            "critical path {critical:.4} s over the ranks: at most {:.2}x over one worker",
            one / critical
        );
        return Ok(());
    }
    let parts = sdg_engine::trace::critical_path_parts(&entries, overhead_s);
    say!(
        "critical path {critical:.4} s: at most {:.2}x over one worker; tents {:.4} s, events \
         {:.4} s, the scheduler alone {:.4} s",
        one / critical,
        parts.tents_s,
        parts.events_s,
        parts.scheduler_s
    );
    Ok(())
}

/// For `sdg study --dry-run`: the overrides of `case` that go with its axes' values (`with`),
/// written out when there are at most three, else counted.
fn with_keys(case: &sdg_engine::study::Case) -> String {
    let rest: Vec<&str> = (case.overrides.iter().zip(&case.sources))
        .filter(|(_, source)| source.contains(".with."))
        .map(|(o, _)| o.as_str())
        .collect();
    match rest.len() {
        0 => String::new(),
        1..=3 => format!(" (with {})", rest.join(", ")),
        n => format!(" (with {n} keys that go with these values)"),
    }
}

/// `sdg scaling --ranks`: the owners of the vertices of the traced run's mesh (its config and
/// overrides) and the latency; `None` without `--ranks`.
fn rank_model(args: &ScalingArgs) -> Result<Option<sdg_engine::trace::RankModel>, EngineError> {
    let (Some(ranks), Some(config), Some(latency_us)) = (args.ranks, &args.config, args.latency_us)
    else {
        return Ok(None);
    };
    if !(latency_us.is_finite() && latency_us >= 0.0) {
        return Err(EngineError::Input(format!(
            "--latency-us: must be a time >= 0 in us, got {latency_us}"
        )));
    }
    let problem = setup(&ConfigArgs {
        config: config.clone(),
        set: args.set.clone(),
        quiet: true,
    })?;
    let kind = args
        .partition
        .map_or(PartitionKind::default(), PartitionArg::kind);
    let partition = sdg_engine::partition_for(&problem, kind, ranks.get())?;
    Ok(Some(sdg_engine::trace::RankModel {
        owners: partition.owners().to_vec(),
        ranks: ranks.get(),
        latency_s: latency_us * 1e-6,
    }))
}

/// Prints a table of predictions, with speedups over `one` (s, the 1-worker wall time).
fn print_predictions(predictions: &[sdg_engine::trace::Prediction], one: f64) {
    say!("workers  wall time (s)  speedup  mean ready tents");
    for p in predictions {
        say!(
            "{:>7}  {:>13.4}  {:>7.2}  {:>16.1}",
            p.workers,
            p.wall_time_s,
            one / p.wall_time_s,
            p.mean_ready
        );
    }
}

fn plot(args: &PlotArgs) -> Result<(), EngineError> {
    if args.lefm {
        let Some(out) = &args.out else {
            return Err(EngineError::Input(
                "--lefm: --out DIR is required (the folder of the figures)".into(),
            ));
        };
        for path in sdg_engine::plot::plot_lefm(&args.inputs, out)? {
            if !args.quiet {
                say!("{}", path.display());
            }
        }
        return Ok(());
    }
    let is_csv = |p: &PathBuf| p.extension().is_some_and(|e| e == "csv");
    if args.inputs.iter().any(is_csv) {
        let usage = |reason: &str| Err(EngineError::Input(reason.into()));
        if !args.inputs.iter().all(is_csv) {
            return usage("give either one VTU file or crack_tips.csv files, not both");
        }
        if args.field.is_some() || args.edges {
            return usage("--field and --edges apply to a VTU file");
        }
        let Some(out) = &args.out else {
            return usage("--out FILE is required to draw crack_tips.csv");
        };
        sdg_engine::plot::plot_tips(&args.inputs, out)?;
        if !args.quiet {
            say!("{}", out.display());
        }
        return Ok(());
    }
    let [vtu] = &args.inputs[..] else {
        return Err(EngineError::Input("draw one VTU file at a time".into()));
    };
    let request = sdg_engine::plot::PlotRequest {
        vtu: vtu.clone(),
        field: args.field.clone(),
        out: args.out.clone(),
        edges: args.edges,
    };
    let path = sdg_engine::plot::plot_vtu(&request)?;
    if !args.quiet {
        say!("{}", path.display());
    }
    Ok(())
}
