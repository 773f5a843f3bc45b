//! Adaptivity policy of a solve: which patches are rejected and refined around, which bisection
//! vertices are coarsened, and the refinement before the first tent.

use std::sync::atomic::Ordering;

use sdg_mesh::{Mesh, SplitError, TriangleId};
use sdg_scheduler::{Changed, Region, VertexId};
use sdg_solver::interface::Law;
use sdg_solver::patch::{PatchReport, PatchSolver};

use super::indicator::Adapt;
use crate::fracture::records::{least_damage, wake_coarsening};
use crate::frontier::{Coarsening, Frontier, Limits, Refined, refinement_edge_length};
use crate::solve::context::Solve;
use crate::solve::tent::{InterfaceRecords, Outcome};

impl Solve<'_> {
    /// The indicator of a patch with `report` over spacetime volume `volume` (m^2 s): the larger
    /// of the bulk (numerical dissipation) and the cohesive (traction mismatch) measures, both
    /// normalized alike.
    pub(crate) fn indicator(&self, adapt: &Adapt, report: &PatchReport, volume: f64) -> f64 {
        let energy = f64::from_bits(self.energy_reference.load(Ordering::Relaxed));
        let measure = report.dissipation.max(report.cohesive_mismatch);
        adapt.indicator(measure, volume, energy)
    }

    /// The edge ends of bisection vertex `m` and the front times of `m` and of the edge's
    /// midpoint (s) when `m` may be coarsened now: its elements are calm, it is at least a
    /// quarter of its smallest tent budget below the edge's midpoint (thinner coarsening
    /// elements are slivers, singular at round-off height), the restored parents keep the
    /// pitcher's invariant, the edge is not longer than `adapt.max_edge` and, when it is longer
    /// than `adapt.tip_edge`, no active crack tip is a corner of `m`'s star (the tip's refinement
    /// would split it again).
    pub(crate) fn coarsening(
        &self,
        adapt: &Adapt,
        state: &Frontier,
        m: VertexId,
    ) -> Option<([VertexId; 2], f64, f64)> {
        let (mesh, front) = (&state.mesh, &state.front);
        let ends = mesh.coarsenable(m)?;
        let (t_m, t_mid) = (
            front.time(m),
            0.5 * (front.time(ends[0]) + front.time(ends[1])),
        );
        let long = sdg_mesh::geometry::distance(mesh.vertex(ends[0]), mesh.vertex(ends[1]));
        let budget = mesh
            .vertex_triangles(m)
            .iter()
            .map(|&t| state.pitcher.budget(t))
            .fold(f64::INFINITY, f64::min);
        let near_tip = || {
            mesh.vertex_triangles(m)
                .iter()
                .flat_map(|&t| mesh.triangles()[t as usize])
                .any(|w| state.tips[w as usize].is_some())
        };
        (t_mid - t_m >= 0.25 * budget
            && long <= adapt.max_edge_at(midpoint(mesh.vertex(ends[0]), mesh.vertex(ends[1])))
            && (long <= adapt.tip_edge || !near_tip())
            && state.calm_around(m)
            && self.debonded_if_damage(state, m, ends)
            && state.pitcher.may_coarsen(mesh, front, m, ends))
        .then_some((ends, t_m, t_mid))
    }

    /// False when `m` joins two halves of a damage interface edge (a crack's path) that are not
    /// both fully debonded, `D >= 1 - eps` at every corner of their last faces: a crack's wake
    /// is merged only where its faces have reached the end of their damage history (seed
    /// 4.4.2, Fig. 4.6), so that no history is averaged over the merged face. (The halves of a
    /// bisection are collinear, and no other crack meets `m`: [`sdg_mesh::Mesh::coarsenable`]
    /// leaves the other edges at `m` untagged.)
    fn debonded_if_damage(&self, state: &Frontier, m: VertexId, ends: [VertexId; 2]) -> bool {
        let (mesh, order) = (&state.mesh, self.problem.loaded.config.solver.order);
        ends.iter().all(|&w| {
            let Some(e) = mesh.edge_between(w, m) else {
                return true;
            };
            match self.problem.interfaces.law(mesh.edges()[e as usize].tag) {
                Law::Damage(d) => least_damage(&state.solution, e, order, d.initial) >= 1.0 - d.eps,
                _ => true,
            }
        })
    }

    /// Solves the coarsening patch of vertex `m`, claimed for a tent, when `m` may be coarsened
    /// now and the patch is within the tolerance: the outcome for the coarsening event.
    pub(crate) fn try_coarsening(
        &self,
        adapt: &Adapt,
        state: &Frontier,
        solver: &mut PatchSolver,
        m: VertexId,
    ) -> Option<Outcome> {
        let (_, t_m, t_mid) = self.coarsening(adapt, state, m)?;
        let (mesh, front) = (&state.mesh, &state.front);
        let report = solver.solve_coarsening(
            mesh,
            front,
            m,
            &self.problem.boundary,
            self.initial,
            &state.solution,
        )?;
        // A patch that fails a guard is left to the tent's own patch, which reports it.
        self.guard(&report).is_none().then_some(())?;
        let area: f64 = mesh.vertex_triangles(m).iter().map(|&t| mesh.area(t)).sum();
        let eta = self.indicator(adapt, &report, area * (t_mid - t_m) / 3.0);
        if eta > adapt.tol {
            return None;
        }
        let times = mesh
            .vertex_neighbors(m)
            .iter()
            .chain([&m])
            .map(|&w| (w, front.time(w)))
            .collect();
        let elements = solver
            .elements()
            .map(|(t, geometry, coefficients)| {
                (
                    mesh.triangles()[t as usize],
                    *geometry,
                    coefficients.to_vec(),
                )
            })
            .collect();
        let coarsening = Coarsening {
            vertex: m,
            at: mesh.vertex(m),
            times,
            elements,
            face: solver.interface_faces().first().map(|&(_, face)| face),
            calm: eta < adapt.lower,
        };
        Some(Outcome::Coarsen {
            coarsening: Box::new(coarsening),
            report,
            interface: self.interface_records(mesh, solver),
        })
    }

    /// The coarsening event: applies `coarsening` (with `report` and its `interface` records) if
    /// nothing changed since it was solved; otherwise the patch counts as rejected.
    pub(crate) fn coarsen(
        &self,
        state: &mut Frontier,
        coarsening: &Coarsening,
        report: &PatchReport,
        interface: InterfaceRecords,
    ) -> Changed {
        let m = coarsening.vertex;
        let Some((merge, parents)) = state.coarsen(coarsening) else {
            let mut book = self.book.lock();
            book.patches += 1;
            book.rejected += 1;
            return Changed::default();
        };
        let t_m = coarsening
            .times
            .iter()
            .find(|&&(w, _)| w == m)
            .map(|&(_, t)| t)
            .expect("the times include the vertex");
        let t_end = self.problem.loaded.config.time.span();
        let mut book = self.book.lock();
        self.add_patch(&mut book, report);
        interface.add_to(&mut book);
        book.coarsenings += 1;
        let [p, q] = merge.ends.map(|w| merge.vertex_after(w));
        if let (Some(fracture), Some(e)) = (&self.problem.fracture, state.mesh.edge_between(p, q))
            && fracture.is_crack(state.mesh.edges()[e as usize].tag)
        {
            let (mesh, front) = (&state.mesh, &state.front);
            let time = 0.5 * (front.time(p) + front.time(q));
            let (a, b) = (mesh.vertex(p), mesh.vertex(q));
            let event = wake_coarsening(&book.fracture_events, time, coarsening.at, a, b);
            book.fracture_events.push(event);
        }
        book.milestones.remove_vertex(t_m);
        book.progress.grow(-(t_end - t_m));
        self.add_to_snapshots(&mut book, &state.solution, &parents);
        let mut offer: Vec<VertexId> = coarsening
            .times
            .iter()
            .filter(|&&(w, _)| w != m)
            .map(|&(w, _)| merge.vertex_after(w))
            .collect();
        if (m as usize) < state.mesh.vertices().len() {
            // The former last vertex now has m's id.
            offer.push(m);
        }
        Changed {
            offer,
            below_end: -1,
        }
    }

    /// True when star triangle `t` may be bisected now: its halves would not be too short, the
    /// front stays causal, and the star of the corner that gains a triangle stays within the
    /// patch solvers' capacity.
    pub(crate) fn may_refine(&self, adapt: &Adapt, state: &Frontier, t: TriangleId) -> bool {
        let mesh = &state.mesh;
        let apex = mesh.triangles()[t as usize][mesh.refinement_edge(t)];
        refinement_edge_length(mesh, t) >= 2.0 * adapt.min_edge
            && mesh.vertex_triangles(apex).len() < self.max_star
            && state.pitcher.may_bisect(mesh, |w| state.front.time(w), t)
    }

    /// The refinement event of a rejected patch at `v` (at `at`, m, to notice renumbering by
    /// coarsening): bisects the triangles of `star` that are unchanged since. When none could
    /// be, the next tent at `v` is accepted whatever its indicator, so that the front keeps
    /// moving. Returns the vertices whose readiness changed.
    pub(crate) fn refine(
        &self,
        state: &mut Frontier,
        region: &Region<'_>,
        v: VertexId,
        at: [f64; 2],
        star: &[(TriangleId, [VertexId; 3])],
    ) -> Changed {
        let adapt = self
            .adapt
            .as_ref()
            .expect("refinement only runs with adaptivity on");
        let mut refined = Refined::default();
        let unchanged = |state: &Frontier, t: TriangleId, corners: [VertexId; 3]| {
            state.mesh.triangles().get(t as usize) == Some(&corners)
        };
        for &(t, corners) in star {
            if unchanged(state, t, corners) {
                let limits = Limits {
                    min_edge: adapt.min_edge,
                    max_star: self.max_star,
                    region: *region,
                };
                state.refine(
                    t,
                    limits,
                    &|corners| self.initial_energy(corners),
                    &mut refined,
                );
            }
        }
        let here = (v as usize) < state.mesh.vertices().len() && state.mesh.vertex(v) == at;
        if here
            && star
                .iter()
                .all(|&(t, corners)| unchanged(state, t, corners))
        {
            state.insist(v);
        }
        if here {
            refined.touched.push(v);
            refined.touched.extend(state.mesh.vertex_neighbors(v));
        }
        self.count_refined(refined)
    }

    /// Splits an edge of triangle `t` at `fraction` of its length from its smaller-id end (its
    /// refinement edge, or with `corner` the edge opposite that corner: see
    /// [`Frontier::split_at`]), after bisecting what the closure needs, within the limits of
    /// refinement ([`Solve::min_edge`] for every piece of an edge; the patch solvers' star
    /// capacity; the pitcher's causality), and books the new vertices like
    /// refinement does. Returns whether `t` was split (a refused step leaves `t` whole and
    /// keeps the closure's bisections done before it), what changed for the scheduler and the
    /// new vertices. Runs as an event: `state` is held exclusively.
    pub(crate) fn split_at(
        &self,
        state: &mut Frontier,
        region: &Region<'_>,
        t: TriangleId,
        corner: Option<usize>,
        fraction: f64,
    ) -> Result<(bool, Changed, Vec<VertexId>), SplitError> {
        let limits = Limits {
            min_edge: self.min_edge,
            max_star: self.max_star,
            region: *region,
        };
        let mut refined = Refined::default();
        let split = state.split_at(
            t,
            corner,
            fraction,
            limits,
            &|corners| self.initial_energy(corners),
            &mut refined,
        )?;
        let new: Vec<VertexId> = refined.vertices.iter().map(|&(v, _)| v).collect();
        Ok((split, self.count_refined(refined), new))
    }

    /// Books what a refinement changed (new vertices, the initial energy's correction) and
    /// returns it for the scheduler: the touched vertices, sorted, and the new ones below the
    /// end time.
    fn count_refined(&self, refined: Refined) -> Changed {
        let t_end = self.problem.loaded.config.time.span();
        let mut book = self.book.lock();
        book.refinements += refined.vertices.len() as u64;
        book.initial_energy += refined.initial_energy;
        for &(_, t) in &refined.vertices {
            book.milestones.add_vertex(t);
            book.progress.grow(t_end - t);
        }
        let mut touched = refined.touched;
        touched.extend(refined.vertices.iter().map(|&(w, _)| w));
        touched.sort_unstable();
        touched.dedup();
        Changed {
            offer: touched,
            below_end: refined.vertices.iter().filter(|&&(_, t)| t < t_end).count() as isize,
        }
    }
}

