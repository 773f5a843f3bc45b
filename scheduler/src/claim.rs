//! Claims: per-vertex reader-writer try-locks.
//!
//! A tent at `v` needs `v` exclusively (its time changes) and its neighbours shared (their times
//! are read, and the triangles of `v`'s star are written). Two tents conflict exactly when their
//! vertices are neighbours or equal. A claim checks and takes all its locks at once behind a
//! short gate, or takes none: claims never wait for each other (no deadlock), and a claim fails
//! only because of a claim that succeeded and is still held, whose release will offer the failed
//! vertex again (no lost wake-up). Releases need no gate.

use crate::sync::{AtomicU32, Mutex, Ordering};

/// Vertex index.
pub type VertexId = u32;

const EXCLUSIVE: u32 = 1 << 31;

/// One lock word per vertex: the top bit marks an exclusive holder, the rest count shared holders.
#[derive(Debug)]
pub struct ClaimTable {
    words: Vec<AtomicU32>,
    gate: Mutex<()>,
}

impl ClaimTable {
    /// A table for `vertices` vertices, all free.
    pub fn new(vertices: usize) -> Self {
        Self {
            words: (0..vertices).map(|_| AtomicU32::new(0)).collect(),
            gate: Mutex::new(()),
        }
    }

    /// Adds free lock words up to `vertices` (for vertices appended by an event).
    pub fn grow(&mut self, vertices: usize) {
        while self.words.len() < vertices {
            self.words.push(AtomicU32::new(0));
        }
    }

    fn release_exclusive(&self, v: VertexId) {
        // Nobody else holds v while it is exclusive: a plain store frees it.
        self.words[v as usize].store(0, Ordering::Release);
    }

    fn release_shared(&self, v: VertexId) {
        self.words[v as usize].fetch_sub(1, Ordering::Release);
    }

    /// Takes `owned` exclusively and `shared` (disjoint from `owned`) shared, all or nothing.
    /// Returns false, holding nothing, when any of them is held in a conflicting way. Claims are
    /// serialized by a gate, so no claim ever sees another's partial state; releases only lower
    /// the words, so a check that fails saw a real holder.
    pub fn try_claim(&self, owned: &[VertexId], shared: &[VertexId]) -> bool {
        let _gate = self.gate.lock().expect("the claim gate is never poisoned");
        let free = owned
            .iter()
            .all(|&v| self.words[v as usize].load(Ordering::Acquire) == 0)
            && shared
                .iter()
                .all(|&v| self.words[v as usize].load(Ordering::Acquire) & EXCLUSIVE == 0);
        if free {
            for &v in owned {
                self.words[v as usize].store(EXCLUSIVE, Ordering::Relaxed);
            }
            for &v in shared {
                self.words[v as usize].fetch_add(1, Ordering::Relaxed);
            }
        }
        free
    }

    /// Releases a claim taken by [`Self::try_claim`] with the same arguments. Writes made while
    /// holding it happen before any later claim of the same vertices (release / acquire).
    pub fn release(&self, owned: &[VertexId], shared: &[VertexId]) {
        shared.iter().for_each(|&v| self.release_shared(v));
        owned.iter().for_each(|&v| self.release_exclusive(v));
    }

    /// True when nobody holds `v` in any way (a vertex appended since the table last grew
    /// is free).
    pub fn is_free(&self, v: VertexId) -> bool {
        self.words
            .get(v as usize)
            .is_none_or(|word| word.load(Ordering::Acquire) == 0)
    }
}

#[cfg(all(test, not(feature = "loom")))]
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
