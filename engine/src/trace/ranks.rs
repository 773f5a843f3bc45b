//! Replaying a trace over ranks (`sdg scaling --ranks R`): the tents of a run on threads, each
//! on the rank that owns its vertex, with the dependencies between ranks delayed by the
//! latency of an update message.
//!
//! A run over ranks takes the tents of the serial reference order in either scheduler mode, by
//! the asynchronous protocol (`sdg_distributed`): a tent waits for the tents at its vertex and
//! its neighbours that it depends on (the trace's dependencies), and one at a vertex another
//! rank owns reaches it as an update message `latency` later. Each rank's workers take its
//! ready tents in trace order, paying the claim overhead per tent. The trace's other rows are
//! left out: over ranks there are no events that hold the whole state (each rank sums its
//! share of the history rows as it goes) and no rounds (the deterministic rounds' tents are the
//! protocol's), and mesh-changing events do not run over ranks (a trace with them is refused).
//! The model leaves out what sending and receiving the messages costs the ranks' cores.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::entry::{Entry, Kind};
use super::replay::{Prediction, Time};
use crate::error::EngineError;

/// How a replay splits the tents among ranks.
#[derive(Clone, Debug, PartialEq)]
pub struct RankModel {
    /// The owner rank of each vertex, by id, each below `ranks`.
    pub owners: Vec<u32>,
    /// Ranks, at least 1.
    pub ranks: usize,
    /// Delay of an update from one rank to another, s (>= 0).
    pub latency_s: f64,
}

/// The tents of `entries` (sorted by id) with each one's rank; bad input when the trace has
/// mesh-changing events or a vertex beyond the model's owners (another mesh than the trace's).
pub fn tents_on_ranks<'a>(
    entries: &'a [Entry],
    model: &RankModel,
) -> Result<Vec<(&'a Entry, usize)>, EngineError> {
    let regions = entries.iter().filter(|e| e.kind == Kind::Region).count();
    if regions > 0 {
        return Err(EngineError::Input(format!(
            "--ranks: the traced run changed its mesh ({regions} refinements, coarsenings or \
             crack extensions), and runs over ranks do not have mesh-changing events yet"
        )));
    }
    entries
        .iter()
        .filter(|e| e.kind.is_tent())
        .map(|e| {
            let v = e.vertex.unwrap_or_default() as usize;
            match model.owners.get(v) {
                Some(&rank) => Ok((e, rank as usize)),
                None => Err(EngineError::Input(format!(
                    "--ranks: the trace has a tent at vertex {v}, and the config's mesh has {} \
                     vertices: give the config (and --set) of the traced run",
                    model.owners.len()
                ))),
            }
        })
        .collect()
}

/// Per tent (positions in `tents`), its dependencies' positions; dependencies on rows that are
/// not tents are left out.
fn dependencies(tents: &[(&Entry, usize)]) -> Vec<Vec<usize>> {
    let position = |id: u64| tents.binary_search_by_key(&id, |(e, _)| e.id).ok();
    tents
        .iter()
        .map(|(e, _)| e.deps.iter().filter_map(|&d| position(d)).collect())
        .collect()
}

/// The delay between a dependency on rank `from` and its dependent on rank `to`, s.
fn delay(model: &RankModel, from: usize, to: usize) -> f64 {
    if from == to { 0.0 } else { model.latency_s }
}

