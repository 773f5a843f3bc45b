//! The state tents share and events change: the space mesh, its front, the elements under the
//! front and the pitcher's budgets, with the refinement that changes all four together.
//!
//! Refinement bisects front triangles (newest-vertex bisection with its conforming closure) in
//! place. A child triangle lies on the top face of the element under its parent, so it keeps
//! that element (its inflow is the parent element's trace on the child: nothing is projected),
//! and a new vertex gets the front's time at its position, the mean of its edge's end times: the
//! front surface does not move. A split is allowed only when the pitcher can keep the children
//! causal ([`Pitcher::may_bisect`]).

use std::sync::atomic::{AtomicBool, Ordering};

use sdg_mesh::{Front, Mesh, Pitcher, Split, TriangleId, VertexId};
use sdg_solver::element::FrontSolution;

/// The space mesh, its front, the elements under the front and the pitcher.
#[derive(Debug)]
pub(crate) struct Frontier {
    pub(crate) mesh: Mesh,
    pub(crate) front: Front,
    pub(crate) solution: FrontSolution,
    pub(crate) pitcher: Pitcher,
    /// Per vertex: its next tent is accepted whatever the error indicator says (set when a
    /// refinement could split nothing around it).
    insist: Vec<AtomicBool>,
}

impl sdg_scheduler::State for Frontier {
    fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    fn front(&self) -> &Front {
        &self.front
    }
}

/// What a refinement changed.
#[derive(Debug, Default)]
pub(crate) struct Refined {
    /// New vertices and their front times (s), in id order.
    pub(crate) vertices: Vec<(VertexId, f64)>,
    /// Every vertex of a split triangle (old or new), unsorted, with repeats.
    pub(crate) touched: Vec<VertexId>,
}

impl Frontier {
    /// A frontier over `mesh` with `front`, `solution` and `pitcher` sized for it.
    pub(crate) fn new(mesh: Mesh, front: Front, solution: FrontSolution, pitcher: Pitcher) -> Self {
        let insist = (0..mesh.vertices().len())
            .map(|_| AtomicBool::new(false))
            .collect();
        Self {
            mesh,
            front,
            solution,
            pitcher,
            insist,
        }
    }

    /// Marks the next tent at `v` as accepted whatever its indicator.
    pub(crate) fn insist(&mut self, v: VertexId) {
        *self.insist[v as usize].get_mut() = true;
    }

    /// True (once) when the tent at `v`, whose claim the caller holds, must be accepted.
    pub(crate) fn insists(&self, v: VertexId) -> bool {
        self.insist[v as usize].swap(false, Ordering::Relaxed)
    }

    /// Bisects triangle `t` (and whatever the closure needs) as long as every split keeps the
    /// front causal, halves no edge shorter than `2 min_edge` (m) and leaves every vertex star
    /// at most `max_star` triangles. Adds what changed to `refined`; `t` itself may be left
    /// whole when a split was refused.
    pub(crate) fn refine(
        &mut self,
        t: TriangleId,
        min_edge: f64,
        max_star: usize,
        refined: &mut Refined,
    ) {
        let Self {
            mesh,
            front,
            solution,
            pitcher,
            insist,
        } = self;
        let first_vertex = mesh.vertices().len();
        let mut splits: Vec<Split> = Vec::new();
        let mut allow = |mesh: &Mesh, done: &[Split], t: TriangleId| {
            let time = |v: VertexId| time_of(front, first_vertex, done, v);
            let apex = mesh.triangles()[t as usize][mesh.refinement_edge(t)];
            refinement_edge_length(mesh, t) >= 2.0 * min_edge
                && mesh.vertex_triangles(apex).len() < max_star
                && pitcher.may_bisect(mesh, time, t)
        };
        mesh.bisect(t, &mut allow, &mut splits);
        for split in &splits {
            let t_mid = 0.5 * (front.time(split.ends[0]) + front.time(split.ends[1]));
            let v = front.push(t_mid);
            insist.push(AtomicBool::new(false));
            debug_assert_eq!(v, split.vertex, "vertices are appended in split order");
            refined.vertices.push((v, t_mid));
            refined.touched.extend(split.ends);
            for &(kept, new) in &split.halves {
                let copy = solution.push_copy(kept as usize);
                debug_assert_eq!(copy, new as usize, "triangles are appended in split order");
                for child in [kept, new] {
                    refined
                        .touched
                        .extend(mesh.triangles()[child as usize].iter().copied());
                }
            }
        }
        pitcher.update(
            mesh,
            splits
                .iter()
                .flat_map(|s| s.halves.iter().flat_map(|&(kept, new)| [kept, new])),
        );
    }
}

/// Length of the refinement edge of triangle `t`, m.
pub(crate) fn refinement_edge_length(mesh: &Mesh, t: TriangleId) -> f64 {
    let corner = mesh.refinement_edge(t);
    let e = mesh.triangle_edges(t)[corner];
    mesh.edge_length(e)
}

/// Front time (s) of `v`, which may be a vertex created by one of `done` (split `k` created
/// vertex `first_vertex + k`) and not yet on `front`.
fn time_of(front: &Front, first_vertex: usize, done: &[Split], v: VertexId) -> f64 {
    match (v as usize).checked_sub(first_vertex) {
        None => front.time(v),
        Some(k) => {
            let [a, b] = done[k].ends;
            0.5 * (time_of(front, first_vertex, done, a) + time_of(front, first_vertex, done, b))
        }
    }
}
