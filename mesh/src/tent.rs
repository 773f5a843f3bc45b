//! Tent pitching: raising one vertex of the front as far as causality and progress allow.
//!
//! # Rule
//! Each triangle `T` gets a time budget `B_T = s (1 - GUARD) h_T / c`, where `h_T` is its
//! smallest altitude (its minimum width), `c` the fastest wave speed and `s` the safety factor.
//! The pitcher keeps the invariant
//!
//! > (I) on every front triangle, `max tau - min tau <= B_T`.
//!
//! A linear function whose vertex values span `R` on a triangle of minimum width `h_T` has
//! `|grad tau| <= R / h_T`, so (I) gives `c |grad tau| <= s (1 - GUARD) < s`: every front facet is
//! space-like with margin. A vertex `v` that is a local minimum of the front is raised to
//!
//! `tau_new(v) = min(t_end, min over T in star(v) of (min over w in T, w != v of tau(w)) + B_T)`,
//!
//! which keeps (I) on the star and changes no other triangle (so does any lower time above
//! `tau(v)`). If that would leave `v` a gap to `t_end` of less than half its step, the vertex goes
//! to the middle of what remains instead, so that no sliver tents appear at the end time (they
//! cost accuracy and conditioning).
//!
//! # Progress
//! Because `v` is a local minimum, every term above is at least `tau(v) + B_T`, so each tent
//! advances its vertex by at least `min(t_end - tau(v), min over the star of B_T / 2) > 0` (the
//! half from the end-time split, which only happens while the gap exceeds the star's budget). The global
//! minimum of the front is always a local minimum, hence a vertex can always be pitched, and the
//! front reaches `t_end` exactly after at most `sum_v (2 t_end / min_star(v) B_T + 1)` tents. This
//! holds on any valid triangulation (obtuse, strongly graded, multiply connected): only positive
//! altitudes are used. The rule is the "range" form of the progress constraint of Ungor and
//! Sheffer: it bounds the spread of times per triangle instead of the gradient, which is what lets
//! a local minimum always move.
//!
//! Tent poles are vertical: the pole top has the same space position as its base. A tilted pole
//! (crack alignment) changes the space position of the vertex; [`Tent`] records only times so
//! far.

use crate::coarsen::Merge;
use crate::front::Front;
use crate::geometry;
use crate::mesh::{Mesh, TriangleId, VertexId};
use crate::refine::lerp;

/// Relative margin under the safety factor that absorbs rounding in times and gradients.
pub const GUARD: f64 = 1e-9;

/// A tent: vertex `vertex` raised from `t_old` to `t_new` (seconds). Its patch consists of one
/// spacetime tetrahedron per triangle of the vertex star, with corners `(vertex, t_old)`,
/// `(vertex, t_new)` and the two other triangle corners at their front times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tent {
    /// The pitched vertex.
    pub vertex: VertexId,
    /// Time at the pole's base, seconds.
    pub t_old: f64,
    /// Time at the pole's top, seconds.
    pub t_new: f64,
}

/// Why a pitcher cannot be set up.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PitchError {
    #[error("the wave speed must be positive and finite, got {0} m/s")]
    WaveSpeed(f64),
    #[error("the safety factor must be in (0, 1), got {0}")]
    Safety(f64),
    #[error("the end time must be finite, got {0} s")]
    EndTime(f64),
}

/// Computes tent heights on a fixed mesh under the rule in the module docs.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Pitcher {
    budgets: Vec<f64>,
    c_max: f64,
    safety: f64,
    t_end: f64,
    /// `kappa` in `B_T = kappa s (1 - GUARD) h_T / c`: 1, or on meshes that get refined the
    /// smallest child-to-parent width ratio of bisection (at least 1/2).
    margin: f64,
}

impl Pitcher {
    /// A pitcher for fastest wave speed `c_max` (m/s), safety factor `safety` in (0, 1) and end
    /// time `t_end` (s).
    pub fn new(mesh: &Mesh, c_max: f64, safety: f64, t_end: f64) -> Result<Self, PitchError> {
        if !(c_max.is_finite() && c_max > 0.0) {
            return Err(PitchError::WaveSpeed(c_max));
        }
        if !(safety > 0.0 && safety < 1.0) {
            return Err(PitchError::Safety(safety));
        }
        if !t_end.is_finite() {
            return Err(PitchError::EndTime(t_end));
        }
        let mut pitcher = Self {
            budgets: Vec::new(),
            c_max,
            safety,
            t_end,
            margin: 1.0,
        };
        pitcher.update(mesh, 0..mesh.triangles().len() as TriangleId);
        Ok(pitcher)
    }

