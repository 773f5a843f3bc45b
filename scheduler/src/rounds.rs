//! Deterministic mode: rounds of an independent set of ready vertices.
//!
//! Each round finds the ready vertices (local minima below the end time; after the first round
//! only those whose neighbourhood the last round or its events changed are examined), sorts them by
//! `(time, id)` and greedily takes every vertex none of whose neighbours is taken. The taken
//! tents do not read each other's data (they are not neighbours), so solving them in parallel in
//! any order gives the same bits; their outcomes are recorded in the round's order, and queued
//! events then run in the order they were queued, with the state held exclusively. The result
//! depends only on the inputs.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Barrier;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use parking_lot::{Mutex, RwLock};

use crate::{
    Clock, Events, Lease, RunError, State, Stats, VertexId, Work, below_end, is_ready,
    panic_message,
};

/// What a worker's tent gave: its outcome or error, or the message of its panic.
type Tried<O, E> = Result<Result<O, E>, String>;

/// Shared state of one round.
struct Round<O, E> {
    chosen: Vec<VertexId>,
    next: AtomicUsize,
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
        results: Vec::new(),
    });
    // The calling thread chooses and records the rounds and solves its share of each: with
    // `threads` threads in all, a run never has more threads than workers.
    let barrier = Barrier::new(threads);
    let done = AtomicBool::new(false);
    let mut stats = Stats {
        tents_per_thread: vec![0; threads],
        ..Stats::default()
    };
    let per_thread: Vec<AtomicUsize> = (0..threads).map(|_| AtomicUsize::new(0)).collect();
    let (event_time, wait_time) = (Clock::default(), Clock::default());
    // The ready vertices with their times. A round takes every ready vertex (it is chosen or
    // beside a chosen one) and changes the front only at its chosen vertices, so the next
    // round's ready vertices are among the taken ones (listed in `touched`). After events
    // (which may renumber vertices) the whole front is scanned again.
    let mut ready: Vec<(f64, VertexId)> = Vec::with_capacity(n);
    let mut taken = vec![false; n];
    let mut touched: Vec<VertexId> = Vec::with_capacity(n);
    let mut scan_all = true;
    // Solves chosen tents of the round until none is left, then waits at the round's end.
    let share = |id: usize, scratch: &mut W::Scratch| {
        {
            let r = round.read();
            let state = state.read();
            let chosen = &r.chosen;
            loop {
                let i = r.next.fetch_add(1, Ordering::Relaxed);
                let Some(&v) = chosen.get(i) else { break };
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
        let idle = std::time::Instant::now();
        barrier.wait();
        wait_time.add_since(idle);
    };
    let mut scratch = scratch.into_iter();
    let mut own = scratch.next().expect("at least one thread");
    let outcome = std::thread::scope(|s| {
        for (id, mut scratch) in scratch.enumerate() {
            let (barrier, done, wait_time, share) = (&barrier, &done, &wait_time, &share);
            s.spawn(move || {
                loop {
                    let idle = std::time::Instant::now();
                    barrier.wait();
                    wait_time.add_since(idle);
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
                let choosing = std::time::Instant::now();
                let guard = state.read();
                let s: &W::State = &guard;
                if scan_all {
                    touched.clear();
                    touched.extend(0..n as VertexId);
                    scan_all = false;
                }
                ready.clear();
                ready.extend(
                    touched
                        .iter()
                        .filter(|&&v| is_ready(s, t_end, v))
                        .map(|&v| (s.front().time(v), v)),
                );
                touched.clear();
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
                {
                    let mut r = round.write();
                    r.chosen.clear();
                    taken.fill(false);
                    for &(_, v) in &ready {
                        if !taken[v as usize] {
                            r.chosen.push(v);
                            taken[v as usize] = true;
                            touched.push(v);
                            for &w in s.mesh().vertex_neighbors(v) {
                                if !taken[w as usize] {
                                    taken[w as usize] = true;
                                    touched.push(w);
                                }
                            }
                        }
                    }
                    let len = r.chosen.len();
                    r.results.resize_with(len, || Mutex::new(None));
                    r.next.store(0, Ordering::Relaxed);
                }
                // The round-setup lock is released before the workers start.
                drop(guard);
                let mut serial = choosing.elapsed();
                barrier.wait();
                share(0, &mut own);
                let recording = std::time::Instant::now();
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
                let running = std::time::Instant::now();
                for event in events.take() {
                    event.run_alone(&mut **guard, &events);
                    stats.events += 1;
                    scan_all = true;
                }
                event_time.add_since(running);
                n = guard.mesh().vertices().len();
                taken.resize(n, false);
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
