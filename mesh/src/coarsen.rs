//! Coarsening: newest-vertex bisection undone. A vertex that [`Mesh::bisect`] created at the
//! midpoint of an edge `ab` is removed and the one or two triangles `(z, a, b)` it split are
//! restored, with `ab` as their refinement edge. A vertex that [`Mesh::split_at`] put elsewhere
//! on its edge is never removed: coarsening restores bisections only. Ids stay dense: freed ids are filled by moving
//! the last vertex, triangle or edge into them, as [`Vec::swap_remove`] does.

use std::cmp::Reverse;

use crate::geometry;
use crate::mesh::{Edge, EdgeId, Mesh, TriangleId, VertexId};
use crate::refine::{midpoint, sort_pair};

/// Largest distance between a removable vertex and the midpoint of the restored edge, relative
/// to the edge's length. Bisection puts the vertex exactly at the midpoint; a vertex split off
/// it ([`Mesh::split_at`]) stays.
const MIDPOINT_TOLERANCE: f64 = 1e-12;

/// One coarsening: vertex `vertex`, the midpoint of edge `ends`, removed by undoing its
/// bisection.
///
/// Ids before the merge are those of the mesh before the call. To keep per-id data in step with
/// the mesh, callers first update each parent's entry (ids before the merge) and then apply
/// [`Merge::apply_to_vertices`] and [`Merge::apply_to_triangles`], which are
/// `data.swap_remove(vertex)` and `data.swap_remove(child)` for each of `halves` in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Merge {
    /// The removed vertex (id before the merge).
    pub vertex: VertexId,
    /// The restored edge, smaller id first (ids before the merge).
    pub ends: [VertexId; 2],
    /// One `(parent, child)` pair per restored triangle (one on the boundary, two inside), in
    /// decreasing `child` order, ids before the merge: `parent` keeps its id and becomes the
    /// restored triangle `(z, a, b)` with refinement edge `ab` opposite corner 0; `child` is
    /// removed. `parent` was the child `(vertex, z, a)` and `child` was `(vertex, b, z)`, as
    /// [`crate::Split::halves`] names them.
    pub halves: Vec<(TriangleId, TriangleId)>,
    /// `(from, to)` when the last vertex `from` was moved into the freed id `to == vertex`;
    /// `None` when `vertex` was the last one.
    pub moved_vertex: Option<(VertexId, VertexId)>,
    /// The triangle moves, in order: removing each `child` of `halves` in turn moves the then
    /// last triangle `from` into `to == child`, unless `child` is the last one. Removing the
    /// larger child first means earlier removals never move a later `child`, so `to` is its id
    /// before the merge; a parent may be moved.
    pub moved_triangles: Vec<(TriangleId, TriangleId)>,
    /// The removed edges (ids before the merge), in removal order: each removal moves the then
    /// last edge into the freed id (`swap_remove`). The restored edge keeps the id of its half
    /// at its smaller end.
    pub removed_edges: Vec<EdgeId>,
}

impl Merge {
    /// Renumbers per-vertex data as the merge renumbered the vertices: `data.swap_remove(vertex)`.
    /// `data` must have one entry per vertex before the merge.
    pub fn apply_to_vertices<T>(&self, data: &mut Vec<T>) {
        data.swap_remove(self.vertex as usize);
    }

    /// The id after the merge of vertex `v` (not the removed one), given its id before.
    pub fn vertex_after(&self, v: VertexId) -> VertexId {
        match self.moved_vertex {
            Some((from, to)) if from == v => to,
            _ => v,
        }
    }

    /// The id after the merge of triangle `t` (not a removed child), given its id before.
    pub fn triangle_after(&self, t: TriangleId) -> TriangleId {
        self.moved_triangles
            .iter()
            .fold(t, |t, &(from, to)| if t == from { to } else { t })
    }

