//! The scheduler under load: no two tents in flight are neighbours, every tent is causal,
//! exclusive events run with no tent in flight, regional ones beside tents that hold none of their
//! vertices, and single-thread runs finish in both modes.

#![cfg(not(feature = "loom"))]

use std::marker::PhantomData;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use parking_lot::Mutex;
use sdg_mesh::{Diagonal, Front, Mesh, Pitcher, Point, Rectangle};
use sdg_scheduler::{Changed, Events, Fixed, Lease, Options, Region, RunError, VertexId, Work};

const C: f64 = 1.0;
const SAFETY: f64 = 0.9;

fn perturbed(n: u32) -> Mesh {
    Rectangle {
        width: 1.0,
        height: 1.0,
        nx: n,
        ny: n,
        diagonal: Diagonal::Alternate,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.2,
        seed: 11,
    }
    .build()
    .unwrap()
}

/// Pitches tents and checks the claim contract from inside each tent; every `event_every`-th
/// record queues a smoothing event that moves the recorded vertex: exclusive, or with `regional`
/// a regional event, while tents solve without the state's lock.
struct Checked<'m> {
    mesh: PhantomData<&'m Mesh>,
    pitcher: Pitcher,
    in_flight: Vec<AtomicBool>,
    /// Vertices a running event moves.
    in_event: Vec<AtomicBool>,
    /// Vertex positions that events move (a mutable copy of the mesh geometry).
    positions: Vec<Mutex<Point>>,
    records: AtomicUsize,
    event_every: usize,
    regional: bool,
    events_run: AtomicU64,
    /// Regional events that ran while some tent was in flight.
    overlapped: AtomicU64,
    max_slope: Mutex<f64>,
    /// [`Work::pause`] answers true once this many tents are recorded (until the next run).
    pause_after: AtomicUsize,
}

impl Checked<'_> {
    fn new(mesh: &Mesh, t_end: f64, event_every: usize) -> Self {
        let n = mesh.vertices().len();
        Self {
            mesh: PhantomData,
            pitcher: Pitcher::new(mesh, C, SAFETY, t_end).unwrap(),
            in_flight: (0..n).map(|_| AtomicBool::new(false)).collect(),
            in_event: (0..n).map(|_| AtomicBool::new(false)).collect(),
            positions: mesh.vertices().iter().map(|&p| Mutex::new(p)).collect(),
            records: AtomicUsize::new(0),
            event_every,
            regional: false,
            events_run: AtomicU64::new(0),
            overlapped: AtomicU64::new(0),
            max_slope: Mutex::new(0.0),
            pause_after: AtomicUsize::new(usize::MAX),
        }
    }

    /// Moves `v` a little towards the mean of its neighbours: the test event. No tent may be in
    /// flight at `v` or a neighbour of it (whose stars it changes), and with an exclusive event
    /// none at all.
    fn smooth(&self, mesh: &Mesh, v: VertexId) {
        let star: Vec<VertexId> = [v]
            .into_iter()
            .chain(mesh.vertex_neighbors(v).iter().copied())
            .collect();
        for (u, flag) in self.in_flight.iter().enumerate() {
            if flag.load(Ordering::SeqCst) {
                assert!(
                    self.regional && !star.contains(&(u as VertexId)),
                    "event at {v} overlaps a tent at {u}"
                );
                self.overlapped.fetch_add(1, Ordering::Relaxed);
            }
        }
        self.in_event[v as usize].store(true, Ordering::SeqCst);
        let neighbours = mesh.vertex_neighbors(v);
        let mean = neighbours.iter().fold([0.0, 0.0], |acc, &u| {
            let p = *self.positions[u as usize].lock();
            [acc[0] + p[0], acc[1] + p[1]]
        });
        let mut p = self.positions[v as usize].lock();
        let k = neighbours.len() as f64;
        *p = [
            0.9 * p[0] + 0.1 * mean[0] / k,
            0.9 * p[1] + 0.1 * mean[1] / k,
        ];
        drop(p);
        std::thread::sleep(Duration::from_micros(50));
        self.in_event[v as usize].store(false, Ordering::SeqCst);
        self.events_run.fetch_add(1, Ordering::Relaxed);
    }
}

