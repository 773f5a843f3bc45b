//! Conforming local refinement by newest-vertex bisection (NVB).
//!
//! A triangle `(z, a, b)` (counter-clockwise, refinement edge `ab` opposite `z`) is bisected at
//! the midpoint `m` of `ab` into the children `(m, z, a)` and `(m, b, z)`, each with its
//! refinement edge opposite the newest vertex `m` at corner 0. With the longest-edge marking of
//! [`Mesh::new`] the descendants of a triangle fall into at most four similarity classes, so
//! angles stay bounded away from zero.
//!
//! [`Mesh::split_at`] splits a refinement edge at any interior point instead (crack alignment):
//! the same closure and the same children, with the new vertex where the caller wants it.

use std::collections::HashMap;

use crate::geometry::{self, Point};
use crate::mesh::{Edge, EdgeId, Mesh, TriangleId, VertexId};

/// Levels of bisection explored by [`Mesh::bisection_width_ratio`].
pub const WIDTH_RATIO_DEPTH: u32 = 6;

/// The test [`Mesh::split_at`] asks before each step: `allow(mesh, done, u, fraction)` is true
/// when triangle `u` of `mesh` may be split at `fraction` of its refinement edge from the
/// smaller-id end, after the steps `done` of the call.
pub type AllowSplit<'a> = dyn FnMut(&Mesh, &[Split], TriangleId, f64) -> bool + 'a;

/// One edge split: edge `ends` split at `fraction` of its length from `ends[0]`, the new vertex
/// `vertex`.
#[derive(Clone, Debug, PartialEq)]
pub struct Split {
    /// The new vertex, at `ends[0] + fraction (ends[1] - ends[0])`.
    pub vertex: VertexId,
    /// End vertices of the split edge, smaller id first.
    pub ends: [VertexId; 2],
    /// Where the new vertex lies on the edge, from `ends[0]` (0) to `ends[1]` (1): exactly 1/2
    /// for a bisection, anything in (0, 1) for [`Mesh::split_at`].
    pub fraction: f64,
    /// One `(kept, new)` entry per split triangle: one on a boundary edge, two inside. Both
    /// children lie inside the old triangle `kept`: for its old corners `(z, a, b)` with
    /// refinement edge `ab`, `kept` keeps its id and becomes `(vertex, z, a)`, and `new` is a
    /// freshly appended triangle `(vertex, b, z)`.
    pub halves: Vec<(TriangleId, TriangleId)>,
    /// The halves of the split edge: the one at `ends[0]` keeps the edge's id, the one at
    /// `ends[1]` is freshly appended; both keep its tag.
    pub edges: [EdgeId; 2],
}

impl Split {
    /// The value at the new vertex of the function linear along the edge that takes the values
    /// `at_ends` at `ends`: `(1 - fraction) at_ends[0] + fraction at_ends[1]`. For a bisection
    /// this is the mean of the two, to the last bit. The mesh places the new vertex by this
    /// rule, and front times follow it, so that the front does not move.
    pub fn interpolate(&self, at_ends: [f64; 2]) -> f64 {
        lerp(at_ends[0], at_ends[1], self.fraction)
    }
}

/// Why [`Mesh::split_at`] cannot split an edge.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum SplitError {
    #[error("triangle {triangle} does not exist: the mesh has {count} triangles")]
    Triangle { triangle: TriangleId, count: usize },
    #[error("the split fraction must be strictly between 0 and 1, got {0}")]
    Fraction(f64),
    #[error(
        "splitting the refinement edge of triangle {triangle} at fraction {fraction} leaves a \
         degenerate child: the point is too close to an end of the edge"
    )]
    Degenerate { triangle: TriangleId, fraction: f64 },
    #[error("a triangle has corners 0, 1 and 2, got corner {0}")]
    Corner(usize),
}

impl Mesh {
    /// Bisects triangle `t` by newest-vertex bisection, first bisecting whatever neighbours the
    /// closure needs so that the mesh stays conforming.
    ///
    /// Each step splits one edge in every triangle that has it as refinement edge (two inside,
    /// one on the boundary). Before each step, `allow` is asked about every triangle the step
    /// would split (all of them, with the mesh as it is before the step and the steps this call
    /// has done so far, in order); if it returns false
    /// for any of them, refinement stops there and `bisect` returns false. Every step done is
    /// pushed to `splits` in order, and the mesh is conforming after each one. Returns true when
    /// `t` itself was bisected.
    ///
    /// Ids are only appended, never removed or renumbered: a step adds one vertex, one triangle
    /// per split triangle, and one edge per split triangle plus one. The split edge keeps its id
    /// for the half at its smaller end vertex; both halves keep its tag, the new interior edges
    /// have none.
    pub fn bisect(
        &mut self,
        t: TriangleId,
        allow: &mut dyn FnMut(&Mesh, &[Split], TriangleId) -> bool,
        splits: &mut Vec<Split>,
    ) -> bool {
        self.refine_edge(t, 0.5, &mut |mesh, done, u, _| allow(mesh, done, u), splits)
    }

