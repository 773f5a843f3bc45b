//! Tracing a run for scaling studies (`sdg run --trace FILE`) and replaying the trace on any
//! number of simulated workers (`sdg scaling FILE --workers 1,2,4,...`).
//!
//! A trace lists every tent with its vertex, its kind, when it ran, how long it took and the
//! earlier tents it depends on: the last tents at its vertex and at the vertex's neighbours
//! (their front times and the elements it reads), and the last scheduler event. Events (mesh
//! changes, history rows) hold the whole state: every tent before an event precedes it and
//! every tent after follows it.
//!
//! The replay models the asynchronous scheduler: a tent is ready once its dependencies are done,
//! and each free worker takes the ready tent that came first in the trace, paying a fixed claim
//! overhead per tent; an event waits for every tent before it and runs alone. It predicts the
//! wall time, the critical path (the time with unlimited workers) and the mean number of ready
//! tents. The costs are those measured in the traced run, so the model leaves out what more
//! threads do to each tent (shared caches and memory bandwidth).

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
    /// A scheduler event.
    Event,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Self::Patch => "patch",
            Self::Newton => "newton",
            Self::Rejected => "rejected",
            Self::Coarsen => "coarsen",
            Self::Event => "event",
        }
    }

    fn parse(name: &str) -> Option<Self> {
        [
            Self::Patch,
            Self::Newton,
            Self::Rejected,
            Self::Coarsen,
            Self::Event,
        ]
        .into_iter()
        .find(|k| k.name() == name)
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

/// Records the trace of a running solve.
#[derive(Debug)]
pub(crate) struct Tracer {
    started: Instant,
    /// The next id, the last event's id plus one (0: none yet) and per vertex the last tent's
    /// id plus one.
    ids: Mutex<Ids>,
    entries: Mutex<Vec<Entry>>,
}

#[derive(Debug, Default)]
struct Ids {
    next: u64,
    last_event: u64,
    last: Vec<u64>,
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
        let id = ids.next;
        ids.next += 1;
        let after = ids.last_event;
        let mut deps: Vec<u64> = std::iter::once(&v)
            .chain(mesh.vertex_neighbors(v))
            .filter_map(|&w| ids.last.get(w as usize).copied())
            .filter(|&last| last > after)
            .map(|last| last - 1)
            .collect();
        drop(ids);
        if after > 0 {
            deps.push(after - 1);
        }
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
        if changed {
            let mut ids = self.ids.lock();
            if ids.last.len() <= v as usize {
                ids.last.resize(v as usize + 1, 0);
            }
            ids.last[v as usize] = begun.id + 1;
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

    /// Runs the event `action` (the state held exclusively) and traces it.
    pub(crate) fn event<T>(&self, action: impl FnOnce() -> T) -> T {
        let id = {
            let mut ids = self.ids.lock();
            ids.next += 1;
            ids.next - 1
        };
        let start = Instant::now();
        let result = action();
        let duration_s = start.elapsed().as_secs_f64();
        self.ids.lock().last_event = id + 1;
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
        let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
        let name = path.file_name().and_then(|n| n.to_str()).ok_or_else(|| {
            EngineError::Input(format!("--trace {}: no file name", path.display()))
        })?;
        write_atomic(dir.unwrap_or(Path::new(".")), name, text.as_bytes()).map(drop)
    }
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

/// Replays `entries` on `workers` simulated workers with `overhead_s` of claiming per tent.
pub fn replay(entries: &[Entry], workers: usize, overhead_s: f64) -> Prediction {
    let workers = workers.max(1);
    let (mut clock, mut ready_area) = (0.0, 0.0);
    for segment in entries.split(|e| e.kind == Kind::Event) {
        let (span, area) = replay_segment(segment, workers, overhead_s);
        clock += span;
        ready_area += area;
    }
    clock += entries
        .iter()
        .filter(|e| e.kind == Kind::Event)
        .map(|e| e.duration_s)
        .sum::<f64>();
    Prediction {
        workers,
        wall_time_s: clock,
        mean_ready: ready_area / clock.max(f64::MIN_POSITIVE),
    }
}

/// The time with unlimited workers: the longest chain of dependencies, events included, s.
pub fn critical_path(entries: &[Entry], overhead_s: f64) -> f64 {
    let events: f64 = entries
        .iter()
        .filter(|e| e.kind == Kind::Event)
        .map(|e| e.duration_s)
        .sum();
    let segments: f64 = entries
        .split(|e| e.kind == Kind::Event)
        .map(|segment| {
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
        })
        .sum();
    segments + events
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

/// `sdg scaling`: replays the trace at `path` on each of `workers`; prints a table and, with
/// `png`, draws the predicted speedup. Returns the predictions and the critical path (s).
pub fn scaling_job(
    path: &Path,
    workers: &[usize],
    overhead_s: f64,
    png: Option<&Path>,
) -> Result<(Vec<Prediction>, f64), EngineError> {
    let entries = read(path)?;
    if entries.is_empty() {
        return Err(EngineError::Input(format!(
            "{}: the trace has no tent",
            path.display()
        )));
    }
    let predictions: Vec<Prediction> = workers
        .iter()
        .map(|&w| replay(&entries, w, overhead_s))
        .collect();
    let critical = critical_path(&entries, overhead_s);
    if let Some(png) = png {
        let one = replay(&entries, 1, overhead_s).wall_time_s;
        let points: Vec<(f64, f64)> = predictions
            .iter()
            .map(|p| (p.workers as f64, one / p.wall_time_s))
            .collect();
        let ideal: Vec<(f64, f64)> = predictions
            .iter()
            .map(|p| (p.workers as f64, p.workers as f64))
            .collect();
        let bound = one / critical;
        let limit: Vec<(f64, f64)> = predictions
            .iter()
            .map(|p| (p.workers as f64, bound))
            .collect();
        LineChart::new("predicted speedup", "workers", "speedup over 1 worker")
            .series("replayed trace", &points, LineStyle::Solid)
            .series("ideal", &ideal, LineStyle::Dashed)
            .series("critical path bound", &limit, LineStyle::Dashed)
            .write_png(png, (900, 600))?;
    }
    Ok((predictions, critical))
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
        // One worker: one tent waits while the other runs, for the first three tents.
        assert!(
            (one.mean_ready - 3.0 / 5.5).abs() < 1e-12,
            "{}",
            one.mean_ready
        );
        assert_eq!(replay(&entries, 2, 0.25).wall_time_s, 4.25);
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
        let c = tracer.begin(&mesh, 0);
        tracer.end(c, 0, Kind::Patch, true);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trace.csv");
        tracer.write(&path).unwrap();
        let entries = read(&path).unwrap();
        let kinds: Vec<Kind> = entries.iter().map(|e| e.kind).collect();
        assert_eq!(kinds, [Kind::Patch, Kind::Event, Kind::Newton, Kind::Patch]);
        // After the event only the event and the later tent at a neighbour are dependencies.
        assert_eq!(entries[2].deps, [1]);
        assert_eq!(entries[3].deps, [1, 2]);
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
