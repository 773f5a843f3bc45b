//! The solve as the scheduler's work: tents, their records and the events they queue.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use sdg_mesh::TriangleId;
use sdg_scheduler::{Changed, Events, Lease, Region, Tried, VertexId, Work};
use sdg_solver::patch::PatchSolver;

use crate::error::EngineError;
use crate::frontier::Frontier;
use crate::trace::{self};

use super::book::Milestone;
use super::context::Solve;
use super::tent::Outcome;
use crate::adaptivity::policy::{coarsening_region, extension_region, refinement_region};
use crate::fracture::propagation::Extension;

/// When a run that starts now must stop: at `limits.max_wall_time_s` or `--max-wall-time`
/// (`max_wall_time_s`), the earlier; with the reason it stops.
pub(crate) fn deadline(limit_s: f64, max_wall_time_s: Option<f64>) -> Option<(Instant, String)> {
    let (seconds, name) = match max_wall_time_s {
        Some(s) if s < limit_s => (s, "--max-wall-time"),
        _ => (limit_s, "limits.max_wall_time_s"),
    };
    let at = Instant::now().checked_add(Duration::try_from_secs_f64(seconds).ok()?)?;
    Some((at, format!("{name} = {seconds} s is up")))
}

impl<'a> Solve<'a> {
    /// Queues the extension of the tip at `v` as a regional event.
    pub(crate) fn push_extension(
        &'a self,
        events: &Events<'a, Frontier>,
        v: VertexId,
        extension: Extension,
    ) {
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

    fn settle(&self, state: &Frontier, v: VertexId, o: &mut Outcome) {
        let Outcome::Accepted {
            t_old,
            t_new,
            retries,
            span,
            extension,
            ..
        } = o
        else {
            return;
        };
        if let Some(fracture) = &self.problem.fracture
            && extension.is_none()
        {
            // A tip's test over a length reads the front beyond the star as the tents left it.
            *extension = self.settled_extension(fracture, state, v, [*t_old, *t_new]);
        }
        // The star's elements span the old and new front times of `v` and its neighbours.
        let neighbours = state.mesh.vertex_neighbors(v);
        *span = (neighbours.iter())
            .map(|&w| state.front.time(w))
            .fold((*t_old, *t_new), |(lo, hi), t| (lo.min(t), hi.max(t)));
        if self.problem.fracture.is_some() {
            // The tent changed the front over the triangles of its neighbours' stars.
            retries.extend(
                (neighbours.iter()).filter_map(|&u| Extension::retry(state, u).map(|e| (u, e))),
            );
        }
    }

    fn record(
        &'a self,
        state: &Frontier,
        v: VertexId,
        o: Outcome,
        events: &Events<'a, Frontier>,
    ) -> Result<(), EngineError> {
        let (t_old, t_new, pitching_s, report, slope, span) = match o {
            Outcome::Accepted {
                t_old,
                t_new,
                pitching_s,
                report,
                interface,
                extension,
                retries,
                span,
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
                for (u, retry) in retries {
                    self.push_extension(events, u, retry);
                }
                (t_old, t_new, pitching_s, report, slope, span)
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
        // Timed only when there is output to make: deterministic rounds record their tents on
        // one thread, and two clock reads per tent are a measurable part of that.
        if self.writes() && book.snapshots.pending_within(span.0, span.1) {
            let started = Instant::now();
            self.add_to_snapshots(book, &state.solution, mesh.vertex_triangles(v));
            book.timings.output_s += started.elapsed().as_secs_f64();
        }
        book.progress.advance(t_new - t_old, book.patches);
        let mut passed = std::mem::take(&mut book.passed);
        book.milestones.advance(t_old, t_new, &mut passed);
        let snapshots = passed.iter().filter(|p| p.1 == Milestone::Snapshot);
        for &(t, _) in snapshots.filter(|_| self.writes()) {
            let started = Instant::now();
            book.snapshots.flush(t)?;
            book.timings.output_s += started.elapsed().as_secs_f64();
        }
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

    fn settled(&self, busy: Duration) {
        if let Some(tracer) = &self.tracer {
            tracer.settled(busy);
        }
    }

    fn round(&self, serial: Duration) {
        if let Some(tracer) = &self.tracer {
            tracer.round(serial);
        }
    }

    fn pause(&self) -> bool {
        match &self.split {
            Some(split) => split.pause(),
            None => self.local_pause(),
        }
    }

    fn solves(&self, index: usize, _: VertexId) -> bool {
        self.split.as_ref().is_none_or(|split| split.solves(index))
    }

    fn exchanges(&self) -> bool {
        self.split.is_some()
    }

    fn exchange(
        &self,
        state: &Frontier,
        round: &[VertexId],
        results: &mut [Option<Tried<Outcome, EngineError>>],
    ) -> Result<(), EngineError> {
        let Some(split) = &self.split else {
            return Ok(());
        };
        // The wall-time and checkpoint-time requests are made here, so that every rank hears
        // of them at the same round.
        self.local_pause();
        split.exchange(state, round, results, self.control.take())
    }
}

impl Solve<'_> {
    /// Whether this process asks to pause: a request of the control, the wall-time limit or a
    /// checkpoint by wall time (which it asks of the control).
    pub(crate) fn local_pause(&self) -> bool {
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
