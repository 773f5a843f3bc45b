//! `sdg run`: the SDG solve, tents pitched and solved by the scheduler's workers.
//!
//! Each worker owns a [`PatchSolver`] (its scratch memory). A tent pitches on the shared front,
//! solves its patch and hands a [`PatchReport`] to the bookkeeping (`Book`), which sums energy
//! terms, cuts snapshots and notices when the whole front has passed a milestone time: a
//! snapshot is then complete, or a history row is due. History rows integrate the energy over the
//! whole front, so they run as scheduler events over every vertex: with no tent in flight.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use parking_lot::Mutex;

use sdg_mesh::{Front, Mesh, Pitcher, TagId, Tent, TriangleId};
use sdg_scheduler::{Changed, Events, Lease, Region, VertexId, Work};
use sdg_solver::crack::Crossing;
use sdg_solver::element::{FrontSolution, Geometry};
use sdg_solver::norms::{front_energy, initial_energy, slice_errors};
use sdg_solver::patch::{Initial, InterfaceSample, Newton, PatchReport, PatchSolver};
use sdg_solver::system::{MAX_FIELDS, State};

use crate::adapt::Adapt;
use crate::error::EngineError;
use crate::estimate::{self, Estimate};
use crate::frontier::{Coarsening, Frontier, refinement_edge_length};
use crate::output::write_atomic;
use crate::plot;
use crate::problem::Problem;
use crate::progress::Progress;
use crate::run::{RunOptions, scheduler_error};
use crate::snapshot::Snapshots;
use crate::trace::{self, Tracer};

mod adaptivity;
mod book;
mod checkpoint;
mod crack_output;
mod interface_output;
mod live;
mod network;
mod propagation;
mod summary;

use adaptivity::{coarsening_region, extension_region, refine_to_max_edge, refinement_region};
use book::{Book, Milestone, Milestones};
pub use checkpoint::Control;
use checkpoint::Counts;
pub use crack_output::{CrackNetwork, CrackSummary};
use live::Intervention;
pub use live::{Live, solve_job_with};
use propagation::Extension;
pub use propagation::FractureSummary;
use summary::state_hash;
pub use summary::{
    CheckpointSummary, EnergySummary, ErrorSummary, InterfaceSummary, RunSummary, Timings,
};

/// The read-only context and the bookkeeping of a solve.
struct Solve<'a> {
    problem: &'a Problem,
    adapt: Option<Adapt>,
    /// Triangles a vertex star may have: the patch solvers' capacity.
    max_star: usize,
    /// Worker threads: events that integrate over the whole front use them all.
    threads: usize,
    /// No split for crack alignment makes a piece of an edge shorter than this, m:
    /// `fracture.min_piece`, by default `adapt.min_edge`, or without adaptivity a quarter of the
    /// initial mesh's shortest edge (cracks running through ever smaller triangles would
    /// otherwise shrink the tents without bound).
    min_edge: f64,
    /// `output.snapshot_times` on the run's own clock (s since `time.start`).
    snapshot_times: Vec<f64>,
    /// `Book::energy_max` as bits, read by tents without the book's lock.
    energy_reference: AtomicU64,
    initial: Initial<'a>,
    /// Basis of every element (each worker's solver has the same).
    basis: sdg_solver::basis::Basis,
    book: Mutex<Book>,
    /// The change [`solve_job_with`] applies once, until its milestone passes.
    intervention: Mutex<Option<Intervention>>,
    /// Requests from outside (signals) and the run's own checkpoint and stop times.
    control: Arc<Control>,
    /// When the wall-time limit is up: the run checkpoints and stops, and why.
    deadline: Option<(Instant, String)>,
    /// When the solve started, and when the next checkpoint by wall time is due
    /// (`checkpoint.every_wall_s`), ns after it; `u64::MAX` for none.
    started: Instant,
    next_wall_checkpoint_ns: AtomicU64,
    /// Records every tent and event with `--trace`.
    tracer: Option<Tracer>,
}

/// The scaled initial state at `x`.
fn initial_state(problem: &Problem, initial: Initial, x: [f64; 2]) -> State {
    match initial {
        Initial::Wave(w) => problem.system.to_scaled(&w.state(x, 0.0)),
        Initial::Rest => [0.0; MAX_FIELDS],
    }
}

/// A patch whose outflow energy exceeds this multiple of the most energy the body has held
/// (initial energy plus boundary work, the patch's own included) has blown up: the scheme's
/// upwind fluxes only ever dissipate.
const BLOW_UP: f64 = 10.0;

impl Solve<'_> {
    /// What is wrong with a solved patch's `report`, if anything: a non-finite value or an
    /// energy blow-up ([`BLOW_UP`]).
    fn guard(&self, report: &PatchReport) -> Option<String> {
        let values = [
            ("energy_in", report.energy_in),
            ("energy_out", report.energy_out),
            ("boundary_work", report.boundary_work),
            ("interface_work", report.interface_work),
            ("friction_dissipation", report.friction_dissipation),
            ("fracture_work", report.fracture_work),
            ("dissipation", report.dissipation),
            ("momentum_residual", report.momentum_residual),
            ("cohesive_mismatch", report.cohesive_mismatch),
        ];
        if let Some((name, value)) = values.iter().find(|(_, v)| !v.is_finite()) {
            return Some(format!("{name} is {value} (a non-finite value)"));
        }
        let held = f64::from_bits(self.energy_reference.load(Ordering::Relaxed))
            + report.boundary_work.max(0.0);
        let rho = self.problem.material.density();
        (report.energy_out > BLOW_UP * held).then(|| {
            format!(
                "energy blow-up: the patch carries {:e} J/m out, more than {BLOW_UP} times the \
                 {:e} J/m the body has held",
                rho * report.energy_out,
                rho * held
            )
        })
    }
}

