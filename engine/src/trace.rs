//! Tracing a run for scaling studies (`sdg run --trace FILE`) and replaying the trace on any
//! number of simulated workers (`sdg scaling FILE --workers 1,2,4,...`).
//!
//! A trace lists every tent with its vertex, its kind, when it ran, how long it took and the
//! earlier tents it depends on: the last tents at its vertex and at the vertex's neighbours
//! (their front times and the elements it reads), or the regional event that last changed
//! them. Events that change the mesh only around some vertices (refinement, coarsening, crack
//! extension: `region` rows) list as dependencies the last tents and events at the vertices
//! they changed and at those vertices' neighbours; the other events (`event` rows: history
//! rows, interventions) hold the whole state.
//!
//! The replay models the asynchronous scheduler: a tent is ready once its dependencies are done,
//! and each free worker takes the ready tent that came first in the trace, paying a fixed claim
//! overhead per tent; a `region` event, like a tent, waits only for its dependencies and takes
//! one worker while the others go on solving, as the scheduler runs regional events; an `event`
//! waits for every tent before it and runs alone. A trace of a deterministic run also marks the
//! end of each round (`round`, with the
//! time the scheduler spent on it alone: choosing its vertices and recording its tents), and is
//! replayed as those rounds, which are the same for any thread count: a round's tents go to the
//! first free worker in trace order, then its events and the scheduler's own time run alone.
//! Either way the replay predicts the wall time, the critical path (the time with unlimited
//! workers) and the mean number of ready tents. The costs are those measured in the traced run,
//! so the model leaves out what more threads do to each tent (shared caches and memory
//! bandwidth) and the barriers' cost.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use parking_lot::Mutex;
use sdg_mesh::{Mesh, VertexId};

use crate::error::EngineError;
use crate::output::write_atomic;
use crate::plot::{LineChart, LineStyle};

/// What a traced item was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A linear patch.
    Patch,
    /// A patch with interface faces solved by Newton iterations.
    Newton,
    /// A patch rejected by the error indicator or a failed Newton solve.
    Rejected,
    /// A coarsening patch.
    Coarsen,
    /// A scheduler event that holds the whole state.
    Event,
    /// A scheduler event that changes the mesh only around some vertices (refinement,
    /// coarsening, crack extension); its dependencies are the tents and events there.
    Region,
    /// The end of a deterministic round: the time the scheduler spent on it alone (choosing its
    /// vertices, recording its tents), after its tents and events.
    Round,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Self::Patch => "patch",
            Self::Newton => "newton",
            Self::Rejected => "rejected",
            Self::Coarsen => "coarsen",
            Self::Event => "event",
            Self::Region => "region",
            Self::Round => "round",
        }
    }

    fn parse(name: &str) -> Option<Self> {
        [
            Self::Patch,
            Self::Newton,
            Self::Rejected,
            Self::Coarsen,
            Self::Event,
            Self::Region,
            Self::Round,
        ]
        .into_iter()
        .find(|k| k.name() == name)
    }
}

impl Kind {
    /// Events of either kind: deterministic rounds run them alone, after the round's tents.
    fn is_event(self) -> bool {
        matches!(self, Self::Event | Self::Region)
    }

    /// What the asynchronous scheduler runs alone: every event but the regional ones.
    fn runs_alone(self) -> bool {
        matches!(self, Self::Event | Self::Round)
    }
}

/// One traced tent or event.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Ids count up in the order items started.
    pub id: u64,
    pub kind: Kind,
    /// The tent's vertex (ids as at the time; none for an event).
    pub vertex: Option<VertexId>,
    /// Start after the solve began, and duration, s.
    pub start_s: f64,
    pub duration_s: f64,
    /// Earlier tents this one needs, by id.
    pub deps: Vec<u64>,
}

/// A tent being traced.
#[derive(Debug)]
pub(crate) struct Begun {
    id: u64,
    start: Instant,
    deps: Vec<u64>,
}

