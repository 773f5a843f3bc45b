//! One tent: pitch, solve, check and refine or accept its patch.

use std::time::Instant;

use sdg_mesh::{TagId, Tent, TriangleId};
use sdg_scheduler::{Lease, VertexId};
use sdg_solver::crack::Crossing;
use sdg_solver::patch::{InterfaceSample, PatchReport, PatchSolver};

use crate::error::EngineError;
use crate::frontier::{Coarsening, Frontier, refinement_edge_length};

use super::book::Book;
use super::context::Solve;
use crate::fracture::propagation::Extension;
use crate::output::interface;

impl Solve<'_> {
    /// [`Work::tent`] without its trace.
    pub(crate) fn solve_tent(
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
            // A non-finite residual comes from non-finite inflow, which refinement copies
            // onto the children: the guard's failure, not a reason to refine. (A face whose
            // separation did not converge is a patch not converged: refined below.)
            Err(failure) if failure.is_non_finite() => {
                let [x, y] = mesh.vertex(v);
                self.control.fail(format!(
                    "the patch of vertex {v} at ({x:e}, {y:e}) m, t = {:e} s: the Newton \
                     residual is {} (a non-finite value)",
                    self.problem.loaded.config.time.clock(tent.t_old),
                    failure.residual
                ));
                return Ok((tent.t_old, Outcome::Failed));
            }
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
            retries: Vec::new(),
            span: (tent.t_old, t_new),
            unresolved,
            slope,
        };
        Ok((t_new, outcome))
    }
}

/// The largest momentum imbalance of an element in `totals`, relative to the largest momentum
/// flux through the faces of any element (0 when nothing moved): an element at rest, whose
/// fluxes are round-off, does not count as a failure of conservation.
pub(crate) fn momentum_residual(totals: &PatchReport) -> f64 {
    if totals.momentum_flux > 0.0 {
        totals.momentum_imbalance / totals.momentum_flux
    } else {
        0.0
    }
}

/// What one tent hands to the bookkeeping.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub(crate) enum Outcome {
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
        /// The neighbours' tips whose pending extensions to try again, as the state is after
        /// the tent (set by [`Work::settle`](sdg_scheduler::Work::settle)).
        retries: Vec<(VertexId, Extension)>,
        /// The least and greatest front time of the star's elements, s (before and after the
        /// tent; set by [`Work::settle`](sdg_scheduler::Work::settle)).
        span: (f64, f64),
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
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct InterfaceRecords {
    pub(crate) samples: Vec<(usize, InterfaceSample)>,
    pub(crate) cuts: Vec<interface::Cut>,
    pub(crate) crossings: Vec<(Option<TagId>, Crossing)>,
}

impl InterfaceRecords {
    /// Adds the records to the bookkeeping.
    pub(crate) fn add_to(self, book: &mut Book) {
        book.samples.extend(self.samples);
        book.crossings.extend(self.crossings);
        for (time, xy, values) in self.cuts {
            book.snapshots.add_interface_segment(time, xy, values);
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.samples.is_empty() && self.cuts.is_empty() && self.crossings.is_empty()
    }
}

impl Solve<'_> {
    /// The interface records of the patch `solver` just solved on `mesh`.
    pub(crate) fn interface_records(
        &self,
        mesh: &sdg_mesh::Mesh,
        solver: &mut PatchSolver,
    ) -> InterfaceRecords {
        InterfaceRecords {
            samples: {
                let mut samples = Vec::new();
                let probes = self.problem.probes.iter().map(|p| p.at);
                solver.probe_samples(mesh, probes, &mut samples);
                samples
            },
            cuts: interface::snapshot_cuts(&self.snapshot_times, solver),
            crossings: solver
                .crack_crossings()
                .iter()
                .map(|c| (mesh.edges()[c.edge as usize].tag, *c))
                .collect(),
        }
    }
}
