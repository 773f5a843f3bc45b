//! Asynchronous mode: workers claim ready vertices from work-stealing deques.
//!
//! Candidates (vertices that may be ready) sit in per-worker FIFO deques and a global injector.
//! A worker pops or steals one, checks that it is ready (optimistically, then again once
//! claimed), runs the tent, records it, releases the claim and pushes the vertex and its
//! neighbours back as candidates. A candidate that is not ready or cannot be claimed is dropped:
//! whatever blocks it (an earlier neighbour, or a claim around it) pushes it again when it
//! changes. Workers with nothing to do sleep on a condition variable. Tents hold the state
//! shared (a read lock) and let go of it while they solve ([`Lease::unlocked`]); events run in
//! batches that take it exclusively. A regional event runs beside the tents that are solving
//! once none of them holds a vertex it changes, and waits otherwise; an exclusive one waits until
//! no tent is in flight, and no tent starts meanwhile. A tent that leaves its vertex in place
//! keeps its claim until the next batch of events. See `scheduler/README.md`.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

use crossbeam_deque::{Injector, Steal, Stealer, Worker};
use parking_lot::{Condvar, Mutex, RwLock, RwLockReadGuard};

use crate::claim::ClaimTable;
use crate::{
    Clock, Events, Lease, Queued, Region, Relock, RunError, State, Stats, VertexId, Work,
    below_end, is_first_among_neighbours, panic_message,
};

/// Queued events that make a worker run them before its next tent; fewer wait until a worker
/// finds nothing to claim. A batch holds the state's lock exclusively, which tents need to start
/// and to store their patches, so batching them saves waits: on `adaptive_pulse` (about 1,000
/// events, 2 threads) the workers waited 0.36 s in all when every event ran at once, 0.06 to
/// 0.07 s with 32 (measured when every batch also waited for the tents in flight).
const EVENT_BATCH: usize = 32;

/// The state and the claims on its vertices: shared by tents, exclusive for events.
struct Locked<'s, S> {
    state: &'s mut S,
    claims: ClaimTable,
}

impl<S> Relock<S> for RwLockReadGuard<'_, Locked<'_, S>> {
    fn state(&self) -> &S {
        self.state
    }

    fn unlocked(&mut self, f: &mut dyn FnMut()) {
        RwLockReadGuard::unlocked(self, f);
    }
}

/// State shared by the workers of one run.
struct Shared<'s, 'a, W: Work<'a>> {
    locked: RwLock<Locked<'s, W::State>>,
    t_end: f64,
    work: &'a W,
    injector: Injector<VertexId>,
    stealers: Vec<Stealer<VertexId>>,
    /// Candidates pushed and not yet taken (an upper bound of what the deques hold).
    queued: AtomicUsize,
    /// Vertices below the end time.
    remaining: AtomicUsize,
    stop: AtomicBool,
    /// A worker saw [`Work::pause`]: the others stop too, and the run returns paused.
    paused: AtomicBool,
    error: Mutex<Option<W::Error>>,
    /// The message of the first panic of a worker.
    panic: Mutex<Option<String>>,
    sleep: Mutex<usize>,
    wake: Condvar,
    events: Events<'a, W::State>,
    events_run: AtomicU64,
    tents: Vec<AtomicU64>,
    event_time: Clock,
    wait_time: Clock,
    /// Claims of tents that left their vertex in place, held until their events have run.
    held: Mutex<Vec<(VertexId, Vec<VertexId>)>>,
    /// Tents claimed and not yet released; changed only with the state's lock held, so that
    /// with it held exclusively this counts the tents solving without it.
    in_flight: AtomicUsize,
    /// Tents released so far.
    releases: AtomicU64,
    /// Regional events the last batch put back because tents in flight held their vertices,
    /// and [`Shared::releases`] then: they are worth another try once a tent is released.
    refused: AtomicUsize,
    refused_at: AtomicU64,
}

impl<'a, W: Work<'a>> Shared<'_, 'a, W> {
    /// True when a batch of events would run something: an event not put back by the last
    /// batch is queued, or a tent was released since.
    fn events_runnable(&self) -> bool {
        self.events.pending.load(Ordering::SeqCst) > self.refused.load(Ordering::SeqCst)
            || self.releases.load(Ordering::SeqCst) != self.refused_at.load(Ordering::SeqCst)
    }

    /// Events queued since the last batch.
    fn fresh_events(&self) -> usize {
        let pending = self.events.pending.load(Ordering::Acquire);
        pending.saturating_sub(self.refused.load(Ordering::Acquire))
    }
}