impl Solve<'_> {
    /// Runs the event `action`, traced with `--trace` as one that holds the whole state.
    fn traced<T>(&self, action: impl FnOnce() -> T) -> T {
        match &self.tracer {
            Some(tracer) => tracer.event(action),
            None => action(),
        }
    }

    /// Runs the event `action` on `state`, which changes the mesh only around the vertices it
    /// offers (refinement, crack extension; with `coarsening`, the coarsening of that vertex,
    /// which the last vertex may replace), traced with `--trace` as a regional event.
    fn traced_region(
        &self,
        state: &mut Frontier,
        coarsening: Option<VertexId>,
        action: impl FnOnce(&mut Frontier) -> Changed,
    ) -> Changed {
        let Some(tracer) = &self.tracer else {
            return action(state);
        };
        let (begun, count) = (tracer.begin_region(), state.mesh.vertices().len());
        let changed = action(state);
        let removed = coarsening.filter(|_| state.mesh.vertices().len() < count);
        tracer.end_region(begun, &state.mesh, &changed.offer, removed);
        changed
    }

    /// [`Work::tent`] without its trace.
    fn solve_tent(
        &self,
        lease: &mut Lease<'_, Frontier>,
        solver: &mut PatchSolver,
        v: VertexId,
    ) -> Result<(f64, Outcome), EngineError> {
        let state = lease.state();
        let (mesh, front) = (&state.mesh, &state.front);
        let star = mesh.vertex_triangles(v);
        if star.len() > self.max_star {
            return Err(EngineError::Runtime(format!(
                "vertex {v} has {} triangles, more than the {} the patch solvers hold",
                star.len(),
                self.max_star
            )));
        }
        if let Some(adapt) = &self.adapt
            && let Some(outcome) = self.try_coarsening(adapt, state, solver, v)
        {
            return Ok((front.time(v), outcome));
        }
        let pitching = Instant::now();
        let t_new = state.pitcher.pole_height(mesh, front, v).ok_or_else(|| {
            EngineError::Runtime(format!("vertex {v} was claimed but cannot be pitched"))
        })?;
        let pitching_s = pitching.elapsed().as_secs_f64();
        let tent = Tent {
            vertex: v,
            t_old: front.time(v),
            t_new,
        };
        solver.prepare(mesh, front, &tent, &state.solution);
        // The claim keeps the star as it is while events run elsewhere.
        let solved = lease.unlocked(|| solver.solve_prepared(&self.problem.boundary, self.initial));
        let state = lease.state();
        let (mesh, front) = (&state.mesh, &state.front);
        let star = mesh.vertex_triangles(v);
        let report = match solved {
            Ok(report) => report,
            Err(failure) => {
                // Not converged: refine around the vertex when adaptivity can, else stop.
                let star: Vec<_> = self
                    .adapt
                    .iter()
                    .flat_map(|adapt| {
                        star.iter()
                            .filter(|&&t| self.may_refine(adapt, state, t))
                            .map(|&t| (t, mesh.triangles()[t as usize]))
                    })
                    .collect();
                let [x, y] = mesh.vertex(v);
                tracing::debug!(
                    vertex = v,
                    x,
                    y,
                    t = tent.t_old,
                    %failure,
                    refine = star.len(),
                    "patch not converged"
                );
                if star.is_empty() {
                    return Err(EngineError::Runtime(format!(
                        "the patch of vertex {v} at ({x:e}, {y:e}) m, t = {:e} s: {failure}",
                        self.problem.loaded.config.time.clock(tent.t_old)
                    )));
                }
                return Ok((tent.t_old, Outcome::Rejected { star }));
            }
        };
        if let Some(quantity) = self.guard(&report) {
            let [x, y] = mesh.vertex(v);
            self.control.fail(format!(
                "the patch of vertex {v} at ({x:e}, {y:e}) m, t = {:e} s: {quantity}",
                self.problem.loaded.config.time.clock(tent.t_old)
            ));
            return Ok((tent.t_old, Outcome::Failed));
        }
        let mut unresolved = None;
        if let Some(adapt) = &self.adapt {
            let area: f64 = star.iter().map(|&t| mesh.area(t)).sum();
            let eta = self.indicator(adapt, &report, area * (t_new - tent.t_old) / 3.0);
            let at_tip = state.tips[v as usize].is_some();
            // Above the tolerance the star is refined, away from cracks down to
            // `adapt.far_edge`; at a crack tip the elements whose refinement edge exceeds
            // `adapt.tip_edge`.
            let coarse = |t: TriangleId| {
                let edge = refinement_edge_length(mesh, t);
                (eta > adapt.tol && (edge >= 2.0 * adapt.far_edge || state.near_crack(t)))
                    || (at_tip && edge > adapt.tip_edge)
            };
            if !state.insists(v) && (eta > adapt.tol || at_tip) {
                let star = star
                    .iter()
                    .filter(|&&t| coarse(t) && self.may_refine(adapt, state, t))
                    .map(|&t| (t, mesh.triangles()[t as usize]))
                    .collect::<Vec<_>>();
                if !star.is_empty() {
                    tracing::debug!(
                        vertex = v,
                        eta,
                        bulk = report.dissipation,
                        cohesive = report.cohesive_mismatch,
                        at_tip,
                        "patch above the tolerance or at a coarse tip"
                    );
                    return Ok((tent.t_old, Outcome::Rejected { star }));
                }
            }
            for &t in star {
                state.set_calm(t, eta < adapt.lower);
            }
            if eta > adapt.tol {
                unresolved = Some(eta / adapt.tol);
            }
        }
        solver.commit(&state.solution);
        front.set_time(v, t_new);
        let slope = star
            .iter()
            .map(|&t| state.pitcher.c_max() * front.slope(mesh, t))
            .fold(0.0, f64::max);
        let extension =
            self.problem.fracture.as_ref().and_then(|fracture| {
                self.extension(fracture, state, solver, v, [tent.t_old, t_new])
            });
        let outcome = Outcome::Accepted {
            t_old: tent.t_old,
            t_new,
            pitching_s,
            report,
            interface: self.interface_records(mesh, solver),
            extension,
            unresolved,
            slope,
        };
        Ok((t_new, outcome))
    }
}

/// The largest momentum imbalance of an element in `totals`, relative to the largest momentum
/// flux through the faces of any element (0 when nothing moved): an element at rest, whose
/// fluxes are round-off, does not count as a failure of conservation.
fn momentum_residual(totals: &PatchReport) -> f64 {
    if totals.momentum_flux > 0.0 {
        totals.momentum_imbalance / totals.momentum_flux
    } else {
        0.0
    }
}

