//! The advancing front: a time value per space vertex, linear on each triangle.

use crate::geometry;
use crate::mesh::{Mesh, TriangleId, VertexId};

/// The front `t = tau(x)`: one time (seconds) per mesh vertex, interpolated linearly on each
/// triangle. Every front triangle is a facet of the spacetime mesh built so far.
#[derive(Clone, Debug, PartialEq)]
pub struct Front {
    times: Vec<f64>,
}

impl Front {
    /// A flat front at time `t0` (seconds) over `vertex_count` vertices.
    pub fn flat(vertex_count: usize, t0: f64) -> Self {
        Self {
            times: vec![t0; vertex_count],
        }
    }

    /// Times of all vertices, seconds.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// Time of vertex `v`, seconds.
    pub fn time(&self, v: VertexId) -> f64 {
        self.times[v as usize]
    }

    /// Moves vertex `v` to time `t` (seconds). Callers keep the front causal: use
    /// [`crate::Pitcher::pitch`].
    pub fn set_time(&mut self, v: VertexId, t: f64) {
        self.times[v as usize] = t;
    }

    /// Earliest time on the front.
    pub fn min_time(&self) -> f64 {
        self.times.iter().copied().fold(f64::INFINITY, f64::min)
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