/// A regional event being traced.
#[derive(Debug)]
pub(crate) struct BegunRegion {
    id: u64,
    start: Instant,
}

/// Records the trace of a running solve.
#[derive(Debug)]
pub(crate) struct Tracer {
    started: Instant,
    ids: Mutex<Ids>,
    entries: Mutex<Vec<Entry>>,
}

/// Ids plus one per vertex (0: none yet); vertex ids as at the time.
#[derive(Debug, Default)]
struct Ids {
    /// The next id.
    next: u64,
    /// The last tent that changed the solution under the vertex's star, or the last regional
    /// event that changed its star.
    last: Vec<u64>,
    /// The last tent at the vertex, whatever it did.
    last_any: Vec<u64>,
}

impl Ids {
    fn take(&mut self) -> u64 {
        self.next += 1;
        self.next - 1
    }
}

/// Sets `table[v]` to `id + 1`, growing the table as needed.
fn set(table: &mut Vec<u64>, v: VertexId, id: u64) {
    if table.len() <= v as usize {
        table.resize(v as usize + 1, 0);
    }
    table[v as usize] = id + 1;
}

impl Tracer {
    pub(crate) fn new() -> Self {
        Self {
            started: Instant::now(),
            ids: Mutex::new(Ids::default()),
            entries: Mutex::new(Vec::new()),
        }
    }

    /// Starts tracing the tent at `v` (claimed): its id and dependencies.
    pub(crate) fn begin(&self, mesh: &Mesh, v: VertexId) -> Begun {
        let mut ids = self.ids.lock();
        let id = ids.take();
        let mut deps: Vec<u64> = std::iter::once(&v)
            .chain(mesh.vertex_neighbors(v))
            .filter_map(|&w| ids.last.get(w as usize).copied())
            .filter(|&last| last > 0)
            .map(|last| last - 1)
            .collect();
        drop(ids);
        deps.sort_unstable();
        deps.dedup();
        Begun {
            id,
            start: Instant::now(),
            deps,
        }
    }

    /// Ends the tent `begun` at `v` as `kind`; a tent that changed the solution under `v`'s
    /// star (`changed`) becomes a dependency of the next tents there.
    pub(crate) fn end(&self, begun: Begun, v: VertexId, kind: Kind, changed: bool) {
        let duration_s = begun.start.elapsed().as_secs_f64();
        {
            let mut ids = self.ids.lock();
            set(&mut ids.last_any, v, begun.id);
            if changed {
                set(&mut ids.last, v, begun.id);
            }
        }
        self.entries.lock().push(Entry {
            id: begun.id,
            kind,
            vertex: Some(v),
            start_s: (begun.start - self.started).as_secs_f64(),
            duration_s,
            deps: begun.deps,
        });
    }

    /// Runs the event `action` (the state held exclusively) and traces it as one that holds
    /// the whole state.
    pub(crate) fn event<T>(&self, action: impl FnOnce() -> T) -> T {
        let id = self.ids.lock().take();
        let start = Instant::now();
        let result = action();
        let duration_s = start.elapsed().as_secs_f64();
        self.entries.lock().push(Entry {
            id,
            kind: Kind::Event,
            vertex: None,
            start_s: (start - self.started).as_secs_f64(),
            duration_s,
            deps: Vec::new(),
        });
        result
    }

    /// Starts tracing a regional event.
    pub(crate) fn begin_region(&self) -> BegunRegion {
        BegunRegion {
            id: self.ids.lock().take(),
            start: Instant::now(),
        }
    }

