//! Block elimination for a patch's linear system.
//!
//! The elements of a tent patch couple only through the vertical faces around the pole: an
//! interior tent's elements form a ring, a boundary tent's a chain. Eliminating element blocks
//! in ring order fills in only the blocks that couple to the ring's last element, so a patch of
//! `d` elements of `m` unknowns costs about `d` times a few `m^3` operations instead of the
//! `(d m)^3` of a dense factorization.
//!
//! A coupling block between two elements acts only through the traces on their shared face, and
//! the upwind flux passes only the incoming waves: it has low rank `r` (at p = 3 in plane strain,
//! 2 waves times the 10 face polynomials: `r = 20` of `m = 100`). Such blocks are kept as factors
//! `U V^T` ([`BlockSystem::add_term`]); the elimination keeps the fill in that form, so each
//! Schur update costs `m^2 r` instead of `m^3`. Diagonal blocks are dense, and a factored block
//! whose rank would pass `m / 2` becomes dense.
//!
//! Blocks live in one pool of `m x m` slots (column-major), sized once, so solving allocates
//! nothing.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

/// What a block of the system holds: a dense `m x m` slot, or factors `U V^T` of some rank in a
/// slot (`U` in its first `m x m/2` values, `V` in the next).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Block {
    Dense(usize),
    Factored(usize, usize),
}

/// A block-sparse linear system of up to `max_blocks` block rows of size up to `max_size`.
pub struct BlockSystem {
    max_blocks: usize,
    blocks: usize,
    size: usize,
    /// Block `(i, j)` at `i * max_blocks + j`.
    index: Vec<Option<Block>>,
    pool: Vec<f64>,
    used: usize,
    rhs: Vec<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    /// Scratch: an `m x m` product, a term's two factors, a small `r x r` product, a vector.
    product: Vec<f64>,
    left: Vec<f64>,
    right: Vec<f64>,
    small: Vec<f64>,
    column: Vec<f64>,
    stack: MemBuffer,
    /// A copy of the assembled system for Newton iterations ([`Self::save`]); grown on first use.
    saved: Saved,
}

