//! Deterministic mode: rounds of the vertices first in `(time, id)` among their neighbours.
//!
//! Each round takes every vertex below the end time that comes first in the order of
//! `(time, id)` among its neighbours (after the first round only those whose neighbourhood the
//! last round or its events changed are examined), in that order. Two such vertices are never
//! neighbours, so the round's tents do not read each other's data and solving them in parallel
//! in any order gives the same bits; and whether a vertex is taken depends on its neighbourhood
//! alone, so that without events the tents are those of the serial order
//! ([`crate::run_serial`]) and of the asynchronous pool, and ranks holding parts of a mesh can
//! each choose their share of a round. Once all have run, the workers settle their outcomes
//! ([`Work::settle`]) and check which of the vertices they took are ready for the next round, in
//! parallel: both only read the state as the round left it. The calling thread then records the
//! outcomes in the round's order, and queued events run in the order they were queued, with the
//! state held exclusively. The result depends only on the inputs.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Barrier;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use parking_lot::{Mutex, RwLock};

use crate::{
    Clock, Events, Lease, RunError, State, Stats, Tried, VertexId, Work, below_end,
    is_first_among_neighbours, panic_message,
};

/// Chosen tents per work item of a round's settling: items of a fixed size make the trace the
/// same for any thread count.
const CHUNK: usize = 16;

/// Shared state of one round.
struct Round<O, E> {
    chosen: Vec<VertexId>,
    /// The next chosen tent to solve, and the next chunk of them to settle.
    next: AtomicUsize,
    next_chunk: AtomicUsize,
    results: Vec<Mutex<Option<Tried<O, E>>>>,
}

