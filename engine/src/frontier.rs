//! The state tents share and events change: the space mesh, its front, the elements under the
//! front and the pitcher's budgets, with the refinement that changes all four together.
//!
//! Refinement bisects front triangles (newest-vertex bisection with its conforming closure) in
//! place, or splits one refinement edge at any point ([`Frontier::split_at`], for crack
//! alignment). A child triangle lies on the top face of the element under its parent, so it keeps
//! that element (its inflow is the parent element's trace on the child: nothing is projected),
//! an edge half keeps its edge's interface face, and a new vertex gets the front's time at its
//! position, its edge's end times interpolated linearly (the mean for a bisection): the front
//! surface does not move. A split is allowed only when the pitcher can keep the children causal
//! ([`Pitcher::may_bisect`], [`Pitcher::may_split_at`]). A vertex split off its edge's midpoint is never coarsened.
//!
//! Coarsening undoes a bisection once the elements around its vertex `m` are calm: the
//! coarsening patch ([`PatchSolver::solve_coarsening`]) fills the spacetime between the four (or
//! two) children and their parents' facets with one element per parent, so the parents again
//! lie each on one element, and `m` leaves the mesh (the last vertex takes its id). On an
//! interface with its own law, the patch's face over the restored edge carries the interface
//! state on from the faces over the two halves, and the restored edge keeps it.

use std::sync::atomic::{AtomicBool, Ordering};

use sdg_mesh::{
    AllowSplit, Front, Merge, Mesh, Pitcher, Point, Split, SplitError, TriangleId, VertexId,
};
use sdg_scheduler::Region;
use sdg_solver::element::{FrontSolution, Geometry};
use sdg_solver::face::FaceState;

use crate::fracture::criteria::Tip;

/// The space mesh, its front, the elements under the front and the pitcher.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Frontier {
    pub(crate) mesh: Mesh,
    pub(crate) front: Front,
    pub(crate) solution: FrontSolution,
    pub(crate) pitcher: Pitcher,
    /// Per vertex: its next tent is accepted whatever the error indicator says (set when a
    /// refinement could split nothing around it).
    insist: Vec<AtomicBool>,
    /// Per triangle: the element under it was accepted below the lower tolerance.
    calm: Vec<AtomicBool>,
    /// Per vertex: the crack tip at it, if any (changed by events only).
    pub(crate) tips: Vec<Option<Tip>>,
    /// The id the next crack branch takes.
    pub(crate) next_branch: u32,
}

impl sdg_scheduler::State for Frontier {
    fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    fn front(&self) -> &Front {
        &self.front
    }
}

/// A coarsening patch solved by the tent at its vertex, applied by an event.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Coarsening {
    /// The vertex to remove and its position, m (to notice renumbering).
    pub(crate) vertex: VertexId,
    pub(crate) at: Point,
    /// The vertex and its neighbours with their front times (s) when the patch was solved.
    pub(crate) times: Vec<(VertexId, f64)>,
    /// Per element: the corners of the child `(m, z, a)` whose id its parent takes, the
    /// element's geometry and coefficients.
    pub(crate) elements: Vec<([VertexId; 3], Geometry, Vec<f64>)>,
    /// The interface face over the restored edge, on an interface with its own law.
    pub(crate) face: Option<FaceState>,
    /// Accepted below the lower tolerance.
    pub(crate) calm: bool,
}

/// How far refinement may go: no piece of an edge shorter than `min_edge` (m), no vertex star
/// above `max_star` triangles, no triangle split with a corner that `region` says a tent in
/// flight holds.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits<'r> {
    pub(crate) min_edge: f64,
    pub(crate) max_star: usize,
    pub(crate) region: Region<'r>,
}

