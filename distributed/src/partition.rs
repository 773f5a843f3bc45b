//! Partitions of a mesh's vertices among ranks: which rank owns (pitches) each vertex.
//!
//! A vertex's weight is the work its tents will cost: by default its star size (the number of
//! its triangles: a tent costs about one patch element per star triangle), or weights the
//! caller gives (`*_weighted`: a run weighs each vertex's star by its tents to the end time,
//! since tents per vertex differ over a mesh). Equal weights mean equal work per rank. Four
//! partitions exist: recursive coordinate bisection ([`Partition::coordinate`], the default
//! for runs), METIS's multilevel k-way partition of the vertex graph ([`Partition::metis`],
//! fewest cut edges), stripes along x ([`Partition::striped`]) and seeded random owners
//! ([`Partition::random`], for tests: nearly every vertex is on a rank boundary).

use sdg_mesh::{Mesh, VertexId};

use crate::rng::SplitMix64;

/// A rank's index, `0..ranks`.
pub type Rank = u32;

/// Why a partition cannot be made or is invalid.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum PartitionError {
    #[error("a partition needs at least one rank")]
    NoRanks,
    #[error("{ranks} ranks need at least as many vertices, but the mesh has {vertices}")]
    TooFewVertices { ranks: usize, vertices: usize },
    #[error("the owner list has {got} entries, but the mesh has {vertices} vertices")]
    Length { got: usize, vertices: usize },
    #[error("the weight list has {got} entries, but the mesh has {vertices} vertices")]
    Weights { got: usize, vertices: usize },
    #[error("vertex {vertex} is owned by rank {rank}, but there are only {ranks} ranks")]
    RankOutOfRange {
        vertex: VertexId,
        rank: Rank,
        ranks: usize,
    },
    #[error("rank {0} owns no vertex")]
    EmptyRank(Rank),
    #[error("METIS: {0}")]
    Metis(String),
}

/// The owner rank of every vertex of a mesh; every rank owns at least one vertex.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Partition {
    ranks: usize,
    owner: Vec<Rank>,
}

/// METIS's random seed: fixed, so that every rank computes the same partition.
const METIS_SEED: metis::Idx = 1;

/// Which coordinate a bisection cuts along.
#[derive(Clone, Copy, Debug)]
enum Cut {
    /// The longer side of the part's bounding box.
    Longest,
    /// Always x.
    X,
}

impl Partition {
    /// A partition of `mesh` (its vertex count) from an owner rank per vertex.
    pub fn from_owners(
        mesh: &Mesh,
        owner: Vec<Rank>,
        ranks: usize,
    ) -> Result<Self, PartitionError> {
        check_sizes(mesh, ranks)?;
        let vertices = mesh.vertices().len();
        if owner.len() != vertices {
            return Err(PartitionError::Length {
                got: owner.len(),
                vertices,
            });
        }
        let mut owns = vec![false; ranks];
        for (v, &rank) in owner.iter().enumerate() {
            let slot = owns
                .get_mut(rank as usize)
                .ok_or(PartitionError::RankOutOfRange {
                    vertex: v as VertexId,
                    rank,
                    ranks,
                })?;
            *slot = true;
        }
        if let Some(r) = owns.iter().position(|&o| !o) {
            return Err(PartitionError::EmptyRank(r as Rank));
        }
        Ok(Self { ranks, owner })
    }

    /// Recursive coordinate bisection weighted by star size: each part is cut across the longer
    /// side of its bounding box into two parts whose weights are in the ratio of their rank counts
    /// (`ranks / 2` to the rest), to within one vertex's weight.
    pub fn coordinate(mesh: &Mesh, ranks: usize) -> Result<Self, PartitionError> {
        Self::coordinate_weighted(mesh, ranks, &star_weights(mesh))
    }

    /// [`Partition::coordinate`] with a weight per vertex.
    pub fn coordinate_weighted(
        mesh: &Mesh,
        ranks: usize,
        weights: &[u64],
    ) -> Result<Self, PartitionError> {
        Self::bisected(mesh, ranks, weights, Cut::Longest)
    }

    /// Stripes across x of equal weight (star size), to within one vertex's weight per cut.
    pub fn striped(mesh: &Mesh, ranks: usize) -> Result<Self, PartitionError> {
        Self::striped_weighted(mesh, ranks, &star_weights(mesh))
    }

