//! The trace file: one entry per tent, event and round, and reading it back.

use std::path::Path;

use sdg_mesh::VertexId;

use crate::error::EngineError;

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
    /// A chunk of a deterministic round's tents that a worker settled after they all ran, with
    /// the readiness checks of the vertices they took; the workers share the chunks.
    Settle,
    /// The end of a deterministic round: the time the scheduler spent on it alone (choosing its
    /// vertices, recording its settled tents in order), after its tents, settling and events.
    Round,
}

impl Kind {
    pub(super) fn name(self) -> &'static str {
        match self {
            Self::Patch => "patch",
            Self::Newton => "newton",
            Self::Rejected => "rejected",
            Self::Coarsen => "coarsen",
            Self::Event => "event",
            Self::Region => "region",
            Self::Settle => "settle",
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
            Self::Settle,
            Self::Round,
        ]
        .into_iter()
        .find(|k| k.name() == name)
    }
}

impl Kind {
    /// A tent, whatever its patch did.
    pub(super) fn is_tent(self) -> bool {
        matches!(
            self,
            Self::Patch | Self::Newton | Self::Rejected | Self::Coarsen
        )
    }

    /// Events of either kind: deterministic rounds run them alone, after the round's tents.
    pub(super) fn is_event(self) -> bool {
        matches!(self, Self::Event | Self::Region)
    }

    /// What the asynchronous scheduler runs alone: every event but the regional ones.
    pub(super) fn runs_alone(self) -> bool {
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

/// The columns of a trace file.
pub(super) const HEADER: [&str; 6] = ["id", "kind", "vertex", "start_s", "duration_s", "deps"];

/// Reads a trace written by `sdg run --trace`.
pub fn read(path: &Path) -> Result<Vec<Entry>, EngineError> {
    // The trace is the command's input: one that cannot be read is bad input (exit 2).
    let text = std::fs::read_to_string(path).map_err(|e| {
        EngineError::Input(format!("{}: cannot read the trace: {e}", path.display()))
    })?;
    let bad = |line: usize, reason: &str| {
        EngineError::Input(format!("{}:{line}: {reason}", path.display()))
    };
    let line = |p: Option<&csv::Position>| p.map_or(0, |p| p.line() as usize);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(text.as_bytes());
    let mut records = reader.records();
    match records.next() {
        Some(Ok(header)) if header.iter().eq(HEADER) => {}
        _ => return Err(bad(1, "not a trace of `sdg run --trace` (header)")),
    }
    let mut entries = Vec::new();
    for record in records {
        let record = record.map_err(|e| bad(line(e.position()), &e.to_string()))?;
        let n = line(record.position());
        let [id, kind, vertex, start, duration, deps] = record.iter().collect::<Vec<_>>()[..]
        else {
            return Err(bad(n, "expected 6 fields"));
        };
        let number = |s: &str, what: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| bad(n, &format!("{what} is not a time in s: {s:?}")))
        };
        let entry = Entry {
            id: id.parse().map_err(|_| bad(n, "bad id"))?,
            kind: Kind::parse(kind).ok_or_else(|| bad(n, "unknown kind"))?,
            vertex: if vertex.is_empty() {
                None
            } else {
                Some(vertex.parse().map_err(|_| bad(n, "bad vertex"))?)
            },
            start_s: number(start, "start_s")?,
            duration_s: number(duration, "duration_s")?,
            deps: deps
                .split(';')
                .filter(|d| !d.is_empty())
                .map(|d| d.parse().map_err(|_| bad(n, "bad dependency")))
                .collect::<Result<_, _>>()?,
        };
        if entry.deps.iter().any(|&d| d >= entry.id) {
            return Err(bad(n, "a dependency on a later tent"));
        }
        entries.push(entry);
    }
    entries.sort_by_key(|e| e.id);
    Ok(entries)
}