    /// The same pitcher with budgets scaled by `kappa` = [`Mesh::bisection_width_ratio`]
    /// (1/sqrt(2) on right isosceles meshes, at least 1/2 on any), so that every front triangle
    /// within its budget may be bisected ([`Self::may_bisect`]); see `docs/theory/pitching.md`.
    pub fn for_refinement(mut self, mesh: &Mesh) -> Self {
        self.margin = mesh.bisection_width_ratio();
        self.update(mesh, 0..mesh.triangles().len() as TriangleId);
        self
    }

    /// Recomputes the budgets of `triangles` (new or changed by a mesh operation), sizing the
    /// table to the mesh.
    pub fn update(&mut self, mesh: &Mesh, triangles: impl IntoIterator<Item = TriangleId>) {
        self.budgets.resize(mesh.triangles().len(), 0.0);
        let scale = self.margin * self.causal_width_factor();
        for t in triangles {
            self.budgets[t as usize] =
                scale * mesh.altitudes(t).into_iter().fold(f64::INFINITY, f64::min);
        }
    }

    /// True when bisecting front triangle `t` keeps the front causal for every later tent: its
    /// time spread (vertex times from `time`, s) is at most `s (1 - GUARD) / c` times the
    /// smallest altitude of either child. A child's spread is at most its parent's (its corners
    /// are the parent's and a midpoint), and pitching never widens a spread beyond
    /// `max(B_T, current spread)` with `B_T <= s (1 - GUARD) h_T / c`, so children that pass
    /// keep every later facet causal; with [`Self::for_refinement`] every triangle within its
    /// budget passes. Adaptive refinement judges bisections by this test.
    pub fn may_bisect(&self, mesh: &Mesh, time: impl Fn(VertexId) -> f64, t: TriangleId) -> bool {
        let spread = spread(mesh.triangles()[t as usize].map(time));
        let width = mesh
            .split_children(t, 0.5)
            .into_iter()
            .flat_map(geometry::altitudes)
            .fold(f64::INFINITY, f64::min);
        spread <= self.causal_width_factor() * width
    }

    /// True when splitting the refinement edge of front triangle `t` at `fraction` (from its
    /// smaller-id end, as [`Mesh::split_at`] takes it) keeps the front causal for every later
    /// tent: each child ([`Mesh::split_children`]) has a time spread at most `s (1 - GUARD) / c`
    /// times its own smallest altitude, with vertex times from `time` (s) and the new vertex at
    /// the front's own time there ([`crate::Split::interpolate`]). That is invariant (I*) on the
    /// children, which pitching keeps (it never widens a spread beyond `max(B_T, current
    /// spread)`). It allows whatever [`Self::may_bisect`] allows at the midpoint, which bounds
    /// both children's spreads by their parent's.
    ///
    /// A split near an end of the edge makes a thin child (smallest altitude about
    /// `min(fraction, 1 - fraction)` times the parent's, or less), which passes only where the
    /// front is nearly flat over it; [`Self::for_refinement`] guarantees bisections only. A
    /// refused split changes nothing: the caller keeps the mesh as it is and may ask again after
    /// later tents have changed the times over `t` (the spread varies as its corners are pitched
    /// in turn), or split nearer the middle of the edge.
    pub fn may_split_at(
        &self,
        mesh: &Mesh,
        time: impl Fn(VertexId) -> f64,
        t: TriangleId,
        fraction: f64,
    ) -> bool {
        let r = mesh.refinement_edge(t);
        let tri = mesh.triangles()[t as usize];
        let [z, a, b] = [0, 1, 2].map(|i| time(tri[(r + i) % 3]));
        let [lo, hi] = if tri[(r + 1) % 3] < tri[(r + 2) % 3] {
            [a, b]
        } else {
            [b, a]
        };
        let m = lerp(lo, hi, fraction);
        let children = mesh.split_children(t, fraction);
        [[m, z, a], [m, b, z]]
            .into_iter()
            .zip(children)
            .all(|(times, points)| {
                let width = geometry::altitudes(points)
                    .into_iter()
                    .fold(f64::INFINITY, f64::min);
                spread(times) <= self.causal_width_factor() * width
            })
    }

    /// Follows a coarsening of `mesh` (already applied): drops the removed children's budgets,
    /// renumbering like the mesh, and computes the restored parents'.
    pub fn remove(&mut self, mesh: &Mesh, merge: &Merge) {
        merge.apply_to_triangles(&mut self.budgets);
        self.update(
            mesh,
            merge
                .halves
                .iter()
                .map(|&(parent, _)| merge.triangle_after(parent)),
        );
    }

