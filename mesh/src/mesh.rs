//! The space triangulation: vertices, counter-clockwise triangles, edges with tags, and the
//! adjacency a tent pitcher and a patch solver need.

use std::collections::HashMap;

use crate::geometry::{self, Point};

/// Index of a vertex in [`Mesh::vertices`].
pub type VertexId = u32;
/// Index of a triangle in [`Mesh::triangles`].
pub type TriangleId = u32;
/// Index of an edge in [`Mesh::edges`].
pub type EdgeId = u32;
/// Index of a tag name in [`Mesh::tag_names`].
pub type TagId = u16;

/// An edge of the triangulation.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Edge {
    /// End vertices, smaller id first.
    pub vertices: [VertexId; 2],
    /// The one or two triangles that contain the edge; the second is `None` on the boundary.
    pub triangles: [Option<TriangleId>; 2],
    /// A boundary side name (`left`, a Gmsh physical group, ...) or, on an interior edge, an
    /// interface (crack or contact line).
    pub tag: Option<TagId>,
}

impl Edge {
    /// True when only one triangle contains the edge.
    pub fn is_boundary(&self) -> bool {
        self.triangles[1].is_none()
    }

    /// True for an interior edge that carries a tag: part of a crack or contact interface.
    pub fn is_interface(&self) -> bool {
        !self.is_boundary() && self.tag.is_some()
    }
}

/// Why a set of vertices and triangles is not a valid triangulation.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    #[error("the mesh has no triangles")]
    Empty,
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex { vertex: usize },
    #[error("triangle {triangle} refers to vertex {vertex}, but there are only {count} vertices")]
    VertexOutOfRange {
        triangle: usize,
        vertex: VertexId,
        count: usize,
    },
    #[error("triangle {triangle} is degenerate (zero area or a repeated vertex)")]
    DegenerateTriangle { triangle: usize },
    #[error("edge ({0}, {1}) belongs to more than two triangles")]
    NonManifoldEdge(VertexId, VertexId),
    #[error("triangles {0} and {1} overlap: they traverse their shared edge in the same direction")]
    Overlap(TriangleId, TriangleId),
    #[error("vertex {0} belongs to no triangle")]
    IsolatedVertex(VertexId),
    #[error("tagged edge ({0}, {1}) is not an edge of the triangulation")]
    UnknownTaggedEdge(VertexId, VertexId),
    #[error("tagged edge ({0}, {1}) refers to tag {2}, but only {3} tags are named")]
    UnknownTag(VertexId, VertexId, TagId, usize),
    #[error("too many {0} for 32-bit indices")]
    TooLarge(&'static str),
}

/// A conforming triangulation of a planar domain with full adjacency.
///
/// Contract: every triangle is counter-clockwise with positive area, every edge belongs to one
/// or two triangles, and every vertex belongs to at least one triangle. Each triangle also
/// carries a refinement edge for newest-vertex bisection (see [`Mesh::bisect`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Mesh {
    pub(crate) vertices: Vec<Point>,
    pub(crate) triangles: Vec<[VertexId; 3]>,
    pub(crate) triangle_edges: Vec<[EdgeId; 3]>,
    /// Per triangle, the corner opposite its refinement edge.
    pub(crate) refinement_edge: Vec<u8>,
    pub(crate) edges: Vec<Edge>,
    /// Per vertex, its triangles in increasing id order.
    pub(crate) vertex_triangles: Vec<Vec<TriangleId>>,
    /// Per vertex, its neighbours in increasing id order.
    pub(crate) vertex_neighbors: Vec<Vec<VertexId>>,
    /// Per vertex, its bisection generation: 0 for the vertices of [`Mesh::new`], and one more
    /// than the largest generation among the corners of the triangles whose bisection created
    /// it. A triangle made by bisection thus has its newest vertex as its youngest corner.
    pub(crate) generation: Vec<u32>,
    pub(crate) tag_names: Vec<String>,
}

