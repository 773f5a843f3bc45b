//! Crack propagation in a run (seed 4.3.2; the criteria are in [`crate::fracture`]).
//!
//! The tent at a crack tip evaluates the stress at the middle of its pole, once the patch is
//! accepted: each patch element's at the tip, in its sector ([`Fracture::candidates`]); with
//! `fracture.criterion_length`, once the tent settles, the stress averaged along segments ahead
//! of the tip ([`super::nonlocal`]). When the tip has directions to extend along, an event
//! extends it: per direction, the crack takes the existing edge of the tip's star when the
//! direction crosses the opposite edge near one of its ends (`snap`) and that edge keeps to the
//! rules ([`Fracture::may_take`]), and otherwise splits that edge where the direction crosses it
//! ([`Frontier::split_at`] towards the tip), or, where no split may be that short, takes an end
//! within the rules. The new edge takes the crack tag (a damage interface, bonded at first:
//! nothing on the front changes) and its far end becomes a tip, unless it lies on the boundary
//! or on another crack (the crack arrests there). A direction that crosses a crack edge joins
//! that crack at an end of the edge ([`Fracture::may_join`]) and arrests, or stops short where
//! the shield angle forbids both ends.
//! Two directions make a branch: the first keeps the tip's branch id, the second takes a new
//! one. A tip makes all its edges or none: when the mesh refuses one, the tip keeps its
//! directions ([`Pending`]) and tries again after each tent of a neighbour, until its own next
//! tent tests anew.

use sdg_mesh::{Mesh, TriangleId, VertexId};
use sdg_scheduler::{Changed, Region};
use sdg_solver::element::evaluate;
use sdg_solver::patch::PatchSolver;

use super::criteria::{self, Fracture, Pending, Tip};
use super::nonlocal;
use super::records::{FractureEvent, Refusal, SCRATCH};
use crate::frontier::Frontier;
use crate::solve::context::{Solve, initial_state};

/// A tip's directions to extend along, found by the tent at its vertex.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Extension {
    /// The tip's position (m), to notice renumbering.
    at: [f64; 2],
    /// Directions (radians), unused entries NaN.
    directions: [f64; 2],
    /// A crack nucleates at the vertex (it is no tip): both directions are new branches.
    nucleation: bool,
    /// A tip's [`Pending`] directions, tried again after a neighbour's tent: made only while
    /// the tip stays where its test left it, and a refusal is not recorded again.
    retry: bool,
}

impl Extension {
    /// The retry of the pending directions of the tip at `v`, when it has fresh ones (its
    /// front time is still that of its test).
    pub(crate) fn retry(state: &Frontier, v: VertexId) -> Option<Extension> {
        let pending = state.tips[v as usize]?.pending?;
        (state.front.time(v) == pending.time).then(|| Extension {
            at: state.mesh.vertex(v),
            directions: pending.directions,
            nucleation: false,
            retry: true,
        })
    }
}

