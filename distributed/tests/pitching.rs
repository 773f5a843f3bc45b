//! Distributed asynchronous pitching gives the serial reference order's tents, bitwise, for
//! every partition and message timing; and it needs few messages per tent.

use std::time::Duration;

use sdg_distributed::{
    Causality, Loopback, LoopbackOptions, Message, Options, Partition, PitchingError, RankReport,
    Transport, TransportError, run_threads,
};
use sdg_mesh::{Diagonal, Front, Mesh, Pitcher, Rectangle, VertexId};
use sdg_scheduler::run_serial;

/// Per vertex, the bit patterns of `(t_old, t_new)` of its tents in order.
type Sequences = Vec<Vec<(u64, u64)>>;

fn rectangle(n: u32, diagonal: Diagonal, perturb: f64, seed: u64) -> Mesh {
    Rectangle {
        width: 1.0,
        height: 0.8,
        nx: n,
        ny: n * 4 / 5,
        diagonal,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb,
        seed,
    }
    .build()
    .expect("a valid rectangle")
}

/// The serial reference: always the earliest vertex, ties to the smaller id.
fn serial(mesh: &Mesh, start: &[f64], causality: Causality) -> Sequences {
    let pitcher = Pitcher::new(mesh, causality.c_max, causality.safety, causality.t_end).unwrap();
    let front = Front::flat(start.len(), 0.0);
    for (v, &t) in start.iter().enumerate() {
        front.set_time(v as VertexId, t);
    }
    let mut sequences = vec![Vec::new(); start.len()];
    let tents = run_serial(start, causality.t_end, |v| {
        let tent = pitcher.pitch(mesh, &front, v).ok_or(v)?;
        sequences[v as usize].push((tent.t_old.to_bits(), tent.t_new.to_bits()));
        Ok::<f64, VertexId>(tent.t_new)
    })
    .unwrap();
    assert_eq!(
        tents as usize,
        sequences.iter().map(Vec::len).sum::<usize>()
    );
    sequences
}

fn sequences(vertices: usize, reports: &[RankReport], partition: &Partition) -> Sequences {
    let mut sequences = vec![Vec::new(); vertices];
    for report in reports {
        for tent in &report.tents {
            assert_eq!(
                partition.owner(tent.vertex),
                report.rank,
                "pitched by its owner"
            );
            sequences[tent.vertex as usize].push((tent.t_old.to_bits(), tent.t_new.to_bits()));
        }
    }
    sequences
}

fn options(seed: u64) -> Options {
    Options::new(seed, Duration::from_secs(10))
}

#[test]
fn tents_are_the_serial_orders_for_every_partition_and_timing() {
    let mesh = rectangle(12, Diagonal::Alternate, 0.2, 4);
    let n = mesh.vertices().len();
    let causality = Causality {
        c_max: 1.0,
        safety: 0.5,
        t_end: 0.3,
    };
    let start = vec![0.0; n];
    let reference = serial(&mesh, &start, causality);
    let tents: usize = reference.iter().map(Vec::len).sum();
    assert!(tents > 8 * n, "{tents} tents on {n} vertices");
    let (mut runs, mut applied) = (0, 0);
    for ranks in 1..=4 {
        let partitions = [
            Partition::coordinate(&mesh, ranks).unwrap(),
            Partition::striped(&mesh, ranks).unwrap(),
            Partition::random(&mesh, ranks, 17 + ranks as u64).unwrap(),
        ];
        for (k, partition) in partitions.iter().enumerate() {
            for fifo in [true, false] {
                let seed = (ranks * 10 + k) as u64;
                let delays = LoopbackOptions {
                    seed,
                    max_delay: Duration::from_micros(40),
                    fifo,
                };
                let reports =
                    run_threads(&mesh, partition, &start, causality, delays, &options(seed))
                        .unwrap();
                let got = sequences(n, &reports, partition);
                assert!(
                    got == reference,
                    "{ranks} ranks, partition {k}, fifo {fifo}: tents differ from the serial order's"
                );
                runs += 1;
                applied += reports.iter().map(|r| r.updates_applied).sum::<u64>();
                let sent: u64 = reports.iter().map(|r| r.updates_sent).sum();
                let received: u64 = reports
                    .iter()
                    .map(|r| r.updates_applied + r.updates_stale)
                    .sum();
                assert_eq!(sent, received, "every update received before the end");
            }
        }
    }
    assert_eq!(runs, 24);
    assert!(applied > 10_000, "{applied} updates applied");
}