/// What a refinement changed.
#[derive(Debug, Default)]
pub(crate) struct Refined {
    /// New vertices and their front times (s), in id order.
    pub(crate) vertices: Vec<(VertexId, f64)>,
    /// Every vertex of a split triangle (old or new), unsorted, with repeats.
    pub(crate) touched: Vec<VertexId>,
    /// Change of the initial data's discrete energy (scaled units) on split triangles that
    /// still carry it: the children's face rules sample it at other points than the parent's.
    pub(crate) initial_energy: f64,
}

impl Frontier {
    /// A frontier over `mesh` with `front`, `solution` and `pitcher` sized for it.
    pub(crate) fn new(mesh: Mesh, front: Front, solution: FrontSolution, pitcher: Pitcher) -> Self {
        let flags = |n: usize| (0..n).map(|_| AtomicBool::new(false)).collect();
        Self {
            tips: vec![None; mesh.vertices().len()],
            next_branch: 0,
            insist: flags(mesh.vertices().len()),
            calm: flags(mesh.triangles().len()),
            mesh,
            front,
            solution,
            pitcher,
        }
    }

    /// Records whether the element just stored under triangle `t` (owned by the caller's claim)
    /// is calm: accepted below the lower tolerance.
    pub(crate) fn set_calm(&self, t: TriangleId, calm: bool) {
        self.calm[t as usize].store(calm, Ordering::Relaxed);
    }

    /// True when a corner of triangle `t` is a crack tip or an end of an interface edge (a
    /// crack, a notch or a contact line).
    pub(crate) fn near_crack(&self, t: TriangleId) -> bool {
        let mesh = &self.mesh;
        mesh.triangles()[t as usize].iter().any(|&w| {
            self.tips[w as usize].is_some()
                || mesh.vertex_neighbors(w).iter().any(|&u| {
                    mesh.edge_between(w, u)
                        .is_some_and(|e| mesh.edges()[e as usize].is_interface())
                })
        })
    }

    /// True when every element around vertex `v` is calm.
    pub(crate) fn calm_around(&self, v: VertexId) -> bool {
        self.mesh
            .vertex_triangles(v)
            .iter()
            .all(|&t| self.calm[t as usize].load(Ordering::Relaxed))
    }

    /// Applies a coarsening patch solved by the tent at its vertex, if nothing it depends on
    /// changed since (the vertex, its star's corners and its neighbours' times): coarsens the
    /// mesh, drops the removed vertex and children from the front, the solution and the pitcher,
    /// and stores the patch's elements under the restored parents. Returns the merge (ids before
    /// it) and the parents (ids after it), or `None`, changing nothing.
    pub(crate) fn coarsen(&mut self, c: &Coarsening) -> Option<(Merge, Vec<TriangleId>)> {
        let m = c.vertex;
        let mesh = &self.mesh;
        if (m as usize) >= mesh.vertices().len()
            || mesh.vertex(m) != c.at
            || mesh.coarsenable(m).is_none()
            || c.times
                .iter()
                .any(|&(w, t)| (w as usize) >= mesh.vertices().len() || self.front.time(w) != t)
        {
            return None;
        }
        let star = mesh.vertex_triangles(m);
        let children: Vec<TriangleId> = c
            .elements
            .iter()
            .map(|(corners, _, _)| {
                star.iter()
                    .copied()
                    .find(|&t| mesh.triangles()[t as usize] == *corners)
            })
            .collect::<Option<_>>()?;
        let merge = self.mesh.coarsen(m)?;
        self.front.remove(&merge);
        self.solution.remove(&merge);
        let parents: Vec<TriangleId> = children.iter().map(|&t| merge.triangle_after(t)).collect();
        for (&parent, (_, geometry, coefficients)) in parents.iter().zip(&c.elements) {
            self.solution
                .store(parent as usize, geometry, coefficients, None);
        }
        if let Some(face) = &c.face {
            // A parent (z, a, b) has the restored edge ab opposite its first corner.
            let restored = self.mesh.triangle_edges(parents[0])[0];
            self.solution.store_face(restored as usize, face);
        }
        self.pitcher.remove(&self.mesh, &merge);
        merge.apply_to_vertices(&mut self.insist);
        merge.apply_to_vertices(&mut self.tips);
        merge.apply_to_triangles(&mut self.calm);
        for &parent in &parents {
            *self.calm[parent as usize].get_mut() = c.calm;
        }
        Some((merge, parents))
    }