impl<'a, 'm> Work<'a> for Checked<'m>
where
    'm: 'a,
{
    type State = Fixed<'m>;
    type Scratch = ();
    type Outcome = ();
    type Error = String;

    fn tent(
        &self,
        lease: &mut Lease<'_, Fixed<'m>>,
        _: &mut (),
        v: VertexId,
        _: &Events<'a, Fixed<'m>>,
    ) -> Result<(f64, ()), String> {
        let Fixed { mesh, front } = *lease.state();
        if self.in_flight[v as usize].swap(true, Ordering::SeqCst) {
            return Err(format!("vertex {v} claimed twice"));
        }
        for &u in mesh.vertex_neighbors(v).iter().chain([&v]) {
            if u != v && self.in_flight[u as usize].load(Ordering::SeqCst) {
                return Err(format!("neighbours {v} and {u} in flight together"));
            }
            if self.in_event[u as usize].load(Ordering::SeqCst) {
                return Err(format!("tent at {v} overlaps an event at {u}"));
            }
        }
        // The star's positions must not move while the tent is in flight.
        let star = || {
            [v].iter()
                .chain(mesh.vertex_neighbors(v))
                .map(|&u| *self.positions[u as usize].lock())
                .collect::<Vec<Point>>()
        };
        let before = star();
        let tent = self
            .pitcher
            .pitch(mesh, front, v)
            .ok_or(format!("{v} not pitchable"))?;
        let mut slope: f64 = 0.0;
        for &t in mesh.vertex_triangles(v) {
            slope = slope.max(C * front.slope(mesh, t));
        }
        if slope >= SAFETY {
            return Err(format!("tent at {v}: slope ratio {slope}"));
        }
        lease.unlocked(|| {
            std::hint::black_box((0..200).fold(0u64, |a, i| a.wrapping_mul(31).wrapping_add(i)));
            if self.regional {
                std::thread::sleep(Duration::from_micros(20));
            }
        });
        if before != star() {
            return Err(format!("star of {v} moved during its tent"));
        }
        let mut max = self.max_slope.lock();
        *max = max.max(slope);
        drop(max);
        self.in_flight[v as usize].store(false, Ordering::SeqCst);
        Ok((tent.t_new, ()))
    }

    fn record(
        &'a self,
        _: &Fixed<'m>,
        v: VertexId,
        (): (),
        events: &Events<'a, Fixed<'m>>,
    ) -> Result<(), String> {
        let k = self.records.fetch_add(1, Ordering::Relaxed);
        let moved = Changed {
            offer: vec![v],
            below_end: 0,
        };
        if self.event_every > 0 && k.is_multiple_of(self.event_every) {
            if self.regional {
                events.push_regional(
                    Box::new(move |_: &Fixed<'m>| vec![v]),
                    Box::new(move |state: &mut Fixed<'m>, region: &Region<'_>| {
                        assert!(region.is_free(v), "a regional event at {v} ran held");
                        self.smooth(state.mesh, v);
                        moved
                    }),
                );
            } else {
                events.push(Box::new(move |state: &mut Fixed<'m>| {
                    self.smooth(state.mesh, v);
                    moved
                }));
            }
        }
        Ok(())
    }

    fn pause(&self) -> bool {
        self.records.load(Ordering::SeqCst) >= self.pause_after.load(Ordering::SeqCst)
    }
}

fn run(mesh: &Mesh, threads: usize, deterministic: bool, event_every: usize) -> (u64, u64) {
    let (tents, events, _) = run_with(mesh, threads, deterministic, event_every, false);
    (tents, events)
}