    /// [`Partition::striped`] with a weight per vertex.
    pub fn striped_weighted(
        mesh: &Mesh,
        ranks: usize,
        weights: &[u64],
    ) -> Result<Self, PartitionError> {
        Self::bisected(mesh, ranks, weights, Cut::X)
    }

    /// Seeded random owners: the first `ranks` vertices of a random permutation go to ranks
    /// `0, 1, ...` (so that none is empty), every other vertex to a uniformly random rank.
    pub fn random(mesh: &Mesh, ranks: usize, seed: u64) -> Result<Self, PartitionError> {
        check_sizes(mesh, ranks)?;
        let n = mesh.vertices().len();
        let mut rng = SplitMix64::new(seed);
        let mut order: Vec<VertexId> = (0..n as VertexId).collect();
        for i in (1..n).rev() {
            order.swap(i, rng.below(i + 1));
        }
        let mut owner: Vec<Rank> = (0..n).map(|_| rng.below(ranks) as Rank).collect();
        for (r, &v) in order.iter().take(ranks).enumerate() {
            owner[v as usize] = r as Rank;
        }
        Ok(Self { ranks, owner })
    }

    /// METIS's multilevel k-way partition (`METIS_PartGraphKway`, its bundled copy) of the
    /// graph of the mesh's vertices and edges, each vertex weighted by its star size, with a
    /// fixed seed: the same partition for the same mesh on every rank and every run. METIS
    /// minimizes the cut edges (so the messages) at up to 3% imbalance.
    pub fn metis(mesh: &Mesh, ranks: usize) -> Result<Self, PartitionError> {
        Self::metis_weighted(mesh, ranks, &star_weights(mesh))
    }

    /// [`Partition::metis`] with a weight per vertex.
    pub fn metis_weighted(
        mesh: &Mesh,
        ranks: usize,
        weights: &[u64],
    ) -> Result<Self, PartitionError> {
        check_sizes(mesh, ranks)?;
        check_weights(mesh, weights)?;
        let n = mesh.vertices().len();
        let too_large = || PartitionError::Metis(format!("a graph of {n} vertices is too large"));
        let idx = |k: usize| metis::Idx::try_from(k).map_err(|_| too_large());
        let mut xadj = Vec::with_capacity(n + 1);
        let mut adjncy = Vec::new();
        let mut vwgt = Vec::with_capacity(n);
        xadj.push(0);
        for v in 0..n as VertexId {
            for &w in mesh.vertex_neighbors(v) {
                adjncy.push(idx(w as usize)?);
            }
            xadj.push(idx(adjncy.len())?);
            vwgt.push(metis::Idx::try_from(weights[v as usize]).map_err(|_| too_large())?);
        }
        let mut part = vec![0; n];
        let failed = |e: &dyn std::fmt::Display| PartitionError::Metis(e.to_string());
        metis::Graph::new(1, idx(ranks)?, &xadj, &adjncy)
            .map_err(|e| failed(&e))?
            .set_vwgt(&vwgt)
            .set_option(metis::option::Seed(METIS_SEED))
            .part_kway(&mut part)
            .map_err(|e| failed(&e))?;
        let owner = part.into_iter().map(|r| r as Rank).collect();
        Self::from_owners(mesh, owner, ranks)
    }

    fn bisected(
        mesh: &Mesh,
        ranks: usize,
        weights: &[u64],
        cut: Cut,
    ) -> Result<Self, PartitionError> {
        check_sizes(mesh, ranks)?;
        check_weights(mesh, weights)?;
        let mut vertices: Vec<VertexId> = (0..mesh.vertices().len() as VertexId).collect();
        let mut owner = vec![0; vertices.len()];
        bisect(mesh, weights, &mut vertices, 0, ranks, cut, &mut owner);
        Ok(Self { ranks, owner })
    }

    /// Number of ranks.
    pub fn ranks(&self) -> usize {
        self.ranks
    }

    /// The rank that owns vertex `v`.
    pub fn owner(&self, v: VertexId) -> Rank {
        self.owner[v as usize]
    }

    /// The owner of every vertex, by vertex id.
    pub fn owners(&self) -> &[Rank] {
        &self.owner
    }

    /// Per rank, the summed `weights` of its vertices (one per vertex, e.g. [`star_weights`]).
    pub fn weights(&self, weights: &[u64]) -> Vec<u64> {
        let mut sums = vec![0; self.ranks];
        for (&r, &w) in self.owner.iter().zip(weights) {
            sums[r as usize] += w;
        }
        sums
    }