/// When a run that starts now must stop: at `limits.max_wall_time_s` or `--max-wall-time`
/// (`max_wall_time_s`), the earlier; with the reason it stops.
fn deadline(limit_s: f64, max_wall_time_s: Option<f64>) -> Option<(Instant, String)> {
    let (seconds, name) = match max_wall_time_s {
        Some(s) if s < limit_s => (s, "--max-wall-time"),
        _ => (limit_s, "limits.max_wall_time_s"),
    };
    let at = Instant::now().checked_add(Duration::try_from_secs_f64(seconds).ok()?)?;
    Some((at, format!("{name} = {seconds} s is up")))
}

impl Solve<'_> {
    /// Writes what a run that stops before the end has produced so far: the history up to now
    /// (a row for the front as it is), the probes, the crack tips crossed so far and the
    /// fracture outputs of the front as it is; complete snapshots are already written. Each
    /// is tried whatever became of the others (the run is failing or stopping already: a
    /// full disk may still take the small files); failures are logged.
    fn write_partial_outputs(&self, state: &Frontier, dir: &Path) {
        let config = &self.problem.loaded.config;
        let mut book = self.book.lock();
        book.progress.finish();
        let warn = |what: &str, result: Result<(), EngineError>| {
            if let Err(e) = result {
                tracing::error!("{what} of the stopped run not written: {e}");
            }
        };
        warn("a snapshot", book.snapshots.finish());
        self.history_row(state, &mut book);
        warn(
            "history.csv",
            write_atomic(dir, "history.csv", book.history.as_bytes()).map(drop),
        );
        if config.output.png {
            plot::write_history_png(dir, &book.history);
        }
        if let Some((csv, _)) = self.crack_tips(&state.mesh, &book) {
            warn("crack_tips.csv", self.write_crack_tips(dir, &csv));
        }
        warn(
            "the crack files",
            self.write_fracture(state, &book.fracture_events, dir),
        );
        warn("interface.csv", self.write_probes(dir, &mut book));
    }

    /// With `[fracture]`: `events.csv` (`events`), `cracks.csv` and, with `output.png`,
    /// `crack_path.png` and `crack_zoom.png` of the crack edges on the front of `state`.
    fn write_fracture(
        &self,
        state: &Frontier,
        events: &[propagation::FractureEvent],
        dir: &Path,
    ) -> Result<(), EngineError> {
        let Some(fracture) = &self.problem.fracture else {
            return Ok(());
        };
        let config = &self.problem.loaded.config;
        write_atomic(
            dir,
            "events.csv",
            propagation::events_csv(events, &config.time).as_bytes(),
        )?;
        let cracks = front_cracks(self.problem, fracture, state);
        if config.output.png {
            let time = config.time.clock(state.front.min_time());
            let fork = (config.fracture.as_ref())
                .and_then(|f| f.macro_length)
                .and_then(|length| {
                    let tips = initial_tip_points(fracture, &self.problem.mesh);
                    propagation::macro_fork(&state.mesh, fracture, events, &cracks, length, &tips)
                });
            propagation::write_crack_path_png(
                dir,
                &state.mesh,
                &cracks,
                fracture.tag,
                time,
                fork.map(|f| f.point),
            );
        }
        let csv = propagation::cracks_csv(&state.mesh, &cracks, events);
        write_atomic(dir, "cracks.csv", csv.as_bytes())?;
        Ok(())
    }

    /// `crack_tips.csv` and its summary from the tip crossings recorded so far: per crack
    /// branch with `[fracture]` (the crossings of one tag would mix the tips of its branches),
    /// else per cohesive or damage interface tag; `None` when the run tracks no crack tips.
    fn crack_tips(&self, mesh: &Mesh, book: &Book) -> Option<(String, CrackSummary)> {
        let c_r = self.problem.material.c_r();
        let time = &self.problem.loaded.config.time;
        if self.problem.fracture.is_some() {
            let crossings: Vec<Crossing> = book.crossings.iter().map(|&(_, c)| c).collect();
            let branches = propagation::branch_tips(&book.fracture_events, &crossings);
            Some(crack_output::tips_csv("branch", &branches, c_r, time))
        } else if self.problem.interfaces.any_cohesive() {
            let names = mesh.tag_names();
            let crossings: Vec<_> = book
                .crossings
                .iter()
                .map(|(tag, c)| {
                    let name = tag.map_or("untagged", |t| names[t as usize].as_str());
                    (name.to_string(), *c)
                })
                .collect();
            Some(crack_output::write(&crossings, c_r, time))
        } else {
            None
        }
    }

    /// Writes `crack_tips.csv` (its text `csv`) and, with `output.png`, its picture: the branch
    /// tips' speeds with `[fracture]`, else the tips against LEFM in the normalized units of
    /// `[loading]` up to the end time.
    fn write_crack_tips(&self, dir: &Path, csv: &str) -> Result<(), EngineError> {
        let problem = self.problem;
        let time = &problem.loaded.config.time;
        write_atomic(dir, "crack_tips.csv", csv.as_bytes())?;
        if problem.loaded.config.output.png && problem.fracture.is_some() {
            plot::write_tip_speed_png(dir, csv, problem.material.c_r());
        } else if problem.loaded.config.output.png {
            let normalization = problem.loading.map(|l| plot::Normalization {
                tau: l.scales.tau,
                c_r: l.scales.c_r,
                arrival: time.clock(l.arrival_time),
                end: time.end,
            });
            plot::write_crack_png(dir, csv, normalization);
        }
        Ok(())
    }

    /// Writes the trace of `--trace`.
    fn write_trace(&self, options: &RunOptions) -> Result<(), EngineError> {
        match (&self.tracer, &options.trace) {
            (Some(tracer), Some(path)) => tracer.write(path),
            _ => Ok(()),
        }
    }

    /// Writes `interface.csv` when probes are configured.
    fn write_probes(&self, dir: &std::path::Path, book: &mut Book) -> Result<(), EngineError> {
        let probes = &self.problem.probes;
        if !probes.is_empty() {
            let time = &self.problem.loaded.config.time;
            let text = interface_output::csv(probes, &mut book.samples, time);
            write_atomic(dir, "interface.csv", text.as_bytes())?;
        }
        Ok(())
    }

    /// Discrete energy of the initial data on the triangle with `corners` (scaled units).
    fn initial_energy(&self, corners: [[f64; 2]; 3]) -> f64 {
        initial_energy(
            &self.problem.system,
            self.problem.loaded.config.solver.order,
            corners,
            |x| initial_state(self.problem, self.initial, x),
        )
    }
}

