//! A rank's local view of the mesh: its owned vertices, every triangle with an owned corner and
//! the one-vertex-deep ghost layer around them (the other corners of those triangles).
//!
//! The view is an ordinary [`Mesh`] whose vertices are numbered in increasing global id order
//! and whose triangles keep their global corner order, so that anything computed from the star
//! of an owned vertex (tent heights, refinement edges, the `(time, id)` order) is bitwise what
//! the whole mesh gives. Global ids of vertices and triangles are kept beside it.

use sdg_mesh::{EdgeId, Mesh, MeshError, TagId, TriangleId, VertexId};

use crate::partition::{Partition, Rank};

/// Why a local view cannot be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ViewError {
    #[error("the partition has {partition} vertices, but the mesh has {mesh}")]
    Mismatch { partition: usize, mesh: usize },
    #[error("rank {rank} is not one of the partition's {ranks} ranks")]
    NoSuchRank { rank: Rank, ranks: usize },
    #[error("rank {rank}'s local mesh is invalid: {source}")]
    Mesh { rank: Rank, source: MeshError },
}

/// One rank's part of the mesh with its ghost layer.
#[derive(Clone, Debug)]
pub struct LocalView {
    rank: Rank,
    mesh: Mesh,
    /// Local vertex -> global vertex, increasing.
    global: Vec<VertexId>,
    /// Local triangle -> global triangle, increasing.
    triangles: Vec<TriangleId>,
    /// Local edge -> global edge, and `(global, local)` pairs sorted by global edge.
    edges: Vec<EdgeId>,
    edge_lookup: Vec<(EdgeId, EdgeId)>,
    /// Per local vertex, its owner rank.
    owner: Vec<Rank>,
    /// Per local vertex, the start of its sharers in `sharer_ranks` (one more entry at the end).
    sharer_start: Vec<u32>,
    /// Per owned vertex, the other ranks that hold it as a ghost, increasing.
    sharer_ranks: Vec<Rank>,
    /// Ranks that hold a ghost of this rank or own one of its ghosts, increasing.
    neighbour_ranks: Vec<Rank>,
}

impl LocalView {
    /// The view of `rank` on `mesh` partitioned by `partition`.
    pub fn new(mesh: &Mesh, partition: &Partition, rank: Rank) -> Result<Self, ViewError> {
        let owners = partition.owners();
        if owners.len() != mesh.vertices().len() {
            return Err(ViewError::Mismatch {
                partition: owners.len(),
                mesh: mesh.vertices().len(),
            });
        }
        if rank as usize >= partition.ranks() {
            return Err(ViewError::NoSuchRank {
                rank,
                ranks: partition.ranks(),
            });
        }
        let triangles: Vec<TriangleId> = (0..mesh.triangles().len() as TriangleId)
            .filter(|&t| {
                mesh.triangles()[t as usize]
                    .iter()
                    .any(|&v| owners[v as usize] == rank)
            })
            .collect();
        let mut global: Vec<VertexId> = triangles
            .iter()
            .flat_map(|&t| mesh.triangles()[t as usize])
            .collect();
        global.sort_unstable();
        global.dedup();
        let local = |v: VertexId| {
            global
                .binary_search(&v)
                .expect("a corner of a local triangle is local") as VertexId
        };
        let corners: Vec<[VertexId; 3]> = triangles
            .iter()
            .map(|&t| mesh.triangles()[t as usize].map(local))
            .collect();
        let tagged: Vec<([VertexId; 2], TagId)> = triangles
            .iter()
            .flat_map(|&t| mesh.triangle_edges(t))
            .filter_map(|e| {
                let edge = &mesh.edges()[e as usize];
                edge.tag.map(|tag| (edge.vertices.map(local), tag))
            })
            .collect();
        let points = global.iter().map(|&v| mesh.vertex(v)).collect();
        let local_mesh = Mesh::new(points, corners, mesh.tag_names().to_vec(), &tagged)
            .map_err(|source| ViewError::Mesh { rank, source })?;

        let edges: Vec<EdgeId> = local_mesh
            .edges()
            .iter()
            .map(|e| {
                let [a, b] = e.vertices.map(|v| global[v as usize]);
                mesh.edge_between(a, b)
                    .expect("a local edge is an edge of the mesh")
            })
            .collect();
        let mut edge_lookup: Vec<(EdgeId, EdgeId)> = (0..edges.len() as EdgeId)
            .map(|e| (edges[e as usize], e))
            .collect();
        edge_lookup.sort_unstable();
        let owner: Vec<Rank> = global.iter().map(|&v| owners[v as usize]).collect();
        let (mut sharer_start, mut sharer_ranks) = (vec![0], Vec::new());
        for (&v, &o) in global.iter().zip(&owner) {
            if o == rank {
                let mut ranks: Vec<Rank> = mesh
                    .vertex_neighbors(v)
                    .iter()
                    .map(|&w| owners[w as usize])
                    .filter(|&r| r != rank)
                    .collect();
                ranks.sort_unstable();
                ranks.dedup();
                sharer_ranks.extend(ranks);
            }
            sharer_start.push(sharer_ranks.len() as u32);
        }
        let mut neighbour_ranks = sharer_ranks.clone();
        neighbour_ranks.sort_unstable();
        neighbour_ranks.dedup();
        Ok(Self {
            rank,
            mesh: local_mesh,
            global,
            triangles,
            edges,
            edge_lookup,
            owner,
            sharer_start,
            sharer_ranks,
            neighbour_ranks,
        })
    }

