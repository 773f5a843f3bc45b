//! Replaying a trace on any number of simulated workers (`sdg scaling`).

use super::entry::{Entry, Kind};

/// What a replay predicts for one number of workers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    pub workers: usize,
    /// Predicted wall time, s.
    pub wall_time_s: f64,
    /// Mean number of tents ready and waiting for a worker.
    pub mean_ready: f64,
}

/// Deterministic rounds in a trace (the rounds model replays it); 0 for an asynchronous run.
pub fn rounds(entries: &[Entry]) -> usize {
    entries.iter().filter(|e| e.kind == Kind::Round).count()
}

/// Replays `entries` on `workers` simulated workers with `overhead_s` of claiming per tent: as
/// the deterministic scheduler's rounds when the trace has them, else as the asynchronous one.
pub fn replay(entries: &[Entry], workers: usize, overhead_s: f64) -> Prediction {
    let workers = workers.max(1);
    if rounds(entries) > 0 {
        return replay_rounds(entries, workers, overhead_s);
    }
    replay_between(entries, workers, overhead_s)
}

/// The dependency-graph replay of an asynchronous trace in segments between the events that run
/// alone ([`Kind::runs_alone`]), which are added to the wall time; a `region` event waits for
/// its dependencies (the tents and events at the vertices it changes and their neighbours),
/// takes one worker and pays the claim overhead, and the tents there after it wait for it.
fn replay_between(entries: &[Entry], workers: usize, overhead_s: f64) -> Prediction {
    let alone = |k: Kind| k.runs_alone();
    let (mut clock, mut ready_area) = (0.0, 0.0);
    for segment in entries.split(|e| alone(e.kind)) {
        let (span, area) = replay_segment(segment, workers, overhead_s);
        clock += span;
        ready_area += area;
    }
    clock += entries
        .iter()
        .filter(|e| alone(e.kind))
        .map(|e| e.duration_s)
        .sum::<f64>();
    Prediction {
        workers,
        wall_time_s: clock,
        mean_ready: ready_area / clock.max(f64::MIN_POSITIVE),
    }
}

/// The rounds of a deterministic trace: the tents of a round (all ready when it starts, none
/// depending on another) go in trace order to the first free worker, each paying `overhead_s`,
/// as the scheduler's shared counter hands them out; once all have run, the chunks that settle
/// them go the same way (without the overhead); then the round's events and the scheduler's
/// own time on it run alone. The rounds are the same for any number of threads, so the model
/// needs no dependencies.
fn replay_rounds(entries: &[Entry], workers: usize, overhead_s: f64) -> Prediction {
    let (mut clock, mut ready_area) = (0.0, 0.0);
    for round in entries.split_inclusive(|e| e.kind == Kind::Round) {
        let (span, area) = list_schedule(round_tents(round), workers, overhead_s);
        let (settling, _) = list_schedule(of_kind(round, Kind::Settle), workers, 0.0);
        clock += span + settling + serial_time(round);
        ready_area += area;
    }
    Prediction {
        workers,
        wall_time_s: clock,
        mean_ready: ready_area / clock.max(f64::MIN_POSITIVE),
    }
}

/// The durations of the tents of `round`, s, in trace order.
fn round_tents(round: &[Entry]) -> impl Iterator<Item = f64> + Clone + '_ {
    round
        .iter()
        .filter(|e| e.kind.is_tent())
        .map(|e| e.duration_s)
}

/// The durations of the items of `kind` in `round`, s, in trace order.
fn of_kind(round: &[Entry], kind: Kind) -> impl Iterator<Item = f64> + Clone + '_ {
    round
        .iter()
        .filter(move |e| e.kind == kind)
        .map(|e| e.duration_s)
}

/// The time `round` runs alone (its events and the scheduler's own time), s.
fn serial_time(round: &[Entry]) -> f64 {
    round
        .iter()
        .filter(|e| e.kind.is_event() || e.kind == Kind::Round)
        .map(|e| e.duration_s)
        .sum()
}

/// Makespan of `durations` (s; all ready at 0) taken in order by the first free of `workers`,
/// each paying `overhead_s`, and the integral over time of the number not started yet (s).
fn list_schedule(
    durations: impl Iterator<Item = f64> + Clone,
    workers: usize,
    overhead_s: f64,
) -> (f64, f64) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let n = durations.clone().count();
    let mut free: BinaryHeap<Reverse<Time>> = (0..workers).map(|_| Reverse(Time(0.0))).collect();
    let (mut span, mut area, mut last_start) = (0.0f64, 0.0, 0.0);
    for (i, d) in durations.enumerate() {
        let Some(Reverse(Time(start))) = free.pop() else {
            unreachable!("at least one worker")
        };
        area += (n - i) as f64 * (start - last_start);
        last_start = start;
        let finish = start + overhead_s + d;
        span = span.max(finish);
        free.push(Reverse(Time(finish)));
    }
    (span, area)
}