    /// Ends the regional event `begun`, which changed the stars of `changed` (ids as after it;
    /// appended vertices included) in `mesh` (as after it) and, with `removed`, removed that
    /// vertex, the last vertex taking its id (coarsening): it depends on the last tents and
    /// events at those vertices and their neighbours (the removed one included), and the next
    /// tents there depend on it.
    pub(crate) fn end_region(
        &self,
        begun: BegunRegion,
        mesh: &Mesh,
        changed: &[VertexId],
        removed: Option<VertexId>,
    ) {
        let duration_s = begun.start.elapsed().as_secs_f64();
        let count = mesh.vertices().len() as VertexId;
        // The id a vertex had before the event.
        let before = |v: VertexId| match removed {
            Some(m) if v == m => count,
            _ => v,
        };
        let mut ids = self.ids.lock();
        let mut deps: Vec<u64> = changed
            .iter()
            .flat_map(|&v| std::iter::once(v).chain(mesh.vertex_neighbors(v).iter().copied()))
            .map(before)
            .chain(removed)
            .flat_map(|w| [ids.last.get(w as usize), ids.last_any.get(w as usize)])
            .flatten()
            .filter(|&&last| last > 0)
            .map(|&last| last - 1)
            .collect();
        if let Some(m) = removed {
            let ids = &mut *ids;
            for table in [&mut ids.last, &mut ids.last_any] {
                let moved = table.get(count as usize).copied().unwrap_or(0);
                if let Some(slot) = table.get_mut(m as usize) {
                    *slot = moved;
                }
                table.truncate(count as usize);
            }
        }
        for &v in changed {
            set(&mut ids.last, v, begun.id);
        }
        drop(ids);
        deps.sort_unstable();
        deps.dedup();
        self.entries.lock().push(Entry {
            id: begun.id,
            kind: Kind::Region,
            vertex: None,
            start_s: (begun.start - self.started).as_secs_f64(),
            duration_s,
            deps,
        });
    }

    /// Traces the end of a deterministic round that kept the scheduler busy alone for `serial`.
    pub(crate) fn round(&self, serial: std::time::Duration) {
        let id = self.ids.lock().take();
        let start = self.started.elapsed().saturating_sub(serial);
        self.entries.lock().push(Entry {
            id,
            kind: Kind::Round,
            vertex: None,
            start_s: start.as_secs_f64(),
            duration_s: serial.as_secs_f64(),
            deps: Vec::new(),
        });
    }

    /// Writes the trace as CSV to `path`.
    pub(crate) fn write(&self, path: &Path) -> Result<(), EngineError> {
        let mut entries = self.entries.lock().clone();
        entries.sort_by_key(|e| e.id);
        let mut text = String::from("id,kind,vertex,start_s,duration_s,deps\n");
        for e in &entries {
            let deps: Vec<String> = e.deps.iter().map(u64::to_string).collect();
            let _ = writeln!(
                text,
                "{},{},{},{:e},{:e},{}",
                e.id,
                e.kind.name(),
                e.vertex.map_or(String::new(), |v| v.to_string()),
                e.start_s,
                e.duration_s,
                deps.join(";")
            );
        }
        let (dir, name) = split(path)?;
        write_atomic(dir, name, text.as_bytes()).map(drop)
    }
}

/// The folder and file name of a `--trace` path.
fn split(path: &Path) -> Result<(&Path, &str), EngineError> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| EngineError::Input(format!("--trace {}: no file name", path.display())))?;
    Ok((dir.unwrap_or(Path::new(".")), name))
}

/// Checks before the run that the trace can be written to `path` (bad input, exit 2): a file
/// name, not a folder, in a folder that can be made and written into.
pub(crate) fn check_path(path: &Path) -> Result<(), EngineError> {
    let (dir, _) = split(path)?;
    if path.is_dir() {
        return Err(EngineError::Input(format!(
            "--trace {}: is a folder; name a file",
            path.display()
        )));
    }
    crate::output::check_writable(dir, &format!("--trace {}", path.display()))
}