pub(crate) fn run<'a, W: Work<'a>>(
    state: &mut W::State,
    t_end: f64,
    work: &'a W,
    scratch: Vec<W::Scratch>,
) -> Result<Stats, RunError<W::Error>> {
    let n = state.mesh().vertices().len();
    let threads = scratch.len();
    let workers: Vec<Worker<VertexId>> = (0..threads).map(|_| Worker::new_fifo()).collect();
    let ready: Vec<VertexId> = (0..n as VertexId)
        .filter(|&v| is_first_among_neighbours(&*state, t_end, v))
        .collect();
    let shared = Shared {
        remaining: AtomicUsize::new(below_end(&*state, t_end)),
        locked: RwLock::new(Locked {
            state,
            claims: ClaimTable::new(n),
        }),
        t_end,
        work,
        injector: Injector::new(),
        stealers: workers.iter().map(Worker::stealer).collect(),
        queued: AtomicUsize::new(0),
        stop: AtomicBool::new(false),
        paused: AtomicBool::new(false),
        error: Mutex::new(None),
        panic: Mutex::new(None),
        sleep: Mutex::new(0),
        wake: Condvar::new(),
        events: Events::default(),
        events_run: AtomicU64::new(0),
        tents: (0..threads).map(|_| AtomicU64::new(0)).collect(),
        event_time: Clock::default(),
        wait_time: Clock::default(),
        held: Mutex::new(Vec::new()),
        in_flight: AtomicUsize::new(0),
        releases: AtomicU64::new(0),
        refused: AtomicUsize::new(0),
        refused_at: AtomicU64::new(0),
    };
    for v in ready {
        shared.queued.fetch_add(1, Ordering::SeqCst);
        shared.injector.push(v);
    }
    std::thread::scope(|s| {
        for (id, (local, scratch)) in workers.into_iter().zip(scratch).enumerate() {
            let shared = &shared;
            s.spawn(move || {
                // A panicking worker stops the others (its locks are released as it unwinds).
                if let Err(payload) =
                    catch_unwind(AssertUnwindSafe(|| worker(shared, id, &local, scratch)))
                {
                    shared.panic.lock().get_or_insert(panic_message(payload));
                    shared.stop.store(true, Ordering::Release);
                    wake_all(shared);
                }
            });
        }
    });
    if let Some(message) = shared.panic.into_inner() {
        return Err(RunError::Panic(message));
    }
    if let Some(e) = shared.error.into_inner() {
        return Err(RunError::Work(e));
    }
    // Events queued by the last tents, which the workers may have left when the front reached
    // the end: no tent is in flight any more, so they run here in queue order.
    let locked = shared.locked.into_inner();
    let draining = std::time::Instant::now();
    for event in shared.events.take() {
        let changed = catch_unwind(AssertUnwindSafe(|| {
            event.run_alone(locked.state, &shared.events)
        }))
        .map_err(|payload| RunError::Panic(panic_message(payload)))?;
        count_remaining(&shared.remaining, changed.below_end);
        shared.events_run.fetch_add(1, Ordering::Relaxed);
    }
    shared.event_time.add_since(draining);
    let remaining = shared.remaining.load(Ordering::SeqCst);
    let paused = shared.paused.load(Ordering::SeqCst);
    if remaining > 0 && !paused {
        return Err(RunError::Stalled { remaining });
    }
    let tents_per_thread: Vec<u64> = shared
        .tents
        .iter()
        .map(|t| t.load(Ordering::Relaxed))
        .collect();
    Ok(Stats {
        tents: tents_per_thread.iter().sum(),
        tents_per_thread,
        rounds: 0,
        events: shared.events_run.load(Ordering::Relaxed),
        paused: paused && remaining > 0,
        event_time: shared.event_time.total(),
        wait_time: shared.wait_time.total(),
    })
}

fn worker<'a, W: Work<'a>>(
    shared: &Shared<'_, 'a, W>,
    id: usize,
    local: &Worker<VertexId>,
    mut scratch: W::Scratch,
) {
    loop {
        if shared.stop.load(Ordering::Acquire) || shared.remaining.load(Ordering::Acquire) == 0 {
            return;
        }
        if shared.work.pause() {
            shared.paused.store(true, Ordering::SeqCst);
            shared.stop.store(true, Ordering::Release);
            wake_all(shared);
            return;
        }
        if shared.events.has_exclusive() {
            // No tent starts until the exclusive events have run; the last tent in flight
            // wakes the workers.
            if shared.in_flight.load(Ordering::SeqCst) == 0 {
                run_events(shared, local);
            } else {
                drain(shared);
            }
            continue;
        }
        if shared.events.is_urgent() || shared.fresh_events() >= EVENT_BATCH {
            run_events(shared, local);
        }
        match find(shared, id, local) {
            Some(v) => {
                shared.queued.fetch_sub(1, Ordering::SeqCst);
                tent(shared, id, local, &mut scratch, v);
            }
            // Nothing to claim: whatever held claims block is waiting for the queued events.
            None if shared.events_runnable() => run_events(shared, local),
            None => sleep(shared),
        }
    }
}

