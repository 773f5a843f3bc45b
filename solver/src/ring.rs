//! Block elimination for a patch's linear system.
//!
//! The elements of a tent patch couple only through the vertical faces around the pole: an
//! interior tent's elements form a ring, a boundary tent's a chain. Eliminating element blocks
//! in ring order fills in only the blocks that couple to the ring's last element, so a patch of
//! `d` elements of `m` unknowns costs about `d` times a few `m^3` operations instead of the
//! `(d m)^3` of a dense factorization.
//!
//! Blocks are `m x m` column-major buffers from a pool sized once, so solving allocates nothing.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

/// A block-sparse linear system of up to `max_blocks` block rows of size up to `max_size`.
pub struct BlockSystem {
    max_blocks: usize,
    blocks: usize,
    size: usize,
    /// Pool index of block `(i, j)` at `i * max_blocks + j`.
    index: Vec<Option<usize>>,
    pool: Vec<f64>,
    used: usize,
    rhs: Vec<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    product: Vec<f64>,
    column: Vec<f64>,
    stack: MemBuffer,
    /// A copy of the assembled system for Newton iterations ([`Self::save`]); grown on first use.
    saved: Saved,
}

/// An assembled, unfactored system: the used blocks, their index and the right-hand side.
#[derive(Debug, Default)]
struct Saved {
    index: Vec<Option<usize>>,
    pool: Vec<f64>,
    used: usize,
    rhs: Vec<f64>,
}

impl std::fmt::Debug for BlockSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlockSystem")
            .field("blocks", &self.blocks)
            .field("size", &self.size)
            .finish_non_exhaustive()
    }
}

impl BlockSystem {
    /// Room for `max_blocks` block rows of size `max_size` with up to 5 nonzero blocks per row
    /// (diagonal, two ring neighbours, and fill towards the ring's last element).
    pub fn new(max_blocks: usize, max_size: usize) -> Self {
        let capacity = 5 * max_blocks + 4;
        let req = StackReq::any_of(&[
            factor::lu_in_place_scratch::<usize, f64>(
                max_size,
                max_size,
                Par::Seq,
                Default::default(),
            ),
            solve::solve_in_place_scratch::<usize, f64>(max_size, max_size, Par::Seq),
        ]);
        Self {
            max_blocks,
            blocks: 0,
            size: 0,
            index: vec![None; max_blocks * max_blocks],
            pool: vec![0.0; capacity * max_size * max_size],
            used: 0,
            rhs: vec![0.0; max_blocks * max_size],
            perm: vec![0; max_blocks * max_size],
            perm_inv: vec![0; max_size],
            product: vec![0.0; max_size * max_size],
            column: vec![0.0; max_size],
            stack: MemBuffer::new(req),
            saved: Saved::default(),
        }
    }

    /// Keeps a copy of the assembled system (blocks and right-hand side) for [`Self::restore`]
    /// and [`Self::residual`]. The copy's buffers grow on first use and are reused after.
    pub fn save(&mut self) {
        let n = self.size * self.size;
        let saved = &mut self.saved;
        saved.index.clone_from(&self.index);
        saved.used = self.used;
        if saved.pool.len() < self.used * n {
            saved.pool.resize(self.used * n, 0.0);
        }
        saved.pool[..self.used * n].copy_from_slice(&self.pool[..self.used * n]);
        saved.rhs.clear();
        saved
            .rhs
            .extend_from_slice(&self.rhs[..self.blocks * self.size]);
    }

    /// Puts back the system kept by [`Self::save`], replacing any factorization or solution.
    pub fn restore(&mut self) {
        let n = self.size * self.size;
        let saved = &self.saved;
        self.index.copy_from_slice(&saved.index);
        self.used = saved.used;
        self.pool[..saved.used * n].copy_from_slice(&saved.pool[..saved.used * n]);
        self.rhs[..saved.rhs.len()].copy_from_slice(&saved.rhs);
    }

    /// `out = b - A x` for the system kept by [`Self::save`]; `x` and `out` hold one vector of
    /// all block rows.
    pub fn residual(&self, x: &[f64], out: &mut [f64]) {
        let (m, n) = (self.size, self.size * self.size);
        let saved = &self.saved;
        out[..saved.rhs.len()].copy_from_slice(&saved.rhs);
        for i in 0..self.blocks {
            for j in 0..self.blocks {
                let Some(k) = saved.index[i * self.max_blocks + j] else {
                    continue;
                };
                let block = &saved.pool[k * n..(k + 1) * n];
                let row = &mut out[i * m..(i + 1) * m];
                for (c, &xc) in x[j * m..(j + 1) * m].iter().enumerate() {
                    if xc == 0.0 {
                        continue;
                    }
                    for (o, a) in row.iter_mut().zip(&block[c * m..(c + 1) * m]) {
                        *o -= a * xc;
                    }
                }
            }
        }
    }