    /// Splits the refinement edge of triangle `t` at the point `p + fraction (q - p)`, where `p`
    /// and `q` are its end vertices, smaller id first (as in [`Edge::vertices`] and
    /// [`Split::ends`]), after the closure [`Mesh::bisect`] does: neighbours are bisected at
    /// midpoints as needed, and only the last step, which splits `t` and the triangle across its
    /// refinement edge, uses `fraction`. That step's children, ids, tags and refinement edges
    /// are those of a bisection (see [`Split`]); with `fraction = 1/2` the call is exactly
    /// [`Mesh::bisect`].
    ///
    /// `allow(mesh, done, u, fraction)` is asked before each step about every triangle `u` the
    /// step would split, with the step's fraction (1/2 for the closure); a refusal stops
    /// refinement there, as in [`Mesh::bisect`]. Returns `Ok(true)` when `t` was split,
    /// `Ok(false)` when a step was refused (the steps done are in `splits`, the mesh is
    /// conforming).
    ///
    /// Errors, with the mesh unchanged: `t` is not a triangle, `fraction` is not strictly between
    /// 0 and 1, or a child of the last step would be degenerate (flatter than [`Mesh::new`]
    /// accepts, or not counter-clockwise after rounding the new point).
    ///
    /// Children of an off-midpoint split leave the similarity classes of newest-vertex
    /// bisection: their descendants' angles are bounded by theirs, not by the initial mesh's,
    /// and [`Mesh::bisection_width_ratio`] does not cover them. A vertex not at the midpoint of
    /// its edge is never removed by [`Mesh::coarsen`].
    pub fn split_at(
        &mut self,
        t: TriangleId,
        fraction: f64,
        allow: &mut AllowSplit,
        splits: &mut Vec<Split>,
    ) -> Result<bool, SplitError> {
        let count = self.triangles.len();
        if t as usize >= count {
            return Err(SplitError::Triangle { triangle: t, count });
        }
        if !(fraction > 0.0 && fraction < 1.0) {
            return Err(SplitError::Fraction(fraction));
        }
        let e = self.refinement_edge_id(t);
        let [p, q] = self.edges[e as usize].vertices;
        let m = lerp_point(self.vertex(p), self.vertex(q), fraction);
        // The closure leaves `t` as it is and bisects the triangle across its refinement edge
        // at most once, if that edge is not its own refinement edge: the child that then lies
        // across has that midpoint as its apex.
        for u in self.edges[e as usize].triangles.into_iter().flatten() {
            let apex = if self.refinement_edge_id(u) == e {
                self.vertex(self.opposite(u, e))
            } else {
                let [x, y] = self.edges[self.refinement_edge_id(u) as usize].vertices;
                midpoint(self.vertex(x), self.vertex(y))
            };
            let (a, b) = self.oriented_ends(u, e);
            let [a, b] = [a, b].map(|v| self.vertex(v));
            if !([[m, apex, a], [m, b, apex]].into_iter()).all(is_valid_triangle) {
                return Err(SplitError::Degenerate {
                    triangle: t,
                    fraction,
                });
            }
        }
        Ok(self.refine_edge(t, fraction, allow, splits))
    }

    /// Splits the edge of triangle `t` opposite its corner `corner` (0, 1 or 2) at `fraction` of
    /// its length from its smaller-id end, so that the new vertex is joined to that corner: the
    /// crack-alignment step, where the corner is a crack tip and the new edge runs in a wanted
    /// direction. `t` first takes that edge as its refinement edge (newest-vertex labels may be
    /// chosen freely: the closure only needs them to form no cycle), then [`Mesh::split_at`]
    /// splits it; the triangle across is bisected first when the edge is not its own
    /// refinement edge.
    ///
    /// Returns `Ok(false)` with the mesh unchanged when the new label would make the closure's
    /// chain of refinement edges come back to `t`, or when the first step is refused; a later
    /// refusal keeps the steps done, as [`Mesh::split_at`] does, and `t` keeps its new label.
    /// Errors as [`Mesh::split_at`], and a corner out of range is a [`SplitError::Corner`]; the
    /// mesh is unchanged on every error. A relabelled triangle's children are never coarsened
    /// into it, and the triangle itself no longer into its former parent.
    pub fn split_toward(
        &mut self,
        t: TriangleId,
        corner: usize,
        fraction: f64,
        allow: &mut AllowSplit,
        splits: &mut Vec<Split>,
    ) -> Result<bool, SplitError> {
        let count = self.triangles.len();
        if t as usize >= count {
            return Err(SplitError::Triangle { triangle: t, count });
        }
        if corner > 2 {
            return Err(SplitError::Corner(corner));
        }
        let label = self.refinement_edge[t as usize];
        self.refinement_edge[t as usize] = corner as u8;
        if self.closure_returns_to(t) {
            self.refinement_edge[t as usize] = label;
            return Ok(false);
        }
        let before = splits.len();
        let result = self.split_at(t, fraction, allow, splits);
        if result.is_err() || splits.len() == before {
            self.refinement_edge[t as usize] = label;
        }
        result
    }

    /// The triangles a bisection of `t` would split as the mesh is now: the chain across
    /// refinement edges that the closure of [`Mesh::bisect`] follows from `t`, and the triangle
    /// across the last one's refinement edge (the closure then also splits children of these,
    /// whose corners are theirs or new vertices). At most `limit` triangles: a longer chain is
    /// cut there.
    pub fn bisection_chain(&self, t: TriangleId, limit: usize) -> Vec<TriangleId> {
        let mut chain = vec![t];
        let mut s = t;
        while chain.len() < limit {
            let Some((u, compatible)) = self.across_refinement_edge(s) else {
                break;
            };
            chain.push(u);
            if compatible {
                break;
            }
            s = u;
        }
        chain
    }

    /// The triangle across the refinement edge of `s`, and whether that edge is its refinement
    /// edge too (the closure's chain ends there); `None` on the boundary.
    fn across_refinement_edge(&self, s: TriangleId) -> Option<(TriangleId, bool)> {
        let e = self.refinement_edge_id(s);
        let u = self.edges[e as usize]
            .triangles
            .into_iter()
            .flatten()
            .find(|&u| u != s)?;
        Some((u, self.refinement_edge_id(u) == e))
    }

    /// True when the chain the closure of a split of `t`'s refinement edge follows (the
    /// triangle across an edge that is not its refinement edge, then across that one, ...)
    /// comes back to `t` or does not end.
    fn closure_returns_to(&self, t: TriangleId) -> bool {
        let mut s = t;
        for _ in 0..self.triangles.len() {
            let Some((u, compatible)) = self.across_refinement_edge(s) else {
                return false;
            };
            if compatible {
                return false;
            }
            if u == t {
                return true;
            }
            s = u;
        }
        true
    }

    /// [`Mesh::split_at`] without its checks: `fraction` is in (0, 1) and gives valid children.
    fn refine_edge(
        &mut self,
        t: TriangleId,
        fraction: f64,
        allow: &mut AllowSplit,
        splits: &mut Vec<Split>,
    ) -> bool {
        // Triangles waiting for the one above them to be split; the last is handled next.
        let mut pending = vec![t];
        let first = splits.len();
        while let Some(&s) = pending.last() {
            let e = self.refinement_edge_id(s);
            let triangles = self.edges[e as usize].triangles;
            if let Some(u) = triangles.into_iter().flatten().find(|&u| u != s)
                && self.refinement_edge_id(u) != e
            {
                assert!(
                    !pending.contains(&u),
                    "refinement edges around triangle {u} form a cycle"
                );
                pending.push(u);
                continue;
            }
            // Only `t`'s own edge, the last step, is split off its midpoint.
            let step = if pending.len() == 1 { fraction } else { 0.5 };
            let mut allowed = true;
            for u in triangles.into_iter().flatten() {
                allowed &= allow(self, &splits[first..], u, step);
            }
            if !allowed {
                return false;
            }
            splits.push(self.split_edge(e, step));
            pending.pop();
        }
        true
    }