/// The midpoint of `a` and `b`.
fn midpoint(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
}

/// Bisects every triangle whose refinement edge is longer than `adapt.max_edge` (or a zone's at
/// the edge's midpoint), on the flat initial front; or says which key asks for what the mesh
/// cannot give, and why.
pub(crate) fn refine_to_max_edge(
    state: &mut Frontier,
    adapt: &Adapt,
    max_star: usize,
) -> Result<(), String> {
    let mut refined = Refined::default();
    let mut t: TriangleId = 0;
    while (t as usize) < state.mesh.triangles().len() {
        let mesh = &state.mesh;
        let e = mesh.triangle_edges(t)[mesh.refinement_edge(t)];
        let [a, b] = mesh.edges()[e as usize].vertices.map(|v| mesh.vertex(v));
        let limit = adapt.max_edge_at(midpoint(a, b));
        if refinement_edge_length(mesh, t) <= limit {
            t += 1;
            continue;
        }
        let before = state.mesh.triangles().len();
        let limits = Limits {
            min_edge: adapt.min_edge,
            max_star,
            region: Region::everything(),
        };
        state.refine(t, limits, &|_| 0.0, &mut refined);
        if state.mesh.triangles().len() == before {
            return Err(format!(
                "adapt.max_edge or adapt.zone: an edge of {limit} m cannot be reached at \
                 ({:e}, {:e}) m: a vertex star would exceed {max_star} triangles",
                a[0], a[1]
            ));
        }
    }
    Ok(())
}