/// [`run`], with regional events when `regional`; also returns how many events overlapped a
/// tent in flight.
fn run_with(
    mesh: &Mesh,
    threads: usize,
    deterministic: bool,
    event_every: usize,
    regional: bool,
) -> (u64, u64, u64) {
    let t_end = 3.0 / 16.0;
    let front = Front::flat(mesh.vertices().len(), 0.0);
    let mut work = Checked::new(mesh, t_end, event_every);
    work.regional = regional;
    let options = Options {
        threads,
        deterministic,
    };
    let mut state = Fixed {
        mesh,
        front: &front,
    };
    let stats = sdg_scheduler::run(&mut state, t_end, &work, vec![(); threads], &options)
        .unwrap_or_else(|e| panic!("{threads} threads, deterministic {deterministic}: {e:?}"));
    assert!(
        front.snapshot().iter().all(|&t| t == t_end),
        "front ends flat at t_end"
    );
    assert_eq!(stats.tents, work.records.load(Ordering::Relaxed) as u64);
    assert_eq!(stats.tents_per_thread.len(), threads);
    assert!(*work.max_slope.lock() < SAFETY);
    assert!(work.in_flight.iter().all(|f| !f.load(Ordering::SeqCst)));
    (
        stats.tents,
        work.events_run.load(Ordering::Relaxed),
        work.overlapped.load(Ordering::Relaxed),
    )
}

/// Pauses a run after `pause_after` records, checks that it stopped quiescent, and resumes it
/// to the end; returns the tents and the final front.
fn paused_and_resumed(mesh: &Mesh, threads: usize, deterministic: bool) -> (u64, Vec<f64>) {
    let t_end = 3.0 / 16.0;
    let front = Front::flat(mesh.vertices().len(), 0.0);
    let work = Checked::new(mesh, t_end, 7);
    work.pause_after.store(300, Ordering::SeqCst);
    let options = Options {
        threads,
        deterministic,
    };
    let mut state = Fixed {
        mesh,
        front: &front,
    };
    let first = sdg_scheduler::run(&mut state, t_end, &work, vec![(); threads], &options).unwrap();
    assert!(
        first.paused,
        "{threads} threads, deterministic {deterministic}"
    );
    assert!(work.in_flight.iter().all(|f| !f.load(Ordering::SeqCst)));
    assert!(front.snapshot().iter().any(|&t| t < t_end));
    // Every queued event ran before the pause: one per 7 records.
    let records = work.records.load(Ordering::SeqCst);
    assert_eq!(
        work.events_run.load(Ordering::SeqCst) as usize,
        records.div_ceil(7)
    );
    work.pause_after.store(usize::MAX, Ordering::SeqCst);
    let rest = sdg_scheduler::run(&mut state, t_end, &work, vec![(); threads], &options).unwrap();
    assert!(!rest.paused);
    assert!(front.snapshot().iter().all(|&t| t == t_end));
    (first.tents + rest.tents, front.snapshot())
}

#[test]
fn a_paused_run_resumes_to_the_end_and_deterministic_runs_do_not_notice() {
    let mesh = perturbed(12);
    let (tents, front) = paused_and_resumed(&mesh, 2, false);
    assert!(tents > 0 && !front.is_empty());
    let uninterrupted = run(&mesh, 2, true, 7).0;
    for threads in [1, 2, 4] {
        let (tents, _) = paused_and_resumed(&mesh, threads, true);
        assert_eq!(tents, uninterrupted, "{threads} threads");
    }
}

#[test]
fn eight_threads_on_a_perturbed_mesh() {
    let mesh = perturbed(24);
    for deterministic in [false, true] {
        let (tents, _) = run(&mesh, 8, deterministic, 0);
        assert!(tents > 5000, "{tents}");
    }
}

#[test]
fn events_run_exclusively_and_move_the_mesh() {
    let mesh = perturbed(16);
    for deterministic in [false, true] {
        let (tents, events) = run(&mesh, 4, deterministic, 37);
        assert_eq!(events, tents.div_ceil(37), "every queued event ran");
    }
}

#[test]
fn regional_events_run_beside_tents_that_hold_none_of_their_vertices() {
    let mesh = perturbed(16);
    let (tents, events, overlapped) = run_with(&mesh, 4, false, 5, true);
    assert_eq!(events, tents.div_ceil(5), "every queued event ran");
    assert!(overlapped > 0, "no event ran beside a tent in flight");
    let (tents, events, overlapped) = run_with(&mesh, 4, true, 5, true);
    assert_eq!(events, tents.div_ceil(5), "every queued event ran");
    assert_eq!(
        overlapped, 0,
        "deterministic rounds run events between rounds"
    );
}