    /// Marks the next tent at `v` as accepted whatever its indicator.
    pub(crate) fn insist(&mut self, v: VertexId) {
        *self.insist[v as usize].get_mut() = true;
    }

    /// Whether the next tent at `v` must be accepted (read without clearing).
    pub(crate) fn insist_flag(&self, v: VertexId) -> bool {
        self.insist[v as usize].load(Ordering::Relaxed)
    }

    /// Sets what [`Frontier::insist_flag`] reads, for a tent at `v` solved elsewhere.
    pub(crate) fn set_insist_flag(&self, v: VertexId, insist: bool) {
        self.insist[v as usize].store(insist, Ordering::Relaxed);
    }

    /// Whether the element under triangle `t` was accepted below the lower tolerance.
    pub(crate) fn calm(&self, t: TriangleId) -> bool {
        self.calm[t as usize].load(Ordering::Relaxed)
    }

    /// True (once) when the tent at `v`, whose claim the caller holds, must be accepted.
    pub(crate) fn insists(&self, v: VertexId) -> bool {
        self.insist[v as usize].swap(false, Ordering::Relaxed)
    }

    /// Bisects triangle `t` (and whatever the closure needs) as long as every split keeps the
    /// front causal and stays within `limits` (no half of an edge shorter than `min_edge`).
    /// Adds what changed to `refined`; `t` itself may be left whole when a split was refused. `initial_energy(corners)` is the discrete energy of the
    /// initial data on a triangle (scaled units).
    pub(crate) fn refine(
        &mut self,
        t: TriangleId,
        limits: Limits<'_>,
        initial_energy: &dyn Fn([Point; 3]) -> f64,
        refined: &mut Refined,
    ) {
        self.apply_splits(limits, initial_energy, refined, |mesh, allow, splits| {
            mesh.bisect(t, &mut |mesh, done, u| allow(mesh, done, u, 0.5), splits)
        });
    }

    /// [`Frontier::refine`] with an edge of `t` split at `fraction` of its length from its
    /// smaller-id end instead of a bisection: its refinement edge ([`Mesh::split_at`]) or, with
    /// `corner`, the edge opposite that corner, whose new vertex is then joined to the corner
    /// ([`Mesh::split_toward`]); the closure still bisects. Every split must keep the front
    /// causal ([`Pitcher::may_bisect`] for bisections, [`Pitcher::may_split_at`] for other
    /// fractions) and stay within `limits`. Returns whether `t` was split; on an error (bad
    /// `t`, `corner` or `fraction`, degenerate children) nothing changed.
    pub(crate) fn split_at(
        &mut self,
        t: TriangleId,
        corner: Option<usize>,
        fraction: f64,
        limits: Limits<'_>,
        initial_energy: &dyn Fn([Point; 3]) -> f64,
        refined: &mut Refined,
    ) -> Result<bool, SplitError> {
        self.apply_splits(
            limits,
            initial_energy,
            refined,
            |mesh, allow, splits| match corner {
                None => mesh.split_at(t, fraction, allow, splits),
                Some(c) => mesh.split_toward(t, c, fraction, allow, splits),
            },
        )
    }