    /// True when the restored parents of coarsening vertex `m` (with edge `ends`, as
    /// [`Mesh::coarsenable`] reports) keep invariant (I*) at the front's times: each parent
    /// `(z, a, b)`'s time spread is within `s (1 - GUARD) / c` times its smallest altitude.
    pub fn may_coarsen(
        &self,
        mesh: &Mesh,
        front: &Front,
        m: VertexId,
        ends: [VertexId; 2],
    ) -> bool {
        let [a, b] = ends;
        mesh.vertex_neighbors(m)
            .iter()
            .filter(|&&z| z != a && z != b)
            .all(|&z| {
                let times = [z, a, b].map(|w| front.time(w));
                let spread = times.iter().fold(f64::NEG_INFINITY, |x, &y| x.max(y))
                    - times.iter().fold(f64::INFINITY, |x, &y| x.min(y));
                let width = geometry::altitudes([z, a, b].map(|w| mesh.vertex(w)))
                    .into_iter()
                    .fold(f64::INFINITY, f64::min);
                spread <= self.causal_width_factor() * width
            })
    }

    /// `s (1 - GUARD) / c`, s/m: a triangle of minimum width `h` whose time spread is at most
    /// `h` times this has a causal facet; the pitcher keeps every front triangle so.
    pub fn causal_width_factor(&self) -> f64 {
        self.safety * (1.0 - GUARD) / self.c_max
    }

    /// The end time, seconds.
    pub fn t_end(&self) -> f64 {
        self.t_end
    }

    /// Moves the end time to `t_end` (s, finite), for a run that goes on past its first end. The
    /// budgets do not depend on it.
    pub fn set_t_end(&mut self, t_end: f64) {
        assert!(t_end.is_finite(), "the end time must be finite");
        self.t_end = t_end;
    }

    /// The fastest wave speed the front is causal for, m/s.
    pub fn c_max(&self) -> f64 {
        self.c_max
    }

    /// The safety factor `s`: every front facet has `c_max |grad tau| < s`.
    pub fn safety(&self) -> f64 {
        self.safety
    }

    /// Time budget `B_T` of triangle `t`, seconds.
    pub fn budget(&self, t: TriangleId) -> f64 {
        self.budgets[t as usize]
    }

    /// The pole-top time for vertex `v` on `front`, or `None` when `v` is not a local minimum or
    /// has reached the end time.
    pub fn pole_height(&self, mesh: &Mesh, front: &Front, v: VertexId) -> Option<f64> {
        let t_v = front.time(v);
        if t_v >= self.t_end
            || mesh
                .vertex_neighbors(v)
                .iter()
                .any(|&w| front.time(w) < t_v)
        {
            return None;
        }
        let mut top = self.t_end;
        for &t in mesh.vertex_triangles(v) {
            let others = mesh.triangles()[t as usize]
                .into_iter()
                .filter(|&w| w != v)
                .map(|w| front.time(w))
                .fold(f64::INFINITY, f64::min);
            top = top.min(others + self.budgets[t as usize]);
        }
        // No slivers at the end time: rather than leave a gap under half this step, split what
        // remains into two equal steps.
        if top < self.t_end && self.t_end - top < 0.5 * (top - t_v) {
            top = 0.5 * (t_v + self.t_end);
        }
        Some(top)
    }

    /// Pitches a tent at `v` and advances the front, or returns `None` (front unchanged) when `v`
    /// is not a local minimum below the end time.
    pub fn pitch(&self, mesh: &Mesh, front: &Front, v: VertexId) -> Option<Tent> {
        let t_new = self.pole_height(mesh, front, v)?;
        let tent = Tent {
            vertex: v,
            t_old: front.time(v),
            t_new,
        };
        front.set_time(v, t_new);
        Some(tent)
    }
}

