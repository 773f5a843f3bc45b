//! Recording a trace while a run goes (`sdg run --trace FILE`).

use std::path::Path;
use std::time::{Duration, Instant};

use parking_lot::Mutex;
use sdg_mesh::{Mesh, VertexId};

use super::entry::{Entry, HEADER, Kind};
use crate::error::EngineError;
use crate::output::table::Table;
use crate::output::write_atomic;

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

    /// Traces a chunk of a deterministic round's tents that a worker settled in `busy`.
    pub(crate) fn settled(&self, busy: Duration) {
        self.just_ended(Kind::Settle, busy);
    }

    /// Traces the end of a deterministic round that kept the scheduler busy alone for `serial`.
    pub(crate) fn round(&self, serial: Duration) {
        self.just_ended(Kind::Round, serial);
    }

    /// Traces an item of `kind` without vertex nor dependencies that ended now after `busy`.
    fn just_ended(&self, kind: Kind, busy: Duration) {
        let id = self.ids.lock().take();
        let start = self.started.elapsed().saturating_sub(busy);
        self.entries.lock().push(Entry {
            id,
            kind,
            vertex: None,
            start_s: start.as_secs_f64(),
            duration_s: busy.as_secs_f64(),
            deps: Vec::new(),
        });
    }

    /// Writes the trace as CSV to `path`.
    pub(crate) fn write(&self, path: &Path) -> Result<(), EngineError> {
        let mut entries = self.entries.lock().clone();
        entries.sort_by_key(|e| e.id);
        let mut table = Table::new(HEADER);
        for e in &entries {
            let deps: Vec<String> = e.deps.iter().map(u64::to_string).collect();
            table.row([
                e.id.to_string(),
                e.kind.name().to_string(),
                e.vertex.map_or(String::new(), |v| v.to_string()),
                format!("{:e}", e.start_s),
                format!("{:e}", e.duration_s),
                deps.join(";"),
            ]);
        }
        let (dir, name) = split(path)?;
        write_atomic(dir, name, table.into_text().as_bytes()).map(drop)
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