impl Solve<'_> {
    /// The extension of the tip at `v` after its patch (of the tent from `t_old` to `t_new`, s)
    /// was accepted, if it has directions to extend along, or of a crack nucleating there. With
    /// [`Fracture::criterion_length`] a tip's test is made when the tent settles instead
    /// ([`Solve::settled_extension`]).
    pub(crate) fn extension(
        &self,
        fracture: &Fracture,
        state: &Frontier,
        solver: &PatchSolver,
        v: VertexId,
        times: [f64; 2],
    ) -> Option<Extension> {
        let mesh = &state.mesh;
        let t_mid = 0.5 * (times[0] + times[1]);
        let stress = |t| element_stress(self, mesh, solver, v, t, t_mid);
        let (directions, nucleation) = match state.tips[v as usize] {
            // Over a length the test reads beyond the star: it waits for `settled_extension`.
            Some(_) if fracture.criterion_length.is_some() => return None,
            Some(tip) => {
                let candidates = fracture.candidates(mesh, v, stress);
                let directions = tip_directions(fracture, mesh, (v, tip), &candidates, times);
                (directions, false)
            }
            None => (fracture.nucleates(mesh, v, times[1], stress)?, true),
        };
        directions[0].is_finite().then_some(Extension {
            at: mesh.vertex(v),
            directions,
            nucleation,
            retry: false,
        })
    }

    /// With [`Fracture::criterion_length`], the extension of the tip at `v` after its patch
    /// (of the tent from `t_old` to `t_new`, s) was accepted, if it has directions to extend
    /// along ([`Fracture::averaged_candidates`]); none without a criterion length or a tip.
    /// Called once the tent settles ([`sdg_scheduler::Work::settle`]): the segments reach
    /// beyond the star, into triangles that other tents of a deterministic round may have
    /// solved, and the state as the round left it does not depend on their order. The stress
    /// in a star triangle is that of the patch element just stored under it at the middle of
    /// the pole, as for the point rule; elsewhere the front's: the element under the triangle
    /// on its top facet (the initial state where none was solved yet).
    pub(crate) fn settled_extension(
        &self,
        fracture: &Fracture,
        state: &Frontier,
        v: VertexId,
        times: [f64; 2],
    ) -> Option<Extension> {
        let length = fracture.criterion_length?;
        let tip = state.tips[v as usize]?;
        let mesh = &state.mesh;
        let t_mid = 0.5 * (times[0] + times[1]);
        let star = mesh.vertex_triangles(v);
        let stress = |t: TriangleId, x: [f64; 2]| {
            let time = if star.contains(&t) {
                t_mid
            } else {
                let corners = mesh.triangles()[t as usize].map(|w| state.front.time(w));
                nonlocal::facet_time(mesh, t, corners, x)
            };
            front_stress(self, state, t, x, time)
        };
        let order = self.basis.degree();
        let candidates =
            fracture.averaged_candidates(mesh, v, tip.direction, length, order, stress);
        let directions = tip_directions(fracture, mesh, (v, tip), &candidates, times);
        directions[0].is_finite().then_some(Extension {
            at: mesh.vertex(v),
            directions,
            nucleation: false,
            retry: false,
        })
    }

    /// The event of an [`Extension`] of the tip at `v`: adds the crack edges (see the module
    /// documentation) and returns what changed for the scheduler.
    pub(crate) fn extend(
        &self,
        state: &mut Frontier,
        region: &Region<'_>,
        v: VertexId,
        extension: &Extension,
    ) -> Changed {
        let fracture = self
            .problem
            .fracture
            .as_ref()
            .expect("extensions need [fracture]");
        let mesh = &state.mesh;
        if (v as usize) >= mesh.vertices().len() || mesh.vertex(v) != extension.at {
            return Changed::default();
        }
        // A nucleation site is no tip (it may be on a crack); a tip must still be one.
        let tip = state.tips[v as usize];
        let still = if extension.nucleation {
            tip.is_none()
        } else {
            tip.is_some() && !fracture.crack_edges(mesh, v).is_empty()
        };
        let fresh = || Extension::retry(state, v).is_some();
        if !still || (extension.retry && !fresh()) {
            return Changed::default();
        }
        let time = state.front.time(v);
        let at = mesh.vertex(v);
        let mut changed = Changed::default();
        // First the far ends of the new edges, splitting edges where the directions need it.
        let mut plans: Vec<Plan> = Vec::new();
        for &d in extension.directions.iter().filter(|d| d.is_finite()) {
            let plan = self.plan(fracture, state, region, (v, tip), d, &mut changed);
            let plan = match plan {
                // Two new edges keep the shield angle between them (snapping may turn them).
                Plan::Edge(w)
                    if plans.iter().any(|&other| match other {
                        Plan::Edge(u) => !fracture.apart(&state.mesh, v, u, w),
                        _ => false,
                    }) =>
                {
                    Plan::Refused(Refusal::Shield, state.mesh.vertex(w))
                }
                plan => plan,
            };
            plans.push(plan);
        }
        // A later split's closure may have split an earlier new edge.
        for plan in &mut plans {
            if let Plan::Edge(w) = *plan
                && state.mesh.edge_between(v, w).is_none()
            {
                *plan = Plan::Refused(Refusal::Closure, state.mesh.vertex(w));
            }
        }
        // The test bounded where the directions cross the opposite edges; an edge that snaps to
        // or takes an end of the crossed edge is longer (up to sqrt 2 on right triangles), and
        // the edge made keeps to `fracture.max_tip_speed` too.
        if let Some(tip) = tip {
            for plan in &mut plans {
                if let Plan::Edge(w) = *plan {
                    let to = state.mesh.vertex(w);
                    let length = (to[0] - at[0]).hypot(to[1] - at[1]);
                    if !fracture.within_reach(tip, time, length) {
                        *plan = Plan::Refused(Refusal::Speed, to);
                    }
                }
            }
        }
        let refusals: Vec<(Refusal, [f64; 2])> = plans
            .iter()
            .filter_map(|&p| match p {
                Plan::Refused(reason, toward) => Some((reason, toward)),
                _ => None,
            })
            .collect();
        let event = |kind: &'static str, branch, to| FractureEvent {
            time,
            kind: kind.into(),
            branch,
            from: at,
            to,
            reason: None,
        };
        let mut events = Vec::new();
        if extension.nucleation {
            events.push(event("nucleation", Some(state.next_branch), at));
        }
        if !extension.retry {
            let branch = tip.map(|tip| tip.branch);
            events.extend(refusals.iter().map(|&(reason, toward)| FractureEvent {
                reason: Some(reason.name().into()),
                ..event("refused", branch, toward)
            }));
        }
        // A tip makes all its edges or none (a branching is not lost half-made); its splits
        // stay as refinements, and the same directions are tried again after neighbours' tents,
        // unless an edge was too long for the time since the tip came (a retry comes at the
        // same time): then the tip's next tent tests anew.
        if let Some(tip) = &mut state.tips[v as usize]
            && !refusals.is_empty()
        {
            let waits = refusals.iter().any(|&(reason, _)| reason == Refusal::Speed);
            tip.pending = (!waits).then_some(Pending {
                directions: extension.directions,
                time,
            });
            self.book.lock().fracture_events.extend(events);
            return sorted(changed);
        }
        let mut extended = 0;
        for plan in plans {
            // Each half of a nucleated crack is a new branch, travelling its way; so is a
            // tip's second direction.
            let (branch, new_branch) = match tip {
                Some(tip) if extended == 0 => (tip.branch, false),
                _ => (state.next_branch, true),
            };
            let target = match plan {
                Plan::Refused(..) => continue,
                Plan::Arrest => {
                    events.push(event("arrest", Some(branch), at));
                    state.tips[v as usize] = None;
                    continue;
                }
                Plan::Edge(w) => w,
            };
            let mesh = &mut state.mesh;
            let edge = mesh
                .edge_between(v, target)
                .expect("the target is a neighbour of the tip");
            let joins = !fracture.crack_edges(mesh, target).is_empty();
            mesh.set_tag(edge, Some(fracture.tag));
            let to = mesh.vertex(target);
            events.push(event("extension", Some(branch), to));
            if new_branch {
                state.next_branch += 1;
            }
            extended += 1;
            changed.offer.extend([v, target]);
            if joins || criteria::on_boundary(&state.mesh, target) {
                events.push(event("arrest", Some(branch), to));
            } else {
                state.tips[target as usize] = Some(Tip {
                    direction: fracture.tangent(tip.map(|t| t.direction), at, to),
                    branch,
                    since: time,
                    pending: None,
                });
            }
            state.tips[v as usize] = None;
        }
        if extension.nucleation && extended == 0 {
            // Both ways ran into cracks at once (or the mesh refused them): nothing nucleated.
            return sorted(changed);
        }
        if extended == 2 && !extension.nucleation {
            let mut branching = events
                .iter()
                .find(|e| e.kind == "extension")
                .expect("two extensions")
                .clone();
            branching.kind = "branching".into();
            events.push(branching);
        }
        self.book.lock().fracture_events.extend(events);
        sorted(changed)
    }

    /// Where the crack of `fracture` from the tip at `v` (`tip`; `None` at a nucleation site)
    /// in direction `d` (radians) ends its new edge: the end of the crossed edge near the
    /// crossing when the rules allow, else a split of that edge where the direction crosses it,
    /// else (when no split can be that short) an end within the rules. Splits made are added to
    /// `changed`.
    fn plan(
        &self,
        fracture: &Fracture,
        state: &mut Frontier,
        region: &Region<'_>,
        (v, tip): (VertexId, Option<Tip>),
        d: f64,
        changed: &mut Changed,
    ) -> Plan {
        let mesh = &state.mesh;
        let Some(c) = criteria::crossing(mesh, v, d) else {
            return Plan::Refused(Refusal::Outside, mesh.vertex(v));
        };
        let tip = tip.unwrap_or(Tip {
            direction: d,
            branch: 0,
            since: f64::NEG_INFINITY,
            pending: None,
        });
        // The edge's ends, the one nearer the crossing first.
        let [p, q] = mesh.edges()[c.edge as usize].vertices;
        let ends = if c.fraction < 0.5 { [p, q] } else { [q, p] };
        let toward = {
            let [a, b] = [p, q].map(|w| mesh.vertex(w));
            [0, 1].map(|k| a[k] + c.fraction * (b[k] - a[k]))
        };
        if fracture.is_crack(mesh.edges()[c.edge as usize].tag) {
            // The direction runs into another crack: the tip joins it at an end of the crack
            // edge it meets, or stops short of it where the shield angle forbids both.
            return ends
                .into_iter()
                .find(|&w| fracture.may_join(mesh, v, tip, w))
                .map_or(Plan::Arrest, Plan::Edge);
        }
        let may_take = |mesh: &Mesh, w, within| fracture.may_take(mesh, (v, tip), d, w, within);
        let near_end = c.fraction.min(1.0 - c.fraction);
        if near_end < fracture.snap && may_take(mesh, ends[0], 0.5 * fracture.shield) {
            return Plan::Edge(ends[0]);
        }
        if near_end * criteria::distance(mesh, p, q) < self.min_edge {
            // No split is allowed there, now or later.
            return ends
                .into_iter()
                .find(|&w| may_take(mesh, w, fracture.floor_angle))
                .map_or(Plan::Refused(Refusal::Floor, toward), Plan::Edge);
        }
        match self.split_at(state, region, c.triangle, Some(c.corner), c.fraction) {
            Ok((split, more, new)) => {
                changed.offer.extend(more.offer);
                changed.below_end += more.below_end;
                if split {
                    Plan::Edge(*new.last().expect("a split adds a vertex"))
                } else {
                    Plan::Refused(Refusal::Front, toward)
                }
            }
            Err(_) => Plan::Refused(Refusal::Degenerate, toward),
        }
    }
}