/// The time with unlimited workers, s: the longest chain of dependencies, events included; for
/// deterministic rounds, the longest tent of each round plus the time it runs alone.
pub fn critical_path(entries: &[Entry], overhead_s: f64) -> f64 {
    let parts = critical_path_parts(entries, overhead_s);
    parts.tents_s + parts.events_s + parts.scheduler_s
}

/// What the critical path is made of, s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CriticalPath {
    /// Tents on it, with their claim overhead: the longest chains between the events that run
    /// alone (regional events included in them), or the longest tent of each round.
    pub tents_s: f64,
    /// Events that run alone: in an asynchronous trace all but the regional ones, in a
    /// deterministic one all.
    pub events_s: f64,
    /// The deterministic scheduler's own time on its rounds: what the calling thread does
    /// alone, and the longest chunk of settling of each round (0 for an asynchronous trace).
    pub scheduler_s: f64,
}

/// The parts of [`critical_path`].
pub fn critical_path_parts(entries: &[Entry], overhead_s: f64) -> CriticalPath {
    // A sum of no f64 is -0.0: start from +0.0.
    let time_of = |kind: Kind| -> f64 {
        (entries.iter())
            .filter(|e| e.kind == kind)
            .fold(0.0, |sum, e| sum + e.duration_s)
    };
    let scheduler_s = time_of(Kind::Round);
    if rounds(entries) > 0 {
        let longest = |durations: &mut dyn Iterator<Item = f64>| durations.fold(0.0, f64::max);
        let (tents_s, settling_s) = entries
            .split_inclusive(|e| e.kind == Kind::Round)
            .map(|round| {
                (
                    longest(&mut round_tents(round).map(|d| d + overhead_s)),
                    longest(&mut of_kind(round, Kind::Settle)),
                )
            })
            .fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
        return CriticalPath {
            tents_s,
            events_s: time_of(Kind::Event) + time_of(Kind::Region),
            scheduler_s: scheduler_s + settling_s,
        };
    }
    CriticalPath {
        tents_s: entries
            .split(|e| e.kind.runs_alone())
            .map(|segment| longest_chain(segment, overhead_s))
            .sum(),
        events_s: time_of(Kind::Event),
        scheduler_s,
    }
}

/// The longest chain of dependencies in `segment` (sorted by id), each item with `overhead_s`,
/// s.
fn longest_chain(segment: &[Entry], overhead_s: f64) -> f64 {
    let index = index_of(segment);
    let mut finish = vec![0.0f64; segment.len()];
    for (i, e) in segment.iter().enumerate() {
        let start = e
            .deps
            .iter()
            .filter_map(|d| index(*d))
            .map(|j| finish[j])
            .fold(0.0, f64::max);
        finish[i] = start + overhead_s + e.duration_s;
    }
    finish.iter().copied().fold(0.0, f64::max)
}

/// Position in `segment` (sorted by id) of a tent id, if it is there.
fn index_of(segment: &[Entry]) -> impl Fn(u64) -> Option<usize> + '_ {
    move |id| segment.binary_search_by_key(&id, |e| e.id).ok()
}

/// Makespan of one segment between events on `workers` workers, and the integral over time
/// of the number of ready tents (s).
fn replay_segment(segment: &[Entry], workers: usize, overhead_s: f64) -> (f64, f64) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    if segment.is_empty() {
        return (0.0, 0.0);
    }
    let index = index_of(segment);
    let mut waiting: Vec<usize> = vec![0; segment.len()];
    let mut dependents: Vec<Vec<usize>> = vec![Vec::new(); segment.len()];
    for (i, e) in segment.iter().enumerate() {
        for j in e.deps.iter().filter_map(|d| index(*d)) {
            waiting[i] += 1;
            dependents[j].push(i);
        }
    }
    // Ready tents by position (trace order); running tents by finish time.
    let mut ready: BinaryHeap<Reverse<usize>> = (0..segment.len())
        .filter(|&i| waiting[i] == 0)
        .map(Reverse)
        .collect();
    let mut running: BinaryHeap<Reverse<(Time, usize)>> = BinaryHeap::new();
    let (mut now, mut area, mut done) = (0.0, 0.0, 0);
    while done < segment.len() {
        while running.len() < workers {
            let Some(Reverse(i)) = ready.pop() else { break };
            let finish = now + overhead_s + segment[i].duration_s;
            running.push(Reverse((Time(finish), i)));
        }
        let Some(Reverse((Time(t), i))) = running.pop() else {
            unreachable!("a tent is running while some are not done: dependencies are earlier")
        };
        area += ready.len() as f64 * (t - now);
        now = t;
        done += 1;
        for &k in &dependents[i] {
            waiting[k] -= 1;
            if waiting[k] == 0 {
                ready.push(Reverse(k));
            }
        }
    }
    (now, area)
}

/// A finite time with a total order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Time(pub(super) f64);

impl Eq for Time {}

impl PartialOrd for Time {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Time {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// Regional events in a trace (`region` rows).
pub fn regions(entries: &[Entry]) -> usize {
    entries.iter().filter(|e| e.kind == Kind::Region).count()
}
