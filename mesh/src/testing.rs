//! Helpers shared by the mesh crate's unit tests.

use crate::mesh::{EdgeId, Mesh, TriangleId};
use crate::rectangle::{Diagonal, Rectangle};
use crate::refine::Split;

/// The unit square in `n x n` cells.
pub(crate) fn square(n: u32, diagonal: Diagonal, perturb: f64) -> Rectangle {
    Rectangle {
        width: 1.0,
        height: 1.0,
        nx: n,
        ny: n,
        diagonal,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb,
        seed: 7,
    }
}

pub(crate) fn allow_all(_: &Mesh, _: &[Split], _: TriangleId) -> bool {
    true
}

/// Bisects `t` with every split allowed and checks the result.
pub(crate) fn refine(m: &mut Mesh, t: TriangleId) -> Vec<Split> {
    let mut splits = Vec::new();
    assert!(m.bisect(t, &mut allow_all, &mut splits));
    m.validate().unwrap();
    splits
}

pub(crate) fn total_area(m: &Mesh) -> f64 {
    (0..m.triangles().len() as TriangleId)
        .map(|t| m.area(t))
        .sum()
}

/// Number and total length (metres) of the edges tagged `name`.
pub(crate) fn tagged(m: &Mesh, name: &str) -> (usize, f64) {
    let tag = m.tag_id(name);
    (0..m.edges().len() as EdgeId)
        .filter(|&e| m.edges()[e as usize].tag == tag)
        .fold((0, 0.0), |(n, l), e| (n + 1, l + m.edge_length(e)))
}

/// xorshift64: a deterministic pseudo-random sequence.
pub(crate) struct XorShift(pub(crate) u64);

impl XorShift {
    /// The next number below `n`.
    pub(crate) fn below(&mut self, n: usize) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n as u64) as u32
    }
}