    /// The heaviest rank's summed `weights` over the mean (1 is perfect balance).
    pub fn imbalance(&self, weights: &[u64]) -> f64 {
        let sums = self.weights(weights);
        let total: u64 = sums.iter().sum();
        let max = sums.iter().copied().max().unwrap_or(0);
        max as f64 * self.ranks as f64 / total as f64
    }
}

/// Every vertex's star size (its number of triangles): the default weights.
pub fn star_weights(mesh: &Mesh) -> Vec<u64> {
    (0..mesh.vertices().len() as VertexId)
        .map(|v| mesh.vertex_triangles(v).len() as u64)
        .collect()
}

fn check_weights(mesh: &Mesh, weights: &[u64]) -> Result<(), PartitionError> {
    match weights.len() == mesh.vertices().len() {
        true => Ok(()),
        false => Err(PartitionError::Weights {
            got: weights.len(),
            vertices: mesh.vertices().len(),
        }),
    }
}

fn check_sizes(mesh: &Mesh, ranks: usize) -> Result<(), PartitionError> {
    let vertices = mesh.vertices().len();
    if ranks == 0 {
        Err(PartitionError::NoRanks)
    } else if vertices < ranks || u32::try_from(ranks).is_err() {
        Err(PartitionError::TooFewVertices { ranks, vertices })
    } else {
        Ok(())
    }
}