    /// The two children that splitting the refinement edge of `t` at `fraction` (from its
    /// smaller-id end, as in [`Mesh::split_at`]; 1/2 for a bisection) would create, as
    /// counter-clockwise corner points in metres: first the one that keeps the id `t`, then the
    /// new one (see [`Split::halves`]).
    pub fn split_children(&self, t: TriangleId, fraction: f64) -> [[Point; 3]; 2] {
        let r = self.refinement_edge(t);
        let tri = self.triangles[t as usize];
        let (z, a, b) = (tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]);
        let m = lerp_point(self.vertex(a.min(b)), self.vertex(a.max(b)), fraction);
        let [z, a, b] = [z, a, b].map(|v| self.vertex(v));
        [[m, z, a], [m, b, z]]
    }

    /// The smallest ratio of a child's minimum width (smallest altitude) to its parent's over
    /// every bisection newest-vertex bisection can make on this mesh: at least 1/2 for any
    /// triangle, 1/sqrt(2) for right isosceles ones. Each initial triangle is bisected on its own
    /// to depth [`WIDTH_RATIO_DEPTH`], which visits all of its descendants' shapes (there are at
    /// most four up to similarity, reached within three levels).
    pub fn bisection_width_ratio(&self) -> f64 {
        let width = |p: [Point; 3]| {
            geometry::altitudes(p)
                .into_iter()
                .fold(f64::INFINITY, f64::min)
        };
        let mut ratio: f64 = 1.0;
        let mut stack = Vec::new();
        for t in 0..self.triangles.len() as TriangleId {
            let r = self.refinement_edge(t);
            let p = self.triangle_points(t);
            // Corners apex first: the refinement edge is opposite corner 0.
            stack.push(([p[r], p[(r + 1) % 3], p[(r + 2) % 3]], 0));
            while let Some(([z, a, b], depth)) = stack.pop() {
                let m = midpoint(a, b);
                let parent = width([z, a, b]);
                for child in [[m, z, a], [m, b, z]] {
                    ratio = ratio.min(width(child) / parent);
                    if depth + 1 < WIDTH_RATIO_DEPTH {
                        stack.push((child, depth + 1));
                    }
                }
            }
        }
        ratio
    }

    /// Consistency check used by tests: rebuilds the adjacency from scratch with [`Mesh::new`]
    /// on the current vertices, triangles and tags and compares edges (end vertices, tags and
    /// triangles), triangle edges, vertex stars and vertex neighbours, and checks that every
    /// triangle is counter-clockwise with positive area and every vertex has a generation.
    /// Returns the first difference found.
    pub fn validate(&self) -> Result<(), String> {
        if self.refinement_edge.len() != self.triangles.len() {
            return Err("one refinement edge per triangle expected".into());
        }
        if self.generation.len() != self.vertices.len() {
            return Err("one generation per vertex expected".into());
        }
        for t in 0..self.triangles.len() as TriangleId {
            if self.area(t) <= 0.0 {
                return Err(format!("triangle {t} is not counter-clockwise"));
            }
            if self.refinement_edge(t) > 2 {
                return Err(format!("triangle {t} has no valid refinement edge"));
            }
        }
        let fresh = Mesh::new(
            self.vertices.clone(),
            self.triangles.clone(),
            self.tag_names.clone(),
            &self.tagged_edges(),
        )
        .map_err(|e| e.to_string())?;
        if fresh.triangles != self.triangles {
            return Err("triangle orientation differs from a rebuild".into());
        }
        if fresh.edges.len() != self.edges.len() {
            return Err(format!(
                "{} edges, a rebuild has {}",
                self.edges.len(),
                fresh.edges.len()
            ));
        }
        let mut expected: HashMap<[VertexId; 2], &Edge> =
            fresh.edges.iter().map(|e| (e.vertices, e)).collect();
        for (id, edge) in self.edges.iter().enumerate() {
            match expected.remove(&edge.vertices) {
                Some(want) if want == edge => {}
                Some(want) => return Err(format!("edge {id} is {edge:?}, expected {want:?}")),
                None => return Err(format!("edge {id} {edge:?} is unknown or repeated")),
            }
        }
        for (t, (tri, ids)) in self.triangles.iter().zip(&self.triangle_edges).enumerate() {
            for (i, &e) in ids.iter().enumerate() {
                let (a, b) = (tri[(i + 1) % 3], tri[(i + 2) % 3]);
                if self.edges[e as usize].vertices != [a.min(b), a.max(b)] {
                    return Err(format!(
                        "edge {i} of triangle {t} is not opposite corner {i}"
                    ));
                }
            }
        }
        if fresh.vertex_triangles != self.vertex_triangles {
            return Err("vertex stars differ from a rebuild".into());
        }
        if fresh.vertex_neighbors != self.vertex_neighbors {
            return Err("vertex neighbours differ from a rebuild".into());
        }
        Ok(())
    }

    /// The refinement edge of triangle `t`.
    fn refinement_edge_id(&self, t: TriangleId) -> EdgeId {
        self.triangle_edges[t as usize][self.refinement_edge(t)]
    }

    /// The corner of triangle `t` opposite its edge `e`.
    fn opposite(&self, t: TriangleId, e: EdgeId) -> VertexId {
        let i = self.triangle_edges[t as usize].iter().position(|&f| f == e);
        self.triangles[t as usize][i.expect("the triangle has the edge")]
    }

    /// The ends `(a, b)` of edge `e` of triangle `t` in the triangle's counter-clockwise order,
    /// so that `t` is `(z, a, b)` with `z` opposite `e`.
    fn oriented_ends(&self, t: TriangleId, e: EdgeId) -> (VertexId, VertexId) {
        let i = self.triangle_edges[t as usize].iter().position(|&f| f == e);
        let i = i.expect("the triangle has the edge");
        let tri = self.triangles[t as usize];
        (tri[(i + 1) % 3], tri[(i + 2) % 3])
    }

    /// Splits edge `e` at `fraction` of its length from its smaller-id end in every triangle
    /// that contains it; each must have `e` as its refinement edge.
    fn split_edge(&mut self, e: EdgeId, fraction: f64) -> Split {
        let old = self.edges[e as usize];
        let [p, q] = old.vertices;
        let m = next_id(self.vertices.len());
        let generation = (old.triangles.into_iter().flatten())
            .flat_map(|k| self.triangles[k as usize])
            .map(|v| self.generation[v as usize])
            .max()
            .expect("an edge has a triangle");
        self.generation.push(generation + 1);
        self.vertices
            .push(lerp_point(self.vertex(p), self.vertex(q), fraction));
        self.vertex_triangles.push(Vec::new());
        self.vertex_neighbors.push(vec![p, q]);
        let eq = next_id(self.edges.len());
        self.edges[e as usize] = Edge {
            vertices: [p, m],
            triangles: [None, None],
            tag: old.tag,
        };
        self.edges.push(Edge {
            vertices: [q, m],
            triangles: [None, None],
            tag: old.tag,
        });
        let half = |v: VertexId| if v == p { e } else { eq };

        let mut halves = Vec::with_capacity(2);
        for k in old.triangles.into_iter().flatten() {
            let r = self.refinement_edge(k);
            debug_assert_eq!(self.triangle_edges[k as usize][r], e);
            let tri = self.triangles[k as usize];
            let (z, a, b) = (tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]);
            let ids = self.triangle_edges[k as usize];
            let (bz, za) = (ids[(r + 1) % 3], ids[(r + 2) % 3]);
            let n = next_id(self.triangles.len());
            let zm = next_id(self.edges.len());
            self.edges.push(Edge {
                vertices: [z, m],
                triangles: [Some(k), Some(n)],
                tag: None,
            });
            let (ha, hb) = (half(a), half(b));
            self.triangles[k as usize] = [m, z, a];
            self.triangle_edges[k as usize] = [za, ha, zm];
            self.refinement_edge[k as usize] = 0;
            self.triangles.push([m, b, z]);
            self.triangle_edges.push([bz, zm, hb]);
            self.refinement_edge.push(0);
            add_triangle(&mut self.edges[ha as usize], k);
            add_triangle(&mut self.edges[hb as usize], n);
            let across = &mut self.edges[bz as usize].triangles;
            for slot in across.iter_mut().filter(|s| **s == Some(k)) {
                *slot = Some(n);
            }
            sort_pair(across);
            self.vertex_triangles[m as usize].extend([k, n]);
            self.vertex_triangles[z as usize].push(n);
            replace_sorted(&mut self.vertex_triangles[b as usize], k, n);
            self.vertex_neighbors[z as usize].push(m);
            self.vertex_neighbors[m as usize].push(z);
            halves.push((k, n));
        }
        replace_sorted(&mut self.vertex_neighbors[p as usize], q, m);
        replace_sorted(&mut self.vertex_neighbors[q as usize], p, m);
        self.vertex_neighbors[m as usize].sort_unstable();
        self.vertex_triangles[m as usize].sort_unstable();
        Split {
            vertex: m,
            ends: [p, q],
            fraction,
            halves,
            edges: [e, eq],
        }
    }
}

