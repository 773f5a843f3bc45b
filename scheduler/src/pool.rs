//! Asynchronous mode: workers claim ready vertices from work-stealing deques.
//!
//! Candidates (vertices that may be ready) sit in per-worker FIFO deques and a global injector.
//! A worker pops or steals one, checks that it is ready (optimistically, then again once
//! claimed), runs the tent, records it, releases the claim and pushes the vertex and its
//! neighbours back as candidates. A candidate that is not ready or cannot be claimed is dropped:
//! whatever blocks it (an earlier neighbour, or a claim around it) pushes it again when it
//! changes. Workers with nothing to do sleep on a condition variable. See `scheduler/README.md`.

use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicUsize, Ordering};

use crossbeam_deque::{Injector, Steal, Stealer, Worker};
use parking_lot::{Condvar, Mutex};
use sdg_mesh::{Front, Mesh};

use crate::claim::ClaimTable;
use crate::{Events, RunError, Stats, VertexId, Work, is_ready, region_and_halo};

/// State shared by the workers of one run.
struct Shared<'s, 'a, W: Work<'a>> {
    mesh: &'s Mesh,
    front: &'s Front,
    t_end: f64,
    work: &'a W,
    claims: ClaimTable,
    /// Per vertex: pending events whose region or halo contains it. No tent starts there.
    reserved: Vec<AtomicU32>,
    injector: Injector<VertexId>,
    stealers: Vec<Stealer<VertexId>>,
    /// Candidates pushed and not yet taken (an upper bound of what the deques hold).
    queued: AtomicUsize,
    /// Vertices below the end time.
    remaining: AtomicUsize,
    stop: AtomicBool,
    error: Mutex<Option<W::Error>>,
    sleep: Mutex<usize>,
    wake: Condvar,
    events: Events<'a>,
    /// Events whose regions are reserved, waiting for their claims.
    reserved_events: Mutex<Vec<Reserved<'a>>>,
    events_run: AtomicU64,
    tents: Vec<AtomicU64>,
}