/// The next candidate: own deque first, then the injector, then other workers' deques.
fn find<'a, W: Work<'a>>(
    shared: &Shared<'_, 'a, W>,
    id: usize,
    local: &Worker<VertexId>,
) -> Option<VertexId> {
    local.pop().or_else(|| {
        std::iter::repeat_with(|| {
            shared.injector.steal_batch_and_pop(local).or_else(|| {
                shared
                    .stealers
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != id)
                    .map(|(_, s)| s.steal())
                    .collect()
            })
        })
        .find(|s| !s.is_retry())
        .and_then(Steal::success)
    })
}

/// Pushes `v` as a candidate and wakes a sleeping worker.
fn offer<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>, local: &Worker<VertexId>, v: VertexId) {
    shared.queued.fetch_add(1, Ordering::SeqCst);
    local.push(v);
    let sleeping = shared.sleep.lock();
    if *sleeping > 0 {
        shared.wake.notify_one();
    }
}

/// Sleeps until a candidate is queued, an event could run, or the run ends.
fn sleep<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>) {
    wait_unless(shared, || {
        shared.queued.load(Ordering::SeqCst) > 0 || shared.events_runnable()
    });
}

/// Sleeps until no tent is in flight while an exclusive event waits, or the run ends.
fn drain<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>) {
    wait_unless(shared, || {
        !shared.events.has_exclusive() || shared.in_flight.load(Ordering::SeqCst) == 0
    });
}

/// Sleeps until woken, unless `awake` or the run's end holds when checked with the sleep mutex
/// held (whoever makes `awake` true notifies under the same mutex: no lost wake-up).
fn wait_unless<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>, awake: impl Fn() -> bool) {
    let mut sleeping = shared.sleep.lock();
    if awake() || shared.stop.load(Ordering::SeqCst) || shared.remaining.load(Ordering::SeqCst) == 0
    {
        return;
    }
    *sleeping += 1;
    let asleep = std::time::Instant::now();
    shared.wake.wait(&mut sleeping);
    shared.wait_time.add_since(asleep);
    *sleeping -= 1;
}

/// Counts a tent released, with the state's lock still held; the last tent in flight wakes the
/// workers waiting for exclusive events.
fn finish<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>) {
    shared.releases.fetch_add(1, Ordering::SeqCst);
    if shared.in_flight.fetch_sub(1, Ordering::SeqCst) == 1 && shared.events.has_exclusive() {
        wake_all(shared);
    }
}

/// Wakes every worker (the run ends or an event needs attention).
fn wake_all<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>) {
    let _guard = shared.sleep.lock();
    shared.wake.notify_all();
}

/// Claims `v` if it is ready and free, runs and records its tent, releases, and offers the
/// vertices whose readiness may have changed.
fn tent<'a, W: Work<'a>>(
    shared: &Shared<'_, 'a, W>,
    id: usize,
    local: &Worker<VertexId>,
    scratch: &mut W::Scratch,
    v: VertexId,
) {
    let asked = std::time::Instant::now();
    let mut locked = shared.locked.read();
    shared.wait_time.add_since(asked);
    {
        let state = &*locked.state;
        if !is_first_among_neighbours(state, shared.t_end, v)
            || !(locked.claims).try_claim(&[v], state.mesh().vertex_neighbors(v))
        {
            return;
        }
    }
    shared.in_flight.fetch_add(1, Ordering::SeqCst);
    let t_old = locked.state.front().time(v);
    // Claimed: the times of v and its neighbours cannot change until the release, nor can any
    // event change their stars or ids while the tent solves without the lock.
    let result = if is_first_among_neighbours(&*locked.state, shared.t_end, v) {
        let mut lease = Lease::lock(&mut locked);
        let work = shared.work;
        Some(
            work.tent(&mut lease, scratch, v, &shared.events)
                .and_then(|(t, mut outcome)| {
                    work.settle(lease.state(), v, &mut outcome);
                    work.record(lease.state(), v, outcome, &shared.events)
                        .map(|()| t)
                }),
        )
    } else {
        None
    };
    let neighbours = locked.state.mesh().vertex_neighbors(v);
    let in_place = matches!(result, Some(Ok(t)) if t <= t_old);
    if in_place && shared.events.pending.load(Ordering::Acquire) > 0 {
        // Left in place: its event is queued. Keep the star as the tent saw it until the
        // events run, and leave `v` out of the candidates meanwhile.
        shared.held.lock().push((v, neighbours.to_vec()));
        shared.tents[id].fetch_add(1, Ordering::Relaxed);
        finish(shared);
        return;
    }
    locked.claims.release(&[v], neighbours);
    finish(shared);
    match result {
        Some(Ok(t)) => {
            shared.tents[id].fetch_add(1, Ordering::Relaxed);
            if t >= shared.t_end && shared.remaining.fetch_sub(1, Ordering::AcqRel) == 1 {
                wake_all(shared);
            }
        }
        Some(Err(e)) => {
            shared.error.lock().get_or_insert(e);
            shared.stop.store(true, Ordering::Release);
            wake_all(shared);
            return;
        }
        None => {}
    }
    offer(shared, local, v);
    for &w in neighbours {
        offer(shared, local, w);
    }
    drop(locked);
}