    /// The views of every rank of `partition`, by rank.
    pub fn all(mesh: &Mesh, partition: &Partition) -> Result<Vec<Self>, ViewError> {
        (0..partition.ranks() as Rank)
            .map(|rank| Self::new(mesh, partition, rank))
            .collect()
    }

    /// The rank whose view this is.
    pub fn rank(&self) -> Rank {
        self.rank
    }

    /// The local mesh (local vertex and triangle ids).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The global id of local vertex `v`.
    pub fn global(&self, v: VertexId) -> VertexId {
        self.global[v as usize]
    }

    /// The local id of global vertex `g`, if this view holds it.
    pub fn local(&self, g: VertexId) -> Option<VertexId> {
        self.global.binary_search(&g).ok().map(|v| v as VertexId)
    }

    /// The global id of local triangle `t`.
    pub fn global_triangle(&self, t: TriangleId) -> TriangleId {
        self.triangles[t as usize]
    }

    /// The local id of global triangle `g`, if this view holds it.
    pub fn local_triangle(&self, g: TriangleId) -> Option<TriangleId> {
        self.triangles
            .binary_search(&g)
            .ok()
            .map(|t| t as TriangleId)
    }

    /// The global id of local edge `e`.
    pub fn global_edge(&self, e: EdgeId) -> EdgeId {
        self.edges[e as usize]
    }

    /// The local id of global edge `g`, if this view holds it.
    pub fn local_edge(&self, g: EdgeId) -> Option<EdgeId> {
        self.edge_lookup
            .binary_search_by_key(&g, |&(global, _)| global)
            .ok()
            .map(|i| self.edge_lookup[i].1)
    }

    /// True when rank `rank` holds local edge `e` too (it holds one of the edge's triangles);
    /// exact for an edge with an owned end (the view holds both its triangles).
    pub fn edge_held_by(&self, e: EdgeId, rank: Rank) -> bool {
        self.mesh.edges()[e as usize]
            .triangles
            .iter()
            .flatten()
            .any(|&t| self.held_by(t, rank))
    }

    /// True when rank `rank` holds local triangle `t` too (one of its corners is `rank`'s).
    pub fn held_by(&self, t: TriangleId, rank: Rank) -> bool {
        self.mesh.triangles()[t as usize]
            .iter()
            .any(|&v| self.owner[v as usize] == rank)
    }

    /// The rank that owns local vertex `v`.
    pub fn owner(&self, v: VertexId) -> Rank {
        self.owner[v as usize]
    }

    /// True when this rank owns local vertex `v` (else it is a ghost).
    pub fn is_owned(&self, v: VertexId) -> bool {
        self.owner[v as usize] == self.rank
    }