#[test]
fn single_thread_runs_finish() {
    for mesh in [perturbed(8), perturbed(20)] {
        for deterministic in [false, true] {
            let start = Instant::now();
            run(&mesh, 1, deterministic, 10);
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "took {:?}",
                start.elapsed()
            );
        }
    }
}

#[test]
fn work_errors_stop_the_run() {
    struct Failing<'m>(PhantomData<&'m ()>);
    impl<'a, 'm: 'a> Work<'a> for Failing<'m> {
        type State = Fixed<'m>;
        type Scratch = ();
        type Outcome = ();
        type Error = &'static str;
        fn tent(
            &self,
            _: &mut Lease<'_, Fixed<'m>>,
            _: &mut (),
            _: VertexId,
            _: &Events<'a, Fixed<'m>>,
        ) -> Result<(f64, ()), &'static str> {
            Err("boom")
        }
        fn record(
            &'a self,
            _: &Fixed<'m>,
            _: VertexId,
            (): (),
            _: &Events<'a, Fixed<'m>>,
        ) -> Result<(), &'static str> {
            Ok(())
        }
    }
    let mesh = perturbed(6);
    for deterministic in [false, true] {
        let front = Front::flat(mesh.vertices().len(), 0.0);
        let options = Options {
            threads: 3,
            deterministic,
        };
        let mut state = Fixed {
            mesh: &mesh,
            front: &front,
        };
        let e = sdg_scheduler::run(
            &mut state,
            1.0,
            &Failing(PhantomData),
            vec![(); 3],
            &options,
        )
        .unwrap_err();
        assert!(matches!(e, RunError::Work("boom")));
    }
}

/// A panic in a tent (a worker), in a record or in an event ends the run with
/// `RunError::Panic` and its message, in both modes and for 1 and 3 threads, instead of leaving
/// the other threads waiting. Each run has 20 s before the test calls it a hang.
#[test]
fn panics_end_the_run_with_their_message() {
    #[derive(Clone, Copy, Debug)]
    enum Where {
        Tent,
        Record,
        Event,
    }
    struct Panicking<'m> {
        pitcher: Pitcher,
        at: Where,
        calls: AtomicUsize,
        fired: AtomicBool,
        _mesh: PhantomData<&'m ()>,
    }
    impl<'a, 'm: 'a> Work<'a> for Panicking<'m> {
        type State = Fixed<'m>;
        type Scratch = ();
        type Outcome = ();
        type Error = &'static str;
        fn tent(
            &self,
            lease: &mut Lease<'_, Fixed<'m>>,
            _: &mut (),
            v: VertexId,
            _: &Events<'a, Fixed<'m>>,
        ) -> Result<(f64, ()), &'static str> {
            let state = *lease.state();
            let call = self.calls.fetch_add(1, Ordering::SeqCst);
            if call == 40 && matches!(self.at, Where::Tent) {
                panic!("tent {call} panics");
            }
            let tent = self
                .pitcher
                .pitch(state.mesh, state.front, v)
                .ok_or("not ready")?;
            Ok((tent.t_new, ()))
        }
        fn record(
            &'a self,
            _: &Fixed<'m>,
            _: VertexId,
            (): (),
            events: &Events<'a, Fixed<'m>>,
        ) -> Result<(), &'static str> {
            if self.calls.load(Ordering::SeqCst) > 40 && !self.fired.swap(true, Ordering::SeqCst) {
                match self.at {
                    Where::Record => panic!("record panics"),
                    Where::Event => events.push(Box::new(|_: &mut Fixed<'m>| -> Changed {
                        panic!("event panics")
                    })),
                    Where::Tent => {}
                }
            }
            Ok(())
        }
    }
    let mesh = perturbed(8);
    for at in [Where::Tent, Where::Record, Where::Event] {
        for (deterministic, threads) in [(false, 1), (false, 3), (true, 1), (true, 3)] {
            let (send, receive) = std::sync::mpsc::channel();
            let mesh = mesh.clone();
            std::thread::spawn(move || {
                let front = Front::flat(mesh.vertices().len(), 0.0);
                let work = Panicking {
                    pitcher: Pitcher::new(&mesh, C, SAFETY, 1.0).unwrap(),
                    at,
                    calls: AtomicUsize::new(0),
                    fired: AtomicBool::new(false),
                    _mesh: PhantomData,
                };
                let mut state = Fixed {
                    mesh: &mesh,
                    front: &front,
                };
                let options = Options {
                    threads,
                    deterministic,
                };
                let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    sdg_scheduler::run(&mut state, 1.0, &work, vec![(); threads], &options)
                        .map(drop)
                        .map_err(|e| e.to_string())
                }));
                send.send(result.map_err(|_| ())).unwrap();
            });
            let case = format!("{at:?}, deterministic {deterministic}, {threads} threads");
            let result = receive
                .recv_timeout(Duration::from_secs(20))
                .unwrap_or_else(|_| panic!("{case}: the run hangs"));
            let message = result
                .unwrap_or_else(|()| panic!("{case}: the panic escaped the run"))
                .expect_err(&case);
            assert!(message.contains("panics"), "{case}: {message}");
        }
    }
}