/// Replays `tents` (from [`tents_on_ranks`]) with `workers` workers on each rank: the
/// predicted wall time and the mean number of ready tents over all ranks.
pub fn replay_over_ranks(
    tents: &[(&Entry, usize)],
    model: &RankModel,
    workers: usize,
    overhead_s: f64,
) -> Prediction {
    let workers = workers.max(1);
    let deps = dependencies(tents);
    let mut waiting: Vec<usize> = deps.iter().map(Vec::len).collect();
    let mut dependents: Vec<Vec<usize>> = vec![Vec::new(); tents.len()];
    for (i, list) in deps.iter().enumerate() {
        for &j in list {
            dependents[j].push(i);
        }
    }
    let mut ready_at = vec![0.0f64; tents.len()];
    // Tents whose dependencies are all done, by the time they reach their rank.
    let mut arriving: BinaryHeap<Reverse<(Time, usize)>> = (0..tents.len())
        .filter(|&i| waiting[i] == 0)
        .map(|i| Reverse((Time(0.0), i)))
        .collect();
    // Per rank: ready tents by trace position, and busy workers.
    let mut ready: Vec<BinaryHeap<Reverse<usize>>> = vec![BinaryHeap::new(); model.ranks];
    let mut busy = vec![0usize; model.ranks];
    let mut running: BinaryHeap<Reverse<(Time, usize)>> = BinaryHeap::new();
    let (mut now, mut area, mut done) = (0.0f64, 0.0, 0);
    let mut ready_count = 0usize;
    while done < tents.len() {
        // What has reached its rank by now is ready; then the free workers take what they can.
        while let Some(&Reverse((Time(t), i))) = arriving.peek() {
            if t > now {
                break;
            }
            arriving.pop();
            ready[tents[i].1].push(Reverse(i));
            ready_count += 1;
        }
        for (rank, queue) in ready.iter_mut().enumerate() {
            while busy[rank] < workers {
                let Some(Reverse(i)) = queue.pop() else { break };
                ready_count -= 1;
                busy[rank] += 1;
                let finish = now + overhead_s + tents[i].0.duration_s;
                running.push(Reverse((Time(finish), i)));
            }
        }
        // The next finish, or the next arrival before it.
        let next_arrival = arriving.peek().map_or(f64::INFINITY, |Reverse((t, _))| t.0);
        let next_finish = running.peek().map_or(f64::INFINITY, |Reverse((t, _))| t.0);
        let t = next_arrival.min(next_finish);
        assert!(
            t.is_finite(),
            "a tent not done is arriving, ready or running"
        );
        area += ready_count as f64 * (t - now);
        now = t;
        if next_arrival < next_finish {
            continue;
        }
        let Some(Reverse((_, i))) = running.pop() else {
            unreachable!("the next finish")
        };
        let rank = tents[i].1;
        busy[rank] -= 1;
        done += 1;
        for &k in &dependents[i] {
            ready_at[k] = ready_at[k].max(now + delay(model, rank, tents[k].1));
            waiting[k] -= 1;
            if waiting[k] == 0 {
                arriving.push(Reverse((Time(ready_at[k]), k)));
            }
        }
    }
    Prediction {
        workers,
        wall_time_s: now,
        mean_ready: area / now.max(f64::MIN_POSITIVE),
    }
}

/// The time with unlimited workers on every rank, s: the longest chain of dependencies, each
/// tent with `overhead_s`, each step between ranks with the latency.
pub fn critical_path_over_ranks(
    tents: &[(&Entry, usize)],
    model: &RankModel,
    overhead_s: f64,
) -> f64 {
    let deps = dependencies(tents);
    let mut finish = vec![0.0f64; tents.len()];
    for (i, (e, rank)) in tents.iter().enumerate() {
        let start = deps[i]
            .iter()
            .map(|&j| finish[j] + delay(model, tents[j].1, *rank))
            .fold(0.0, f64::max);
        finish[i] = start + overhead_s + e.duration_s;
    }
    finish.iter().copied().fold(0.0, f64::max)
}