/// `max - min` of three times, s.
fn spread(times: [f64; 3]) -> f64 {
    times.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - times.iter().fold(f64::INFINITY, |a, &b| a.min(b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rectangle::{Diagonal, Rectangle};

    fn mesh() -> Mesh {
        Rectangle {
            width: 1.0,
            height: 1.0,
            nx: 2,
            ny: 2,
            diagonal: Diagonal::Right,
            interfaces: Vec::new(),
            sides: Vec::new(),
            perturb: 0.0,
            seed: 0,
        }
        .build()
        .unwrap()
    }

    #[test]
    fn first_tent_reaches_the_slope_bound() {
        let m = mesh();
        let p = Pitcher::new(&m, 2.0, 0.5, 10.0).unwrap();
        let front = Front::flat(m.vertices().len(), 0.0);
        let tent = p.pitch(&m, &front, 4).unwrap();
        let h_min = 0.5 / 2f64.sqrt();
        assert!((tent.t_new - 0.5 * h_min / 2.0).abs() < 1e-9 * tent.t_new);
        let ratio = m
            .vertex_triangles(4)
            .iter()
            .map(|&t| front.slope(&m, t) * p.c_max())
            .fold(0.0, f64::max);
        assert!(ratio < 0.5 && ratio > 0.5 * (1.0 - 1e-6), "{ratio}");
    }

    #[test]
    fn only_local_minima_below_the_end_are_pitched() {
        let m = mesh();
        let p = Pitcher::new(&m, 1.0, 0.9, 0.01).unwrap();
        let front = Front::flat(m.vertices().len(), 0.0);
        let tent = p.pitch(&m, &front, 4).unwrap();
        assert_eq!(tent.t_new, 0.01, "capped exactly at the end time");
        assert!(p.pitch(&m, &front, 4).is_none(), "at the end time");
        assert!(p.pitch(&m, &front, 0).is_some());
        assert!(p.pitch(&m, &front, 0).is_none(), "neighbour 1 is earlier");
        assert!(p.pitch(&m, &front, 1).is_some());
    }

    #[test]
    fn rejects_bad_parameters() {
        let m = mesh();
        assert_eq!(
            Pitcher::new(&m, 0.0, 0.9, 1.0).unwrap_err(),
            PitchError::WaveSpeed(0.0)
        );
        assert_eq!(
            Pitcher::new(&m, 1.0, 1.0, 1.0).unwrap_err(),
            PitchError::Safety(1.0)
        );
        assert!(Pitcher::new(&m, 1.0, 0.9, f64::NAN).is_err());
    }

    #[test]
    fn splits_near_an_edge_end_need_a_flat_front_over_the_thin_child() {
        let m = mesh();
        let p = Pitcher::new(&m, 2.0, 0.5, 10.0).unwrap();
        let f = p.causal_width_factor();
        // Triangle 0 is (0, 1, 4) with refinement edge 0-4 opposite corner 1; at 0.1 the thin
        // child is (m, 0, 1), near vertex 0.
        assert_eq!((m.triangles()[0], m.refinement_edge(0)), ([0, 1, 4], 1));
        let widths = |fraction: f64| {
            m.split_children(0, fraction).map(|c| {
                geometry::altitudes(c)
                    .into_iter()
                    .fold(f64::INFINITY, f64::min)
            })
        };
        let [big, thin] = widths(0.1);
        let half = widths(0.5)[0].min(widths(0.5)[1]);
        assert!(thin < 0.3 * half && big > half, "{thin} {half} {big}");

        // Apex 1 raised: both children span the whole spread, the thin one is refused.
        let spread = 0.5 * f * half;
        let apex = |v: VertexId| if v == 1 { spread } else { 0.0 };
        assert!(p.may_bisect(&m, apex, 0));
        assert!(p.may_split_at(&m, apex, 0, 0.5));
        assert!(p.may_split_at(&m, apex, 0, 0.3));
        assert!(!p.may_split_at(&m, apex, 0, 0.1));
        assert!(
            p.may_split_at(&m, |_| 1.0, 0, 0.01),
            "a flat front allows any split"
        );

        // Vertex 4 raised: the thin child at vertex 0 spans a tenth of the spread only, so the
        // split at 0.1 passes where the parent's spread over the thin child's width would not.
        let spread = 0.9 * f * half;
        let far = |v: VertexId| if v == 4 { spread } else { 0.0 };
        assert!(spread > f * thin);
        assert!(p.may_bisect(&m, far, 0));
        assert!(p.may_split_at(&m, far, 0, 0.1));
        assert!(
            !p.may_split_at(&m, far, 0, 0.9),
            "the thin child at vertex 4 spans it all"
        );

        // The new vertex's time is the front's own value at its fraction of the edge.
        let mut split_mesh = m.clone();
        let mut splits = Vec::new();
        let mut allow = |_: &Mesh, _: &[crate::Split], _: TriangleId, _: f64| true;
        split_mesh
            .split_at(0, 0.3, &mut allow, &mut splits)
            .unwrap();
        let front = Front::flat(m.vertices().len(), 0.0);
        front.set_time(4, 1.0);
        let v = splits[0].vertex;
        assert_eq!(splits[0].ends, [0, 4]);
        assert_eq!(front.time_after(&splits, v), 0.3);
    }
}