/// Longest closure chain a region probe follows ([`Mesh::bisection_chain`]); a refinement
/// checks every split it makes against the claims, past that too.
const PROBE_CHAIN: usize = 64;

/// The vertices a refinement of `triangles` changes as the mesh is now
/// ([`sdg_scheduler::Probe`]): the corners of the triangles the closures of their bisections
/// split. Ids past the mesh are left out.
pub(crate) fn refinement_region(
    mesh: &Mesh,
    triangles: impl IntoIterator<Item = TriangleId>,
) -> Vec<VertexId> {
    let count = mesh.triangles().len();
    let mut region: Vec<VertexId> = triangles
        .into_iter()
        .filter(|&t| (t as usize) < count)
        .flat_map(|t| mesh.bisection_chain(t, PROBE_CHAIN))
        .flat_map(|t| mesh.triangles()[t as usize])
        .collect();
    region.sort_unstable();
    region.dedup();
    region
}

/// The vertices a crack extension from the tip `v` changes: those of refining its star and the
/// triangles across the edges opposite `v`, where a split toward `v` sends the closure.
pub(crate) fn extension_region(mesh: &Mesh, v: VertexId) -> Vec<VertexId> {
    if v as usize >= mesh.vertices().len() {
        return Vec::new();
    }
    let star = mesh.vertex_triangles(v);
    let across = star.iter().filter_map(|&t| {
        let [a, b] = mesh.triangles()[t as usize]
            .into_iter()
            .filter(|&w| w != v)
            .collect::<Vec<_>>()
            .try_into()
            .ok()?;
        let e = mesh.edge_between(a, b)?;
        mesh.edges()[e as usize]
            .triangles
            .into_iter()
            .flatten()
            .find(|&u| u != t)
    });
    refinement_region(mesh, star.iter().copied().chain(across))
}