/// `changed` with its offered vertices sorted and without repeats.
fn sorted(mut changed: Changed) -> Changed {
    changed.offer.sort_unstable();
    changed.offer.dedup();
    changed
}

/// How a direction of an extension ends its new edge.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Plan {
    /// At this vertex, a neighbour of the tip.
    Edge(VertexId),
    /// The direction crosses a crack and no edge may join it: the tip stops short.
    Arrest,
    /// The mesh cannot make the edge now, for this reason; it would have ended at this point
    /// (m).
    Refused(Refusal, [f64; 2]),
}

/// The in-plane stress (Pa) at the tent's vertex `v` at time `t` (s), the middle of its pole, in
/// the element over star triangle `triangle` of the patch `solver` just solved.
fn element_stress(
    solve: &Solve,
    mesh: &Mesh,
    solver: &PatchSolver,
    v: VertexId,
    triangle: TriangleId,
    t: f64,
) -> [f64; 3] {
    let system = &solve.problem.system;
    let (mut phi, mut values) = ([0.0; SCRATCH], [0.0; SCRATCH]);
    let (n, width) = (solve.basis.len(), solver.width());
    let (_, geometry, coefficients) = solver
        .elements()
        .find(|&(t, _, _)| t == triangle)
        .expect("the patch has an element over every star triangle");
    let [x, y] = mesh.vertex(v);
    evaluate(
        &solve.basis,
        geometry,
        coefficients,
        [x, y, system.c_ref() * t],
        &mut phi[..n],
        &mut values[..width],
    );
    let z = system.z_ref();
    [values[2], values[3], values[4]].map(|s| z * s)
}