/// What one tent hands to the bookkeeping.
#[derive(Debug)]
enum Outcome {
    /// The patch is stored and the vertex advanced.
    Accepted {
        t_old: f64,
        t_new: f64,
        /// Wall time computing the tent height, s.
        pitching_s: f64,
        report: PatchReport,
        interface: InterfaceRecords,
        /// The crack tip at the vertex extends.
        extension: Option<Extension>,
        /// The indicator over the tolerance when it was above and no star triangle could be
        /// bisected.
        unresolved: Option<f64>,
        /// The steepest new front facet of the star relative to causality, `c_max |grad t|`.
        slope: f64,
    },
    /// The indicator rejected the patch: nothing advanced; these star triangles (with their
    /// corners, to notice a change) are to be bisected.
    Rejected {
        star: Vec<(TriangleId, [VertexId; 3])>,
    },
    /// The patch failed a guard (a non-finite value, an energy blow-up): nothing is stored,
    /// and the run stops with a checkpoint of the front before it.
    Failed,
    /// The tent's vertex is to be removed by the coarsening patch solved in its place.
    Coarsen {
        coarsening: Box<Coarsening>,
        report: PatchReport,
        interface: InterfaceRecords,
    },
}

/// What a patch's interface faces add to the outputs: `samples` are the interface probes on
/// it, `cuts` its faces' cuts by snapshot planes, `crossings` its cohesive faces'
/// crack-tracking crossings with their edge's tag.
#[derive(Debug, Default)]
struct InterfaceRecords {
    samples: Vec<(usize, InterfaceSample)>,
    cuts: Vec<interface_output::Cut>,
    crossings: Vec<(Option<TagId>, Crossing)>,
}

impl InterfaceRecords {
    /// Adds the records to the bookkeeping.
    fn add_to(self, book: &mut Book) {
        book.samples.extend(self.samples);
        book.crossings.extend(self.crossings);
        for (time, xy, values) in self.cuts {
            book.snapshots.add_interface_segment(time, xy, values);
        }
    }

    fn is_empty(&self) -> bool {
        self.samples.is_empty() && self.cuts.is_empty() && self.crossings.is_empty()
    }
}

impl Solve<'_> {
    /// The interface records of the patch `solver` just solved on `mesh`.
    fn interface_records(
        &self,
        mesh: &sdg_mesh::Mesh,
        solver: &mut PatchSolver,
    ) -> InterfaceRecords {
        InterfaceRecords {
            samples: interface_output::sample(&self.problem.probes, mesh, solver),
            cuts: interface_output::snapshot_cuts(
                &self.snapshot_times,
                self.problem.system.c_ref(),
                solver,
            ),
            crossings: solver
                .crack_crossings()
                .iter()
                .map(|c| (mesh.edges()[c.edge as usize].tag, *c))
                .collect(),
        }
    }
}

impl<'a> Solve<'a> {
    /// Queues the extension of the tip at `v` as a regional event.
    fn push_extension(&'a self, events: &Events<'a, Frontier>, v: VertexId, extension: Extension) {
        events.push_regional(
            Box::new(move |state: &Frontier| extension_region(&state.mesh, v)),
            Box::new(move |state: &mut Frontier, region: &Region<'_>| {
                self.traced_region(state, None, |state| {
                    self.extend(state, region, v, &extension)
                })
            }),
        );
    }
}