    /// Renumbers per-triangle data as the merge renumbered the triangles: `data.swap_remove(child)`
    /// for each of `halves` in order. `data` must have one entry per triangle before the merge;
    /// each parent's entry is kept as it is (update it before calling this).
    pub fn apply_to_triangles<T>(&self, data: &mut Vec<T>) {
        for &(_, child) in &self.halves {
            data.swap_remove(child as usize);
        }
    }

    /// Renumbers per-edge data as the merge renumbered the edges: `data.swap_remove(e)` for each
    /// of `removed_edges` in order. `data` must have one entry per edge before the merge.
    pub fn apply_to_edges<T>(&self, data: &mut Vec<T>) {
        for &e in &self.removed_edges {
            data.swap_remove(e as usize);
        }
    }
}

/// A child of `m` viewed from `m`: triangle `t` is `(m, x, y)` counter-clockwise with `m`
/// opposite its refinement edge; `edges` are its edges opposite `m`, `x` and `y`.
#[derive(Clone, Copy)]
struct Fan {
    t: TriangleId,
    x: VertexId,
    y: VertexId,
    edges: [EdgeId; 3],
}

/// One restored triangle: `parent` is `(m, z, a)`, `child` is `(m, b, z)`, each edge named by its
/// ends (`am` is the half of `ab` at `a`).
#[derive(Clone, Copy)]
struct Half {
    parent: TriangleId,
    child: TriangleId,
    z: VertexId,
    a: VertexId,
    b: VertexId,
    za: EdgeId,
    bz: EdgeId,
    am: EdgeId,
    mb: EdgeId,
    zm: EdgeId,
}

impl Mesh {
    /// The edge ends `[a, b]`, smaller id first, if vertex `m` can be removed by undoing a
    /// bisection; `None` otherwise. Conditions: `m` was created by bisection (not by
    /// [`Mesh::new`]); every triangle of the star of `m` has `m` opposite
    /// its refinement edge; the star has four triangles around `m` (interior) or two (boundary)
    /// that pair up as `(m, z, a)`, `(m, b, z)` around the two (or one) apexes `z`, restoring
    /// `(z, a, b)`; `m` is the midpoint of `ab` (relative tolerance 1e-12, so a vertex of
    /// [`Mesh::split_at`] off the midpoint never qualifies) and `ab` is not an edge yet; the
    /// halves `am`, `mb` carry the same tag and the edges `zm` none.
    ///
    /// When both diagonals of an interior star qualify (`m` the midpoint of both, as in right
    /// isosceles meshes), the pairing whose apexes are of the later generation wins: a triangle
    /// made by bisection has its apex as its youngest corner, so this finds the bisection that
    /// created `m` unless its parents were triangles of [`Mesh::new`]. Then the pairing whose
    /// parents include the smallest triangle id of the star wins, which undoes the bisection if
    /// no renumbering moved its children. Panics if `m` is not a vertex id.
    pub fn coarsenable(&self, m: VertexId) -> Option<[VertexId; 2]> {
        self.merge_plan(m).map(|(ends, _)| ends)
    }

