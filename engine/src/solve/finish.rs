//! The end of a solve: the last history row, the summary of the run, and its files.

use std::path::{Path, PathBuf};
use std::time::Instant;

use sdg_scheduler::Options;
use sdg_solver::norms::{front_energy, slice_errors};

use crate::error::EngineError;
use crate::estimate::{self, Estimate};
use crate::frontier::Frontier;
use crate::job::RunOptions;
use crate::output::write_output;
use crate::plot;

use super::checkpoint::Counts;
use super::context::{Solve, initial_state};
use super::outputs::{
    crack_tips, front_cracks, initial_tip_points, lefm, write_crack_tips, write_probes,
};
use super::split::Split;
use super::summary::{
    CheckpointSummary, EnergySummary, ErrorSummary, InterfaceSummary, RunSummary, Timings,
    state_hash,
};
use super::tent::momentum_residual;
use crate::fracture::records;
use crate::fracture::tips::{CrackNetwork, CrackSummary};

impl Solve<'_> {
    /// Writes the outputs of the run that brought the front to `state` and its `summary.json`
    /// into `dir`, from its `counts`, `checkpoints` and `estimate` on `scheduler`. Returns the
    /// summary and the folder; a file that cannot be written is an error after every other
    /// file was tried (no `summary.json` then). A run that writes no files ([`Solve::writes`])
    /// returns the summary only.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn finish(
        &self,
        state: &Frontier,
        options: &RunOptions,
        dir: &Path,
        counts: Counts,
        checkpoints: CheckpointSummary,
        estimate: Estimate,
        scheduler: &Options,
    ) -> Result<(RunSummary, PathBuf), EngineError> {
        let problem = self.problem;
        let config = &problem.loaded.config;
        let system = &problem.system;
        let rho = problem.material.density();
        let t_end = config.time.span();
        let (basis, width, initial) = (&self.basis, self.width, self.initial);
        let wall_time_s = counts.wall_time_s;
        let stats = counts;
        let finishing = Instant::now();
        let mut book = self.book.lock();
        book.progress.finish();
        self.history_row(state, &mut book);
        // A snapshot that cannot be written fails the run (exit 1, no summary.json) after every
        // other output is written.
        let snapshots = match self.writes() {
            true => (book.snapshots.flush(t_end)).and_then(|_| book.snapshots.finish()),
            false => Ok(()),
        };
        tracing::info!(patches = stats.tents, wall_time_s, "solve finished");
        // Said once: the ranks other than 0 of split rounds hold copies of rank 0's books.
        if self.writes() && book.unresolved as f64 > 0.01 * book.patches as f64 {
            tracing::warn!(
                unresolved_patches = book.unresolved,
                patches = book.patches,
                largest_over_tol = book.unresolved_max,
                "more than 1% of the patches were accepted above adapt.tol because refinement was at \
                 its floor (adapt.min_edge, or adapt.far_edge away from cracks): the run is less \
                 resolved than its tolerance asks"
            );
        }

        let Frontier {
            mesh,
            front,
            solution,
            ..
        } = state;
        let e = front_energy(
            mesh,
            front,
            solution,
            basis,
            system,
            scheduler.threads,
            |x| initial_state(problem, initial, x),
        );
        let energy = EnergySummary::new(rho, book.initial_energy, &e, &book.totals);
        let interface = InterfaceSummary {
            nonlinear_patches: book.nonlinear_patches,
            newton_iterations_mean: book.newton_iterations as f64
                / book.nonlinear_patches.max(1) as f64,
            newton_iterations_max: book.newton_max,
        };
        let tips = crack_tips(problem, mesh, &book.crossings, &book.fracture_events);
        let (crack_csv, crack) = tips.unzip();
        let error = problem.exact.as_ref().map(|w| {
            let e = slice_errors(mesh, solution, basis, system, t_end, w);
            ErrorSummary {
                velocity_l2_rel: e.velocity,
                stress_l2_rel: e.stress,
            }
        });
        let fracture = problem.fracture.as_ref().map(|fracture| {
            let initial_tips = initial_tip_points(fracture, &problem.mesh);
            let lengths = config
                .fracture
                .as_ref()
                .map_or([None; 2], |f| [f.macro_length, f.short_macro_length]);
            records::summary(
                &book.fracture_events,
                (state, &front_cracks(problem, fracture, state)),
                fracture,
                (&initial_tips, lengths),
                &config.time,
            )
        });
        let (min_edge, max_edge) = mesh.edge_length_range();
        let summary = RunSummary {
            command: "run",
            config_file: problem.loaded.file.clone(),
            overrides: problem.loaded.overrides.clone(),
            vertices: mesh.vertices().len(),
            triangles: mesh.triangles().len(),
            order: config.solver.order,
            patches: book.patches,
            elements: book.elements,
            dofs_per_patch: book.dofs as f64 / book.patches.max(1) as f64,
            final_time: config.time.clock(front.min_time()),
            max_slope_ratio: book.max_slope_ratio,
            max_momentum_residual: momentum_residual(&book.totals),
            mode: if scheduler.deterministic {
                "deterministic"
            } else {
                "asynchronous"
            },
            state_hash: state_hash(front, solution, basis.len() * width),
            wall_time_s,
            patches_per_second: book.patches as f64 / wall_time_s.max(f64::MIN_POSITIVE),
            threads: scheduler.threads * self.split.as_ref().map_or(1, Split::ranks),
            ranks: self.split.as_ref().map_or(1, Split::ranks),
            distributed: None,
            peak_memory_bytes: estimate::peak_resident_bytes(),
            estimate,
            energy,
            interface,
            loading: problem.loading,
            lefm: lefm(problem, crack_csv.as_deref(), &book.history),
            crack: crack.map(|crack| CrackSummary {
                network: fracture.as_ref().map(|f| CrackNetwork {
                    branches: f.branches,
                    total_length: f.total_length,
                    first_branching_time: f.first_branching_time,
                    first_branching_distance: f.first_branching_distance,
                    max_branch_speed_over_c_r: crack.max_speed_over_c_r,
                }),
                ..crack
            }),
            fracture,
            error,
            snapshots: book.snapshots.written().to_vec(),
            refinements: book.refinements,
            rejected_patches: book.rejected,
            unresolved_patches: book.unresolved,
            unresolved_max: book.unresolved_max,
            coarsenings: book.coarsenings,
            events: stats.events,
            rounds: stats.rounds,
            checkpoint: checkpoints,
            timings: Timings {
                events_s: stats.events_s,
                waiting_s: stats.waiting_s,
                ..book.timings
            },
            min_edge,
            max_edge,
        };
        if !self.writes() {
            return Ok((summary, dir.to_path_buf()));
        }
        let mut written = vec![
            snapshots,
            write_output(dir, "history.csv", book.history.as_bytes()).map(drop),
        ];
        if config.output.png {
            plot::write_history_png(dir, &book.history);
        }
        written.push(write_probes(problem, dir, &mut book.samples));
        if let Some(csv) = crack_csv {
            written.push(write_crack_tips(problem, dir, &csv));
        }
        written.push(self.write_fracture(state, &book.fracture_events, dir));
        written.push(self.write_trace(options));
        write_summary(dir, written, summary, finishing)
    }
}

/// The end of a run's outputs: when every file of `written` was written, adds the time since
/// `finishing` to the summary's output time and writes `summary.json` into `dir`; returns the
/// summary and the folder. Otherwise the first failure, the others logged (no `summary.json`).
pub(crate) fn write_summary(
    dir: &Path,
    written: Vec<Result<(), EngineError>>,
    mut summary: RunSummary,
    finishing: Instant,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let mut failures = written.into_iter().filter_map(Result::err);
    if let Some(first) = failures.next() {
        for e in failures {
            tracing::error!("not written either: {e}");
        }
        return Err(first);
    }
    summary.timings.output_s += finishing.elapsed().as_secs_f64();
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    write_output(dir, "summary.json", json.as_bytes())?;
    Ok((summary, dir.to_path_buf()))
}