impl<'a> Work<'a> for Solve<'a> {
    type State = Frontier;
    type Scratch = PatchSolver;
    type Outcome = Outcome;
    type Error = EngineError;

    fn tent(
        &self,
        lease: &mut Lease<'_, Frontier>,
        solver: &mut PatchSolver,
        v: VertexId,
        _: &Events<'a, Frontier>,
    ) -> Result<(f64, Outcome), EngineError> {
        let Some(tracer) = &self.tracer else {
            return self.solve_tent(lease, solver, v);
        };
        let begun = tracer.begin(&lease.state().mesh, v);
        let result = self.solve_tent(lease, solver, v);
        if let Ok((_, outcome)) = &result {
            let (kind, changed) = match outcome {
                Outcome::Accepted { report, .. } if report.newton_iterations > 0 => {
                    (trace::Kind::Newton, true)
                }
                Outcome::Accepted { .. } => (trace::Kind::Patch, true),
                Outcome::Coarsen { .. } => (trace::Kind::Coarsen, false),
                Outcome::Rejected { .. } | Outcome::Failed => (trace::Kind::Rejected, false),
            };
            tracer.end(begun, v, kind, changed);
        }
        result
    }

    fn record(
        &'a self,
        state: &Frontier,
        v: VertexId,
        o: Outcome,
        events: &Events<'a, Frontier>,
    ) -> Result<(), EngineError> {
        let (t_old, t_new, pitching_s, report, slope) = match o {
            Outcome::Accepted {
                t_old,
                t_new,
                pitching_s,
                report,
                interface,
                extension,
                unresolved,
                slope,
            } => {
                if let Some(ratio) = unresolved {
                    let mut book = self.book.lock();
                    book.unresolved += 1;
                    book.unresolved_max = book.unresolved_max.max(ratio);
                }
                if !interface.is_empty() {
                    let mut book = self.book.lock();
                    let started = Instant::now();
                    interface.add_to(&mut book);
                    book.timings.output_s += started.elapsed().as_secs_f64();
                }
                if let Some(extension) = extension {
                    self.push_extension(events, v, extension);
                }
                if self.problem.fracture.is_some() {
                    // The tent changed the front over the triangles of its neighbours' stars.
                    for &u in state.mesh.vertex_neighbors(v) {
                        if let Some(retry) = Extension::retry(state, u) {
                            self.push_extension(events, u, retry);
                        }
                    }
                }
                (t_old, t_new, pitching_s, report, slope)
            }
            Outcome::Coarsen {
                coarsening,
                report,
                interface,
            } => {
                let m = coarsening.vertex;
                events.push_regional(
                    Box::new(move |state: &Frontier| coarsening_region(&state.mesh, m)),
                    Box::new(move |state: &mut Frontier, _: &Region<'_>| {
                        self.traced_region(state, Some(m), |state| {
                            self.coarsen(state, &coarsening, &report, interface)
                        })
                    }),
                );
                return Ok(());
            }
            Outcome::Failed => return Ok(()),
            Outcome::Rejected { star } => {
                let mut book = self.book.lock();
                book.patches += 1;
                book.rejected += 1;
                let at = state.mesh.vertex(v);
                let triangles: Vec<TriangleId> = star.iter().map(|&(t, _)| t).collect();
                events.push_regional(
                    Box::new(move |state: &Frontier| {
                        refinement_region(&state.mesh, triangles.iter().copied())
                    }),
                    Box::new(move |state: &mut Frontier, region: &Region<'_>| {
                        self.traced_region(state, None, |state| {
                            self.refine(state, region, v, at, &star)
                        })
                    }),
                );
                return Ok(());
            }
        };
        let mesh = &state.mesh;
        let mut guard = self.book.lock();
        let book = &mut *guard;
        self.add_patch(book, &report);
        book.timings.pitching_s += pitching_s;
        book.max_slope_ratio = book.max_slope_ratio.max(slope);
        let started = Instant::now();
        // The star's elements span the old and new front times of `v` and its neighbours.
        let (lo, hi) = mesh
            .vertex_neighbors(v)
            .iter()
            .map(|&w| state.front.time(w))
            .fold((t_old, t_new), |(lo, hi), t| (lo.min(t), hi.max(t)));
        if book.snapshots.pending_within(lo, hi) {
            self.add_to_snapshots(book, &state.solution, mesh.vertex_triangles(v));
        }
        book.progress.advance(t_new - t_old, book.patches);
        let mut passed = std::mem::take(&mut book.passed);
        book.milestones.advance(t_old, t_new, &mut passed);
        for &(t, _) in passed.iter().filter(|p| p.1 == Milestone::Snapshot) {
            book.snapshots.flush(t)?;
        }
        book.timings.output_s += started.elapsed().as_secs_f64();
        // One row for however many history milestones passed at once.
        if passed.iter().any(|p| p.1 == Milestone::History) {
            events.push_now(Box::new(move |state: &mut Frontier| {
                self.traced(|| self.history_row(state, &mut self.book.lock()));
                Changed::default()
            }));
        }
        if passed.iter().any(|p| p.1 == Milestone::Checkpoint) {
            self.control.checkpoint();
        }
        if passed.iter().any(|p| p.1 == Milestone::Intervention) {
            events.push_now(Box::new(move |state: &mut Frontier| {
                self.traced(|| self.intervene(state))
            }));
        }
        passed.clear();
        book.passed = passed;
        Ok(())
    }

    fn round(&self, serial: Duration) {
        if let Some(tracer) = &self.tracer {
            tracer.round(serial);
        }
    }

    fn pause(&self) -> bool {
        if self.control.is_pending() {
            return true;
        }
        let now = Instant::now();
        if let Some((deadline, reason)) = &self.deadline
            && now >= *deadline
        {
            self.control.stop(reason.clone());
            return true;
        }
        let due = self.next_wall_checkpoint_ns.load(Ordering::Relaxed);
        if due != u64::MAX && now.duration_since(self.started).as_nanos() >= u128::from(due) {
            self.control.checkpoint();
            return true;
        }
        false
    }
}

/// A patch solver for `problem` whose stars have at most `max_star` triangles.
fn patch_solver(problem: &Problem, max_star: usize) -> PatchSolver {
    let config = &problem.loaded.config;
    PatchSolver::new(problem.system.clone(), config.solver.order, max_star).with_interfaces(
        problem.interfaces.clone(),
        Newton {
            tol: config.solver.newton_tol,
            max_iter: config.solver.newton_max_iter,
        },
    )
}

/// What a solve starts from: the flat front at time 0 (refined to the zones' `max_edge`), with
/// crack tips, the adaptivity and the patch solvers' capacity.
struct Start {
    state: Frontier,
    adapt: Option<Adapt>,
    /// Triangles a vertex star may have.
    max_star: usize,
}

impl Start {
    fn new(problem: &Problem) -> Result<Self, EngineError> {
        let config = &problem.loaded.config;
        let mesh = &problem.mesh;
        let c_max = problem.material.max_wave_speed();
        let pitcher = Pitcher::new(mesh, c_max, config.pitch.safety, config.time.span())
            .map_err(|e| EngineError::Runtime(e.to_string()))?;
        let adapt = Adapt::new(&config.adapt, mesh, c_max, problem.material.density());
        // Crack alignment splits edges as refinement does.
        let splits = adapt.is_some() || problem.fracture.is_some();
        let pitcher = if splits {
            pitcher.for_refinement(mesh)
        } else {
            pitcher
        };
        let initial_star = (0..mesh.vertices().len() as u32)
            .map(|v| mesh.vertex_triangles(v).len())
            .max()
            .unwrap_or(0);
        // Bisection adds triangles to stars; the solvers are sized once, and refinement never
        // grows a star beyond them.
        let max_star = if splits {
            (2 * initial_star).max(12)
        } else {
            initial_star
        };
        let (n, width) = {
            let solver = PatchSolver::new(problem.system.clone(), config.solver.order, 0);
            (solver.basis().len(), solver.width())
        };
        let mut state = Frontier::new(
            mesh.clone(),
            Front::flat(mesh.vertices().len(), 0.0),
            FrontSolution::new(mesh.triangles().len(), n, width).with_edges(mesh.edges().len()),
            pitcher,
        );
        if let Some(adapt) = &adapt {
            // The config asks for what the mesh cannot give: bad input (exit 2).
            refine_to_max_edge(&mut state, adapt, max_star).map_err(|reason| {
                EngineError::Input(format!("{}: {reason}", problem.loaded.file.display()))
            })?;
        }
        if let Some(fracture) = &problem.fracture {
            state.tips = fracture.initial_tips(&state.mesh);
            state.next_branch = state.tips.iter().flatten().count() as u32;
        }
        Ok(Self {
            state,
            adapt,
            max_star,
        })
    }
}