/// Adds `delta` to the count of vertices below the end time.
fn count_remaining(remaining: &AtomicUsize, delta: isize) {
    if delta >= 0 {
        remaining.fetch_add(delta as usize, Ordering::SeqCst);
    } else {
        remaining.fetch_sub(delta.unsigned_abs(), Ordering::SeqCst);
    }
}

/// Runs queued events with the state held exclusively while the tents in flight solve without
/// it: first releases the held claims (before any event renumbers vertices), then runs the
/// events in queue order: an exclusive one only when no tent is in flight, a regional one when
/// no tent in flight holds a vertex its probe lists. The others are put back, ahead of later
/// ones. Offers the held vertices, their neighbours and whatever the events touched or appended.
fn run_events<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>, local: &Worker<VertexId>) {
    if shared.events.pending.load(Ordering::Acquire) == 0 {
        return;
    }
    let asked = std::time::Instant::now();
    let mut locked = shared.locked.write();
    shared.wait_time.add_since(asked);
    let events = shared.events.take();
    if events.is_empty() {
        return;
    }
    let running = std::time::Instant::now();
    let Locked { state, claims } = &mut *locked;
    let mut touched = Vec::new();
    let mut released = Vec::new();
    for (v, neighbours) in shared.held.lock().drain(..) {
        claims.release(&[v], &neighbours);
        released.push(v);
        touched.push(v);
        touched.extend(neighbours);
    }
    // With the lock held exclusively, the tents in flight are solving without it.
    let alone = shared.in_flight.load(Ordering::SeqCst) == 0;
    let (mut waiting, mut refused, mut waiting_region) = (Vec::new(), 0, Vec::new());
    let mut removed = false;
    for event in events {
        let vertices = state.mesh().vertices().len();
        let changed = match event {
            Queued::Exclusive(action) if alone => {
                let changed = action(state);
                shared.events.ran(true);
                changed
            }
            Queued::Regional(probe, action) => {
                let region = if alone { Vec::new() } else { probe(&**state) };
                if !region.iter().all(|&v| claims.is_free(v)) {
                    waiting_region.extend(region);
                    refused += 1;
                    waiting.push(Queued::Regional(probe, action));
                    continue;
                }
                let changed = action(
                    state,
                    &Region {
                        claims: Some(claims),
                    },
                );
                shared.events.ran(false);
                changed
            }
            event => {
                waiting.push(event);
                continue;
            }
        };
        removed |= state.mesh().vertices().len() < vertices;
        claims.grow(state.mesh().vertices().len());
        count_remaining(&shared.remaining, changed.below_end);
        touched.extend(changed.offer);
        shared.events_run.fetch_add(1, Ordering::Relaxed);
    }
    // A held vertex that an event put back will change keeps its claim, so that it is not
    // pitched again meanwhile (only while no event removed a vertex, which renumbers).
    if !removed && !waiting_region.is_empty() {
        waiting_region.sort_unstable();
        let mut held = shared.held.lock();
        for v in released {
            if waiting_region.binary_search(&v).is_ok()
                && (v as usize) < state.mesh().vertices().len()
            {
                let neighbours = state.mesh().vertex_neighbors(v);
                if claims.try_claim(&[v], neighbours) {
                    held.push((v, neighbours.to_vec()));
                }
            }
        }
    }
    shared.events.put_back(waiting);
    shared.refused.store(refused, Ordering::SeqCst);
    (shared.refused_at).store(shared.releases.load(Ordering::SeqCst), Ordering::SeqCst);
    let end_reached = shared.remaining.load(Ordering::SeqCst) == 0;
    drop(locked);
    shared.event_time.add_since(running);
    if end_reached {
        wake_all(shared);
    }
    for v in touched {
        offer(shared, local, v);
    }
}