pub(crate) fn run<'a, W: Work<'a>>(
    mesh: &Mesh,
    front: &Front,
    t_end: f64,
    work: &'a W,
    scratch: Vec<W::Scratch>,
) -> Result<Stats, RunError<W::Error>> {
    let n = mesh.vertices().len();
    let threads = scratch.len();
    let workers: Vec<Worker<VertexId>> = (0..threads).map(|_| Worker::new_fifo()).collect();
    let shared = Shared {
        mesh,
        front,
        t_end,
        work,
        claims: ClaimTable::new(n),
        reserved: (0..n).map(|_| AtomicU32::new(0)).collect(),
        injector: Injector::new(),
        stealers: workers.iter().map(Worker::stealer).collect(),
        queued: AtomicUsize::new(0),
        remaining: AtomicUsize::new(
            (0..n as VertexId)
                .filter(|&v| front.time(v) < t_end)
                .count(),
        ),
        stop: AtomicBool::new(false),
        error: Mutex::new(None),
        sleep: Mutex::new(0),
        wake: Condvar::new(),
        events: Events::default(),
        reserved_events: Mutex::new(Vec::new()),
        events_run: AtomicU64::new(0),
        tents: (0..threads).map(|_| AtomicU64::new(0)).collect(),
    };
    for v in 0..n as VertexId {
        if is_ready(mesh, front, t_end, v) {
            shared.queued.fetch_add(1, Ordering::SeqCst);
            shared.injector.push(v);
        }
    }
    std::thread::scope(|s| {
        for (id, (local, scratch)) in workers.into_iter().zip(scratch).enumerate() {
            let shared = &shared;
            s.spawn(move || worker(shared, id, &local, scratch));
        }
    });
    if let Some(e) = shared.error.into_inner() {
        return Err(RunError::Work(e));
    }
    // Events queued by the last tents, which the workers may have left when the front reached
    // the end: no tent is in flight any more, so they run here in queue order.
    let leftover = std::mem::take(&mut *shared.reserved_events.lock());
    for event in leftover {
        (event.action)();
        shared.events_run.fetch_add(1, Ordering::Relaxed);
    }
    for event in std::mem::take(&mut *shared.events.queue.lock()) {
        (event.action)();
        shared.events_run.fetch_add(1, Ordering::Relaxed);
    }
    let remaining = shared.remaining.load(Ordering::SeqCst);
    if remaining > 0 {
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
        run_events(shared, local);
        match find(shared, id, local) {
            Some(v) => {
                shared.queued.fetch_sub(1, Ordering::SeqCst);
                tent(shared, id, local, &mut scratch, v);
            }
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

/// Sleeps until a candidate is queued, an event is pending, or the run ends.
fn sleep<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>) {
    let mut sleeping = shared.sleep.lock();
    if shared.queued.load(Ordering::SeqCst) > 0
        || shared.stop.load(Ordering::SeqCst)
        || shared.remaining.load(Ordering::SeqCst) == 0
    {
        return;
    }
    *sleeping += 1;
    shared.wake.wait(&mut sleeping);
    *sleeping -= 1;
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
    let (mesh, front) = (shared.mesh, shared.front);
    if shared.reserved[v as usize].load(Ordering::Acquire) > 0
        || !is_ready(mesh, front, shared.t_end, v)
    {
        return;
    }
    let neighbours = mesh.vertex_neighbors(v);
    if !shared.claims.try_claim(&[v], neighbours) {
        return;
    }
    // Claimed: the times of v and its neighbours cannot change until the release.
    let result = if is_ready(mesh, front, shared.t_end, v) {
        Some(
            shared
                .work
                .tent(scratch, v, &shared.events)
                .and_then(|(t, outcome)| {
                    shared.work.record(v, outcome, &shared.events).map(|()| t)
                }),
        )
    } else {
        None
    };
    shared.claims.release(&[v], neighbours);
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
    if shared.events.pending.load(Ordering::Acquire) > 0 {
        wake_all(shared);
    }
}

/// An event whose region and halo are reserved: no tent starts there until it has run.
struct Reserved<'a> {
    owned: Vec<VertexId>,
    halo: Vec<VertexId>,
    action: Box<dyn FnOnce() + Send + 'a>,
}

/// Reserves the regions of newly queued events, then runs every reserved event whose region and
/// halo can be claimed, and offers their vertices as candidates afterwards.
fn run_events<'a, W: Work<'a>>(shared: &Shared<'_, 'a, W>, local: &Worker<VertexId>) {
    if shared.events.pending.load(Ordering::Acquire) == 0 {
        return;
    }
    let mut reserved = shared.reserved_events.lock();
    for event in std::mem::take(&mut *shared.events.queue.lock()) {
        let (owned, halo) = region_and_halo(shared.mesh, &event.region);
        for &v in owned.iter().chain(&halo) {
            shared.reserved[v as usize].fetch_add(1, Ordering::AcqRel);
        }
        reserved.push(Reserved {
            owned,
            halo,
            action: event.action,
        });
    }
    let mut i = 0;
    while i < reserved.len() {
        if !shared
            .claims
            .try_claim(&reserved[i].owned, &reserved[i].halo)
        {
            i += 1;
            continue;
        }
        let event = reserved.swap_remove(i);
        drop(reserved);
        (event.action)();
        shared.claims.release(&event.owned, &event.halo);
        for &v in event.owned.iter().chain(&event.halo) {
            shared.reserved[v as usize].fetch_sub(1, Ordering::AcqRel);
            offer(shared, local, v);
        }
        shared.events_run.fetch_add(1, Ordering::Relaxed);
        shared.events.pending.fetch_sub(1, Ordering::AcqRel);
        reserved = shared.reserved_events.lock();
    }
}