impl Frontier {
    /// The estimate of a solve from this (initial) state on `threads`; `adapts` when
    /// refinement is on.
    fn estimate(
        &self,
        problem: &Problem,
        max_star: usize,
        threads: usize,
        adapts: bool,
    ) -> Estimate {
        let start = estimate::Start {
            mesh: &self.mesh,
            pitcher: &self.pitcher,
            solution: &self.solution,
            initial: problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave),
            new_solver: || patch_solver(problem, max_star),
        };
        estimate::solve(
            problem,
            start,
            threads,
            adapts || problem.fracture.is_some(),
        )
    }
}

/// The estimate of `sdg run` for `problem` with `options`, made as the run makes it before
/// any work (`sdg validate`).
pub fn estimate_job(problem: &Problem, options: &RunOptions) -> Result<Estimate, EngineError> {
    let start = Start::new(problem)?;
    let threads = options.scheduler(problem).threads;
    Ok(start
        .state
        .estimate(problem, start.max_star, threads, start.adapt.is_some()))
}

/// The crack edges of `state` with their damage on the front (initial cracks without a face
/// solved at their law's initial damage, 1 for other laws).
fn front_cracks(
    problem: &Problem,
    fracture: &crate::fracture::Fracture,
    state: &Frontier,
) -> Vec<propagation::CrackEdge> {
    propagation::crack_edges(
        &state.mesh,
        &state.solution,
        fracture,
        problem.loaded.config.solver.order,
        |tag| match problem.interfaces.law(tag) {
            sdg_solver::interface::Law::Damage(d) => d.initial,
            _ => 1.0,
        },
    )
}

/// The positions (m) of the tips of the initial cracks on the initial `mesh`.
fn initial_tip_points(fracture: &crate::fracture::Fracture, mesh: &Mesh) -> Vec<[f64; 2]> {
    (fracture.initial_tips(mesh).iter())
        .zip(mesh.vertices())
        .filter_map(|(tip, &p)| tip.as_ref().map(|_| p))
        .collect()
}

impl Solve<'_> {
    /// Writes a checkpoint of `state`, quiescent (no tent in flight, no event queued), once the
    /// snapshots it counts as written are on disk; counts it in `counts` and `summary`.
    fn checkpoint(
        &self,
        folder: &checkpoint::Folder,
        state: &Frontier,
        counts: &mut Counts,
        summary: &mut CheckpointSummary,
    ) -> Result<PathBuf, EngineError> {
        let config = &self.problem.loaded.config;
        let written = Instant::now();
        let mut book = self.book.lock();
        book.snapshots.finish()?;
        let path = folder.write(config, *counts, state, &book)?;
        drop(book);
        counts.written += 1;
        summary.written += 1;
        summary.write_seconds += written.elapsed().as_secs_f64();
        tracing::info!(
            checkpoint = %path.display(),
            time = config.time.clock(state.front.min_time()),
            seconds = written.elapsed().as_secs_f64(),
            "checkpoint written"
        );
        Ok(path)
    }
}

/// A resumed run whose `time.end` or `output.snapshot_times` differ from its checkpoint's: the
/// pitcher ends at the config's end (s, run clock `t_end`), the snapshots and milestones are
/// the config's after the checkpoint's front. `checkpoint` names the file in errors (exit 2).
fn extend(
    state: &mut Frontier,
    book: &mut Book,
    config: &crate::config::Config,
    t_end: f64,
    checkpoint: &Path,
) -> Result<(), EngineError> {
    let times = state.front.snapshot();
    let reached = times.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let clock = |t: f64| config.time.clock(t);
    let refuse = |reason: String| {
        EngineError::Input(format!(
            "{}: {reason}; a restart may only move the end and add snapshots after the \
             checkpoint's front, which reaches {:.6e} s in places",
            checkpoint.display(),
            clock(reached)
        ))
    };
    if t_end < reached {
        return Err(refuse(format!(
            "time.end = {:e} s is before the front",
            config.time.end
        )));
    }
    let start = config.time.start;
    (book.snapshots)
        .retime(&config.output.snapshot_times, start, reached)
        .map_err(|t| {
            refuse(format!(
                "output.snapshot_times: {t:e} s is not a snapshot of the run so far"
            ))
        })?;
    let snapshot_times: Vec<f64> = (config.output.snapshot_times.iter())
        .map(|&t| config.time.elapsed(t))
        .collect();
    book.milestones = Milestones::resumed(
        &times,
        t_end,
        &snapshot_times,
        config.checkpoint.every_sim_s,
    );
    state.pitcher.set_t_end(t_end);
    tracing::info!(
        end = config.time.end,
        "the run goes on to a new end time or snapshot times"
    );
    Ok(())
}

/// `sdg run`: solves the problem to the end time; writes `summary.json`, `history.csv` and the
/// configured snapshots. Returns the summary and the output folder.
pub fn solve_job(
    problem: &Problem,
    options: &RunOptions,
) -> Result<(RunSummary, PathBuf), EngineError> {
    run_job(problem, options, None)
}