pub(crate) fn run<'a, W: Work<'a>>(
    state: &mut W::State,
    t_end: f64,
    work: &'a W,
    scratch: Vec<W::Scratch>,
) -> Result<Stats, RunError<W::Error>> {
    let mut n = state.mesh().vertices().len();
    let state = RwLock::new(state);
    let threads = scratch.len();
    let events: Events<'a, W::State> = Events::default();
    let round: RwLock<Round<W::Outcome, W::Error>> = RwLock::new(Round {
        chosen: Vec::with_capacity(n),
        next: AtomicUsize::new(0),
        next_chunk: AtomicUsize::new(0),
        results: Vec::new(),
    });
    // The calling thread chooses the rounds, solves and settles its share of each and records
    // them: with `threads` threads in all, a run never has more threads than workers.
    let barrier = Barrier::new(threads);
    let done = AtomicBool::new(false);
    let mut stats = Stats {
        tents_per_thread: vec![0; threads],
        ..Stats::default()
    };
    let per_thread: Vec<AtomicUsize> = (0..threads).map(|_| AtomicUsize::new(0)).collect();
    let (event_time, wait_time) = (Clock::default(), Clock::default());
    // The ready vertices (first among their neighbours) with their times. A round takes every
    // ready vertex and changes the front only at them, so the next round's ready vertices are
    // among the chosen ones and their neighbours, which the workers check and list in `found`,
    // one list per worker (a neighbour of two chosen vertices twice: sorted, the copies are
    // adjacent and dropped). Events change readiness only at the vertices they offer
    // ([`crate::Changed::offer`], ids as after the event); a coarsening renumbers (the last
    // vertex takes the removed one's id, and offers it), so after events the calling thread
    // checks again every vertex found or offered that still exists (`offered`), as the
    // asynchronous pool does. Only the first round scans the whole front.
    let mut ready: Vec<(f64, VertexId)> = Vec::with_capacity(n);
    let found: Vec<Mutex<Vec<(f64, VertexId)>>> = (0..threads)
        .map(|_| Mutex::new(Vec::with_capacity(n)))
        .collect();
    let mut scan_all = true;
    let mut offered: Vec<VertexId> = Vec::new();
    let mut after_events = false;
    let wait = |barrier: &Barrier| {
        let idle = Instant::now();
        barrier.wait();
        wait_time.add_since(idle);
    };
    let split = work.exchanges();
    let solve = |id: usize, scratch: &mut W::Scratch| {
        {
            let r = round.read();
            let state = state.read();
            loop {
                let i = r.next.fetch_add(1, Ordering::Relaxed);
                let Some(&v) = r.chosen.get(i) else { break };
                if split && !work.solves(i, v) {
                    continue;
                }
                // A panic is handed to the calling thread, which ends the run; the solving
                // thread goes on to the barrier so that nobody waits for it.
                let result = catch_unwind(AssertUnwindSafe(|| {
                    work.tent(&mut Lease::kept(&**state), scratch, v, &events)
                        .map(|(_, o)| o)
                }))
                .map_err(panic_message);
                *r.results[i].lock() = Some(result);
                per_thread[id].fetch_add(1, Ordering::Relaxed);
            }
        }
        wait(&barrier);
    };
    let settle = |id: usize| {
        {
            let r = round.read();
            let state = state.read();
            let mut found = found[id].lock();
            loop {
                let c = r.next_chunk.fetch_add(1, Ordering::Relaxed);
                let start = c * CHUNK;
                if start >= r.chosen.len() {
                    break;
                }
                let begun = Instant::now();
                let end = (start + CHUNK).min(r.chosen.len());
                for (i, &v) in r.chosen.iter().enumerate().take(end).skip(start) {
                    let mut slot = r.results[i].lock();
                    // A panic is the calling thread's to report when it records.
                    let panicked = match slot.as_mut() {
                        Some(Ok(Ok(outcome))) => catch_unwind(AssertUnwindSafe(|| {
                            work.settle(&**state, v, outcome);
                        }))
                        .err(),
                        _ => None,
                    };
                    if let Some(payload) = panicked {
                        *slot = Some(Err(panic_message(payload)));
                    }
                }
                let mesh = state.mesh();
                found.extend(
                    (r.chosen[start..end].iter())
                        .flat_map(|&v| {
                            std::iter::once(v).chain(mesh.vertex_neighbors(v).iter().copied())
                        })
                        .filter(|&v| is_first_among_neighbours(&**state, t_end, v))
                        .map(|v| (state.front().time(v), v)),
                );
                work.settled(begun.elapsed());
            }
        }
        wait(&barrier);
    };
    // Solves chosen tents of the round until none is left and waits for the others (and, split
    // over processes, for the calling thread's exchange), then settles chunks of them until
    // none is left and waits again.
    let share = |id: usize, scratch: &mut W::Scratch| {
        solve(id, scratch);
        if split {
            wait(&barrier);
        }
        settle(id);
    };
    let mut scratch = scratch.into_iter();
    let mut own = scratch.next().expect("at least one thread");
    let outcome = std::thread::scope(|s| {
        for (id, mut scratch) in scratch.enumerate() {
            let (barrier, done, wait, share) = (&barrier, &done, &wait, &share);
            s.spawn(move || {
                loop {
                    wait(barrier);
                    if done.load(Ordering::Acquire) {
                        return;
                    }
                    share(id + 1, &mut scratch);
                }
            });
        }
        // A panic here leaves the workers at the round's first barrier, as an error does.
        let result = catch_unwind(AssertUnwindSafe(|| {
            loop {
                let choosing = Instant::now();
                let guard = state.read();
                let s: &W::State = &guard;
                let mut r = round.write();
                ready.clear();
                for found in &found {
                    let mut found = found.lock();
                    if !scan_all {
                        ready.extend_from_slice(&found);
                    }
                    found.clear();
                }
                if after_events {
                    // Found before the events: ids and readiness as they were; offered: ids
                    // as after the event that offered them. Each is checked again now.
                    offered.extend(ready.drain(..).map(|(_, v)| v));
                    offered.sort_unstable();
                    offered.dedup();
                    ready.extend(
                        (offered.drain(..))
                            .filter(|&v| (v as usize) < n && is_first_among_neighbours(s, t_end, v))
                            .map(|v| (s.front().time(v), v)),
                    );
                    after_events = false;
                }
                if scan_all {
                    ready.extend(
                        (0..n as VertexId)
                            .filter(|&v| is_first_among_neighbours(s, t_end, v))
                            .map(|v| (s.front().time(v), v)),
                    );
                    scan_all = false;
                }
                if ready.is_empty() {
                    let remaining = below_end(s, t_end);
                    return if remaining == 0 {
                        Ok(false)
                    } else {
                        Err(RunError::Stalled { remaining })
                    };
                }
                if work.pause() {
                    return Ok(true);
                }
                ready.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                ready.dedup_by_key(|&mut (_, v)| v);
                // Every ready vertex is chosen; none is a neighbour of another.
                r.chosen.clear();
                r.chosen.extend(ready.iter().map(|&(_, v)| v));
                let len = r.chosen.len();
                r.results.resize_with(len, || Mutex::new(None));
                r.next.store(0, Ordering::Relaxed);
                r.next_chunk.store(0, Ordering::Relaxed);
                // The round-setup locks are released before the workers start.
                drop(r);
                drop(guard);
                let mut serial = choosing.elapsed();
                wait(&barrier);
                solve(0, &mut own);
                let mut exchanged = Ok(());
                if split {
                    // The workers wait at the barrier meanwhile.
                    let mut r = round.write();
                    let mut results: Vec<_> = (r.results.iter_mut())
                        .map(|slot| slot.get_mut().take())
                        .collect();
                    let guard = state.read();
                    exchanged = work.exchange(&**guard, &r.chosen, &mut results);
                    for (slot, result) in r.results.iter_mut().zip(results) {
                        *slot.get_mut() = result;
                    }
                    drop((r, guard));
                    wait(&barrier);
                }
                settle(0);
                exchanged.map_err(RunError::Work)?;
                let recording = Instant::now();
                let mut r = round.write();
                let chosen = std::mem::take(&mut r.chosen);
                {
                    // Every tent of the round has run: all are recorded, in order, even after
                    // a failure, so that what the work books matches the state; the first
                    // failure is returned.
                    let guard = state.read();
                    let mut failure = None;
                    for (i, &v) in chosen.iter().enumerate() {
                        let result = r.results[i].lock().take().expect("every chosen tent ran");
                        let recorded = result
                            .map_err(RunError::Panic)
                            .and_then(|tent| tent.map_err(RunError::Work))
                            .and_then(|outcome| {
                                work.record(&**guard, v, outcome, &events)
                                    .map_err(RunError::Work)
                            });
                        if let Err(e) = recorded {
                            failure.get_or_insert(e);
                        }
                    }
                    if let Some(e) = failure {
                        return Err(e);
                    }
                }
                stats.tents += chosen.len() as u64;
                r.chosen = chosen;
                stats.rounds += 1;
                drop(r);
                serial += recording.elapsed();
                let mut guard = state.write();
                let running = Instant::now();
                for event in events.take() {
                    let changed = event.run_alone(&mut **guard, &events);
                    offered.extend(changed.offer);
                    stats.events += 1;
                    after_events = true;
                }
                event_time.add_since(running);
                n = guard.mesh().vertices().len();
                work.round(serial);
            }
        }))
        .unwrap_or_else(|payload| Err(RunError::Panic(panic_message(payload))));
        done.store(true, Ordering::Release);
        barrier.wait();
        result
    });
    for (count, total) in per_thread.iter().zip(&mut stats.tents_per_thread) {
        *total = count.load(Ordering::Relaxed) as u64;
    }
    outcome.map(|paused| Stats {
        paused,
        event_time: event_time.total(),
        wait_time: wait_time.total(),
        ..stats
    })
}
