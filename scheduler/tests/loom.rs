//! Model check of the claim protocol with loom: every interleaving with up to three preemptions
//! of threads claiming vertices of a path `0 - 1 - 2`, each exclusive on its vertex and shared on
//! its neighbours.
//!
//! Run: `cargo test -p sdg-scheduler --features loom --test loom --release`.

#![cfg(feature = "loom")]

use loom::sync::Arc;
use loom::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use sdg_scheduler::ClaimTable;

/// Tracks who holds what, to assert mutual exclusion inside the critical sections.
struct Holders {
    exclusive: [AtomicBool; 3],
    shared: [AtomicUsize; 3],
}

fn neighbours(v: u32) -> &'static [u32] {
    match v {
        0 => &[1],
        1 => &[0, 2],
        _ => &[1],
    }
}

/// Explores interleavings with at most three preemptions (loom's recommended bound).
fn model(f: impl Fn() + Sync + Send + 'static) {
    let mut builder = loom::model::Builder::new();
    builder.preemption_bound = Some(3);
    builder.check(f);
}

#[test]
fn claims_on_neighbours_exclude_each_other() {
    model(|| {
        let table = Arc::new(ClaimTable::new(3));
        let holders = Arc::new(Holders {
            exclusive: [
                AtomicBool::new(false),
                AtomicBool::new(false),
                AtomicBool::new(false),
            ],
            shared: [
                AtomicUsize::new(0),
                AtomicUsize::new(0),
                AtomicUsize::new(0),
            ],
        });
        let threads: Vec<_> = [0u32, 1, 2]
            .into_iter()
            .map(|v| {
                let (table, holders) = (table.clone(), holders.clone());
                loom::thread::spawn(move || {
                    let nbrs = neighbours(v);
                    if !table.try_claim(&[v], nbrs) {
                        return false;
                    }
                    let i = v as usize;
                    assert!(
                        !holders.exclusive[i].swap(true, Ordering::SeqCst),
                        "{v} held twice"
                    );
                    assert_eq!(
                        holders.shared[i].load(Ordering::SeqCst),
                        0,
                        "{v} read by a neighbour"
                    );
                    for &u in nbrs {
                        assert!(
                            !holders.exclusive[u as usize].load(Ordering::SeqCst),
                            "{v} and {u}"
                        );
                        holders.shared[u as usize].fetch_add(1, Ordering::SeqCst);
                    }
                    for &u in nbrs {
                        holders.shared[u as usize].fetch_sub(1, Ordering::SeqCst);
                    }
                    holders.exclusive[i].store(false, Ordering::SeqCst);
                    table.release(&[v], nbrs);
                    true
                })
            })
            .collect();
        let claimed: Vec<bool> = threads.into_iter().map(|t| t.join().unwrap()).collect();
        // A claim fails only on a real conflict, so at least one thread gets its claim.
        assert!(claimed.iter().any(|&c| c));
        for v in 0..3 {
            assert!(table.is_free(v), "vertex {v} left held");
        }
    });
}

#[test]
fn distance_two_claims_can_overlap_in_time() {
    model(|| {
        let table = Arc::new(ClaimTable::new(3));
        // Vertices 0 and 2 share neighbour 1: both claims always succeed.
        let threads: Vec<_> = [0u32, 2]
            .into_iter()
            .map(|v| {
                let table = table.clone();
                loom::thread::spawn(move || {
                    let ok = table.try_claim(&[v], &[1]);
                    if ok {
                        table.release(&[v], &[1]);
                    }
                    ok
                })
            })
            .collect();
        for t in threads {
            assert!(t.join().unwrap());
        }
    });
}