    /// Starts a new system of `blocks` block rows of size `size`, all zero.
    pub fn reset(&mut self, blocks: usize, size: usize) {
        assert!(blocks <= self.max_blocks && size * size * 5 * blocks <= self.pool.len());
        self.blocks = blocks;
        self.size = size;
        self.index.fill(None);
        self.used = 0;
        self.rhs[..blocks * size].fill(0.0);
    }

    fn block_index(&mut self, i: usize, j: usize) -> usize {
        let slot = &mut self.index[i * self.max_blocks + j];
        match *slot {
            Some(k) => k,
            None => {
                let k = self.used;
                self.used += 1;
                *slot = Some(k);
                let n = self.size * self.size;
                self.pool[k * n..(k + 1) * n].fill(0.0);
                k
            }
        }
    }

    /// Block `(i, j)`, column-major, created zero on first use.
    pub fn block_mut(&mut self, i: usize, j: usize) -> &mut [f64] {
        let k = self.block_index(i, j);
        let n = self.size * self.size;
        &mut self.pool[k * n..(k + 1) * n]
    }

    /// Right-hand side of block row `i`; after [`Self::solve`], the solution.
    pub fn rhs_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.rhs[i * self.size..(i + 1) * self.size]
    }

    /// The whole right-hand side / solution, block row after block row.
    pub fn rhs(&self) -> &[f64] {
        &self.rhs[..self.blocks * self.size]
    }

    fn has(&self, i: usize, j: usize) -> bool {
        self.index[i * self.max_blocks + j].is_some()
    }

    /// Solves in place by block Gaussian elimination in the given order of block rows (a
    /// permutation of `0..blocks`); each diagonal block is factored with partial pivoting.
    pub fn solve(&mut self, order: &[usize]) {
        let (m, n) = (self.size, self.size * self.size);
        for (k, &e) in order.iter().enumerate() {
            let later = &order[k + 1..];
            let d = self.block_index(e, e);
            let stack = MemStack::new(&mut self.stack);
            let (_, perm) = factor::lu_in_place(
                MatMut::from_column_major_slice_mut(&mut self.pool[d * n..(d + 1) * n], m, m),
                &mut self.perm[e * m..(e + 1) * m],
                &mut self.perm_inv[..m],
                Par::Seq,
                stack,
                Default::default(),
            );
            let (pool, rhs) = (&mut self.pool, &mut self.rhs);
            let (before, rest) = pool.split_at_mut(d * n);
            let (lu, after) = rest.split_at_mut(n);
            let lu = MatRef::from_column_major_slice(lu, m, m);
            // Row e: every later block and the right-hand side times D_ee^-1.
            for &j in later {
                if let Some(b) = self.index[e * self.max_blocks + j] {
                    let block = if b < d {
                        &mut before[b * n..(b + 1) * n]
                    } else {
                        &mut after[(b - d - 1) * n..(b - d) * n]
                    };
                    solve::solve_in_place(
                        lu,
                        lu,
                        perm,
                        MatMut::from_column_major_slice_mut(block, m, m),
                        Par::Seq,
                        stack,
                    );
                }
            }
            solve::solve_in_place(
                lu,
                lu,
                perm,
                MatMut::from_column_major_slice_mut(&mut rhs[e * m..(e + 1) * m], m, 1),
                Par::Seq,
                stack,
            );
            // Schur complement on the later rows that couple to e.
            for &i in later {
                let Some(a) = self.index[i * self.max_blocks + e] else {
                    continue;
                };
                self.product[..n].copy_from_slice(&self.pool[a * n..(a + 1) * n]);
                self.column[..m].copy_from_slice(&self.rhs[e * m..(e + 1) * m]);
                matmul(
                    MatMut::from_column_major_slice_mut(&mut self.rhs[i * m..(i + 1) * m], m, 1),
                    Accum::Add,
                    MatRef::from_column_major_slice(&self.product[..n], m, m),
                    MatRef::from_column_major_slice(&self.column[..m], m, 1),
                    -1.0,
                    Par::Seq,
                );
                for &j in later {
                    let Some(b) = self.index[e * self.max_blocks + j] else {
                        continue;
                    };
                    let c = self.block_index(i, j);
                    let (dst, src) = two_blocks(&mut self.pool, c, b, n);
                    matmul(
                        MatMut::from_column_major_slice_mut(dst, m, m),
                        Accum::Add,
                        MatRef::from_column_major_slice(&self.product[..n], m, m),
                        MatRef::from_column_major_slice(src, m, m),
                        -1.0,
                        Par::Seq,
                    );
                }
            }
        }
        // Back substitution: x_e = y_e - sum over later j of (D_ee^-1 A_ej) x_j.
        for (k, &e) in order.iter().enumerate().rev() {
            for &j in &order[k + 1..] {
                if !self.has(e, j) {
                    continue;
                }
                let b = self.index[e * self.max_blocks + j].expect("checked");
                self.column[..m].copy_from_slice(&self.rhs[j * m..(j + 1) * m]);
                matmul(
                    MatMut::from_column_major_slice_mut(&mut self.rhs[e * m..(e + 1) * m], m, 1),
                    Accum::Add,
                    MatRef::from_column_major_slice(&self.pool[b * n..(b + 1) * n], m, m),
                    MatRef::from_column_major_slice(&self.column[..m], m, 1),
                    -1.0,
                    Par::Seq,
                );
            }
        }
    }
}