impl Mesh {
    /// Builds a mesh from vertex positions (metres) and triangles (any orientation; they are
    /// made counter-clockwise by swapping corners 1 and 2). `tagged_edges` lists edges by their
    /// end vertices with an index into `tag_names`. Each triangle's refinement edge is its
    /// longest edge; equal lengths are ordered by the edges' (smaller, larger) vertex ids, the
    /// smaller pair winning, so that neighbours agree on ties.
    pub fn new(
        vertices: Vec<Point>,
        mut triangles: Vec<[VertexId; 3]>,
        tag_names: Vec<String>,
        tagged_edges: &[([VertexId; 2], TagId)],
    ) -> Result<Self, MeshError> {
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if u32::try_from(vertices.len()).is_err() {
            return Err(MeshError::TooLarge("vertices"));
        }
        if u32::try_from(triangles.len() * 3).is_err() {
            return Err(MeshError::TooLarge("triangles"));
        }
        if let Some(vertex) = vertices
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(MeshError::NonFiniteVertex { vertex });
        }
        for (t, tri) in triangles.iter_mut().enumerate() {
            if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= vertices.len()) {
                return Err(MeshError::VertexOutOfRange {
                    triangle: t,
                    vertex,
                    count: vertices.len(),
                });
            }
            let p = tri.map(|v| vertices[v as usize]);
            if tri[0] == tri[1]
                || tri[1] == tri[2]
                || tri[0] == tri[2]
                || geometry::is_degenerate(p)
            {
                return Err(MeshError::DegenerateTriangle { triangle: t });
            }
            if geometry::signed_area2(p[0], p[1], p[2]) < 0.0 {
                tri.swap(1, 2);
            }
        }

        let mut edges: Vec<Edge> = Vec::new();
        let mut edge_of: HashMap<[VertexId; 2], EdgeId> = HashMap::new();
        let mut triangle_edges = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            let t = t as TriangleId;
            let mut ids = [0; 3];
            for (i, id) in ids.iter_mut().enumerate() {
                let (a, b) = (tri[(i + 1) % 3], tri[(i + 2) % 3]);
                let key = [a.min(b), a.max(b)];
                *id = match edge_of.get(&key) {
                    Some(&e) => {
                        let edge = &mut edges[e as usize];
                        if edge.triangles[1].is_some() {
                            return Err(MeshError::NonManifoldEdge(key[0], key[1]));
                        }
                        let other = edge.triangles[0].expect("an edge has a first triangle");
                        if traverses(triangles[other as usize], a, b) {
                            return Err(MeshError::Overlap(other, t));
                        }
                        edge.triangles[1] = Some(t);
                        e
                    }
                    None => {
                        let e = edges.len() as EdgeId;
                        edges.push(Edge {
                            vertices: key,
                            triangles: [Some(t), None],
                            tag: None,
                        });
                        edge_of.insert(key, e);
                        e
                    }
                };
            }
            triangle_edges.push(ids);
        }
        for &([a, b], tag) in tagged_edges {
            let e = edge_of
                .get(&[a.min(b), a.max(b)])
                .ok_or(MeshError::UnknownTaggedEdge(a, b))?;
            if tag as usize >= tag_names.len() {
                return Err(MeshError::UnknownTag(a, b, tag, tag_names.len()));
            }
            edges[*e as usize].tag = Some(tag);
        }

        let mut vt = vec![Vec::new(); vertices.len()];
        for (t, tri) in triangles.iter().enumerate() {
            for &v in tri {
                vt[v as usize].push(t as TriangleId);
            }
        }
        let mut vn = vec![Vec::new(); vertices.len()];
        for edge in &edges {
            let [a, b] = edge.vertices;
            vn[a as usize].push(b);
            vn[b as usize].push(a);
        }
        if let Some(v) = vt.iter().position(Vec::is_empty) {
            return Err(MeshError::IsolatedVertex(v as VertexId));
        }
        for list in &mut vn {
            list.sort_unstable();
        }
        let refinement_edge = triangle_edges
            .iter()
            .map(|ids| {
                let key = |i: usize| {
                    let edge = &edges[ids[i] as usize];
                    let [a, b] = edge.vertices.map(|v| vertices[v as usize]);
                    (geometry::distance(a, b), edge.vertices)
                };
                // Longest first; among equal lengths the smaller vertex pair.
                (0..3)
                    .reduce(|best, i| {
                        let (lb, vb) = key(best);
                        let (li, vi) = key(i);
                        if li > lb || (li == lb && vi < vb) {
                            i
                        } else {
                            best
                        }
                    })
                    .expect("a triangle has three edges") as u8
            })
            .collect();
        Ok(Self {
            generation: vec![0; vertices.len()],
            vertices,
            triangles,
            triangle_edges,
            refinement_edge,
            edges,
            vertex_triangles: vt,
            vertex_neighbors: vn,
            tag_names,
        })
    }

    /// Vertex positions in metres.
    pub fn vertices(&self) -> &[Point] {
        &self.vertices
    }

    /// Triangles as counter-clockwise vertex triples.
    pub fn triangles(&self) -> &[[VertexId; 3]] {
        &self.triangles
    }

    /// All edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Names of the tags that edges refer to.
    pub fn tag_names(&self) -> &[String] {
        &self.tag_names
    }

    /// The id of a tag name, if any edge set is named so.
    pub fn tag_id(&self, name: &str) -> Option<TagId> {
        self.tag_names
            .iter()
            .position(|n| n == name)
            .map(|i| i as TagId)
    }

    /// The id of tag `name`, added to [`Mesh::tag_names`] if no edge set is named so yet.
    pub fn add_tag(&mut self, name: &str) -> TagId {
        self.tag_id(name).unwrap_or_else(|| {
            self.tag_names.push(name.to_string());
            (self.tag_names.len() - 1) as TagId
        })
    }

    /// Sets the tag of edge `e` (turning an interior edge into an interface, or back). Panics if
    /// `e` is not an edge or `tag` is not a tag id.
    pub fn set_tag(&mut self, e: EdgeId, tag: Option<TagId>) {
        assert!(tag.is_none_or(|t| (t as usize) < self.tag_names.len()));
        self.edges[e as usize].tag = tag;
    }

    /// The edge joining vertices `a` and `b`, if any.
    pub fn edge_between(&self, a: VertexId, b: VertexId) -> Option<EdgeId> {
        self.vertex_triangles[a as usize]
            .iter()
            .flat_map(|&t| self.triangle_edges[t as usize])
            .find(|&e| {
                let [p, q] = self.edges[e as usize].vertices;
                (p == a && q == b) || (p == b && q == a)
            })
    }

    /// Position of vertex `v`.
    pub fn vertex(&self, v: VertexId) -> Point {
        self.vertices[v as usize]
    }

    /// The corners of triangle `t`, counter-clockwise.
    pub fn triangle_points(&self, t: TriangleId) -> [Point; 3] {
        self.triangles[t as usize].map(|v| self.vertex(v))
    }

    /// Edges of triangle `t`; edge `i` is opposite corner `i`.
    pub fn triangle_edges(&self, t: TriangleId) -> [EdgeId; 3] {
        self.triangle_edges[t as usize]
    }

    /// Triangles that contain vertex `v` (its star), in increasing id order.
    pub fn vertex_triangles(&self, v: VertexId) -> &[TriangleId] {
        &self.vertex_triangles[v as usize]
    }

    /// Vertices joined to `v` by an edge, in increasing id order.
    pub fn vertex_neighbors(&self, v: VertexId) -> &[VertexId] {
        &self.vertex_neighbors[v as usize]
    }

    /// The corner of triangle `t` opposite its refinement edge (0, 1 or 2): the edge that
    /// [`Mesh::bisect`] splits at its midpoint and [`Mesh::split_at`] at any point.
    pub fn refinement_edge(&self, t: TriangleId) -> usize {
        self.refinement_edge[t as usize] as usize
    }

    /// Length of edge `e` in metres.
    pub fn edge_length(&self, e: EdgeId) -> f64 {
        let [a, b] = self.edges[e as usize].vertices;
        geometry::distance(self.vertex(a), self.vertex(b))
    }

    /// Area of triangle `t` in square metres.
    pub fn area(&self, t: TriangleId) -> f64 {
        let p = self.triangle_points(t);
        0.5 * geometry::signed_area2(p[0], p[1], p[2])
    }

    /// Altitudes of triangle `t` (metres); entry `i` belongs to corner `i`.
    pub fn altitudes(&self, t: TriangleId) -> [f64; 3] {
        geometry::altitudes(self.triangle_points(t))
    }

    /// Interior angles of triangle `t` (radians); entry `i` belongs to corner `i`.
    pub fn angles(&self, t: TriangleId) -> [f64; 3] {
        geometry::angles(self.triangle_points(t))
    }

    /// The same triangulation, tags, refinement edges and vertex generations with every vertex
    /// moved by `f` (metres to metres). Fails when a triangle degenerates or folds over a
    /// neighbour.
    pub fn map_vertices(&self, f: impl Fn(Point) -> Point) -> Result<Mesh, MeshError> {
        let vertices = self.vertices.iter().map(|&p| f(p)).collect();
        let mut mesh = Mesh::new(
            vertices,
            self.triangles.clone(),
            self.tag_names.clone(),
            &self.tagged_edges(),
        )?;
        for (t, tri) in self.triangles.iter().enumerate() {
            let z = tri[self.refinement_edge[t] as usize];
            let corner = mesh.triangles[t].iter().position(|&v| v == z);
            mesh.refinement_edge[t] = corner.expect("the same triangle") as u8;
        }
        mesh.generation.clone_from(&self.generation);
        Ok(mesh)
    }

    /// Every tagged edge as (end vertices, tag), as [`Mesh::new`] takes them.
    pub(crate) fn tagged_edges(&self) -> Vec<([VertexId; 2], TagId)> {
        self.edges
            .iter()
            .filter_map(|e| e.tag.map(|t| (e.vertices, t)))
            .collect()
    }

    /// Shortest and longest edge lengths of the mesh, in metres.
    pub fn edge_length_range(&self) -> (f64, f64) {
        (0..self.edges.len() as EdgeId)
            .map(|e| self.edge_length(e))
            .fold((f64::INFINITY, 0.0), |(lo, hi), l| (lo.min(l), hi.max(l)))
    }
}