    /// Runs the mesh refinement `split` with the frontier's test for each step (see
    /// [`Frontier::split_at`]) and carries the steps done over to the front, the solution and
    /// the pitcher: a new vertex gets the front's own time at its place on its edge
    /// ([`Split::interpolate`]), a child keeps its parent's element and an edge half its face.
    fn apply_splits<R>(
        &mut self,
        Limits {
            min_edge,
            max_star,
            region,
        }: Limits<'_>,
        initial_energy: &dyn Fn([Point; 3]) -> f64,
        refined: &mut Refined,
        split: impl FnOnce(&mut Mesh, &mut AllowSplit, &mut Vec<Split>) -> R,
    ) -> R {
        let Self {
            mesh,
            front,
            solution,
            pitcher,
            insist,
            calm,
            tips,
            ..
        } = self;
        let mut splits: Vec<Split> = Vec::new();
        // Triangles asked about that still carry initial data: (step, corners, apex corner).
        let mut initial_parents: Vec<(usize, [VertexId; 3], usize)> = Vec::new();
        let mut allow = |mesh: &Mesh, done: &[Split], t: TriangleId, fraction: f64| {
            let time = |v: VertexId| front.time_after(done, v);
            let corners = mesh.triangles()[t as usize];
            let r = mesh.refinement_edge(t);
            if !solved(solution, done, t) {
                initial_parents.push((done.len(), corners, r));
            }
            // Bisections keep the test refinement has always used, so that runs reproduce.
            let causal = if fraction == 0.5 {
                pitcher.may_bisect(mesh, time, t)
            } else {
                pitcher.may_split_at(mesh, time, t, fraction)
            };
            fraction.min(1.0 - fraction) * refinement_edge_length(mesh, t) >= min_edge
                && mesh.vertex_triangles(corners[r]).len() < max_star
                && causal
                && corners.iter().all(|&c| region.is_free(c))
        };
        let result = split(mesh, &mut allow, &mut splits);
        // A step was done when its index is below the number of splits.
        for (step, corners, r) in initial_parents {
            if let Some(split) = splits.get(step) {
                let [z, a, b] = [0, 1, 2].map(|i| corners[(r + i) % 3]);
                let m = split.vertex;
                let points = |c: [VertexId; 3]| c.map(|v| mesh.vertex(v));
                refined.initial_energy += initial_energy(points([m, z, a]))
                    + initial_energy(points([m, b, z]))
                    - initial_energy(points(corners));
            }
        }
        for split in &splits {
            let t_new = split.interpolate(split.ends.map(|w| front.time(w)));
            let v = front.push(t_new);
            insist.push(AtomicBool::new(false));
            tips.push(None);
            debug_assert_eq!(v, split.vertex, "vertices are appended in split order");
            refined.vertices.push((v, t_new));
            refined.touched.extend(split.ends);
            for &(kept, new) in &split.halves {
                *calm[kept as usize].get_mut() = false;
                calm.push(AtomicBool::new(false));
                let copy = solution.push_copy(kept as usize);
                debug_assert_eq!(copy, new as usize, "triangles are appended in split order");
                for child in [kept, new] {
                    refined
                        .touched
                        .extend(mesh.triangles()[child as usize].iter().copied());
                }
            }
        }
        solution.follow_splits(mesh.edges().len(), &splits);
        pitcher.update(
            mesh,
            splits
                .iter()
                .flat_map(|s| s.halves.iter().flat_map(|&(kept, new)| [kept, new])),
        );
        result
    }
}

/// Length of the refinement edge of triangle `t`, m.
pub(crate) fn refinement_edge_length(mesh: &Mesh, t: TriangleId) -> f64 {
    let corner = mesh.refinement_edge(t);
    let e = mesh.triangle_edges(t)[corner];
    mesh.edge_length(e)
}

/// True when an element lies under triangle `t`, which may be a triangle created by one of
/// `done` and not yet in `solution` (it then lies on its parent's element).
fn solved(solution: &FrontSolution, done: &[Split], t: TriangleId) -> bool {
    if (t as usize) < solution.len() {
        return solution.is_solved(t as usize);
    }
    let parent = done
        .iter()
        .flat_map(|s| &s.halves)
        .find_map(|&(kept, new)| (new == t).then_some(kept))
        .expect("a triangle beyond the solution was created by a split of this call");
    solved(solution, done, parent)
}