/// Pitches tents and lists them in the order they are recorded; every `event_every`-th record
/// queues an event that changes nothing.
struct Listed<'m> {
    mesh: PhantomData<&'m Mesh>,
    pitcher: Pitcher,
    order: Mutex<Vec<VertexId>>,
    event_every: usize,
}

impl<'a, 'm: 'a> Work<'a> for Listed<'m> {
    type State = Fixed<'m>;
    type Scratch = ();
    type Outcome = ();
    type Error = String;

    fn tent(
        &self,
        lease: &mut Lease<'_, Fixed<'m>>,
        _: &mut (),
        v: VertexId,
        _: &Events<'a, Fixed<'m>>,
    ) -> Result<(f64, ()), String> {
        let state = *lease.state();
        let tent = self
            .pitcher
            .pitch(state.mesh, state.front, v)
            .ok_or(format!("{v} not pitchable"))?;
        Ok((tent.t_new, ()))
    }

    fn record(
        &'a self,
        _: &Fixed<'m>,
        v: VertexId,
        (): (),
        events: &Events<'a, Fixed<'m>>,
    ) -> Result<(), String> {
        let mut order = self.order.lock();
        order.push(v);
        if order.len().is_multiple_of(self.event_every) {
            events.push(Box::new(|_: &mut Fixed<'m>| Changed::default()));
        }
        Ok(())
    }
}

/// The rounds by definition: scan the whole front for the vertices first in `(time, id)` among
/// their neighbours, sort them by time and id, pitch them all; repeat.
fn rounds_by_full_scans(mesh: &Mesh, t_end: f64) -> Vec<VertexId> {
    let n = mesh.vertices().len();
    let front = Front::flat(n, 0.0);
    let pitcher = Pitcher::new(mesh, C, SAFETY, t_end).unwrap();
    let mut order = Vec::new();
    loop {
        let first = |v: VertexId| {
            let t = front.time(v);
            t < t_end
                && (mesh.vertex_neighbors(v).iter())
                    .all(|&w| front.time(w) > t || (front.time(w) == t && w > v))
        };
        let mut ready: Vec<(f64, VertexId)> = (0..n as VertexId)
            .filter(|&v| first(v))
            .map(|v| (front.time(v), v))
            .collect();
        if ready.is_empty() {
            return order;
        }
        ready.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (_, v) in ready {
            pitcher.pitch(mesh, &front, v).unwrap();
            order.push(v);
        }
    }
}

#[test]
fn deterministic_rounds_take_every_vertex_first_among_its_neighbours_as_a_full_scan_would() {
    let mesh = perturbed(14);
    let t_end = 3.0 / 16.0;
    let expected = rounds_by_full_scans(&mesh, t_end);
    assert!(expected.len() > 1000, "{}", expected.len());
    for (threads, event_every) in [(1, usize::MAX), (2, 13), (3, 1)] {
        let front = Front::flat(mesh.vertices().len(), 0.0);
        let work = Listed {
            mesh: PhantomData,
            pitcher: Pitcher::new(&mesh, C, SAFETY, t_end).unwrap(),
            order: Mutex::new(Vec::new()),
            event_every,
        };
        let mut state = Fixed {
            mesh: &mesh,
            front: &front,
        };
        let options = Options {
            threads,
            deterministic: true,
        };
        sdg_scheduler::run(&mut state, t_end, &work, vec![(); threads], &options).unwrap();
        assert!(
            *work.order.lock() == expected,
            "{threads} threads, an event every {event_every} tents"
        );
    }
}

/// Leaves every third tent at every fifth vertex in place and queues an event that checks
/// that the vertex and its neighbours still have the times the tent saw.
struct Deferring<'m> {
    mesh: PhantomData<&'m Mesh>,
    pitcher: Pitcher,
    visits: Vec<AtomicUsize>,
    /// Events that found their star as their tent left it, and those that did not.
    kept: AtomicUsize,
    moved: AtomicUsize,
}