/// Gives `vertices` (at least `ranks` of them) to ranks `first..first + ranks`: cuts them
/// across `cut` (ties by id) where the prefix weight is nearest `ranks / 2` parts of `ranks`,
/// leaving each side at least as many vertices as ranks, and recurses on both sides.
fn bisect(
    mesh: &Mesh,
    weights: &[u64],
    vertices: &mut [VertexId],
    first: Rank,
    ranks: usize,
    cut: Cut,
    owner: &mut [Rank],
) {
    if ranks == 1 {
        vertices.iter().for_each(|&v| owner[v as usize] = first);
        return;
    }
    let axis = match cut {
        Cut::X => 0,
        Cut::Longest => {
            let (lo, hi) = vertices.iter().map(|&v| mesh.vertex(v)).fold(
                ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                |(lo, hi), p| {
                    (
                        [lo[0].min(p[0]), lo[1].min(p[1])],
                        [hi[0].max(p[0]), hi[1].max(p[1])],
                    )
                },
            );
            usize::from(hi[1] - lo[1] > hi[0] - lo[0])
        }
    };
    vertices.sort_unstable_by(|&a, &b| {
        mesh.vertex(a)[axis]
            .total_cmp(&mesh.vertex(b)[axis])
            .then(a.cmp(&b))
    });
    let left = ranks / 2;
    let total: u64 = vertices.iter().map(|&v| weights[v as usize]).sum();
    // Prefix weight goal: total * left / ranks, compared exactly as prefix * ranks vs total * left.
    let goal = u128::from(total) * left as u128;
    let (mut prefix, mut best, mut best_miss) = (0u128, left, u128::MAX);
    for (k, &v) in vertices
        .iter()
        .enumerate()
        .take(vertices.len() - (ranks - left) + 1)
    {
        if k >= left {
            let miss = (prefix * ranks as u128).abs_diff(goal);
            if miss < best_miss {
                (best, best_miss) = (k, miss);
            }
        }
        prefix += u128::from(weights[v as usize]);
    }
    let (a, b) = vertices.split_at_mut(best);
    bisect(mesh, weights, a, first, left, cut, owner);
    bisect(
        mesh,
        weights,
        b,
        first + left as Rank,
        ranks - left,
        cut,
        owner,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rectangle;

    #[test]
    fn coordinate_bisection_balances_star_sizes_on_a_64_by_64_rectangle() {
        let mesh = rectangle(64, 64, 0.0, 0);
        for ranks in 2..=8 {
            let p = Partition::coordinate(&mesh, ranks).unwrap();
            let imbalance = p.imbalance(&star_weights(&mesh));
            assert!(imbalance <= 1.005, "{ranks} ranks: {imbalance}");
            assert_eq!(
                Partition::from_owners(&mesh, p.owners().to_vec(), ranks),
                Ok(p)
            );
        }
    }

    #[test]
    fn coordinate_bisection_cuts_across_the_longer_side() {
        // A 4 x 1 strip in 2 ranks: the cut is at x = 2 (the column there splits by id).
        let mesh = crate::testing::strip(16, 4);
        let p = Partition::coordinate(&mesh, 2).unwrap();
        for v in 0..mesh.vertices().len() as VertexId {
            let x = mesh.vertex(v)[0];
            if x < 1.99 {
                assert_eq!(p.owner(v), 0, "vertex {v} at x = {x}");
            } else if x > 2.01 {
                assert_eq!(p.owner(v), 1, "vertex {v} at x = {x}");
            }
        }
    }

    #[test]
    fn metis_balances_star_sizes_and_cuts_fewer_edges_than_coordinate_bisection() {
        let mesh = rectangle(64, 64, 0.2, 3);
        let cut = |p: &Partition| {
            (mesh.edges().iter())
                .filter(|e| p.owner(e.vertices[0]) != p.owner(e.vertices[1]))
                .count()
        };
        for ranks in [2, 3, 4, 7] {
            let p = Partition::metis(&mesh, ranks).unwrap();
            assert_eq!(p, Partition::metis(&mesh, ranks).unwrap(), "seeded");
            assert!(
                p.imbalance(&star_weights(&mesh)) <= 1.031,
                "{ranks} ranks: {}",
                p.imbalance(&star_weights(&mesh))
            );
            let coordinate = Partition::coordinate(&mesh, ranks).unwrap();
            assert!(
                cut(&p) as f64 <= 1.05 * cut(&coordinate) as f64,
                "{ranks} ranks: METIS cuts {} edges, coordinate bisection {}",
                cut(&p),
                cut(&coordinate)
            );
        }
        assert_eq!(
            Partition::metis(&mesh, 1).unwrap().owners(),
            vec![0; 65 * 65]
        );
        assert_eq!(
            Partition::metis(&rectangle(1, 1, 0.0, 0), 5),
            Err(PartitionError::TooFewVertices {
                ranks: 5,
                vertices: 4
            })
        );
    }

    #[test]
    fn stripes_are_ordered_along_x() {
        let mesh = rectangle(24, 8, 0.2, 1);
        let p = Partition::striped(&mesh, 3).unwrap();
        let mut by_x: Vec<VertexId> = (0..mesh.vertices().len() as VertexId).collect();
        by_x.sort_by(|&a, &b| mesh.vertex(a)[0].total_cmp(&mesh.vertex(b)[0]));
        let ranks: Vec<Rank> = by_x.iter().map(|&v| p.owner(v)).collect();
        assert!(ranks.windows(2).all(|w| w[0] <= w[1]), "{ranks:?}");
        assert!(
            p.imbalance(&star_weights(&mesh)) < 1.03,
            "{}",
            p.imbalance(&star_weights(&mesh))
        );
    }

    #[test]
    fn random_partitions_are_seeded_and_use_every_rank() {
        let mesh = rectangle(4, 4, 0.0, 0);
        let a = Partition::random(&mesh, 7, 11).unwrap();
        assert_eq!(a, Partition::random(&mesh, 7, 11).unwrap());
        assert_ne!(a, Partition::random(&mesh, 7, 12).unwrap());
        assert!(a.weights(&star_weights(&mesh)).iter().all(|&w| w > 0));
        assert_eq!(Partition::random(&mesh, 25, 0).unwrap().ranks(), 25);
    }

    #[test]
    fn rejects_bad_partitions() {
        let mesh = rectangle(1, 1, 0.0, 0);
        assert_eq!(
            Partition::coordinate(&mesh, 0),
            Err(PartitionError::NoRanks)
        );
        assert_eq!(
            Partition::striped(&mesh, 5),
            Err(PartitionError::TooFewVertices {
                ranks: 5,
                vertices: 4
            })
        );
        assert_eq!(
            Partition::from_owners(&mesh, vec![0, 1, 0], 2),
            Err(PartitionError::Length {
                got: 3,
                vertices: 4
            })
        );
        assert_eq!(
            Partition::from_owners(&mesh, vec![0, 2, 0, 0], 2),
            Err(PartitionError::RankOutOfRange {
                vertex: 1,
                rank: 2,
                ranks: 2
            })
        );
        assert_eq!(
            Partition::from_owners(&mesh, vec![0, 0, 2, 0], 3),
            Err(PartitionError::EmptyRank(1))
        );
    }
}