    /// Removes vertex `m` and restores the triangles it split (see [`Mesh::coarsenable`]), or
    /// returns `None` and leaves the mesh unchanged if `m` is not coarsenable.
    ///
    /// The restored edge `ab` keeps the id of its half at its smaller end and its tag; the other
    /// half and the edges `zm` are removed. Freed ids are filled by moving the last vertex,
    /// triangle or edge into them (see [`Merge`]); all adjacency is updated accordingly. Edge
    /// moves are not reported.
    pub fn coarsen(&mut self, m: VertexId) -> Option<Merge> {
        let ([p, q], halves) = self.merge_plan(m)?;
        let first = halves[0];
        let (kept_edge, other_half) = if first.a == p {
            (first.am, first.mb)
        } else {
            (first.mb, first.am)
        };
        let mut parents = [Some(first.parent), halves.get(1).map(|h| h.parent)];
        sort_pair(&mut parents);
        self.edges[kept_edge as usize] = Edge {
            vertices: [p, q],
            triangles: parents,
            tag: self.edges[kept_edge as usize].tag,
        };
        for h in &halves {
            let parent = h.parent as usize;
            self.triangles[parent] = [h.z, h.a, h.b];
            self.triangle_edges[parent] = [kept_edge, h.bz, h.za];
            self.refinement_edge[parent] = 0;
            let across = &mut self.edges[h.bz as usize].triangles;
            for slot in across.iter_mut().filter(|s| **s == Some(h.child)) {
                *slot = Some(h.parent);
            }
            sort_pair(across);
            remove_sorted(&mut self.vertex_triangles[h.z as usize], h.child);
            replace_sorted(&mut self.vertex_triangles[h.b as usize], h.child, h.parent);
            remove_sorted(&mut self.vertex_neighbors[h.z as usize], m);
        }
        replace_sorted(&mut self.vertex_neighbors[p as usize], m, q);
        replace_sorted(&mut self.vertex_neighbors[q as usize], m, p);

        // Largest id first, so that the last edge is never one still to be removed.
        let mut dead: Vec<EdgeId> = halves.iter().map(|h| h.zm).collect();
        dead.push(other_half);
        dead.sort_unstable_by_key(|&e| Reverse(e));
        for &e in &dead {
            self.remove_edge(e);
        }
        let moved_triangles = halves
            .iter()
            .filter_map(|h| self.remove_triangle(h.child))
            .collect();
        let moved_vertex = self.remove_vertex(m);
        Some(Merge {
            vertex: m,
            ends: [p, q],
            halves: halves.iter().map(|h| (h.parent, h.child)).collect(),
            moved_vertex,
            moved_triangles,
            removed_edges: dead,
        })
    }

    /// The restored edge (smaller id first) and the halves, in decreasing child order, of the
    /// merge that removes `m` (see [`Mesh::coarsenable`]).
    fn merge_plan(&self, m: VertexId) -> Option<([VertexId; 2], Vec<Half>)> {
        let star = &self.vertex_triangles[m as usize];
        if self.generation[m as usize] == 0 || (star.len() != 2 && star.len() != 4) {
            return None;
        }
        let mut fan = Vec::with_capacity(4);
        for &t in star {
            let (tri, ids) = (self.triangles[t as usize], self.triangle_edges[t as usize]);
            let r = self.refinement_edge(t);
            if tri[r] != m {
                return None;
            }
            let rot = |i: usize| (r + i) % 3;
            fan.push(Fan {
                t,
                x: tri[rot(1)],
                y: tri[rot(2)],
                edges: [ids[r], ids[rot(1)], ids[rot(2)]],
            });
        }
        // The half whose parent is `kept`: the child is the triangle across the edge `m x`.
        let half = |kept: &Fan| {
            let child = fan.iter().find(|f| f.y == kept.x)?;
            Some(Half {
                parent: kept.t,
                child: child.t,
                z: kept.x,
                a: kept.y,
                b: child.x,
                za: kept.edges[0],
                bz: child.edges[0],
                am: kept.edges[1],
                mb: child.edges[2],
                zm: kept.edges[2],
            })
        };
        // Each choice of parents: one triangle on the boundary, two of the four inside.
        let choices: Vec<Vec<&Fan>> = if fan.len() == 2 {
            fan.iter().map(|f| vec![f]).collect()
        } else {
            (0..4)
                .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
                .map(|(i, j)| vec![&fan[i], &fan[j]])
                .collect()
        };
        choices
            .into_iter()
            .filter_map(|kept| {
                let halves = kept.into_iter().map(half).collect::<Option<Vec<_>>>()?;
                self.merge_is_valid(m, &halves).then_some(halves)
            })
            .min_by_key(|halves| {
                let apexes = halves.iter().map(|h| self.generation[h.z as usize]);
                let parents = halves.iter().map(|h| h.parent);
                (Reverse(apexes.min()), parents.min())
            })
            .map(|mut halves| {
                halves.sort_unstable_by_key(|h| Reverse(h.child));
                let [a, b] = [halves[0].a, halves[0].b];
                ([a.min(b), a.max(b)], halves)
            })
    }

