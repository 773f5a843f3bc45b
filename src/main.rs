//! `sdg`: adaptive spacetime discontinuous Galerkin simulation of dynamic fracture.
//!
//! Exit codes: 0 success, 2 invalid arguments, configuration or mesh, 1 runtime failure.

use std::io::IsTerminal;
use std::num::NonZeroUsize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use sdg_engine::{EngineError, LoadedConfig, Problem, RunOptions};

/// Adaptive spacetime DG simulation of dynamic fracture on tent-pitched meshes.
#[derive(Debug, Parser)]
#[command(name = "sdg", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Output folder (overrides `output.dir`).
    #[arg(long, global = true, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Worker threads (default: all available cores).
    #[arg(long, global = true, value_name = "N")]
    threads: Option<NonZeroUsize>,
    /// Results independent of thread count and timing (sets `scheduler.deterministic`).
    #[arg(long, global = true)]
    deterministic: bool,
    /// Print nothing but errors; no progress bar.
    #[arg(long, global = true)]
    quiet: bool,
    /// Log level on stderr: error, warn, info, debug or trace.
    #[arg(long, global = true, value_name = "LEVEL", default_value = "warn")]
    log_level: tracing::Level,
    /// Log format: text, or json (one object per line, for job scripts).
    #[arg(long, global = true, value_enum, default_value_t = LogFormat::Text)]
    log_format: LogFormat,
    /// Override a config key, e.g. `--set mesh.nx=64` (repeatable, applied in order).
    #[arg(long = "set", global = true, value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum LogFormat {
    Text,
    Json,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Solve the configured problem to the end time.
    Run {
        /// TOML configuration file.
        config: PathBuf,
    },
    /// Pitch tents to the end time without solving; write the summary and spacetime mesh.
    Mesh {
        /// TOML configuration file.
        config: PathBuf,
    },
    /// Check a configuration and its mesh, then exit.
    Validate {
        /// TOML configuration file.
        config: PathBuf,
    },
    /// Draw a field of a VTU file (a snapshot, or any triangle grid) as PNG.
    Plot {
        /// VTU file: ASCII, base64 binary or appended, uncompressed or zlib.
        vtu: PathBuf,
        /// Point or cell field: NAME (vectors: magnitude), NAME_x, NAME_xy, or von_mises
        /// [default: velocity, i.e. its magnitude].
        #[arg(long, value_name = "NAME")]
        field: Option<String>,
        /// PNG file [default: the VTU path with extension png].
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
        /// Overlay the mesh edges.
        #[arg(long)]
        edges: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let logs = tracing_subscriber::fmt()
        .with_max_level(cli.log_level)
        .with_ansi(std::io::stderr().is_terminal())
        .with_writer(std::io::stderr);
    match cli.log_format {
        LogFormat::Text => logs.init(),
        LogFormat::Json => logs.json().init(),
    }
    match execute(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

fn execute(cli: &Cli) -> Result<(), EngineError> {
    let (job, config) = match &cli.command {
        Command::Run { config } => (Job::Run, config),
        Command::Mesh { config } => (Job::Mesh, config),
        Command::Validate { config } => (Job::Validate, config),
        Command::Plot {
            vtu,
            field,
            out,
            edges,
        } => {
            let request = sdg_engine::plot::PlotRequest {
                vtu: vtu.clone(),
                field: field.clone(),
                out: out.clone(),
                edges: *edges,
            };
            let path = sdg_engine::plot::plot_vtu(&request)?;
            if !cli.quiet {
                println!("{}", path.display());
            }
            return Ok(());
        }
    };
    config_command(cli, job, config)
}

/// The commands that load a config.
#[derive(Clone, Copy, Debug)]
enum Job {
    Run,
    Mesh,
    Validate,
}

fn config_command(cli: &Cli, job: Job, config: &Path) -> Result<(), EngineError> {
    let problem = Problem::setup(LoadedConfig::load(config, &cli.set)?)?;
    let options = RunOptions {
        output_dir: cli.output.clone(),
        threads: cli.threads.map(NonZeroUsize::get),
        deterministic: cli.deterministic,
        progress: !cli.quiet,
    };
    match job {
        Job::Validate => {
            if !cli.quiet {
                println!(
                    "{}: valid ({} vertices, {} triangles)",
                    config.display(),
                    problem.mesh.vertices().len(),
                    problem.mesh.triangles().len()
                );
            }
            Ok(())
        }
        Job::Mesh => {
            let (summary, dir) = sdg_engine::mesh_job(&problem, &options)?;
            if !cli.quiet {
                println!(
                    "{} tents, {} tetrahedra to t = {} s, max slope ratio {} (safety {}), \
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
        Job::Run => {
            let (summary, dir) = sdg_engine::solve_job(&problem, &options)?;
            if !cli.quiet {
                let error = summary.error.map_or(String::new(), |e| {
                    format!(
                        ", error: velocity {:.3e}, stress {:.3e}",
                        e.velocity_l2_rel, e.stress_l2_rel
                    )
                });
                println!(
                    "{} patches (order {}, {:.0} dofs each) to t = {} s in {:.3} s on {} \
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
            }
            Ok(())
        }
    }
}