/// Midpoint of segment `ab`; symmetric in `a` and `b` to the last bit.
pub(crate) fn midpoint(a: Point, b: Point) -> Point {
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
}

/// `(1 - f) a + f b`. At `f = 1/2` both products are exact halvings, so the one rounding of the
/// sum gives the midpoint `0.5 (a + b)` to the last bit (no intermediate is subnormal for
/// coordinates and times).
pub(crate) fn lerp(a: f64, b: f64, f: f64) -> f64 {
    (1.0 - f) * a + f * b
}

/// [`lerp`] of each coordinate: the point at `fraction` of segment `ab` from `a`.
fn lerp_point(a: Point, b: Point, fraction: f64) -> Point {
    [0, 1].map(|i| lerp(a[i], b[i], fraction))
}

/// True when corners `p` form a counter-clockwise triangle that [`Mesh::new`] accepts.
fn is_valid_triangle(p: [Point; 3]) -> bool {
    geometry::signed_area2(p[0], p[1], p[2]) > 0.0 && !geometry::is_degenerate(p)
}

/// The id of the next item of a list of length `len`.
fn next_id(len: usize) -> u32 {
    u32::try_from(len).expect("mesh ids exceed 32 bits")
}

/// Adds triangle `t` to an edge that has a free slot, keeping the smaller id first.
fn add_triangle(edge: &mut Edge, t: TriangleId) {
    let slot = edge.triangles.iter().position(Option::is_none);
    edge.triangles[slot.expect("an edge has at most two triangles")] = Some(t);
    sort_pair(&mut edge.triangles);
}

/// Orders an edge's triangles: the smaller id first, `None` last.
pub(crate) fn sort_pair(pair: &mut [Option<TriangleId>; 2]) {
    match *pair {
        [None, Some(_)] => pair.swap(0, 1),
        [Some(a), Some(b)] if b < a => pair.swap(0, 1),
        _ => {}
    }
}