impl<'a, 'm: 'a> Work<'a> for Deferring<'m> {
    type State = Fixed<'m>;
    type Scratch = ();
    /// The star's times when the tent left its vertex in place.
    type Outcome = Option<Vec<(VertexId, f64)>>;
    type Error = String;

    fn tent(
        &self,
        lease: &mut Lease<'_, Fixed<'m>>,
        _: &mut (),
        v: VertexId,
        _: &Events<'a, Fixed<'m>>,
    ) -> Result<(f64, Self::Outcome), String> {
        let Fixed { mesh, front } = *lease.state();
        if v.is_multiple_of(5)
            && self.visits[v as usize]
                .fetch_add(1, Ordering::Relaxed)
                .is_multiple_of(3)
        {
            let star = mesh
                .vertex_neighbors(v)
                .iter()
                .chain([&v])
                .map(|&u| (u, front.time(u)))
                .collect();
            return Ok((front.time(v), Some(star)));
        }
        let tent = self
            .pitcher
            .pitch(mesh, front, v)
            .ok_or(format!("{v} not pitchable"))?;
        Ok((tent.t_new, None))
    }

    fn record(
        &'a self,
        _: &Fixed<'m>,
        v: VertexId,
        star: Self::Outcome,
        events: &Events<'a, Fixed<'m>>,
    ) -> Result<(), String> {
        if let Some(star) = star {
            events.push(Box::new(move |state: &mut Fixed<'m>| {
                let same = star.iter().all(|&(u, t)| state.front.time(u) == t);
                let count = if same { &self.kept } else { &self.moved };
                count.fetch_add(1, Ordering::Relaxed);
                Changed {
                    offer: vec![v],
                    below_end: 0,
                }
            }));
        }
        Ok(())
    }
}

#[test]
fn a_tent_that_leaves_its_vertex_in_place_finds_its_star_unchanged_when_its_event_runs() {
    let mesh = perturbed(16);
    let t_end = 3.0 / 16.0;
    for (threads, deterministic) in [(1, false), (2, false), (4, false), (4, true)] {
        let front = Front::flat(mesh.vertices().len(), 0.0);
        let work = Deferring {
            mesh: PhantomData,
            pitcher: Pitcher::new(&mesh, C, SAFETY, t_end).unwrap(),
            visits: (0..mesh.vertices().len())
                .map(|_| AtomicUsize::new(0))
                .collect(),
            kept: AtomicUsize::new(0),
            moved: AtomicUsize::new(0),
        };
        let mut state = Fixed {
            mesh: &mesh,
            front: &front,
        };
        let options = Options {
            threads,
            deterministic,
        };
        sdg_scheduler::run(&mut state, t_end, &work, vec![(); threads], &options).unwrap();
        let case = format!("{threads} threads, deterministic {deterministic}");
        assert!(front.snapshot().iter().all(|&t| t == t_end), "{case}");
        assert!(work.kept.load(Ordering::Relaxed) > 100, "{case}");
        assert_eq!(work.moved.load(Ordering::Relaxed), 0, "{case}");
    }
}