/// A transport that holds a rank's updates back while it is busy and sends them newest first
/// when it waits (or says done). Two updates of one vertex to one rank rarely pile up (the
/// vertex's next tent mostly waits for the ghost holder's neighbours to move), but all the
/// others arrive reversed.
#[derive(Debug)]
struct Reversing(Loopback, Vec<(u32, Message)>);

impl Reversing {
    fn flush(&mut self) -> Result<(), TransportError> {
        while let Some((to, message)) = self.1.pop() {
            self.0.send(to, message)?;
        }
        Ok(())
    }
}

impl Transport for Reversing {
    fn rank(&self) -> u32 {
        self.0.rank()
    }

    fn ranks(&self) -> usize {
        self.0.ranks()
    }

    fn send(&mut self, to: u32, message: Message) -> Result<(), TransportError> {
        let update = matches!(message, Message::Update(_));
        self.1.push((to, message));
        if update { Ok(()) } else { self.flush() }
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<(u32, Message)>, TransportError> {
        if !timeout.is_zero() {
            self.flush()?;
        }
        self.0.receive(timeout)
    }

    fn sum(&mut self, values: &[u64]) -> Result<Vec<u64>, TransportError> {
        self.flush()?;
        self.0.sum(values)
    }

    fn all_gather(&mut self, bytes: Vec<u8>) -> Result<Vec<Vec<u8>>, TransportError> {
        self.flush()?;
        self.0.all_gather(bytes)
    }

    fn is_fifo(&self) -> bool {
        false
    }
}

#[test]
fn updates_arriving_newest_first_give_the_same_tents() {
    use sdg_distributed::{LocalView, pitch_rank};

    let mesh = rectangle(12, Diagonal::Alternate, 0.2, 4);
    let n = mesh.vertices().len();
    let causality = Causality {
        c_max: 1.0,
        safety: 0.5,
        t_end: 0.3,
    };
    let reference = serial(&mesh, &vec![0.0; n], causality);
    let partition = Partition::random(&mesh, 3, 5).unwrap();
    let views = LocalView::all(&mesh, &partition).unwrap();
    let delays = LoopbackOptions {
        seed: 3,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let ends = Loopback::connect(3, delays);
    let reports: Vec<RankReport> = std::thread::scope(|s| {
        let handles: Vec<_> = views
            .iter()
            .zip(ends)
            .map(|(view, end)| {
                s.spawn(move || {
                    let pitcher = Pitcher::new(view.mesh(), 1.0, 0.5, 0.3).unwrap();
                    let front = Front::flat(view.mesh().vertices().len(), 0.0);
                    let mut end = Reversing(end, Vec::new());
                    pitch_rank(view, &pitcher, &front, &mut end, &options(2)).unwrap()
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert!(sequences(n, &reports, &partition) == reference);
    let received: u64 = reports
        .iter()
        .map(|r| r.updates_applied + r.updates_stale)
        .sum();
    let sent: u64 = reports.iter().map(|r| r.updates_sent).sum();
    assert!(
        sent == received && sent > 1000,
        "{sent} sent, {received} received"
    );
}

#[test]
fn a_ghost_copy_takes_an_update_only_if_it_is_newer() {
    use sdg_distributed::{LocalView, Update, pitch_rank};

    let mesh = rectangle(8, Diagonal::Alternate, 0.1, 2);
    let partition = Partition::striped(&mesh, 2).unwrap();
    let view = LocalView::new(&mesh, &partition, 0).unwrap();
    let t_end = 0.2;
    let pitcher = Pitcher::new(view.mesh(), 1.0, 0.5, t_end).unwrap();
    let front = Front::flat(view.mesh().vertices().len(), 0.0);
    let delays = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let mut ends = Loopback::connect(2, delays);
    // Rank 1 plays its part by hand: its vertices next to rank 0 jump to the end (generation
    // 9), then an older update (generation 2) comes late, then done.
    let ghosts: Vec<VertexId> = view.ghosts().map(|v| view.global(v)).collect();
    assert!(ghosts.len() >= 7, "{ghosts:?}");
    for (generation, time) in [(9, t_end), (2, 0.01)] {
        for &vertex in &ghosts {
            let update = Update {
                vertex,
                time,
                generation,
                ..Update::default()
            };
            ends[1].send(0, Message::Update(update)).unwrap();
        }
    }
    let sent = 2 * ghosts.len() as u64;
    ends[1].send(0, Message::Done { sent }).unwrap();
    let report = pitch_rank(&view, &pitcher, &front, &mut ends[0], &options(0)).unwrap();
    assert!(view.ghosts().all(|v| front.time(v) == t_end));
    assert!(view.owned().all(|v| front.time(v) == t_end));
    assert_eq!(report.updates_applied, ghosts.len() as u64);
    assert_eq!(report.updates_stale, ghosts.len() as u64);
    assert_eq!(
        report.updates_sent,
        report
            .tents
            .iter()
            .map(|t| { view.sharers(view.local(t.vertex).unwrap()).len() as u64 })
            .sum::<u64>()
    );
}

#[test]
fn a_256_by_256_rectangle_on_4_ranks_needs_few_messages_per_tent() {
    let mesh = Rectangle {
        width: 1.0,
        height: 1.0,
        nx: 256,
        ny: 256,
        diagonal: Diagonal::Right,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.0,
        seed: 0,
    }
    .build()
    .unwrap();
    let n = mesh.vertices().len();
    let causality = Causality {
        c_max: 1.0,
        safety: 0.5,
        t_end: 0.006,
    };
    let start = vec![0.0; n];
    let partition = Partition::coordinate(&mesh, 4).unwrap();
    let delays = LoopbackOptions {
        seed: 1,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let reports = run_threads(&mesh, &partition, &start, causality, delays, &options(1)).unwrap();
    let tents: usize = reports.iter().map(|r| r.tents.len()).sum();
    let messages: u64 = reports.iter().map(|r| r.updates_sent).sum();
    let bytes: u64 = reports.iter().map(|r| r.update_bytes).sum();
    let boundary: usize = reports.iter().map(|r| r.boundary_vertices).sum();
    let per_tent = messages as f64 / tents as f64;
    eprintln!(
        "256 x 256, 4 ranks, coordinate bisection: {tents} tents, {messages} update messages \
         ({per_tent:.4} per tent, {:.3} bytes per tent), {boundary} boundary vertices of {n}",
        bytes as f64 / tents as f64
    );
    assert!(tents > 4 * n, "{tents} tents");
    assert!(
        (0.01..=0.03).contains(&per_tent),
        "{per_tent} messages per tent"
    );
    assert!(sequences(n, &reports, &partition) == serial(&mesh, &start, causality));
}

/// A transport that loses every update: the ranks cannot finish.
#[derive(Debug)]
struct Lossy(Loopback);

impl Transport for Lossy {
    fn rank(&self) -> u32 {
        self.0.rank()
    }

    fn ranks(&self) -> usize {
        self.0.ranks()
    }

    fn send(&mut self, to: u32, message: Message) -> Result<(), TransportError> {
        match message {
            Message::Update(_) => Ok(()),
            _ => self.0.send(to, message),
        }
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<(u32, Message)>, TransportError> {
        self.0.receive(timeout)
    }

    fn sum(&mut self, values: &[u64]) -> Result<Vec<u64>, TransportError> {
        self.0.sum(values)
    }

    fn all_gather(&mut self, bytes: Vec<u8>) -> Result<Vec<Vec<u8>>, TransportError> {
        self.0.all_gather(bytes)
    }

    fn is_fifo(&self) -> bool {
        self.0.is_fifo()
    }
}

#[test]
fn lost_updates_stall_with_an_error_and_a_stray_update_aborts_every_rank() {
    use sdg_distributed::{LocalView, pitch_rank};

    let mesh = rectangle(6, Diagonal::Alternate, 0.0, 0);
    let partition = Partition::striped(&mesh, 2).unwrap();
    let views = LocalView::all(&mesh, &partition).unwrap();
    let fronts: Vec<Front> = views
        .iter()
        .map(|v| Front::flat(v.mesh().vertices().len(), 0.0))
        .collect();
    let pitchers: Vec<Pitcher> = views
        .iter()
        .map(|v| Pitcher::new(v.mesh(), 1.0, 0.5, 0.2).unwrap())
        .collect();
    let run = |ends: Vec<Lossy>| -> Vec<Result<RankReport, PitchingError>> {
        let options = &Options::new(0, Duration::from_millis(200));
        std::thread::scope(|s| {
            let handles: Vec<_> = ends
                .into_iter()
                .enumerate()
                .map(|(r, mut end)| {
                    let (view, pitcher, front) = (&views[r], &pitchers[r], &fronts[r]);
                    s.spawn(move || pitch_rank(view, pitcher, front, &mut end, options))
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        })
    };
    let delays = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let results = run(Loopback::connect(2, delays)
        .into_iter()
        .map(Lossy)
        .collect());
    assert!(
        results
            .iter()
            .any(|r| matches!(r, Err(PitchingError::Stalled { .. }))),
        "{results:?}"
    );
    assert!(results.iter().all(|r| matches!(
        r,
        Err(PitchingError::Stalled { .. } | PitchingError::Aborted { .. })
    )));

    // Rank 1 tells rank 0 about a vertex rank 1 does not own.
    for f in &fronts {
        (0..f.len() as VertexId).for_each(|v| f.set_time(v, 0.0));
    }
    let mut ends = Loopback::connect(2, delays);
    let foreign = (0..mesh.vertices().len() as VertexId)
        .find(|&v| partition.owner(v) == 0)
        .unwrap();
    let stray = sdg_distributed::Update {
        vertex: foreign,
        time: 0.1,
        generation: 1,
        ..sdg_distributed::Update::default()
    };
    ends[1].send(0, Message::Update(stray)).unwrap();
    let results = run(ends.into_iter().map(Lossy).collect());
    assert_eq!(
        results[0],
        Err(PitchingError::Stray {
            rank: 0,
            from: 1,
            vertex: foreign
        })
    );
    assert_eq!(results[1], Err(PitchingError::Aborted { rank: 1, by: 0 }));
}

#[test]
fn a_start_front_of_the_wrong_length_is_an_error() {
    let mesh = rectangle(4, Diagonal::Right, 0.0, 0);
    let partition = Partition::coordinate(&mesh, 2).unwrap();
    let causality = Causality {
        c_max: 1.0,
        safety: 0.5,
        t_end: 0.1,
    };
    let delays = LoopbackOptions {
        seed: 0,
        max_delay: Duration::ZERO,
        fifo: true,
    };
    let err = run_threads(&mesh, &partition, &[0.0; 3], causality, delays, &options(0));
    assert_eq!(
        err.unwrap_err(),
        PitchingError::FrontLength {
            front: 3,
            mesh: mesh.vertices().len()
        }
    );
    let bad = Causality {
        c_max: -1.0,
        ..causality
    };
    let start = vec![0.0; mesh.vertices().len()];
    let err = run_threads(&mesh, &partition, &start, bad, delays, &options(0)).unwrap_err();
    assert_eq!(
        err.to_string(),
        "the wave speed must be positive and finite, got -1 m/s"
    );
}

/// Records each tent's times per vertex; the scheduler calls `record` with the vertex still
/// claimed, so each vertex's tents are recorded in order.
struct Recording<'a> {
    pitcher: &'a Pitcher,
    sequences: std::sync::Mutex<Sequences>,
}

impl<'a> sdg_scheduler::Work<'a> for Recording<'a> {
    type State = sdg_scheduler::Fixed<'a>;
    type Scratch = ();
    type Outcome = (u64, u64);
    type Error = VertexId;

    fn tent(
        &self,
        lease: &mut sdg_scheduler::Lease<'_, Self::State>,
        _: &mut (),
        v: VertexId,
        _: &sdg_scheduler::Events<'a, Self::State>,
    ) -> Result<(f64, (u64, u64)), VertexId> {
        let state = *lease.state();
        let tent = self.pitcher.pitch(state.mesh, state.front, v).ok_or(v)?;
        Ok((tent.t_new, (tent.t_old.to_bits(), tent.t_new.to_bits())))
    }

    fn record(
        &'a self,
        _: &Self::State,
        v: VertexId,
        outcome: (u64, u64),
        _: &sdg_scheduler::Events<'a, Self::State>,
    ) -> Result<(), VertexId> {
        self.sequences.lock().unwrap()[v as usize].push(outcome);
        Ok(())
    }
}

#[test]
fn the_serial_order_is_the_threaded_schedulers_in_both_modes() {
    let mesh = rectangle(12, Diagonal::Alternate, 0.2, 4);
    let n = mesh.vertices().len();
    let causality = Causality {
        c_max: 1.0,
        safety: 0.5,
        t_end: 0.3,
    };
    let reference = serial(&mesh, &vec![0.0; n], causality);
    let pitcher = Pitcher::new(&mesh, causality.c_max, causality.safety, causality.t_end).unwrap();
    for deterministic in [false, true] {
        let front = Front::flat(n, 0.0);
        let work = Recording {
            pitcher: &pitcher,
            sequences: std::sync::Mutex::new(vec![Vec::new(); n]),
        };
        let mut state = sdg_scheduler::Fixed {
            mesh: &mesh,
            front: &front,
        };
        let options = sdg_scheduler::Options {
            threads: 2,
            deterministic,
        };
        sdg_scheduler::run(&mut state, causality.t_end, &work, vec![(), ()], &options).unwrap();
        let got = work.sequences.into_inner().unwrap();
        assert!(got == reference, "deterministic {deterministic}");
    }
}

#[test]
fn a_pause_at_a_time_stops_after_the_tents_below_it_and_going_on_gives_the_rest() {
    let mesh = rectangle(8, Diagonal::Alternate, 0.2, 5);
    let n = mesh.vertices().len();
    let causality = Causality {
        c_max: 1.0,
        safety: 0.5,
        t_end: 0.3,
    };
    let reference = serial(&mesh, &vec![0.0; n], causality);
    let pause_at = 0.13;
    for ranks in [2, 3] {
        let partition = Partition::random(&mesh, ranks, 3).unwrap();
        let delays = LoopbackOptions {
            seed: ranks as u64,
            max_delay: Duration::from_micros(40),
            fifo: false,
        };
        let mut paused = options(1);
        paused.pause.at = Some(pause_at);
        let first =
            run_threads(&mesh, &partition, &vec![0.0; n], causality, delays, &paused).unwrap();
        let before = sequences(n, &first, &partition);
        let below = |s: &Vec<(u64, u64)>| {
            s.iter()
                .filter(|t| f64::from_bits(t.0) < pause_at)
                .copied()
                .collect::<Vec<_>>()
        };
        assert_eq!(before, reference.iter().map(below).collect::<Vec<_>>());
        assert!(first.iter().any(|r| r.below_end > 0));
        let front: Vec<f64> = (0..n)
            .map(|v| before[v].last().map_or(0.0, |t| f64::from_bits(t.1)))
            .collect();
        assert!(front.iter().all(|&t| t >= pause_at));
        let rest = run_threads(&mesh, &partition, &front, causality, delays, &options(2)).unwrap();
        let mut all = before;
        for (v, tents) in sequences(n, &rest, &partition).into_iter().enumerate() {
            all[v].extend(tents);
        }
        assert!(
            all == reference,
            "{ranks} ranks: paused and resumed tents differ"
        );
    }
}