/// Disjoint mutable block `dst` and shared block `src` of the pool (blocks of `n` values).
fn two_blocks(pool: &mut [f64], dst: usize, src: usize, n: usize) -> (&mut [f64], &[f64]) {
    if dst < src {
        let (a, b) = pool.split_at_mut(src * n);
        (&mut a[dst * n..(dst + 1) * n], &b[..n])
    } else {
        let (a, b) = pool.split_at_mut(dst * n);
        (&mut b[..n], &a[src * n..(src + 1) * n])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dense reference solve of the same system.
    fn dense_solve(a: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
        let n = b.len();
        let mut m: Vec<Vec<f64>> = a.to_vec();
        let mut x = b.to_vec();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| m[i][k].abs().total_cmp(&m[j][k].abs()))
                .unwrap();
            m.swap(k, p);
            x.swap(k, p);
            let (top, bottom) = m.split_at_mut(k + 1);
            let pivot = &top[k];
            for (row, i) in bottom.iter_mut().zip(k + 1..) {
                let f = row[k] / pivot[k];
                for (a, b) in row[k..].iter_mut().zip(&pivot[k..]) {
                    *a -= f * b;
                }
                x[i] -= f * x[k];
            }
        }
        for k in (0..n).rev() {
            x[k] = (x[k] - (k + 1..n).map(|j| m[k][j] * x[j]).sum::<f64>()) / m[k][k];
        }
        x
    }

    #[test]
    fn ring_and_chain_systems_match_a_dense_solve() {
        let mut seed = 12345u64;
        let mut rand = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut system = BlockSystem::new(8, 6);
        for (blocks, closed) in [(6, true), (5, false), (1, false), (2, true), (8, true)] {
            let m = 6;
            let n = blocks * m;
            let mut dense = vec![vec![0.0; n]; n];
            let mut b = vec![0.0; n];
            system.reset(blocks, m);
            let mut couple = |i: usize, j: usize, system: &mut BlockSystem, diagonal: bool| {
                let block = system.block_mut(i, j);
                for c in 0..m {
                    for r in 0..m {
                        let v = rand() + if diagonal && r == c { 4.0 } else { 0.0 };
                        block[c * m + r] += v;
                        dense[i * m + r][j * m + c] += v;
                    }
                }
            };
            for i in 0..blocks {
                couple(i, i, &mut system, true);
                if i + 1 < blocks || (closed && blocks > 2) {
                    let j = (i + 1) % blocks;
                    couple(i, j, &mut system, false);
                    couple(j, i, &mut system, false);
                }
            }
            for i in 0..blocks {
                for (r, x) in system.rhs_mut(i).iter_mut().enumerate() {
                    *x = rand();
                    b[i * m + r] = *x;
                }
            }
            system.save();
            // A scrambled ring order still solves correctly (with more fill).
            let order: Vec<usize> = (0..blocks).rev().collect();
            system.solve(&order);
            let expected = dense_solve(&dense, &b);
            for (x, e) in system.rhs().iter().zip(&expected) {
                assert!((x - e).abs() < 1e-10, "{blocks} blocks: {x} vs {e}");
            }
            // The saved system gives the solution's residual and solves again after restore.
            let x = system.rhs().to_vec();
            let mut r = vec![1.0; n];
            system.residual(&x, &mut r);
            assert!(r.iter().all(|v| v.abs() < 1e-12), "{blocks} blocks: {r:?}");
            system.restore();
            system.solve(&order);
            assert_eq!(system.rhs(), &x[..]);
        }
    }
}