/// The vertices a coarsening that removes `m` changes: `m` and its neighbours, and the last
/// vertex, the corners of the last two triangles and the ends of the last three edges, which
/// the removal may move into the freed ids ([`sdg_mesh::Merge`]).
pub(crate) fn coarsening_region(mesh: &Mesh, m: VertexId) -> Vec<VertexId> {
    let n = mesh.vertices().len();
    if m as usize >= n {
        return Vec::new();
    }
    let mut region = vec![m, n as VertexId - 1];
    region.extend(mesh.vertex_neighbors(m));
    region.extend(mesh.triangles().iter().rev().take(2).flatten());
    region.extend(mesh.edges().iter().rev().take(3).flat_map(|e| e.vertices));
    region.sort_unstable();
    region.dedup();
    region
}

#[cfg(test)]
mod tests {
    use super::*;
    use sdg_mesh::{Diagonal, Rectangle};

    /// A vertex's star as a tent holds it: its triangles' ids, corners and edge ids.
    fn star(mesh: &Mesh, v: VertexId) -> Vec<(TriangleId, [VertexId; 3], [u32; 3])> {
        let mut star: Vec<_> = mesh
            .vertex_triangles(v)
            .iter()
            .map(|&t| (t, mesh.triangles()[t as usize], mesh.triangle_edges(t)))
            .collect();
        star.sort_unstable();
        star
    }

    /// Every vertex whose star (triangle ids, corners, edge ids) or id a coarsening changes is
    /// in its region, so that a regional coarsening leaves every claimed star alone.
    #[test]
    fn a_coarsening_changes_nothing_outside_its_region() {
        let mut mesh = Rectangle {
            width: 1.0,
            height: 1.0,
            nx: 4,
            ny: 4,
            diagonal: Diagonal::Alternate,
            interfaces: Vec::new(),
            sides: Vec::new(),
            perturb: 0.1,
            seed: 3,
        }
        .build()
        .unwrap();
        let mut splits = Vec::new();
        for k in 0..60u32 {
            let t = (k * 37) % mesh.triangles().len() as u32;
            mesh.bisect(t, &mut |_, _, _| true, &mut splits);
        }
        let mut checked = 0;
        for m in 0..mesh.vertices().len() as VertexId {
            if mesh.coarsenable(m).is_none() {
                continue;
            }
            let region = coarsening_region(&mesh, m);
            let mut after = mesh.clone();
            let merge = after.coarsen(m).expect("coarsenable");
            for w in (0..mesh.vertices().len() as VertexId).filter(|&w| w != m) {
                let moved = merge.vertex_after(w) != w;
                let renamed: Vec<_> = star(&mesh, w)
                    .into_iter()
                    .map(|(t, corners, edges)| {
                        (
                            merge.triangle_after(t),
                            corners.map(|c| merge.vertex_after(c)),
                            edges,
                        )
                    })
                    .collect();
                let changed = moved || renamed != star(&after, merge.vertex_after(w));
                assert!(
                    !changed || region.contains(&w),
                    "coarsening {m} changes vertex {w} outside {region:?}"
                );
            }
            checked += 1;
        }
        assert!(checked > 20, "{checked} coarsenings");
    }
}