/// True when the counter-clockwise triangle `tri` traverses its edge from `a` to `b`.
fn traverses(tri: [VertexId; 3], a: VertexId, b: VertexId) -> bool {
    (0..3).any(|i| tri[i] == a && tri[(i + 1) % 3] == b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        Mesh::new(
            v,
            vec![[0, 1, 2], [0, 3, 2]],
            vec!["diag".into()],
            &[([0, 2], 0)],
        )
        .unwrap()
    }

    #[test]
    fn builds_adjacency_and_orients_counter_clockwise() {
        let m = square();
        assert_eq!(m.edges().len(), 5);
        assert!((0..2).all(|t| m.area(t) > 0.0));
        assert_eq!(m.vertex_triangles(0), &[0, 1]);
        assert_eq!(m.vertex_neighbors(0), &[1, 2, 3]);
        assert_eq!(m.edges().iter().filter(|e| e.is_boundary()).count(), 4);
        let interface: Vec<_> = m.edges().iter().filter(|e| e.is_interface()).collect();
        assert_eq!(interface.len(), 1);
        assert_eq!(interface[0].vertices, [0, 2]);
        for t in 0..2 {
            for (i, &e) in m.triangle_edges(t).iter().enumerate() {
                let corner = m.triangles()[t as usize][i];
                assert!(!m.edges()[e as usize].vertices.contains(&corner));
            }
        }
    }

    #[test]
    fn rejects_invalid_triangulations() {
        let v = || vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let err = |t: Vec<[u32; 3]>| Mesh::new(v(), t, vec![], &[]).unwrap_err();
        assert_eq!(err(vec![]), MeshError::Empty);
        assert!(matches!(
            err(vec![[0, 1, 7]]),
            MeshError::VertexOutOfRange { vertex: 7, .. }
        ));
        assert!(matches!(
            err(vec![[0, 1, 1], [1, 2, 3]]),
            MeshError::DegenerateTriangle { triangle: 0 }
        ));
        assert_eq!(err(vec![[0, 1, 2]]), MeshError::IsolatedVertex(3));
        assert_eq!(err(vec![[0, 1, 2], [0, 1, 3]]), MeshError::Overlap(0, 1));
        let v5 = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [0.5, -1.0], [0.5, 2.0]];
        let e = Mesh::new(v5, vec![[0, 1, 2], [0, 3, 1], [0, 1, 4]], vec![], &[]);
        assert!(matches!(e, Err(MeshError::NonManifoldEdge(0, 1))));
    }

    #[test]
    fn geometric_queries() {
        let m = square();
        assert!((m.edge_length_range().1 - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(m.edge_length_range().0, 1.0);
        assert!(
            (m.angles(0).iter().cloned().fold(0.0, f64::max) - std::f64::consts::FRAC_PI_2).abs()
                < 1e-15
        );
        assert!(
            (m.altitudes(0).iter().cloned().fold(f64::INFINITY, f64::min) - 0.5f64.sqrt()).abs()
                < 1e-15
        );
    }
}