/// The fraction of the tents' dependencies that cross ranks (each one an update message).
pub fn cross_rank_fraction(tents: &[(&Entry, usize)]) -> f64 {
    let deps = dependencies(tents);
    let (mut all, mut cross) = (0usize, 0usize);
    for (i, list) in deps.iter().enumerate() {
        all += list.len();
        cross += list.iter().filter(|&&j| tents[j].1 != tents[i].1).count();
    }
    cross as f64 / all.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::replay;

    fn tent(id: u64, duration_s: f64, deps: &[u64]) -> Entry {
        Entry {
            id,
            kind: Kind::Patch,
            vertex: Some(id as sdg_mesh::VertexId),
            start_s: 0.0,
            duration_s,
            deps: deps.to_vec(),
        }
    }

    fn model(owners: &[u32], latency_s: f64) -> RankModel {
        RankModel {
            owners: owners.to_vec(),
            ranks: owners.iter().max().map_or(1, |&r| r as usize + 1),
            latency_s,
        }
    }

    #[test]
    fn a_chain_across_ranks_waits_for_each_update() {
        // Five unit tents, each after the one before, on ranks 0, 1, 0, 1, 0.
        let entries: Vec<Entry> = (0..5)
            .map(|i| {
                tent(
                    i,
                    1.0,
                    &(0..i)
                        .skip((i as usize).saturating_sub(1))
                        .collect::<Vec<_>>(),
                )
            })
            .collect();
        let m = model(&[0, 1, 0, 1, 0], 0.5);
        let tents = tents_on_ranks(&entries, &m).unwrap();
        assert_eq!(replay_over_ranks(&tents, &m, 1, 0.0).wall_time_s, 7.0);
        assert_eq!(replay_over_ranks(&tents, &m, 4, 0.25).wall_time_s, 8.25);
        assert_eq!(critical_path_over_ranks(&tents, &m, 0.0), 7.0);
        assert_eq!(cross_rank_fraction(&tents), 1.0);
        // On one rank no update travels.
        let one = model(&[0; 5], 0.5);
        let tents = tents_on_ranks(&entries, &one).unwrap();
        assert_eq!(replay_over_ranks(&tents, &one, 1, 0.0).wall_time_s, 5.0);
        assert_eq!(cross_rank_fraction(&tents), 0.0);
    }

    #[test]
    fn each_rank_runs_its_own_tents() {
        // Two independent chains of three tents (ids 0-2 and 3-5), of 1 s and 2 s a tent.
        let entries = vec![
            tent(0, 1.0, &[]),
            tent(1, 1.0, &[0]),
            tent(2, 1.0, &[1]),
            tent(3, 2.0, &[]),
            tent(4, 2.0, &[3]),
            tent(5, 2.0, &[4]),
        ];
        // A chain per rank: the longer one decides.
        let split = model(&[0, 0, 0, 1, 1, 1], 1.0);
        let tents = tents_on_ranks(&entries, &split).unwrap();
        assert_eq!(replay_over_ranks(&tents, &split, 1, 0.0).wall_time_s, 6.0);
        // Both chains on rank 1 (rank 0 idle) with one worker: one after the other.
        let piled = model(&[1, 1, 1, 1, 1, 1], 1.0);
        let piled = RankModel { ranks: 2, ..piled };
        let tents = tents_on_ranks(&entries, &piled).unwrap();
        let p = replay_over_ranks(&tents, &piled, 1, 0.0);
        assert_eq!(p.wall_time_s, 9.0);
        assert_eq!(replay_over_ranks(&tents, &piled, 2, 0.0).wall_time_s, 6.0);
    }

    #[test]
    fn one_rank_is_the_threaded_replay() {
        // A pseudo-random graph of 300 tents (each on up to three earlier ones, random costs):
        // one rank with W workers is the scheduler's replay on W workers, whatever the latency.
        let mut state = 12345u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            state >> 33
        };
        let entries: Vec<Entry> = (0..300u64)
            .map(|i| {
                let deps: Vec<u64> = (0..3)
                    .filter(|_| i > 0)
                    .map(|_| i.saturating_sub(1 + next() % 20))
                    .collect::<std::collections::BTreeSet<_>>()
                    .into_iter()
                    .collect();
                tent(i, 1e-3 * (1 + next() % 100) as f64, &deps)
            })
            .collect();
        let m = model(&[0; 300], 1.0);
        let tents = tents_on_ranks(&entries, &m).unwrap();
        for workers in [1, 2, 3, 5] {
            let threaded = replay(&entries, workers, 1e-4);
            let ranked = replay_over_ranks(&tents, &m, workers, 1e-4);
            assert_eq!(ranked.wall_time_s, threaded.wall_time_s, "{workers}");
            assert!(
                (ranked.mean_ready - threaded.mean_ready).abs() < 1e-9,
                "{workers} {} {}",
                ranked.mean_ready,
                threaded.mean_ready
            );
        }
    }

    #[test]
    fn mesh_changes_and_another_mesh_are_refused() {
        let region = Entry {
            kind: Kind::Region,
            vertex: None,
            ..tent(1, 1.0, &[0])
        };
        let m = model(&[0, 1], 0.0);
        let err = tents_on_ranks(&[tent(0, 1.0, &[]), region], &m).unwrap_err();
        assert!(err.to_string().contains("mesh-changing"), "{err}");
        let err = tents_on_ranks(&[tent(0, 1.0, &[]), tent(2, 1.0, &[0])], &m).unwrap_err();
        assert!(err.to_string().contains("vertex 2"), "{err}");
    }
}