/// [`solve_job`], with `intervention` (its time and change) applied once mid-run.
fn run_job(
    problem: &Problem,
    options: &RunOptions,
    intervention: Option<(f64, Intervention)>,
) -> Result<(RunSummary, PathBuf), EngineError> {
    let (after, intervention) = intervention.unzip();
    let config = &problem.loaded.config;
    let system = &problem.system;
    let c_max = problem.material.max_wave_speed();
    let rho = problem.material.density();
    let t_end = config.time.span();
    let snapshot_times: Vec<f64> = (config.output.snapshot_times.iter())
        .map(|&t| config.time.elapsed(t))
        .collect();
    let scheduler = options.scheduler(problem);
    let Start {
        mut state,
        adapt,
        max_star,
    } = Start::new(problem)?;
    let estimate = state.estimate(problem, max_star, scheduler.threads, adapt.is_some());
    let restored = match &options.restart {
        Some(path) => Some(checkpoint::restore(path, config)?),
        None => None,
    };
    // A restarted run has only the rest of the way before it.
    let estimate = match &restored {
        Some((_, r)) => estimate.remaining(&r.frontier.front.snapshot(), t_end),
        None => estimate,
    };
    tracing::info!(
        tents = estimate.tents,
        lower_bound = estimate.lower_bound,
        wall_time_s = estimate.wall_time_s,
        memory_bytes = estimate.memory_bytes,
        "estimate"
    );
    if options.progress {
        crate::progress::note(format_args!("estimate: {}", estimate.describe()));
    }
    if !options.force {
        estimate.check(problem)?;
    }
    let dir = options.output_dir(problem)?;
    let folder = checkpoint::Folder::new(config, &dir);
    if config.checkpoint.dir.is_some() {
        let named = format!("checkpoint.dir {}", folder.dir.display());
        crate::output::check_writable(&folder.dir, &named)?;
    }
    if let Some(trace) = &options.trace {
        crate::trace::check_path(trace)?;
    }
    folder.check_unmixed(options.restart.as_deref())?;
    // `summary.json` is written when a run finishes: an earlier run's must not stand for this
    // one should it fail or stop.
    match std::fs::remove_file(dir.join("summary.json")) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(EngineError::io(dir.join("summary.json"), e));
        }
        _ => {}
    }
    if restored.is_none() {
        let removed = crate::snapshot::remove_earlier(&dir)?;
        if removed > 0 {
            tracing::info!(removed, dir = %dir.display(), "snapshot files of an earlier run removed");
        }
    }
    let (basis, width) = {
        let solver = PatchSolver::new(system.clone(), config.solver.order, 0);
        (solver.basis().clone(), solver.width())
    };
    let initial = problem.exact.as_ref().map_or(Initial::Rest, Initial::Wave);
    let energy0 = front_energy(
        &state.mesh,
        &state.front,
        &state.solution,
        &basis,
        system,
        scheduler.threads,
        |x| initial_state(problem, initial, x),
    );
    let min_edge = problem
        .loaded
        .config
        .fracture
        .as_ref()
        .and_then(|f| f.min_piece)
        .unwrap_or_else(|| {
            adapt
                .as_ref()
                .map_or(problem.mesh.edge_length_range().0 / 4.0, |a| a.min_edge)
        });
    let solve = Solve {
        problem,
        adapt,
        max_star,
        threads: scheduler.threads,
        min_edge,
        snapshot_times: snapshot_times.clone(),
        energy_reference: AtomicU64::new(energy0.total.to_bits()),
        initial,
        basis: basis.clone(),
        book: Mutex::new(Book {
            totals: PatchReport::default(),
            patches: 0,
            rejected: 0,
            refinements: 0,
            coarsenings: 0,
            unresolved: 0,
            unresolved_max: 0.0,
            samples: Vec::new(),
            crossings: Vec::new(),
            fracture_events: Vec::new(),
            nonlinear_patches: 0,
            newton_iterations: 0,
            newton_max: 0,
            initial_energy: energy0.total,
            energy_max: energy0.total,
            elements: 0,
            dofs: 0,
            max_slope_ratio: 0.0,
            timings: Timings::default(),
            snapshots: Snapshots::on_clock(
                &config.output.snapshot_times,
                config.time.start,
                c_max,
                // Absolute, so that a restart from another working directory finds the files.
                std::path::absolute(&dir).unwrap_or_else(|_| dir.clone()),
            )
            .with_png(config.output.png)
            .with_vtu(config.output.vtu),
            milestones: Milestones::new(
                state.mesh.vertices().len(),
                t_end,
                &snapshot_times,
                config.checkpoint.every_sim_s,
                after,
            ),
            passed: Vec::new(),
            history: String::from(
                "time_s,patches,front_energy_j,kinetic_j,strain_j,boundary_work_j,dissipation_j,\
                 interface_work_j,friction_dissipation_j,fracture_energy_j,balance_residual_j\n",
            ),
            progress: Progress::new(options.progress, state.mesh.vertices().len() as f64 * t_end),
            phi: vec![0.0; basis.len()],
            values: vec![0.0; width],
            geometry: Geometry::default(),
            coefficients: vec![0.0; basis.len() * width],
        }),
        intervention: Mutex::new(intervention),
        control: options.control.clone().unwrap_or_default(),
        deadline: deadline(config.limits.max_wall_time_s, options.max_wall_time_s),
        started: Instant::now(),
        next_wall_checkpoint_ns: AtomicU64::new(u64::MAX),
        tracer: options.trace.as_ref().map(|_| Tracer::new()),
    };
    let mut counts = Counts::default();
    let restarted = match restored {
        Some((file, restored)) => {
            tracing::info!(
                checkpoint = %file.display(),
                time = config.time.clock(restored.header.time),
                "restarting"
            );
            counts = restored.counts;
            counts.written = folder.next_number(counts.written);
            state = restored.frontier;
            let mut book = restored.book;
            book.resume(&dir, config.output.vtu, basis.len(), width)?;
            if checkpoint::extends(&restored.header.config, config) {
                extend(&mut state, &mut book, config, t_end, &file)?;
            }
            let done: f64 = state.front.snapshot().iter().sum();
            book.progress =
                Progress::new(options.progress, state.mesh.vertices().len() as f64 * t_end);
            book.progress.advance(done, book.patches);
            solve
                .energy_reference
                .store(book.energy_max.to_bits(), Ordering::Relaxed);
            *solve.book.lock() = book;
            Some((file, config.time.clock(restored.header.time)))
        }
        None => {
            solve.history_row(&state, &mut solve.book.lock());
            None
        }
    };
    let _span = tracing::info_span!("solve", config = %problem.loaded.file.display()).entered();
    tracing::info!(
        threads = scheduler.threads,
        deterministic = scheduler.deterministic,
        order = config.solver.order,
        vertices = state.mesh.vertices().len(),
        "solve started"
    );
    let wall_every = Duration::try_from_secs_f64(config.checkpoint.every_wall_s).ok();
    let (restarted_from, restart_time) = restarted.unzip();
    let mut checkpoints = CheckpointSummary {
        restarted_from,
        restart_time,
        ..CheckpointSummary::default()
    };
    loop {
        let segment = Instant::now();
        if let Some(every) = wall_every {
            let due = (segment - solve.started + every).as_nanos();
            let due = u64::try_from(due).unwrap_or(u64::MAX - 1);
            solve.next_wall_checkpoint_ns.store(due, Ordering::Relaxed);
        }
        let solvers: Vec<PatchSolver> = (0..scheduler.threads)
            .map(|_| patch_solver(problem, max_star))
            .collect();
        let result = sdg_scheduler::run(&mut state, t_end, &solve, solvers, &scheduler);
        counts.wall_time_s += segment.elapsed().as_secs_f64();
        let stats = match result {
            Ok(stats) => stats,
            Err(e) => {
                solve.write_partial_outputs(&state, &dir);
                return Err(scheduler_error(e));
            }
        };
        counts.tents += stats.tents;
        counts.events += stats.events;
        counts.rounds += stats.rounds;
        counts.events_s += stats.event_time.as_secs_f64();
        counts.waiting_s += stats.wait_time.as_secs_f64();
        if !stats.paused {
            break;
        }
        // Quiescent: no tent in flight, no event queued.
        let request = solve.control.take();
        let path = match solve.checkpoint(&folder, &state, &mut counts, &mut checkpoints) {
            Ok(path) => path,
            Err(e) => {
                solve.write_partial_outputs(&state, &dir);
                return Err(match request.failure {
                    Some(failure) => EngineError::Runtime(format!(
                        "{failure}; and the checkpoint of the front before this patch failed: \
                         {e}"
                    )),
                    None => e,
                });
            }
        };
        if let Some(failure) = request.failure {
            solve.write_partial_outputs(&state, &dir);
            return Err(EngineError::Runtime(format!(
                "{failure}; the front before this patch is in checkpoint {}",
                path.display()
            )));
        }
        if let Some(reason) = request.stop {
            solve.write_partial_outputs(&state, &dir);
            return Err(EngineError::Checkpointed {
                reason,
                time: config.time.clock(state.front.min_time()),
                checkpoint: path,
            });
        }
    }
    if config.checkpoint.at_end
        && let Err(e) = solve.checkpoint(&folder, &state, &mut counts, &mut checkpoints)
    {
        solve.write_partial_outputs(&state, &dir);
        return Err(e);
    }
    let wall_time_s = counts.wall_time_s;
    let stats = counts;
    let finishing = Instant::now();
    let mut book = solve.book.lock();
    book.progress.finish();
    solve.history_row(&state, &mut book);
    // A snapshot that cannot be written fails the run (exit 1, no summary.json) after every
    // other output is written.
    let snapshots = book
        .snapshots
        .flush(t_end)
        .and_then(|_| book.snapshots.finish());
    tracing::info!(patches = stats.tents, wall_time_s, "solve finished");
    if book.unresolved as f64 > 0.01 * book.patches as f64 {
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
    } = &state;
    let e = front_energy(
        mesh,
        front,
        solution,
        &basis,
        system,
        scheduler.threads,
        |x| initial_state(problem, initial, x),
    );
    let initial_j = rho * book.initial_energy;
    let work = rho * book.totals.boundary_work;
    let dissipation = rho * book.totals.dissipation;
    let interface_work = rho * book.totals.interface_work;
    let final_j = rho * e.total;
    let energy = EnergySummary {
        initial: initial_j,
        final_kinetic: rho * e.kinetic,
        final_strain: rho * e.strain,
        r#final: final_j,
        boundary_work: work,
        dissipation,
        interface_work,
        friction_dissipation: rho * book.totals.friction_dissipation,
        fracture_energy: rho * book.totals.fracture_work,
        balance_residual_rel: (initial_j + work - final_j - dissipation - interface_work)
            / (initial_j + work.abs()).max(f64::MIN_POSITIVE),
    };
    let interface = InterfaceSummary {
        nonlinear_patches: book.nonlinear_patches,
        newton_iterations_mean: book.newton_iterations as f64
            / book.nonlinear_patches.max(1) as f64,
        newton_iterations_max: book.newton_max,
    };
    let (crack_csv, crack) = solve.crack_tips(mesh, &book).unzip();
    let error = problem.exact.as_ref().map(|w| {
        let e = slice_errors(mesh, solution, &basis, system, t_end, w);
        ErrorSummary {
            velocity_l2_rel: e.velocity,
            stress_l2_rel: e.stress,
        }
    });
    let fracture = problem.fracture.as_ref().map(|fracture| {
        let initial_tips = initial_tip_points(fracture, &problem.mesh);
        let macro_length = config.fracture.as_ref().and_then(|f| f.macro_length);
        propagation::summary(
            &book.fracture_events,
            (&state, &front_cracks(problem, fracture, &state)),
            fracture,
            (&initial_tips, macro_length),
            &config.time,
        )
    });
    let (min_edge, max_edge) = mesh.edge_length_range();
    let mut summary = RunSummary {
        command: "run",
        config_file: problem.loaded.file.clone(),
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
        threads: scheduler.threads,
        peak_memory_bytes: estimate::peak_resident_bytes(),
        estimate,
        energy,
        interface,
        loading: problem.loading,
        crack: crack.map(|crack| CrackSummary {
            network: fracture.as_ref().map(|f| CrackNetwork {
                branches: f.branches,
                total_length: f.total_length,
                first_branching_time: f.first_branching_time,
                first_branching_distance: f.first_branching_distance,
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
    let mut written = vec![
        snapshots,
        write_atomic(&dir, "history.csv", book.history.as_bytes()).map(drop),
    ];
    if config.output.png {
        plot::write_history_png(&dir, &book.history);
    }
    written.push(solve.write_probes(&dir, &mut book));
    if let Some(csv) = crack_csv {
        written.push(solve.write_crack_tips(&dir, &csv));
    }
    written.push(solve.write_fracture(&state, &book.fracture_events, &dir));
    written.push(solve.write_trace(options));
    let mut failures = written.into_iter().filter_map(Result::err);
    if let Some(first) = failures.next() {
        for e in failures {
            tracing::error!("not written either: {e}");
        }
        return Err(first);
    }
    summary.timings.output_s += finishing.elapsed().as_secs_f64();
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    write_atomic(&dir, "summary.json", json.as_bytes())?;
    Ok((summary, dir))
}