/// An assembled, unfactored system: the used blocks, their index and the right-hand side.
#[derive(Debug, Default)]
struct Saved {
    index: Vec<Option<Block>>,
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

/// An `r x c` column-major view of `values`.
fn view(values: &[f64], r: usize, c: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(values, r, c)
}

/// An `r x c` column-major mutable view of `values`.
fn view_mut(values: &mut [f64], r: usize, c: usize) -> MatMut<'_, f64> {
    MatMut::from_column_major_slice_mut(values, r, c)
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
        let square = max_size * max_size;
        Self {
            max_blocks,
            blocks: 0,
            size: 0,
            index: vec![None; max_blocks * max_blocks],
            pool: vec![0.0; capacity * square],
            used: 0,
            rhs: vec![0.0; max_blocks * max_size],
            perm: vec![0; max_blocks * max_size],
            perm_inv: vec![0; max_size],
            product: vec![0.0; square],
            left: vec![0.0; square],
            right: vec![0.0; square],
            small: vec![0.0; square],
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
        let (m, n, h) = (self.size, self.size * self.size, self.v_offset());
        let saved = &self.saved;
        out[..saved.rhs.len()].copy_from_slice(&saved.rhs);
        for i in 0..self.blocks {
            for j in 0..self.blocks {
                let Some(block) = saved.index[i * self.max_blocks + j] else {
                    continue;
                };
                let (row, x) = (&mut out[i * m..(i + 1) * m], &x[j * m..(j + 1) * m]);
                match block {
                    Block::Dense(k) => {
                        let a = view(&saved.pool[k * n..(k + 1) * n], m, m);
                        matmul(
                            view_mut(row, m, 1),
                            Accum::Add,
                            a,
                            view(x, m, 1),
                            -1.0,
                            Par::Seq,
                        );
                    }
                    Block::Factored(k, r) => {
                        // row -= U (V^T x), one column of U and V at a time.
                        let slot = &saved.pool[k * n..(k + 1) * n];
                        let (u, v) = (&slot[..m * r], &slot[h..h + m * r]);
                        for (uc, vc) in u.chunks_exact(m).zip(v.chunks_exact(m)) {
                            let t: f64 = vc.iter().zip(x).map(|(a, b)| a * b).sum();
                            for (o, a) in row.iter_mut().zip(uc) {
                                *o -= a * t;
                            }
                        }
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

    /// The most columns a factored block keeps; beyond, a dense block is cheaper.
    fn rank_capacity(&self) -> usize {
        self.size / 2
    }

    fn new_slot(&mut self) -> usize {
        let k = self.used;
        self.used += 1;
        k
    }

    /// The dense slot of block `(i, j)`: created zero, or multiplied out from its factors.
    fn dense_slot(&mut self, i: usize, j: usize) -> usize {
        match self.index[i * self.max_blocks + j] {
            Some(Block::Dense(k)) => k,
            Some(Block::Factored(..)) => self.densify(i, j),
            None => {
                let k = self.new_slot();
                let n = self.size * self.size;
                self.pool[k * n..(k + 1) * n].fill(0.0);
                self.index[i * self.max_blocks + j] = Some(Block::Dense(k));
                k
            }
        }
    }

    /// Replaces the factored block `(i, j)` by the dense product of its factors; returns its slot.
    fn densify(&mut self, i: usize, j: usize) -> usize {
        let Some(Block::Factored(k, r)) = self.index[i * self.max_blocks + j] else {
            unreachable!("only factored blocks are made dense");
        };
        let (m, n, h) = (self.size, self.size * self.size, self.v_offset());
        let slot = &self.pool[k * n..(k + 1) * n];
        matmul(
            view_mut(&mut self.product[..n], m, m),
            Accum::Replace,
            view(&slot[..m * r], m, r),
            view(&slot[h..h + m * r], m, r).transpose(),
            1.0,
            Par::Seq,
        );
        self.pool[k * n..(k + 1) * n].copy_from_slice(&self.product[..n]);
        self.index[i * self.max_blocks + j] = Some(Block::Dense(k));
        k
    }

    /// Where a factored slot's `V` starts.
    fn v_offset(&self) -> usize {
        self.size * self.rank_capacity()
    }

    /// Block `(i, j)`, which must not exist yet, as a dense column-major slice whose entries
    /// are left over from earlier systems: the caller writes every one of them (this saves
    /// zeroing a block that is assigned at once).
    pub fn new_block_mut(&mut self, i: usize, j: usize) -> &mut [f64] {
        let at = i * self.max_blocks + j;
        assert!(self.index[at].is_none(), "block ({i}, {j}) exists already");
        let k = self.new_slot();
        self.index[at] = Some(Block::Dense(k));
        let n = self.size * self.size;
        &mut self.pool[k * n..(k + 1) * n]
    }

    /// Block `(i, j)` as a dense column-major slice, created zero on first use (a factored
    /// block is multiplied out).
    pub fn block_mut(&mut self, i: usize, j: usize) -> &mut [f64] {
        let k = self.dense_slot(i, j);
        let n = self.size * self.size;
        &mut self.pool[k * n..(k + 1) * n]
    }

    /// Room for the factors `U` and `V` (`m x r` column-major each) of a term for
    /// [`Self::add_term`]; their entries are left over from earlier terms: the caller writes
    /// every one of them.
    pub fn term_mut(&mut self, r: usize) -> (&mut [f64], &mut [f64]) {
        let m = self.size;
        (&mut self.left[..m * r], &mut self.right[..m * r])
    }

    /// Adds `scale U V^T`, the rank-`r` term left by [`Self::term_mut`], to block `(i, j)`:
    /// appended to its factors while their rank stays within `m / 2`, else added densely.
    pub fn add_term(&mut self, i: usize, j: usize, r: usize, scale: f64) {
        if r == 0 {
            return;
        }
        let (m, n, h) = (self.size, self.size * self.size, self.v_offset());
        let at = i * self.max_blocks + j;
        let current = self.index[at];
        let room = match current {
            None if i != j && r <= self.rank_capacity() => Some((self.new_slot(), 0)),
            Some(Block::Factored(k, rank)) if rank + r <= self.rank_capacity() => Some((k, rank)),
            _ => None,
        };
        if let Some((k, rank)) = room {
            let slot = &mut self.pool[k * n..(k + 1) * n];
            for (u, l) in slot[m * rank..m * (rank + r)].iter_mut().zip(&self.left) {
                *u = scale * l;
            }
            slot[h + m * rank..h + m * (rank + r)].copy_from_slice(&self.right[..m * r]);
            self.index[at] = Some(Block::Factored(k, rank + r));
        } else {
            let k = self.dense_slot(i, j);
            matmul(
                view_mut(&mut self.pool[k * n..(k + 1) * n], m, m),
                Accum::Add,
                view(&self.left[..m * r], m, r),
                view(&self.right[..m * r], m, r).transpose(),
                scale,
                Par::Seq,
            );
        }
    }

    /// Right-hand side of block row `i`; after [`Self::solve`], the solution.
    pub fn rhs_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.rhs[i * self.size..(i + 1) * self.size]
    }

    /// The whole right-hand side / solution, block row after block row.
    pub fn rhs(&self) -> &[f64] {
        &self.rhs[..self.blocks * self.size]
    }

    /// `rhs_row += alpha B x` for block `B` and `x` in `self.column`.
    fn apply(&mut self, block: Block, row: usize, alpha: f64) {
        let (m, n, h) = (self.size, self.size * self.size, self.v_offset());
        let out = view_mut(&mut self.rhs[row * m..(row + 1) * m], m, 1);
        let x = view(&self.column[..m], m, 1);
        match block {
            Block::Dense(k) => {
                matmul(
                    out,
                    Accum::Add,
                    view(&self.pool[k * n..(k + 1) * n], m, m),
                    x,
                    alpha,
                    Par::Seq,
                );
            }
            Block::Factored(k, r) => {
                let slot = &self.pool[k * n..(k + 1) * n];
                matmul(
                    view_mut(&mut self.small[..r], r, 1),
                    Accum::Replace,
                    view(&slot[h..h + m * r], m, r).transpose(),
                    x,
                    1.0,
                    Par::Seq,
                );
                matmul(
                    out,
                    Accum::Add,
                    view(&slot[..m * r], m, r),
                    view(&self.small[..r], r, 1),
                    alpha,
                    Par::Seq,
                );
            }
        }
    }

    /// Subtracts `A W` from block `(i, j)`, for `A = A_ie` and `W = D_ee^-1 A_ej` (either dense
    /// or factored): the product of a factored block with anything is factored, of rank at
    /// most the factored one's.
    fn subtract_product(&mut self, i: usize, j: usize, a: Block, w: Block) {
        let (m, n, h) = (self.size, self.size * self.size, self.v_offset());
        let pool = &self.pool;
        let u = |k: usize, r: usize| view(&pool[k * n..k * n + m * r], m, r);
        let v = |k: usize, r: usize| view(&pool[k * n + h..k * n + h + m * r], m, r);
        let dense = |k: usize| view(&pool[k * n..(k + 1) * n], m, m);
        let rank = match (a, w) {
            (Block::Factored(ka, ra), Block::Factored(kw, rw)) => {
                // A W = U_a (V_a^T U_w) V_w^T: multiply the small middle into the lower rank.
                matmul(
                    view_mut(&mut self.small[..ra * rw], ra, rw),
                    Accum::Replace,
                    v(ka, ra).transpose(),
                    u(kw, rw),
                    1.0,
                    Par::Seq,
                );
                let middle = view(&self.small[..ra * rw], ra, rw);
                if ra <= rw {
                    self.left[..m * ra].copy_from_slice(&pool[ka * n..ka * n + m * ra]);
                    matmul(
                        view_mut(&mut self.right[..m * ra], m, ra),
                        Accum::Replace,
                        v(kw, rw),
                        middle.transpose(),
                        1.0,
                        Par::Seq,
                    );
                    ra
                } else {
                    matmul(
                        view_mut(&mut self.left[..m * rw], m, rw),
                        Accum::Replace,
                        u(ka, ra),
                        middle,
                        1.0,
                        Par::Seq,
                    );
                    self.right[..m * rw].copy_from_slice(&pool[kw * n + h..kw * n + h + m * rw]);
                    rw
                }
            }
            (Block::Dense(ka), Block::Factored(kw, rw)) => {
                matmul(
                    view_mut(&mut self.left[..m * rw], m, rw),
                    Accum::Replace,
                    dense(ka),
                    u(kw, rw),
                    1.0,
                    Par::Seq,
                );
                self.right[..m * rw].copy_from_slice(&pool[kw * n + h..kw * n + h + m * rw]);
                rw
            }
            (Block::Factored(ka, ra), Block::Dense(kw)) => {
                self.left[..m * ra].copy_from_slice(&pool[ka * n..ka * n + m * ra]);
                matmul(
                    view_mut(&mut self.right[..m * ra], m, ra),
                    Accum::Replace,
                    dense(kw).transpose(),
                    v(ka, ra),
                    1.0,
                    Par::Seq,
                );
                ra
            }
            (Block::Dense(ka), Block::Dense(kw)) => {
                let c = self.dense_slot(i, j);
                self.product[..n].copy_from_slice(&self.pool[ka * n..(ka + 1) * n]);
                let (dst, src) = two_blocks(&mut self.pool, c, kw, n);
                matmul(
                    view_mut(dst, m, m),
                    Accum::Add,
                    view(&self.product[..n], m, m),
                    view(src, m, m),
                    -1.0,
                    Par::Seq,
                );
                return;
            }
        };
        self.add_term(i, j, rank, -1.0);
    }

    /// Solves in place by block Gaussian elimination in the given order of block rows (a
    /// permutation of `0..blocks`); each diagonal block is factored with partial pivoting.
    pub fn solve(&mut self, order: &[usize]) {
        let (m, n) = (self.size, self.size * self.size);
        let mb = self.max_blocks;
        for (k, &e) in order.iter().enumerate() {
            let later = &order[k + 1..];
            let d = self.dense_slot(e, e);
            {
                let stack = MemStack::new(&mut self.stack);
                let (_, perm) = factor::lu_in_place(
                    view_mut(&mut self.pool[d * n..(d + 1) * n], m, m),
                    &mut self.perm[e * m..(e + 1) * m],
                    &mut self.perm_inv[..m],
                    Par::Seq,
                    stack,
                    Default::default(),
                );
                let (before, rest) = self.pool.split_at_mut(d * n);
                let (lu, after) = rest.split_at_mut(n);
                let lu = view(lu, m, m);
                // Row e: every later block (a factored one's U) and the right-hand side times
                // D_ee^-1.
                for &j in later {
                    let (b, columns) = match self.index[e * mb + j] {
                        None => continue,
                        Some(Block::Dense(b)) => (b, m),
                        Some(Block::Factored(b, r)) => (b, r),
                    };
                    let slot = if b < d {
                        &mut before[b * n..(b + 1) * n]
                    } else {
                        &mut after[(b - d - 1) * n..(b - d) * n]
                    };
                    solve::solve_in_place(
                        lu,
                        lu,
                        perm,
                        view_mut(&mut slot[..m * columns], m, columns),
                        Par::Seq,
                        stack,
                    );
                }
                solve::solve_in_place(
                    lu,
                    lu,
                    perm,
                    view_mut(&mut self.rhs[e * m..(e + 1) * m], m, 1),
                    Par::Seq,
                    stack,
                );
            }
            // Schur complement on the later rows that couple to e.
            for &i in later {
                let Some(a) = self.index[i * mb + e] else {
                    continue;
                };
                self.column[..m].copy_from_slice(&self.rhs[e * m..(e + 1) * m]);
                self.apply(a, i, -1.0);
                for &j in later {
                    if let Some(w) = self.index[e * mb + j] {
                        self.subtract_product(i, j, a, w);
                    }
                }
            }
        }
        // Back substitution: x_e = y_e - sum over later j of (D_ee^-1 A_ej) x_j.
        for (k, &e) in order.iter().enumerate().rev() {
            for &j in &order[k + 1..] {
                if let Some(w) = self.index[e * mb + j] {
                    self.column[..m].copy_from_slice(&self.rhs[j * m..(j + 1) * m]);
                    self.apply(w, e, -1.0);
                }
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

    /// A pseudo-random number in `[-0.5, 0.5)`.
    fn generator(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// How the test couples two blocks.
    #[derive(Clone, Copy, Debug)]
    enum Coupling {
        Dense,
        /// Terms `U V^T` of these ranks, added one after the other.
        Factored(&'static [usize]),
    }

    /// Assembles a ring or chain system of random blocks into `system`; returns it dense with
    /// its right-hand side.
    fn assemble(
        system: &mut BlockSystem,
        (blocks, closed, m): (usize, bool, usize),
        coupling: Coupling,
        seed: u64,
    ) -> (Vec<Vec<f64>>, Vec<f64>) {
        let mut rand = generator(seed);
        let n = blocks * m;
        let mut dense = vec![vec![0.0; n]; n];
        system.reset(blocks, m);
        let mut couple = |i: usize, j: usize, system: &mut BlockSystem| match coupling {
            Coupling::Factored(ranks) if i != j => {
                for &rank in ranks {
                    let scale = 2.0 * rand();
                    let (u, v) = system.term_mut(rank);
                    u.iter_mut().for_each(|x| *x = rand());
                    v.iter_mut().for_each(|x| *x = rand());
                    for r in 0..m {
                        for c in 0..m {
                            dense[i * m + r][j * m + c] +=
                                scale * (0..rank).map(|s| u[s * m + r] * v[s * m + c]).sum::<f64>();
                        }
                    }
                    system.add_term(i, j, rank, scale);
                }
            }
            _ => {
                let block = system.block_mut(i, j);
                for c in 0..m {
                    for r in 0..m {
                        let v = rand() + if i == j && r == c { 4.0 } else { 0.0 };
                        block[c * m + r] += v;
                        dense[i * m + r][j * m + c] += v;
                    }
                }
            }
        };
        for i in 0..blocks {
            couple(i, i, system);
            if i + 1 < blocks || (closed && blocks > 2) {
                let j = (i + 1) % blocks;
                couple(i, j, system);
                couple(j, i, system);
            }
        }
        let mut b = vec![0.0; n];
        for i in 0..blocks {
            for (r, x) in system.rhs_mut(i).iter_mut().enumerate() {
                *x = rand();
                b[i * m + r] = *x;
            }
        }
        (dense, b)
    }

    /// Solves a random ring or chain system in a scrambled order (more fill than ring order)
    /// against a dense solve; the copy kept by [`BlockSystem::save`] gives the solution's
    /// residual and solves again after restore.
    fn check(shape: (usize, bool, usize), coupling: Coupling, seed: u64) {
        let mut system = BlockSystem::new(8, 12);
        let label = format!("{shape:?}, {coupling:?}");
        let order: Vec<usize> = (0..shape.0).rev().collect();
        let (dense, b) = assemble(&mut system, shape, coupling, seed);
        if let (Coupling::Factored(&[rank]), (blocks, _, m)) = (coupling, shape)
            && blocks > 1
        {
            let kept = system.index[1];
            assert_eq!(
                kept,
                Some(Block::Factored(kept.map_or(0, slot), rank)),
                "{label}"
            );
            assert!(rank <= m / 2);
        }
        let expected = dense_solve(&dense, &b);
        system.solve(&order);
        for (x, e) in system.rhs().iter().zip(&expected) {
            assert!((x - e).abs() < 1e-10, "{label}: {x} vs {e}");
        }
        assemble(&mut system, shape, coupling, seed);
        system.save();
        system.solve(&order);
        for (x, e) in system.rhs().iter().zip(&expected) {
            assert!((x - e).abs() < 1e-10, "{label}, saved: {x} vs {e}");
        }
        let x = system.rhs().to_vec();
        let mut r = vec![1.0; b.len()];
        system.residual(&x, &mut r);
        assert!(r.iter().all(|v| v.abs() < 1e-12), "{label}: {r:?}");
        system.restore();
        system.solve(&order);
        assert_eq!(system.rhs(), &x[..]);
    }

    fn slot(block: Block) -> usize {
        match block {
            Block::Dense(k) | Block::Factored(k, _) => k,
        }
    }

    #[test]
    fn ring_and_chain_systems_match_a_dense_solve() {
        for (blocks, closed) in [(6, true), (5, false), (1, false), (2, true), (8, true)] {
            check((blocks, closed, 6), Coupling::Dense, 12345);
            // Rank 2 of 6 (capacity 3): factored fill, some made dense when ranks add up.
            check((blocks, closed, 6), Coupling::Factored(&[2]), 777);
            // Ranks 1 + 1 appended, then 2 more: made dense at assembly.
            check((blocks, closed, 6), Coupling::Factored(&[1, 1, 2]), 778);
            check((blocks, closed, 12), Coupling::Factored(&[3]), 779);
        }
    }
}