    /// Whether `halves` (pairs of triangles around `m` as [`Mesh::merge_plan`] builds them)
    /// restore conforming triangles: they cover the star of `m` once, share the edge `ab`
    /// with `m` at its midpoint, and tags allow removing `m`.
    fn merge_is_valid(&self, m: VertexId, halves: &[Half]) -> bool {
        let mut used: Vec<TriangleId> = halves.iter().flat_map(|h| [h.parent, h.child]).collect();
        used.sort_unstable();
        if used != self.vertex_triangles[m as usize] {
            return false;
        }
        let [a, b] = [halves[0].a, halves[0].b];
        if let [_, other] = halves
            && [other.a, other.b] != [b, a]
        {
            return false;
        }
        let (pa, pb) = (self.vertex(a), self.vertex(b));
        let off = geometry::distance(self.vertex(m), midpoint(pa, pb));
        let tag = |e: EdgeId| self.edges[e as usize].tag;
        off <= MIDPOINT_TOLERANCE * geometry::distance(pa, pb)
            && self.vertex_neighbors[a as usize].binary_search(&b).is_err()
            && tag(halves[0].am) == tag(halves[0].mb)
            && halves.iter().all(|h| tag(h.zm).is_none())
    }

    /// Removes edge `e`, which no triangle refers to, moving the last edge into its id.
    fn remove_edge(&mut self, e: EdgeId) {
        let last = (self.edges.len() - 1) as EdgeId;
        self.edges.swap_remove(e as usize);
        if e == last {
            return;
        }
        for t in self.edges[e as usize].triangles.into_iter().flatten() {
            let ids = &mut self.triangle_edges[t as usize];
            let slot = ids.iter_mut().find(|id| **id == last);
            *slot.expect("a triangle lists its edges") = e;
        }
    }

    /// Removes triangle `t`, which no edge or vertex star refers to, moving the last triangle
    /// into its id; returns that move as `(from, to)`.
    fn remove_triangle(&mut self, t: TriangleId) -> Option<(TriangleId, TriangleId)> {
        let last = (self.triangles.len() - 1) as TriangleId;
        self.triangles.swap_remove(t as usize);
        self.triangle_edges.swap_remove(t as usize);
        self.refinement_edge.swap_remove(t as usize);
        if t == last {
            return None;
        }
        for e in self.triangle_edges[t as usize] {
            let pair = &mut self.edges[e as usize].triangles;
            for slot in pair.iter_mut().filter(|s| **s == Some(last)) {
                *slot = Some(t);
            }
            sort_pair(pair);
        }
        for v in self.triangles[t as usize] {
            replace_sorted(&mut self.vertex_triangles[v as usize], last, t);
        }
        Some((last, t))
    }

    /// Removes vertex `v`, which no triangle, edge or neighbour list refers to, moving the last
    /// vertex into its id; returns that move as `(from, to)`.
    fn remove_vertex(&mut self, v: VertexId) -> Option<(VertexId, VertexId)> {
        let last = (self.vertices.len() - 1) as VertexId;
        self.vertices.swap_remove(v as usize);
        self.generation.swap_remove(v as usize);
        self.vertex_triangles.swap_remove(v as usize);
        self.vertex_neighbors.swap_remove(v as usize);
        if v == last {
            return None;
        }
        for &t in &self.vertex_triangles[v as usize] {
            for corner in &mut self.triangles[t as usize] {
                if *corner == last {
                    *corner = v;
                }
            }
            for e in self.triangle_edges[t as usize] {
                let ends = &mut self.edges[e as usize].vertices;
                if ends[1] == last {
                    // `last` exceeds every other id, so it was the larger end.
                    *ends = [ends[0].min(v), ends[0].max(v)];
                }
            }
        }
        let neighbors = std::mem::take(&mut self.vertex_neighbors[v as usize]);
        for &w in &neighbors {
            replace_sorted(&mut self.vertex_neighbors[w as usize], last, v);
        }
        self.vertex_neighbors[v as usize] = neighbors;
        Some((last, v))
    }
}

