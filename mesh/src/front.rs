//! The advancing front: a time value per space vertex, linear on each triangle.
//!
//! Times are atomics so that worker threads can share one front: a vertex's time is written only
//! by the thread that holds its tent claim (release store) and read by others after they claim
//! (acquire load), see `scheduler/README.md`.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::coarsen::Merge;
use crate::geometry;
use crate::mesh::{Mesh, TriangleId, VertexId};
use crate::refine::Split;

/// The front `t = tau(x)`: one time (seconds) per mesh vertex, interpolated linearly on each
/// triangle. Every front triangle is a facet of the spacetime mesh built so far.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct Front {
    times: Vec<AtomicU64>,
}

impl Clone for Front {
    fn clone(&self) -> Self {
        Self {
            times: self
                .snapshot()
                .into_iter()
                .map(|t| AtomicU64::new(t.to_bits()))
                .collect(),
        }
    }
}

impl Front {
    /// A flat front at time `t0` (seconds) over `vertex_count` vertices.
    pub fn flat(vertex_count: usize, t0: f64) -> Self {
        Self {
            times: (0..vertex_count)
                .map(|_| AtomicU64::new(t0.to_bits()))
                .collect(),
        }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// True for a front over no vertices.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Time of vertex `v`, seconds.
    pub fn time(&self, v: VertexId) -> f64 {
        f64::from_bits(self.times[v as usize].load(Ordering::Acquire))
    }

    /// Moves vertex `v` to time `t` (seconds). Callers keep the front causal ([`crate::Pitcher`])
    /// and hold the vertex's claim when threads share the front.
    pub fn set_time(&self, v: VertexId, t: f64) {
        self.times[v as usize].store(t.to_bits(), Ordering::Release);
    }

    /// Appends a vertex at time `t` (seconds), for a vertex just added to the mesh; returns its
    /// id.
    pub fn push(&mut self, t: f64) -> VertexId {
        self.times.push(AtomicU64::new(t.to_bits()));
        (self.times.len() - 1) as VertexId
    }

    /// Drops the time of the vertex a coarsening removed, renumbering like the mesh.
    pub fn remove(&mut self, merge: &Merge) {
        merge.apply_to_vertices(&mut self.times);
    }

    /// Time (s) of `v`, which may be a vertex that the splits `done` created and that is not on
    /// the front yet: split `k` created vertex `len() + k`, at its ends' times interpolated
    /// linearly ([`Split::interpolate`]: the front's own value there, so a split does not move
    /// the front; the mean for a bisection).
    pub fn time_after(&self, done: &[Split], v: VertexId) -> f64 {
        match (v as usize).checked_sub(self.times.len()) {
            None => self.time(v),
            Some(k) => {
                let split = &done[k];
                split.interpolate(split.ends.map(|w| self.time_after(done, w)))
            }
        }
    }

    /// A copy of all times, seconds.
    pub fn snapshot(&self) -> Vec<f64> {
        (0..self.times.len() as VertexId)
            .map(|v| self.time(v))
            .collect()
    }

    /// Earliest time on the front.
    pub fn min_time(&self) -> f64 {
        (0..self.times.len() as VertexId)
            .map(|v| self.time(v))
            .fold(f64::INFINITY, f64::min)
    }

    /// True when no neighbour of `v` is earlier than `v`.
    pub fn is_local_minimum(&self, mesh: &Mesh, v: VertexId) -> bool {
        let t = self.time(v);
        mesh.vertex_neighbors(v).iter().all(|&w| self.time(w) >= t)
    }

    /// `|grad tau|` on triangle `t`, in seconds per metre: the front facet is space-like for
    /// wave speed `c` when `c * |grad tau| < 1`.
    pub fn slope(&self, mesh: &Mesh, t: TriangleId) -> f64 {
        let tri = mesh.triangles()[t as usize];
        let g = geometry::linear_gradient(mesh.triangle_points(t), tri.map(|v| self.time(v)));
        g[0].hypot(g[1])
    }
}