/// Reads a trace written by `sdg run --trace`.
pub fn read(path: &Path) -> Result<Vec<Entry>, EngineError> {
    let text = std::fs::read_to_string(path).map_err(|e| EngineError::io(path, e))?;
    let bad = |line: usize, reason: &str| {
        EngineError::Input(format!("{}:{line}: {reason}", path.display()))
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, "id,kind,vertex,start_s,duration_s,deps")) => {}
        _ => return Err(bad(1, "not a trace of `sdg run --trace` (header)")),
    }
    let mut entries = Vec::new();
    for (i, line) in lines {
        let fields: Vec<&str> = line.split(',').collect();
        let [id, kind, vertex, start, duration, deps] = fields[..] else {
            return Err(bad(i + 1, "expected 6 fields"));
        };
        let number = |s: &str, what: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| bad(i + 1, &format!("{what} is not a time in s: {s:?}")))
        };
        let entry = Entry {
            id: id.parse().map_err(|_| bad(i + 1, "bad id"))?,
            kind: Kind::parse(kind).ok_or_else(|| bad(i + 1, "unknown kind"))?,
            vertex: if vertex.is_empty() {
                None
            } else {
                Some(vertex.parse().map_err(|_| bad(i + 1, "bad vertex"))?)
            },
            start_s: number(start, "start_s")?,
            duration_s: number(duration, "duration_s")?,
            deps: deps
                .split(';')
                .filter(|d| !d.is_empty())
                .map(|d| d.parse().map_err(|_| bad(i + 1, "bad dependency")))
                .collect::<Result<_, _>>()?,
        };
        if entry.deps.iter().any(|&d| d >= entry.id) {
            return Err(bad(i + 1, "a dependency on a later tent"));
        }
        entries.push(entry);
    }
    entries.sort_by_key(|e| e.id);
    Ok(entries)
}

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
/// as the scheduler's shared counter hands them out; then the round's events and the
/// scheduler's own time on it run alone. The rounds are the same for any number of threads, so
/// the model needs no dependencies.
fn replay_rounds(entries: &[Entry], workers: usize, overhead_s: f64) -> Prediction {
    let (mut clock, mut ready_area) = (0.0, 0.0);
    for round in entries.split_inclusive(|e| e.kind == Kind::Round) {
        let (span, area) = list_schedule(round_tents(round), workers, overhead_s);
        clock += span + serial_time(round);
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
        .filter(|e| !(e.kind.is_event() || e.kind == Kind::Round))
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
    /// The deterministic scheduler's own time on its rounds (0 for an asynchronous trace).
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
        let tents_s = entries
            .split_inclusive(|e| e.kind == Kind::Round)
            .map(|round| {
                round_tents(round)
                    .map(|d| d + overhead_s)
                    .fold(0.0, f64::max)
            })
            .sum();
        return CriticalPath {
            tents_s,
            events_s: time_of(Kind::Event) + time_of(Kind::Region),
            scheduler_s,
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
struct Time(f64);

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

/// What `sdg scaling` predicts for a trace.
#[derive(Clone, Debug, PartialEq)]
pub struct Scaling {
    /// One per number of workers asked for, as the scheduler runs ([`replay`]).
    pub predictions: Vec<Prediction>,
    /// Its critical path, s.
    pub critical_s: f64,
}

/// `sdg scaling`: replays the trace at `path` on each of `workers`; with `png`, draws the
/// predicted speedups.
pub fn scaling_job(
    path: &Path,
    workers: &[usize],
    overhead_s: f64,
    png: Option<&Path>,
) -> Result<Scaling, EngineError> {
    let entries = read(path)?;
    if entries.is_empty() {
        return Err(EngineError::Input(format!(
            "{}: the trace has no tent",
            path.display()
        )));
    }
    let predict = |model: fn(&[Entry], usize, f64) -> Prediction| -> Vec<Prediction> {
        workers
            .iter()
            .map(|&w| model(&entries, w, overhead_s))
            .collect()
    };
    let scaling = Scaling {
        predictions: predict(replay),
        critical_s: critical_path(&entries, overhead_s),
    };
    if let Some(png) = png {
        let one = replay(&entries, 1, overhead_s).wall_time_s;
        let speedups = |predictions: &[Prediction]| -> Vec<(f64, f64)> {
            (predictions.iter())
                .map(|p| (p.workers as f64, one / p.wall_time_s))
                .collect()
        };
        let at = |y: f64| -> Vec<(f64, f64)> {
            (scaling.predictions.iter())
                .map(|p| (p.workers as f64, y))
                .collect()
        };
        let ideal: Vec<(f64, f64)> = (scaling.predictions.iter())
            .map(|p| (p.workers as f64, p.workers as f64))
            .collect();
        LineChart::new("predicted speedup", "workers", "speedup over 1 worker")
            .series(
                "replayed trace",
                &speedups(&scaling.predictions),
                LineStyle::Solid,
            )
            .series("ideal", &ideal, LineStyle::Dashed)
            .series(
                "critical path bound",
                &at(one / scaling.critical_s),
                LineStyle::Dashed,
            )
            .write_png(png, (900, 600))?;
    }
    Ok(scaling)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tent(id: u64, duration_s: f64, deps: &[u64]) -> Entry {
        Entry {
            id,
            kind: Kind::Patch,
            vertex: Some(id as VertexId),
            start_s: 0.0,
            duration_s,
            deps: deps.to_vec(),
        }
    }

    #[test]
    fn the_replay_follows_dependencies_workers_and_events() {
        // Two independent chains of two unit tents, then an event of 0.5 s, then one tent.
        let mut entries = vec![
            tent(0, 1.0, &[]),
            tent(1, 1.0, &[]),
            tent(2, 1.0, &[0]),
            tent(3, 1.0, &[1]),
        ];
        entries.push(Entry {
            kind: Kind::Event,
            vertex: None,
            ..tent(4, 0.5, &[])
        });
        entries.push(tent(5, 1.0, &[4]));
        let one = replay(&entries, 1, 0.0);
        assert_eq!(one.wall_time_s, 5.5);
        let two = replay(&entries, 2, 0.0);
        assert_eq!(two.wall_time_s, 3.5);
        assert_eq!(replay(&entries, 8, 0.0).wall_time_s, 3.5);
        assert_eq!(critical_path(&entries, 0.0), 3.5);
        let parts = critical_path_parts(&entries, 0.0);
        assert_eq!(
            (parts.tents_s, parts.events_s, parts.scheduler_s),
            (3.0, 0.5, 0.0)
        );
        // One worker: one tent waits while the other runs, for the first three tents.
        assert!(
            (one.mean_ready - 3.0 / 5.5).abs() < 1e-12,
            "{}",
            one.mean_ready
        );
        assert_eq!(replay(&entries, 2, 0.25).wall_time_s, 4.25);
    }

    /// A regional event waits only for its dependencies and takes one worker; an event of the
    /// other kind still runs alone.
    #[test]
    fn the_replay_lets_other_tents_run_beside_a_region_event() {
        let event = |id: u64, duration_s: f64, kind: Kind, deps: &[u64]| Entry {
            kind,
            vertex: None,
            ..tent(id, duration_s, deps)
        };
        let entries = vec![
            tent(0, 1.0, &[]),
            tent(1, 2.0, &[]),
            event(2, 0.5, Kind::Region, &[0]),
            tent(3, 1.0, &[2]),
            event(4, 0.25, Kind::Event, &[]),
            tent(5, 1.0, &[]),
        ];
        assert_eq!(regions(&entries), 1);
        // Tent 1 runs beside the event and tent 3 (1 + 0.5 + 1), then 0.25 + 1.
        assert_eq!(replay(&entries, 2, 0.0).wall_time_s, 3.75);
        assert_eq!(critical_path(&entries, 0.0), 3.75);
        let parts = critical_path_parts(&entries, 0.0);
        assert_eq!((parts.tents_s, parts.events_s), (3.5, 0.25));
        // One worker does everything in turn.
        assert_eq!(replay(&entries, 1, 0.0).wall_time_s, 5.75);
    }

    /// Two rounds: three unit tents, an event of 0.5 s and 0.25 s of the scheduler's own; then
    /// one tent of 2 s and 0.25 s.
    #[test]
    fn the_rounds_replay_hands_each_round_s_tents_to_free_workers() {
        let marker = |id: u64, duration_s: f64, kind: Kind| Entry {
            kind,
            vertex: None,
            ..tent(id, duration_s, &[])
        };
        let entries = vec![
            tent(0, 1.0, &[]),
            tent(1, 1.0, &[]),
            tent(2, 1.0, &[]),
            marker(3, 0.5, Kind::Event),
            marker(4, 0.25, Kind::Round),
            tent(5, 2.0, &[]),
            marker(6, 0.25, Kind::Round),
        ];
        assert_eq!(rounds(&entries), 2);
        let wall = |workers, overhead| replay(&entries, workers, overhead).wall_time_s;
        assert_eq!(wall(1, 0.0), 6.0);
        assert_eq!(wall(2, 0.0), 5.0);
        assert_eq!(wall(8, 0.0), 4.0);
        assert_eq!(critical_path(&entries, 0.0), 4.0);
        let parts = critical_path_parts(&entries, 0.0);
        assert_eq!(
            (parts.tents_s, parts.events_s, parts.scheduler_s),
            (3.0, 0.5, 0.5)
        );
        // Two workers: the third tent of the first round waits 1 s.
        assert_eq!(replay(&entries, 2, 0.0).mean_ready, 1.0 / 5.0);
        assert_eq!(wall(2, 0.5), 6.5);
    }

    #[test]
    fn a_written_trace_reads_back_and_bad_ones_are_refused() {
        let tracer = Tracer::new();
        let mesh = sdg_mesh::Rectangle {
            width: 1.0,
            height: 1.0,
            nx: 2,
            ny: 2,
            diagonal: sdg_mesh::Diagonal::Right,
            interfaces: Vec::new(),
            perturb: 0.0,
            seed: 0,
        }
        .build()
        .unwrap();
        let a = tracer.begin(&mesh, 0);
        tracer.end(a, 0, Kind::Patch, true);
        tracer.event(|| ());
        let b = tracer.begin(&mesh, 1);
        tracer.end(b, 1, Kind::Newton, true);
        let rejected = tracer.begin(&mesh, 8);
        tracer.end(rejected, 8, Kind::Rejected, false);
        let region = tracer.begin_region();
        tracer.end_region(region, &mesh, &[8], None);
        let c = tracer.begin(&mesh, 0);
        tracer.end(c, 0, Kind::Patch, true);
        let d = tracer.begin(&mesh, 5);
        tracer.end(d, 5, Kind::Patch, true);
        tracer.round(std::time::Duration::from_micros(3));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trace.csv");
        tracer.write(&path).unwrap();
        let entries = read(&path).unwrap();
        let kinds: Vec<Kind> = entries.iter().map(|e| e.kind).collect();
        assert_eq!(
            kinds,
            [
                Kind::Patch,
                Kind::Event,
                Kind::Newton,
                Kind::Rejected,
                Kind::Region,
                Kind::Patch,
                Kind::Patch,
                Kind::Round
            ]
        );
        assert_eq!(entries[7].duration_s, 3e-6);
        assert_eq!(rounds(&entries), 1);
        // Tents depend on the last tents at their vertex and its neighbours (vertices 0, 1, 3
        // and 4 of the 3 x 3 grid are neighbours), across an event that holds the whole state.
        assert_eq!(entries[2].deps, [0]);
        // The regional event at the corner 8 depends on the rejected tent there (its
        // neighbours 5 and 7 have had none); the later tent at 5 depends on the event and on
        // the tent at its diagonal neighbour 1.
        assert_eq!(entries[4].deps, [3]);
        assert_eq!(entries[5].deps, [0, 2]);
        assert_eq!(entries[6].deps, [2, 4]);
        std::fs::write(&path, "id,kind\n").unwrap();
        assert!(read(&path).unwrap_err().to_string().contains("header"));
        std::fs::write(
            &path,
            "id,kind,vertex,start_s,duration_s,deps\n0,patch,0,0,1,3\n",
        )
        .unwrap();
        assert!(
            read(&path)
                .unwrap_err()
                .to_string()
                .contains(":2: a dependency on a later")
        );
    }
}
