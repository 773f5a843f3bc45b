//! Claims: per-vertex reader-writer try-locks.
//!
//! A tent at `v` needs `v` exclusively (its time changes) and its neighbours shared (their times
//! are read, and the triangles of `v`'s star are written). Two tents conflict exactly when their
//! vertices are neighbours or equal. Every operation is a non-blocking try: a claim either takes
//! all its locks or none, so claims can never deadlock.

use crate::sync::{AtomicU32, Ordering};

/// Vertex index.
pub type VertexId = u32;

const EXCLUSIVE: u32 = 1 << 31;

/// One lock word per vertex: the top bit marks an exclusive holder, the rest count shared holders.
#[derive(Debug)]
pub struct ClaimTable {
    words: Vec<AtomicU32>,
}

impl ClaimTable {
    /// A table for `vertices` vertices, all free.
    pub fn new(vertices: usize) -> Self {
        Self {
            words: (0..vertices).map(|_| AtomicU32::new(0)).collect(),
        }
    }

    fn try_exclusive(&self, v: VertexId) -> bool {
        self.words[v as usize]
            .compare_exchange(0, EXCLUSIVE, Ordering::Acquire, Ordering::Relaxed)
            .is_ok()
    }

    fn try_shared(&self, v: VertexId) -> bool {
        let word = &self.words[v as usize];
        let mut current = word.load(Ordering::Relaxed);
        loop {
            if current & EXCLUSIVE != 0 {
                return false;
            }
            match word.compare_exchange_weak(
                current,
                current + 1,
                Ordering::Acquire,
                Ordering::Relaxed,
            ) {
                Ok(_) => return true,
                Err(now) => current = now,
            }
        }
    }

    fn release_exclusive(&self, v: VertexId) {
        self.words[v as usize].store(0, Ordering::Release);
    }

    fn release_shared(&self, v: VertexId) {
        self.words[v as usize].fetch_sub(1, Ordering::Release);
    }

    /// Takes `owned` exclusively and `shared` (disjoint from `owned`) shared, all or nothing.
    /// Returns false, holding nothing, when any of them is held in a conflicting way.
    pub fn try_claim(&self, owned: &[VertexId], shared: &[VertexId]) -> bool {
        for (i, &v) in owned.iter().enumerate() {
            if !self.try_exclusive(v) {
                owned[..i].iter().for_each(|&w| self.release_exclusive(w));
                return false;
            }
        }
        for (i, &v) in shared.iter().enumerate() {
            if !self.try_shared(v) {
                shared[..i].iter().for_each(|&w| self.release_shared(w));
                owned.iter().for_each(|&w| self.release_exclusive(w));
                return false;
            }
        }
        true
    }

    /// Releases a claim taken by [`Self::try_claim`] with the same arguments. Writes made while
    /// holding it happen before any later claim of the same vertices (release / acquire).
    pub fn release(&self, owned: &[VertexId], shared: &[VertexId]) {
        shared.iter().for_each(|&v| self.release_shared(v));
        owned.iter().for_each(|&v| self.release_exclusive(v));
    }

    /// True when nobody holds `v` in any way.
    pub fn is_free(&self, v: VertexId) -> bool {
        self.words[v as usize].load(Ordering::Acquire) == 0
    }
}

#[cfg(all(test, not(loom)))]
mod tests {
    use super::*;

    #[test]
    fn neighbours_exclude_each_other_and_distance_two_shares() {
        // Path 0 - 1 - 2 - 3.
        let t = ClaimTable::new(4);
        assert!(t.try_claim(&[1], &[0, 2]));
        assert!(!t.try_claim(&[2], &[1, 3]), "neighbour of a claimed vertex");
        assert!(!t.try_claim(&[0], &[1]), "neighbour of a claimed vertex");
        assert!(t.is_free(3));
        // Vertex 3 shares neighbour 2 with the tent at 1: allowed.
        assert!(t.try_claim(&[3], &[2]));
        t.release(&[1], &[0, 2]);
        assert!(!t.try_claim(&[2], &[1, 3]), "3 still holds itself");
        t.release(&[3], &[2]);
        assert!(t.try_claim(&[2], &[1, 3]));
        t.release(&[2], &[1, 3]);
        assert!((0..4).all(|v| t.is_free(v)));
    }

    #[test]
    fn a_failed_claim_leaves_nothing_held() {
        let t = ClaimTable::new(5);
        assert!(t.try_claim(&[4], &[3]));
        assert!(!t.try_claim(&[0, 1], &[2, 3, 4]));
        assert!((0..3).all(|v| t.is_free(v)));
        t.release(&[4], &[3]);
        assert!((0..5).all(|v| t.is_free(v)));
    }
}