    /// The owned vertices, local ids increasing.
    pub fn owned(&self) -> impl Iterator<Item = VertexId> + '_ {
        (0..self.global.len() as VertexId).filter(|&v| self.is_owned(v))
    }

    /// The ghost vertices, local ids increasing.
    pub fn ghosts(&self) -> impl Iterator<Item = VertexId> + '_ {
        (0..self.global.len() as VertexId).filter(|&v| !self.is_owned(v))
    }

    /// The other ranks that hold local vertex `v` as a ghost (empty for a ghost or an interior
    /// vertex): the ranks a tent at `v` must tell.
    pub fn sharers(&self, v: VertexId) -> &[Rank] {
        let (a, b) = (
            self.sharer_start[v as usize],
            self.sharer_start[v as usize + 1],
        );
        &self.sharer_ranks[a as usize..b as usize]
    }

    /// The ranks this one exchanges updates with, increasing.
    pub fn neighbour_ranks(&self) -> &[Rank] {
        &self.neighbour_ranks
    }

    /// Owned vertices that another rank holds as a ghost.
    pub fn boundary_vertices(&self) -> usize {
        self.owned()
            .filter(|&v| !self.sharers(v).is_empty())
            .count()
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::testing::rectangle;

    fn partitions(mesh: &Mesh) -> Vec<Partition> {
        let mut all = Vec::new();
        for ranks in 1..=5 {
            all.push(Partition::coordinate(mesh, ranks).unwrap());
            all.push(Partition::striped(mesh, ranks).unwrap());
            all.push(Partition::random(mesh, ranks, ranks as u64).unwrap());
        }
        all
    }

    #[test]
    fn every_vertex_is_owned_once_and_every_triangle_is_on_its_corners_ranks() {
        let mesh = rectangle(9, 7, 0.2, 3);
        for p in partitions(&mesh) {
            let views = LocalView::all(&mesh, &p).unwrap();
            let mut owned = vec![0; mesh.vertices().len()];
            for view in &views {
                for v in view.owned() {
                    owned[view.global(v) as usize] += 1;
                    assert_eq!(p.owner(view.global(v)), view.rank());
                }
            }
            assert!(owned.iter().all(|&n| n == 1), "{owned:?}");
            for (t, tri) in mesh.triangles().iter().enumerate() {
                let ranks: BTreeSet<Rank> = tri.iter().map(|&v| p.owner(v)).collect();
                for view in &views {
                    let local = (0..view.mesh().triangles().len() as TriangleId)
                        .find(|&l| view.global_triangle(l) == t as TriangleId);
                    assert_eq!(local.is_some(), ranks.contains(&view.rank()));
                    assert_eq!(view.local_triangle(t as TriangleId), local);
                    for e in mesh.triangle_edges(t as TriangleId) {
                        let l = view.local_edge(e);
                        if let Some(l) = l {
                            assert_eq!(view.global_edge(l), e);
                            let ends = view.mesh().edges()[l as usize]
                                .vertices
                                .map(|v| view.global(v));
                            assert_eq!(ends, mesh.edges()[e as usize].vertices);
                            let holders: BTreeSet<Rank> = mesh.edges()[e as usize]
                                .triangles
                                .iter()
                                .flatten()
                                .flat_map(|&u| mesh.triangles()[u as usize].map(|v| p.owner(v)))
                                .collect();
                            let spoke = ends.iter().any(|&v| p.owner(v) == view.rank());
                            for r in (0..p.ranks() as Rank).filter(|_| spoke) {
                                assert_eq!(view.edge_held_by(l, r), holders.contains(&r));
                            }
                        }
                        if local.is_some() {
                            assert!(l.is_some(), "a held triangle's edges are held");
                        }
                    }
                    if let Some(l) = local {
                        for r in 0..p.ranks() as Rank {
                            assert_eq!(view.held_by(l, r), ranks.contains(&r));
                        }
                    }
                    if let Some(l) = local {
                        let corners = view.mesh().triangles()[l as usize].map(|v| view.global(v));
                        assert_eq!(&corners, tri, "corner order kept");
                    }
                }
            }
        }
    }

    #[test]
    fn ghosts_are_the_neighbours_of_owned_vertices_owned_elsewhere() {
        let mesh = rectangle(8, 8, 0.15, 5);
        for p in partitions(&mesh) {
            for view in LocalView::all(&mesh, &p).unwrap() {
                let rank = view.rank();
                let owned: BTreeSet<VertexId> = view.owned().map(|v| view.global(v)).collect();
                let expected: BTreeSet<VertexId> = owned
                    .iter()
                    .flat_map(|&v| mesh.vertex_neighbors(v).iter().copied())
                    .filter(|&w| p.owner(w) != rank)
                    .collect();
                let ghosts: BTreeSet<VertexId> = view.ghosts().map(|v| view.global(v)).collect();
                assert_eq!(ghosts, expected, "rank {rank} of {}", p.ranks());
                for v in view.owned() {
                    let g = view.global(v);
                    let neighbours: Vec<VertexId> = view
                        .mesh()
                        .vertex_neighbors(v)
                        .iter()
                        .map(|&w| view.global(w))
                        .collect();
                    assert_eq!(neighbours, mesh.vertex_neighbors(g), "whole star of {g}");
                    let sharers: BTreeSet<Rank> = mesh
                        .vertex_neighbors(g)
                        .iter()
                        .map(|&w| p.owner(w))
                        .filter(|&r| r != rank)
                        .collect();
                    assert_eq!(view.sharers(v), sharers.into_iter().collect::<Vec<_>>());
                    assert_eq!(view.local(g), Some(v));
                }
                assert!(view.ghosts().all(|v| view.sharers(v).is_empty()));
                let ghost_owners: BTreeSet<Rank> = view.ghosts().map(|v| view.owner(v)).collect();
                let listed: BTreeSet<Rank> = view.neighbour_ranks().iter().copied().collect();
                assert_eq!(ghost_owners, listed, "adjacency of ranks is symmetric");
            }
        }
    }

    #[test]
    fn one_rank_sees_the_whole_mesh_and_no_boundary() {
        let mesh = rectangle(5, 4, 0.1, 2);
        let view = LocalView::new(&mesh, &Partition::coordinate(&mesh, 1).unwrap(), 0).unwrap();
        assert_eq!(view.mesh().vertices(), mesh.vertices());
        assert_eq!(view.mesh().triangles(), mesh.triangles());
        assert_eq!(view.boundary_vertices(), 0);
        assert!(view.neighbour_ranks().is_empty());
        let p = Partition::coordinate(&mesh, 2).unwrap();
        assert_eq!(
            LocalView::new(&mesh, &p, 2).unwrap_err(),
            ViewError::NoSuchRank { rank: 2, ranks: 2 }
        );
    }
}