/// Removes `old` from an increasing list and appends `new`, which exceeds every entry.
fn replace_sorted(list: &mut Vec<u32>, old: u32, new: u32) {
    let i = list
        .binary_search(&old)
        .expect("the entry to replace is listed");
    list.remove(i);
    list.push(new);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry;
    use crate::rectangle::{Diagonal, GridSegment};
    use crate::testing::{XorShift, allow_all, refine, square, tagged, total_area};

    fn counts(m: &Mesh) -> [usize; 3] {
        [m.vertices().len(), m.triangles().len(), m.edges().len()]
    }

    fn min_angle(m: &Mesh) -> f64 {
        (0..m.triangles().len() as TriangleId)
            .flat_map(|t| m.angles(t))
            .fold(f64::INFINITY, f64::min)
    }

    /// `count` bisections of random triangles, validating after each.
    fn refine_randomly(m: &mut Mesh, count: usize, seed: u64) {
        let mut rng = XorShift(seed);
        for _ in 0..count {
            let t = rng.below(m.triangles().len());
            refine(m, t);
        }
    }

    #[test]
    fn initial_refinement_edge_is_the_longest() {
        let m = square(4, Diagonal::Alternate, 0.2).build().unwrap();
        for t in 0..m.triangles().len() as TriangleId {
            let lengths = m.triangle_edges(t).map(|e| m.edge_length(e));
            let longest = lengths.iter().cloned().fold(0.0, f64::max);
            assert_eq!(lengths[m.refinement_edge(t)], longest);
        }
        let right = square(2, Diagonal::Right, 0.0).build().unwrap();
        // Triangle (0, 1, 4): the diagonal 0-4 is opposite corner 1.
        assert_eq!(right.triangles()[0], [0, 1, 4]);
        assert_eq!(right.refinement_edge(0), 1);
    }

    #[test]
    fn bisecting_an_interior_refinement_edge_splits_both_triangles() {
        let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
        assert_eq!(counts(&m), [9, 8, 16]);
        let predicted = [m.split_children(0, 0.5), m.split_children(1, 0.5)];
        let splits = refine(&mut m, 0);
        assert_eq!(
            splits,
            vec![Split {
                vertex: 9,
                ends: [0, 4],
                fraction: 0.5,
                halves: vec![(0, 8), (1, 9)],
                edges: splits[0].edges,
            }]
        );
        let halves = splits[0].edges.map(|e| m.edges()[e as usize].vertices);
        assert_eq!(halves, [[0, 9], [4, 9]]);
        assert_eq!(counts(&m), [10, 10, 19]);
        assert_eq!(m.vertex(9), [0.25, 0.25]);
        for (k, ((kept, new), children)) in splits[0].halves.iter().zip(predicted).enumerate() {
            assert_eq!(m.triangle_points(*kept), children[0], "half {k}");
            assert_eq!(m.triangle_points(*new), children[1], "half {k}");
            assert_eq!(m.area(*kept), 0.0625);
            assert_eq!(m.area(*new), 0.0625);
        }
        assert!((total_area(&m) - 1.0).abs() < 1e-15);
        assert_eq!(tagged(&m, "bottom"), (2, 1.0));
        let diagonal: Vec<_> = m.edges().iter().filter(|e| e.vertices[1] == 9).collect();
        assert_eq!(diagonal.len(), 4);
        assert!(diagonal.iter().all(|e| !e.is_boundary() && e.tag.is_none()));
    }

    #[test]
    fn bisecting_a_boundary_refinement_edge_keeps_the_side_tag() {
        let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
        refine(&mut m, 0);
        let bottom = m.tag_id("bottom");
        let t = (0..m.triangles().len() as TriangleId)
            .find(|&t| m.edges()[m.refinement_edge_id(t) as usize].tag == bottom)
            .unwrap();
        let before = counts(&m);
        let splits = refine(&mut m, t);
        assert_eq!(splits.len(), 1);
        assert_eq!(splits[0].ends, [0, 1]);
        assert_eq!(splits[0].halves, vec![(t, before[1] as TriangleId)]);
        assert_eq!(counts(&m), [before[0] + 1, before[1] + 1, before[2] + 2]);
        assert_eq!(m.vertex(splits[0].vertex), [0.25, 0.0]);
        let (count, length) = tagged(&m, "bottom");
        assert_eq!(count, 3);
        assert!((length - 1.0).abs() < 1e-15);
        assert!(m.edges().iter().all(|e| e.tag != bottom || e.is_boundary()));
        assert!((total_area(&m) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn closure_bisects_the_neighbour_first() {
        let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
        refine(&mut m, 0);
        // Triangle 0 is now (9, 1, 4) with refinement edge 1-4, which its neighbour (1, 5, 4)
        // does not share as refinement edge: that neighbour's diagonal goes first.
        assert_eq!(m.triangles()[0], [9, 1, 4]);
        let splits = refine(&mut m, 0);
        assert_eq!(splits.len(), 2);
        assert_eq!(splits[0].ends, [1, 5]);
        assert_eq!(splits[1].ends, [1, 4]);
        assert_eq!(splits[1].halves.len(), 2);
        assert_eq!(splits[1].halves[0].0, 0);
        assert_eq!(counts(&m), [12, 14, 25]);
    }

    #[test]
    fn random_refinement_of_a_right_isosceles_mesh_keeps_triangles_similar() {
        for diagonal in [Diagonal::Right, Diagonal::Alternate] {
            let mut m = square(3, diagonal, 0.0).build().unwrap();
            refine_randomly(&mut m, 300, 0x9E37_79B9_7F4A_7C15);
            assert!(m.triangles().len() > 600);
            assert!((total_area(&m) - 1.0).abs() < 1e-12);
            for t in 0..m.triangles().len() as TriangleId {
                for a in m.angles(t).map(f64::to_degrees) {
                    assert!(
                        (a - 45.0).abs() < 1e-9 || (a - 90.0).abs() < 1e-9,
                        "{diagonal:?} triangle {t} angle {a}"
                    );
                }
            }
        }
    }

    /// Smallest angle over the bisection tree of a triangle given by counter-clockwise corners
    /// with the refinement edge opposite corner 0, `depth` levels deep.
    fn tree_min_angle(p: [Point; 3], depth: u32) -> f64 {
        let own = geometry::angles(p)
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        if depth == 0 {
            return own;
        }
        let m = midpoint(p[1], p[2]);
        let left = tree_min_angle([m, p[0], p[1]], depth - 1);
        let right = tree_min_angle([m, p[2], p[0]], depth - 1);
        own.min(left).min(right)
    }

    #[test]
    fn random_refinement_of_a_perturbed_mesh_keeps_angles_bounded() {
        let mut r = square(4, Diagonal::Alternate, 0.2);
        r.interfaces = vec![GridSegment {
            from: [0.0, 0.5],
            to: [0.75, 0.5],
            tag: "crack".into(),
        }];
        let mut m = r.build().unwrap();
        let initial = min_angle(&m);
        // Every triangle NVB creates lies in the bisection tree of an initial triangle, whose
        // shapes repeat after two levels (at most four similarity classes): six levels give the
        // exact smallest angle refinement can reach.
        let reachable = (0..m.triangles().len() as TriangleId)
            .map(|t| {
                let (r, p) = (m.refinement_edge(t), m.triangle_points(t));
                tree_min_angle([p[r], p[(r + 1) % 3], p[(r + 2) % 3]], 6)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(reachable >= initial / 4.0);
        assert!(reachable < initial);
        let sides = ["left", "right", "bottom", "top", "crack"].map(|s| tagged(&m, s).1);

        refine_randomly(&mut m, 400, 12345);
        assert!(m.triangles().len() > 800);
        let smallest = min_angle(&m);
        assert!(smallest >= reachable - 1e-12, "{smallest} < {reachable}");
        assert!((total_area(&m) - 1.0).abs() < 1e-12);
        for (name, length) in ["left", "right", "bottom", "top", "crack"]
            .iter()
            .zip(sides)
        {
            assert!((tagged(&m, name).1 - length).abs() < 1e-12, "{name}");
        }
        let crack = m.tag_id("crack");
        assert!(m.edges().iter().all(|e| e.tag != crack || e.is_interface()));
        assert!(tagged(&m, "crack").0 > 3);
    }

    #[test]
    fn width_ratio_bounds_every_bisection_refinement_makes() {
        let right = square(3, Diagonal::Right, 0.0).build().unwrap();
        assert!((right.bisection_width_ratio() - 0.5f64.sqrt()).abs() < 1e-12);
        let mut m = square(4, Diagonal::Alternate, 0.2).build().unwrap();
        let kappa = m.bisection_width_ratio();
        assert!((0.5..0.5f64.sqrt()).contains(&kappa), "{kappa}");
        let width =
            |m: &Mesh, t: TriangleId| m.altitudes(t).into_iter().fold(f64::INFINITY, f64::min);
        let mut rng = XorShift(99);
        let mut checked = 0;
        for _ in 0..300 {
            let t = rng.below(m.triangles().len());
            let before: Vec<f64> = (0..m.triangles().len() as TriangleId)
                .map(|u| width(&m, u))
                .collect();
            let splits = refine(&mut m, t);
            // A single split has the triangles of `before` as parents.
            if let [split] = &splits[..] {
                for &(kept, new) in &split.halves {
                    for child in [kept, new] {
                        let r = width(&m, child) / before[kept as usize];
                        assert!(r >= kappa * (1.0 - 1e-12), "{r} < {kappa}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 200, "{checked}");
    }

    /// The chain lists exactly the triangles a bisection then splits (kept ids, existing
    /// before it); the closure's other splits are of their children.
    #[test]
    fn the_bisection_chain_lists_the_triangles_a_bisection_splits() {
        let mut m = square(4, Diagonal::Alternate, 0.1).build().unwrap();
        let mut rng = XorShift(5);
        let mut longest = 0;
        for _ in 0..300 {
            let t = rng.below(m.triangles().len());
            let chain = m.bisection_chain(t, usize::MAX);
            let before = m.triangles().len() as TriangleId;
            let mut split: Vec<TriangleId> = refine(&mut m, t)
                .iter()
                .flat_map(|s| s.halves.iter().map(|&(kept, _)| kept))
                .filter(|&kept| kept < before)
                .collect();
            split.sort_unstable();
            split.dedup();
            let mut listed = chain.clone();
            listed.sort_unstable();
            assert_eq!(listed, split, "triangle {t}: chain {chain:?}");
            longest = longest.max(chain.len());
        }
        assert!(longest >= 4, "only chains of {longest}");
        let cut = m.bisection_chain(0, 2);
        assert!(cut.len() <= 2);
    }

    #[test]
    fn grading_toward_a_corner_stays_local() {
        let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
        let mut calls = 0;
        loop {
            let (shortest, longest) = m.edge_length_range();
            if shortest / longest < 1e-4 {
                break;
            }
            let &t = m
                .vertex_triangles(0)
                .iter()
                .min_by(|&&a, &&b| m.area(a).total_cmp(&m.area(b)))
                .unwrap();
            let mut splits = Vec::new();
            assert!(m.bisect(t, &mut allow_all, &mut splits));
            calls += 1;
        }
        m.validate().unwrap();
        assert!(calls < 40, "{calls} bisections");
        // O(levels): a bounded number of triangles per level, far below 2000.
        let triangles = m.triangles().len();
        assert!(triangles < 8 + 4 * calls, "{triangles} triangles");
        assert!((total_area(&m) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn refused_split_stops_refinement_and_lists_the_splits_done() {
        let mut m = square(3, Diagonal::Alternate, 0.1).build().unwrap();
        refine_randomly(&mut m, 40, 99);
        // A triangle whose closure takes at least three splits.
        let t = (0..m.triangles().len() as TriangleId)
            .find(|&t| {
                let mut trial = m.clone();
                let mut splits = Vec::new();
                trial.bisect(t, &mut allow_all, &mut splits);
                splits.len() >= 3
            })
            .unwrap();
        let corners = m.triangles()[t as usize];

        let mut nothing = Vec::new();
        let mut untouched = m.clone();
        assert!(!untouched.bisect(t, &mut |_, _, _| false, &mut nothing));
        assert!(nothing.is_empty());
        assert_eq!(counts(&untouched), counts(&m));
        assert_eq!(untouched.triangles(), m.triangles());

        let before = counts(&m);
        let mut asked = Vec::new();
        let mut splits = Vec::new();
        let done = m.bisect(
            t,
            &mut |mesh, done, u| {
                assert!(
                    done.iter()
                        .all(|s| (s.vertex as usize) < mesh.vertices().len())
                );
                asked.push((mesh.triangles().len(), u));
                u != t
            },
            &mut splits,
        );
        assert!(!done);
        m.validate().unwrap();
        assert_eq!(m.triangles()[t as usize], corners);
        assert!(splits.len() >= 2);

        // Each split was asked about its triangles with the mesh as it was before the split.
        let mut triangles = before[1];
        let mut edges = before[2];
        let mut asked = asked.into_iter();
        for (i, split) in splits.iter().enumerate() {
            assert_eq!(split.vertex as usize, before[0] + i);
            let size = triangles;
            for &(kept, new) in &split.halves {
                assert_eq!(asked.next(), Some((size, kept)));
                assert!((kept as usize) < size);
                assert_eq!(new as usize, triangles);
                assert!(m.triangles()[new as usize].contains(&split.vertex));
                triangles += 1;
                edges += 1;
            }
            edges += 1;
            let half = m
                .edges()
                .iter()
                .find(|e| e.vertices == [split.ends[0], split.vertex])
                .unwrap();
            assert_eq!(half.is_boundary(), split.halves.len() == 1);
        }
        assert_eq!(counts(&m), [before[0] + splits.len(), triangles, edges]);
        // The refused step asked about `t` and then changed nothing.
        assert!(asked.any(|(size, u)| size == triangles && u == t));
    }

    #[test]
    fn map_vertices_keeps_refinement_edges() {
        let mut m = square(2, Diagonal::Left, 0.0).build().unwrap();
        refine(&mut m, 3);
        refine(&mut m, 5);
        // A reflection reverses orientation, so corners get reordered by `Mesh::new`.
        let mirrored = m.map_vertices(|p| [2.0 - 3.0 * p[0], p[1]]).unwrap();
        for t in 0..m.triangles().len() as TriangleId {
            let z = m.triangles()[t as usize][m.refinement_edge(t)];
            let mz = mirrored.triangles()[t as usize][mirrored.refinement_edge(t)];
            assert_eq!(z, mz, "triangle {t}");
        }
        let mut mirrored = mirrored;
        refine(&mut mirrored, 0);
    }

    /// Twice the signed area of corners `p`.
    fn area2(p: [Point; 3]) -> f64 {
        geometry::signed_area2(p[0], p[1], p[2])
    }

    /// Triangles of a refined, perturbed mesh whose refinement edges are interior with a shared
    /// refinement edge, interior needing the closure, and on the boundary.
    fn split_cases() -> (Mesh, Vec<TriangleId>) {
        let mut m = square(4, Diagonal::Alternate, 0.2).build().unwrap();
        refine_randomly(&mut m, 30, 7);
        let kind = |m: &Mesh, t: TriangleId| {
            let e = m.refinement_edge_id(t);
            match m.edges()[e as usize].triangles {
                [_, None] => 0,
                [Some(a), Some(b)] => {
                    let u = if a == t { b } else { a };
                    1 + usize::from(m.refinement_edge_id(u) != e)
                }
                [None, _] => unreachable!("an edge has a first triangle"),
            }
        };
        let cases = (0..3)
            .map(|k| {
                (0..m.triangles().len() as TriangleId)
                    .find(|&t| kind(&m, t) == k)
                    .unwrap()
            })
            .collect();
        (m, cases)
    }

    #[test]
    fn split_at_any_fraction_puts_the_vertex_on_the_edge_and_keeps_the_mesh_conforming() {
        let (base, cases) = split_cases();
        for fraction in [0.1, 0.3, 0.5, 0.77] {
            for &t in &cases {
                let mut m = base.clone();
                let e = m.refinement_edge_id(t);
                let [p, q] = m.edges()[e as usize].vertices;
                let [pp, pq] = [p, q].map(|v| m.vertex(v));
                let predicted = m.split_children(t, fraction);
                let tag = m.edges()[e as usize].tag;
                // Per triangle `allow` is asked about: the step, the triangle, twice its area
                // and the step's fraction.
                let mut asked = Vec::new();
                let mut splits = Vec::new();
                let mut allow = |mesh: &Mesh, done: &[Split], u: TriangleId, f: f64| {
                    asked.push((done.len(), u, area2(mesh.triangle_points(u)), f));
                    true
                };
                assert_eq!(m.split_at(t, fraction, &mut allow, &mut splits), Ok(true));
                m.validate().unwrap();
                let last = splits.last().unwrap();
                assert!(splits[..splits.len() - 1].iter().all(|s| s.fraction == 0.5));
                let parents: Vec<(TriangleId, f64)> = asked
                    .iter()
                    .filter(|a| a.0 == splits.len() - 1)
                    .map(|&(_, u, twice, f)| {
                        assert_eq!(f, fraction);
                        (u, twice)
                    })
                    .collect();
                assert!(asked.iter().all(|a| a.0 == splits.len() - 1 || a.3 == 0.5));
                assert_eq!((last.ends, last.fraction), ([p, q], fraction));
                let x = m.vertex(last.vertex);
                let want = [0, 1].map(|i| (1.0 - fraction) * pp[i] + fraction * pq[i]);
                assert_eq!(x, want, "{fraction} {t}");
                // On the segment to round-off, at the asked fraction of its length.
                let length = geometry::distance(pp, pq);
                let along = geometry::distance(pp, x) / length;
                assert!((along - fraction).abs() < 1e-14, "{along} vs {fraction}");
                assert!(area2([pp, x, pq]).abs() < 1e-14 * length * length);
                let halves = last.edges.map(|h| m.edges()[h as usize]);
                assert_eq!(
                    halves.map(|h| h.vertices),
                    [[p, last.vertex], [q, last.vertex]]
                );
                assert!(halves.iter().all(|h| h.tag == tag));
                assert_eq!(parents.len(), last.halves.len());
                for (&(kept, new), &(parent, twice)) in last.halves.iter().zip(&parents) {
                    assert_eq!(kept, parent);
                    let children = [kept, new].map(|c| area2(m.triangle_points(c)));
                    assert!(children.iter().all(|&a| a > 0.0), "counter-clockwise");
                    assert!((children[0] + children[1] - twice).abs() < 1e-14 * twice);
                    // Each child has the share of the parent's area of its half of the edge.
                    let mut shares = children.map(|c| c / twice);
                    shares.sort_by(f64::total_cmp);
                    let mut expected = [fraction, 1.0 - fraction];
                    expected.sort_by(f64::total_cmp);
                    assert!((shares[0] - expected[0]).abs() < 1e-12, "{shares:?}");
                    // Refinement edges opposite the new vertex, as for a bisection.
                    for c in [kept, new] {
                        let r = m.refinement_edge(c);
                        assert_eq!(m.triangles()[c as usize][r], last.vertex);
                    }
                }
                let (kept, new) = last.halves.iter().find(|h| h.0 == t).copied().unwrap();
                assert_eq!(m.triangle_points(kept), predicted[0]);
                assert_eq!(m.triangle_points(new), predicted[1]);
                assert!((total_area(&m) - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn split_at_the_midpoint_is_bisection_to_the_last_bit() {
        let (base, cases) = split_cases();
        for &t in &cases {
            let (mut bisected, mut split) = (base.clone(), base.clone());
            let (mut a, mut b) = (Vec::new(), Vec::new());
            assert!(bisected.bisect(t, &mut allow_all, &mut a));
            assert_eq!(
                split.split_at(t, 0.5, &mut |_, _, _, _| true, &mut b),
                Ok(true)
            );
            assert_eq!(a, b);
            let bits = |m: &Mesh| -> Vec<[u64; 2]> {
                m.vertices().iter().map(|p| p.map(f64::to_bits)).collect()
            };
            assert_eq!(bits(&bisected), bits(&split));
            assert_eq!(bisected.triangles(), split.triangles());
            assert_eq!(bisected.edges(), split.edges());
        }
        let mut rng = XorShift(5);
        for _ in 0..1000 {
            let [x, y] = [0, 1].map(|_| rng.below(1 << 30) as f64 * 1.37e-9 - 0.7);
            let split = Split {
                vertex: 0,
                ends: [0, 1],
                fraction: 0.5,
                halves: Vec::new(),
                edges: [0, 1],
            };
            assert_eq!(split.interpolate([x, y]), 0.5 * (x + y));
            assert_eq!(midpoint([x, y], [y, x]), lerp_point([x, y], [y, x], 0.5));
        }
    }

    #[test]
    fn split_at_rejects_bad_input_and_leaves_the_mesh_unchanged() {
        let (base, cases) = split_cases();
        let mut m = base.clone();
        let mut splits = Vec::new();
        let mut allow = |_: &Mesh, _: &[Split], _: TriangleId, _: f64| true;
        for bad in [0.0, 1.0, -0.2, 1.5, f64::NAN, f64::INFINITY] {
            let e = m.split_at(cases[0], bad, &mut allow, &mut splits);
            assert!(matches!(e, Err(SplitError::Fraction(_))), "{bad}: {e:?}");
        }
        let count = m.triangles().len();
        let e = m.split_at(count as TriangleId, 0.5, &mut allow, &mut splits);
        assert_eq!(
            e,
            Err(SplitError::Triangle {
                triangle: count as TriangleId,
                count
            })
        );
        // So close to an end that a child is flat at round-off, with and without closure.
        for &t in &cases {
            for f in [1e-15, 1.0 - 1e-15] {
                let e = m.split_at(t, f, &mut allow, &mut splits);
                assert!(matches!(e, Err(SplitError::Degenerate { .. })), "{e:?}");
            }
        }
        assert!(splits.is_empty());
        assert_eq!(counts(&m), counts(&base));
        assert_eq!(m.triangles(), base.triangles());
    }

    #[test]
    fn split_toward_joins_the_corner_to_a_point_of_the_opposite_edge() {
        let (base, cases) = split_cases();
        for &t in &cases {
            for corner in 0..3 {
                let mut m = base.clone();
                let tri = m.triangles()[t as usize];
                let e = m.triangle_edges(t)[corner];
                let [p, q] = m.edges()[e as usize].vertices;
                let mut splits = Vec::new();
                let done = m.split_toward(t, corner, 0.37, &mut |_, _, _, _| true, &mut splits);
                assert_eq!(done, Ok(true), "{t} {corner}");
                m.validate().unwrap();
                let last = splits.last().unwrap();
                assert_eq!((last.ends, last.fraction), ([p, q], 0.37));
                assert!(m.edge_between(tri[corner], last.vertex).is_some());
                let [pp, pq] = [p, q].map(|v| m.vertex(v));
                let want = [0, 1].map(|i| 0.63 * pp[i] + 0.37 * pq[i]);
                assert_eq!(m.vertex(last.vertex), want);
                assert!((total_area(&m) - 1.0).abs() < 1e-12);
            }
        }
        // Refused at the first step, or bad input: nothing changes, labels included.
        let t = cases[2];
        let mut m = base.clone();
        let corner = (m.refinement_edge(t) + 1) % 3;
        let mut splits = Vec::new();
        let refuse = &mut |_: &Mesh, _: &[Split], _: TriangleId, _: f64| false;
        assert_eq!(
            m.split_toward(t, corner, 0.4, refuse, &mut splits),
            Ok(false)
        );
        assert_eq!(
            m.split_toward(t, 3, 0.4, &mut |_, _, _, _| true, &mut splits),
            Err(SplitError::Corner(3))
        );
        let e = m.split_toward(t, corner, 1e-15, &mut |_, _, _, _| true, &mut splits);
        assert!(matches!(e, Err(SplitError::Degenerate { .. })), "{e:?}");
        assert!(splits.is_empty());
        assert_eq!(m.refinement_edge(t), base.refinement_edge(t));
        assert_eq!(m.triangles(), base.triangles());
    }

    #[test]
    fn repeated_splits_toward_corners_keep_the_mesh_valid() {
        let mut m = square(4, Diagonal::Alternate, 0.2).build().unwrap();
        let mut rng = XorShift(11);
        let (mut done, mut refused) = (0, 0);
        for _ in 0..300 {
            let t = rng.below(m.triangles().len());
            let corner = rng.below(3) as usize;
            let fraction = 0.25 + 0.5 * f64::from(rng.below(1000)) / 1000.0;
            let mut splits = Vec::new();
            match m.split_toward(t, corner, fraction, &mut |_, _, _, _| true, &mut splits) {
                Ok(true) => done += 1,
                Ok(false) => refused += 1,
                Err(e) => panic!("{e}"),
            }
            m.validate().unwrap();
        }
        assert!((total_area(&m) - 1.0).abs() < 1e-12);
        assert!(done > 250, "{done} done, {refused} refused");
    }

    #[test]
    fn refused_last_step_keeps_the_closure_done() {
        let (base, cases) = split_cases();
        let t = cases[2];
        let mut m = base.clone();
        let mut splits = Vec::new();
        let done = m.split_at(t, 0.3, &mut |_, _, _, f| f == 0.5, &mut splits);
        assert_eq!(done, Ok(false));
        m.validate().unwrap();
        assert!(!splits.is_empty() && splits.iter().all(|s| s.fraction == 0.5));
        assert_eq!(m.triangles()[t as usize], base.triangles()[t as usize]);
        // Asking again finds the closure done: one step, at the fraction.
        let mut again = Vec::new();
        assert_eq!(
            m.split_at(t, 0.3, &mut |_, _, _, _| true, &mut again),
            Ok(true)
        );
        assert_eq!(again.len(), 1);
        assert_eq!(again[0].fraction, 0.3);
        m.validate().unwrap();
    }
}