/// Removes `old` from an increasing list.
fn remove_sorted(list: &mut Vec<u32>, old: u32) {
    let i = list
        .binary_search(&old)
        .expect("the entry to remove is listed");
    list.remove(i);
}

/// Replaces `old` by `new` in an increasing list, keeping it increasing.
fn replace_sorted(list: &mut Vec<u32>, old: u32, new: u32) {
    remove_sorted(list, old);
    let i = list
        .binary_search(&new)
        .expect_err("the new entry is not listed yet");
    list.insert(i, new);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;
    use crate::rectangle::{Diagonal, GridSegment, Rectangle};
    use crate::testing::{XorShift, refine, square, tagged, total_area};

    /// Coarsens `v`, which must be coarsenable, and checks the result.
    fn coarsen(m: &mut Mesh, v: VertexId) -> Merge {
        let ends = m.coarsenable(v).expect("coarsenable");
        let merge = m.coarsen(v).unwrap();
        assert_eq!(merge.ends, ends);
        m.validate().unwrap();
        merge
    }

    /// Positions, triangles with their edges, edges, vertex stars and vertex neighbours.
    type Snapshot = (
        Vec<Point>,
        Vec<([VertexId; 3], [EdgeId; 3])>,
        Vec<Edge>,
        Vec<Vec<TriangleId>>,
        Vec<Vec<VertexId>>,
    );

    /// Everything a mesh stores, with each triangle's corners (and edges) rotated so that the
    /// corner opposite its refinement edge comes first.
    fn canonical(m: &Mesh) -> Snapshot {
        let triangles = (0..m.triangles().len() as TriangleId)
            .map(|t| {
                let r = m.refinement_edge(t);
                let (tri, ids) = (m.triangles()[t as usize], m.triangle_edges(t));
                let rot = |i| (r + i) % 3;
                (
                    [tri[r], tri[rot(1)], tri[rot(2)]],
                    [ids[r], ids[rot(1)], ids[rot(2)]],
                )
            })
            .collect();
        let vertices = 0..m.vertices().len() as VertexId;
        (
            m.vertices().to_vec(),
            triangles,
            m.edges().to_vec(),
            vertices
                .clone()
                .map(|v| m.vertex_triangles(v).to_vec())
                .collect(),
            vertices.map(|v| m.vertex_neighbors(v).to_vec()).collect(),
        )
    }

    #[test]
    fn coarsening_an_interior_bisection_restores_the_mesh() {
        let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
        let original = canonical(&m);
        let splits = refine(&mut m, 0);
        assert_eq!(splits.len(), 1);
        // Both diagonals of the cell pass through the new vertex 9 at their midpoints.
        assert_eq!(m.vertex_neighbors(9), &[0, 1, 3, 4]);
        assert_eq!(m.coarsenable(9), Some([0, 4]));
        let moved = m.map_vertices(|p| [p[0], 2.0 * p[1]]).unwrap();
        assert_eq!(moved.coarsenable(9), Some([0, 4]));
        let merge = coarsen(&mut m, 9);
        assert_eq!(
            merge,
            Merge {
                vertex: 9,
                ends: [0, 4],
                halves: vec![(1, 9), (0, 8)],
                moved_vertex: None,
                moved_triangles: vec![],
                removed_edges: merge.removed_edges.clone(),
            }
        );
        assert_eq!(
            merge.removed_edges.len(),
            3,
            "both edges zm and one half of ab"
        );
        assert!(canonical(&m) == original);
    }

    #[test]
    fn coarsening_a_boundary_bisection_restores_the_mesh() {
        let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
        refine(&mut m, 0);
        let before = canonical(&m);
        let bottom = m.tag_id("bottom");
        let t = (0..m.triangles().len() as TriangleId)
            .find(|&t| {
                let e = m.triangle_edges(t)[m.refinement_edge(t)];
                m.edges()[e as usize].tag == bottom
            })
            .unwrap();
        let splits = refine(&mut m, t);
        assert_eq!(splits.len(), 1);
        let split = &splits[0];
        assert_eq!(split.halves.len(), 1);
        assert_eq!(m.vertex_triangles(split.vertex).len(), 2);
        let merge = coarsen(&mut m, split.vertex);
        assert_eq!(merge.vertex, split.vertex);
        assert_eq!(merge.ends, split.ends);
        assert_eq!(merge.halves, split.halves);
        assert_eq!((merge.moved_vertex, merge.moved_triangles), (None, vec![]));
        assert!(canonical(&m) == before);
        assert!((tagged(&m, "bottom").1 - 1.0).abs() < 1e-15);
    }

    #[test]
    fn undoing_random_refinement_in_reverse_restores_the_mesh() {
        let mut r = square(4, Diagonal::Alternate, 0.2);
        r.interfaces = vec![GridSegment {
            from: [0.0, 0.5],
            to: [0.75, 0.5],
            tag: "crack".into(),
        }];
        let mut m = r.build().unwrap();
        let original = canonical(&m);
        let mut rng = XorShift(2024);
        let mut splits = Vec::new();
        for _ in 0..150 {
            let t = rng.below(m.triangles().len());
            splits.extend(refine(&mut m, t));
        }
        assert!(splits.len() > 150);
        for split in splits.iter().rev() {
            let merge = coarsen(&mut m, split.vertex);
            assert_eq!(merge.ends, split.ends);
            let undone: Vec<_> = merge.halves.iter().rev().copied().collect();
            assert_eq!(undone, split.halves);
            assert_eq!((merge.moved_vertex, merge.moved_triangles), (None, vec![]));
        }
        assert!(canonical(&m) == original);
    }

    #[test]
    fn only_newest_vertices_of_unrefined_children_are_coarsenable() {
        for diagonal in [Diagonal::Right, Diagonal::Left] {
            let m = square(3, diagonal, 0.0).build().unwrap();
            assert!((0..16).all(|v| m.coarsenable(v).is_none()), "{diagonal:?}");
        }
        let m = square(4, Diagonal::Alternate, 0.2).build().unwrap();
        assert!((0..25).all(|v| m.coarsenable(v).is_none()));

        // The children of a boundary bisection: refining one of them makes the vertex stay.
        let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
        refine(&mut m, 0);
        let bottom = m.tag_id("bottom");
        let t = (0..m.triangles().len() as TriangleId)
            .find(|&t| {
                let e = m.triangle_edges(t)[m.refinement_edge(t)];
                m.edges()[e as usize].tag == bottom
            })
            .unwrap();
        let boundary = refine(&mut m, t);
        assert_eq!(boundary.len(), 1);
        let (v, (kept, new)) = (boundary[0].vertex, boundary[0].halves[0]);
        assert_eq!(m.vertex_triangles(v), &[kept, new]);
        assert!(m.coarsenable(v).is_some());
        let mut one = m.clone();
        refine(&mut one, new);
        assert_eq!(one.vertex_triangles(v).len(), 3);
        assert_eq!(one.coarsenable(v), None);
        assert!(one.coarsen(v).is_none());
        one.validate().unwrap();

        // An interior bisection whose four children were all bisected again.
        let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
        let v = refine(&mut m, 0)[0].vertex;
        for _ in 0..4 {
            let &t = m
                .vertex_triangles(v)
                .iter()
                .find(|&&t| m.triangles()[t as usize][m.refinement_edge(t)] == v)
                .unwrap();
            refine(&mut m, t);
        }
        assert_eq!(m.vertex_triangles(v).len(), 8);
        assert_eq!(m.coarsenable(v), None);
        let newest: Vec<_> = (9..m.vertices().len() as VertexId)
            .filter(|&w| m.coarsenable(w).is_some())
            .collect();
        assert!(!newest.is_empty() && !newest.contains(&v));
    }

    #[test]
    fn generation_tags_and_position_decide_whether_a_boundary_vertex_goes() {
        // Triangle (z, a, b) = (2, 0, 1) with its refinement edge 0-1 on the side "right".
        let v = vec![[0.0, 0.0], [2.0, 0.0], [1.0, 0.5]];
        let names = vec!["left".into(), "right".into()];
        let base = Mesh::new(v, vec![[0, 1, 2]], names, &[([0, 1], 1)]).unwrap();
        assert_eq!(base.refinement_edge(0), 2);
        let mut m = base.clone();
        let split = refine(&mut m, 0).remove(0);
        assert_eq!((split.vertex, split.ends), (3, [0, 1]));
        assert_eq!(m.coarsenable(3), Some([0, 1]));

        let mut retagged = m.clone();
        let half = retagged.edges.iter_mut().find(|e| e.vertices == [0, 3]);
        half.unwrap().tag = Some(0);
        assert_eq!(retagged.coarsenable(3), None);
        for off in [[0.9, 0.0], [1.0, 1e-9]] {
            let mut moved = m.clone();
            moved.vertices[3] = off;
            assert_eq!(moved.coarsenable(3), None, "{off:?}");
        }
        let rebuilt = Mesh::new(
            m.vertices().to_vec(),
            m.triangles().to_vec(),
            m.tag_names().to_vec(),
            &m.tagged_edges(),
        )
        .unwrap();
        assert_eq!(rebuilt.coarsenable(3), None);

        let merge = coarsen(&mut m, 3);
        assert_eq!(merge.halves, vec![(0, 1)]);
        assert_eq!(m.triangles(), &[[2, 0, 1]]);
        assert_eq!(m.refinement_edge(0), 0);
        assert_eq!(m.edges()[m.triangle_edges(0)[0] as usize].tag, Some(1));
        assert!(canonical(&m) == canonical(&base));
    }

    #[test]
    fn merge_helpers_match_swap_remove() {
        let merge = |vertex, halves, moved_triangles| Merge {
            vertex,
            ends: [7, 8],
            halves,
            moved_vertex: None,
            moved_triangles,
            removed_edges: vec![],
        };
        let mut vertices = vec![10, 11, 12, 13];
        merge(1, vec![], vec![]).apply_to_vertices(&mut vertices);
        assert_eq!(vertices, [10, 13, 12]);
        merge(2, vec![], vec![]).apply_to_vertices(&mut vertices);
        assert_eq!(vertices, [10, 13]);
        // The first child is the last triangle: nothing moves into its id.
        let mut triangles: Vec<u32> = (0..5).collect();
        merge(9, vec![(0, 4), (2, 1)], vec![(3, 1)]).apply_to_triangles(&mut triangles);
        assert_eq!(triangles, [0, 3, 2]);
        // Parent 4 is moved into child 3's id, then into child 0's.
        let mut triangles: Vec<u32> = (0..5).collect();
        merge(9, vec![(4, 3), (1, 0)], vec![(4, 3), (3, 0)]).apply_to_triangles(&mut triangles);
        assert_eq!(triangles, [4, 1, 2]);
    }

    /// The triangles as corner points, the corner opposite the refinement edge first, sorted:
    /// the triangulation and its refinement edges independent of ids.
    fn shapes(m: &Mesh) -> Vec<[[u64; 2]; 3]> {
        let mut shapes: Vec<_> = (0..m.triangles().len() as TriangleId)
            .map(|t| {
                let (r, p) = (m.refinement_edge(t), m.triangle_points(t));
                [0, 1, 2].map(|i| p[(r + i) % 3].map(f64::to_bits))
            })
            .collect();
        shapes.sort_unstable();
        shapes
    }

    /// Random refinement, then coarsening until no vertex is left to remove, keeping per-vertex
    /// positions and per-triangle areas in step through the merges' renumbering.
    fn refine_and_coarsen_back(r: &Rectangle, seed: u64) {
        let mut m = r.build().unwrap();
        let original = shapes(&m);
        let (vertices, triangles) = (m.vertices().len(), m.triangles().len());
        let names = ["left", "right", "bottom", "top", "crack"];
        let lengths = names.map(|s| tagged(&m, s).1);
        let mut positions = m.vertices().to_vec();
        let mut areas: Vec<f64> = (0..triangles as TriangleId).map(|t| m.area(t)).collect();
        let mut rng = XorShift(seed);
        for _ in 0..200 {
            let t = rng.below(m.triangles().len());
            for split in refine(&mut m, t) {
                positions.push(m.vertex(split.vertex));
                for (kept, new) in split.halves {
                    areas[kept as usize] = m.area(kept);
                    assert_eq!(areas.len(), new as usize);
                    areas.push(m.area(new));
                }
            }
        }
        assert!(m.triangles().len() > 3 * triangles);

        let mut moves = 0;
        while let Some(v) =
            (0..m.vertices().len() as VertexId).find(|&v| m.coarsenable(v).is_some())
        {
            let merge = coarsen(&mut m, v);
            let last = positions.len() as VertexId - 1;
            assert_eq!(merge.moved_vertex, (v != last).then_some((last, v)));
            // The triangle moves are those of `swap_remove` of each child in turn.
            let mut count = areas.len() as TriangleId;
            let mut expected = Vec::new();
            for &(parent, child) in &merge.halves {
                areas[parent as usize] += areas[child as usize];
                count -= 1;
                if child != count {
                    expected.push((count, child));
                }
            }
            assert_eq!(merge.moved_triangles, expected);
            moves += expected.len();
            merge.apply_to_vertices(&mut positions);
            merge.apply_to_triangles(&mut areas);
            assert_eq!(positions, m.vertices());
        }
        assert!(moves > 10, "{moves} triangle moves");
        assert_eq!(m.vertices().len(), vertices);
        assert_eq!(m.triangles().len(), triangles);
        assert!((total_area(&m) - 1.0).abs() < 1e-12);
        for (name, length) in names.iter().zip(lengths) {
            assert!((tagged(&m, name).1 - length).abs() < 1e-12, "{name}");
        }
        assert_eq!(shapes(&m), original);
        for (t, area) in areas.iter().enumerate() {
            assert!(
                (area - m.area(t as TriangleId)).abs() < 1e-15,
                "triangle {t}"
            );
        }
    }

    #[test]
    fn random_refinement_coarsens_back_to_the_initial_mesh() {
        let mut cracked = square(4, Diagonal::Alternate, 0.2);
        cracked.interfaces = vec![GridSegment {
            from: [0.0, 0.5],
            to: [0.75, 0.5],
            tag: "crack".into(),
        }];
        refine_and_coarsen_back(&square(3, Diagonal::Right, 0.0), 0x9E37_79B9_7F4A_7C15);
        refine_and_coarsen_back(&cracked, 12345);
    }

    #[test]
    fn only_midpoint_splits_are_coarsenable() {
        for (fraction, coarsenable) in [(0.5, true), (0.3, false), (0.5 + 1e-9, false)] {
            for t in [0, 2] {
                let mut m = square(2, Diagonal::Right, 0.0).build().unwrap();
                let mut splits = Vec::new();
                let mut allow = |_: &Mesh, _: &[crate::Split], _: TriangleId, _: f64| true;
                assert_eq!(m.split_at(t, fraction, &mut allow, &mut splits), Ok(true));
                let v = splits.last().unwrap().vertex;
                assert_eq!(m.coarsenable(v).is_some(), coarsenable, "{fraction} {t}");
                if !coarsenable {
                    assert!(m.coarsen(v).is_none());
                    m.validate().unwrap();
                }
            }
        }
    }
}