/// The directions (radians, unused entries NaN) `tip` at vertex `v` extends along after the
/// tent from `times[0]` to `times[1]` (s), of its `candidates` (`(direction, traction)`,
/// radians and Pa): [`Fracture::select`], unless the tip would be faster than
/// [`Fracture::max_tip_speed`] ([`Fracture::in_time`]); logged at debug level.
fn tip_directions(
    fracture: &Fracture,
    mesh: &Mesh,
    (v, tip): (VertexId, Tip),
    candidates: &[(f64, f64)],
    times: [f64; 2],
) -> [f64; 2] {
    let mut directions = fracture.select(mesh, v, tip, candidates);
    if !fracture.in_time(mesh, v, tip, directions, times[1]) {
        // Faster than a crack: the tip waits for its next tent.
        directions = [f64::NAN; 2];
    }
    if !candidates.is_empty() {
        let [x, y] = mesh.vertex(v);
        let degrees_mpa = |(d, s): (f64, f64)| (d.to_degrees(), s * 1e-6);
        tracing::debug!(
            vertex = v,
            x,
            y,
            t = 0.5 * (times[0] + times[1]),
            travel = tip.direction.to_degrees(),
            maxima = ?candidates.iter().copied().map(degrees_mpa).collect::<Vec<_>>(),
            chosen = ?directions.map(f64::to_degrees),
            "propagation test (degrees, MPa)"
        );
    }
    directions
}

/// The in-plane stress (Pa) at the point `x` (m) of triangle `triangle` at time `t` (s) in the
/// element stored under it in the front solution, or of the initial state where none is.
fn front_stress(
    solve: &Solve,
    state: &Frontier,
    triangle: TriangleId,
    x: [f64; 2],
    t: f64,
) -> [f64; 3] {
    let system = &solve.problem.system;
    let (mut phi, mut values) = ([0.0; SCRATCH], [0.0; SCRATCH]);
    let (n, width) = (solve.basis.len(), solve.width);
    let scaled = state
        .solution
        .with_element(triangle as usize, |element| match element {
            Some((geometry, coefficients)) => {
                evaluate(
                    &solve.basis,
                    geometry,
                    coefficients,
                    [x[0], x[1], system.c_ref() * t],
                    &mut phi[..n],
                    &mut values[..width],
                );
                [values[2], values[3], values[4]]
            }
            None => {
                let q = initial_state(solve.problem, solve.initial, x);
                [q[2], q[3], q[4]]
            }
        });
    scaled.map(|s| system.z_ref() * s)
}
