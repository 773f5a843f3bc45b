//! Deterministic rounds split over ranks that each hold the whole state
//! (`distributed/README.md`, "Design"): every rank runs the same rounds, settling, recording
//! and events on its own copy of the state; of each round's tents a rank solves every
//! `ranks`-th (by place in the round), and after the solves an all-gather gives every rank the
//! others' results, whose writes it applies to its copy. So the copies stay identical, and are
//! the threaded deterministic run's, bit for bit.
//!
//! What a tent writes (`tent.rs`): its vertex's front time and insist flag, the elements under
//! its star triangles and their calm flags, the interface faces over its spokes; and a guard's
//! failure to the run's [`Control`]. The requests of the ranks' controls (signals, wall time,
//! failures) travel in the same all-gather, and a round pauses on every rank when any rank
//! asked, with the union of what they asked.

use parking_lot::Mutex;
use sdg_distributed::Transport;
use sdg_mesh::TriangleId;
use sdg_scheduler::{Tried, VertexId};
use sdg_solver::element::Geometry;
use sdg_solver::face::FaceState;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::EngineError;
use crate::frontier::Frontier;

use super::control::{Control, Request};

/// A rank's part in rounds split over ranks.
pub(crate) struct Split {
    rank: usize,
    ranks: usize,
    transport: Mutex<Box<dyn Transport + Send>>,
    /// The union of the ranks' requests at the last all-gather, until the pause it asks for.
    agreed: Mutex<Option<Request>>,
    /// Requests this rank's control got after the all-gather that agreed the pause: they go
    /// to the next all-gather.
    carried: Mutex<Request>,
}

/// What a tent left under one star triangle.
#[derive(serde::Serialize, serde::Deserialize)]
struct Cell {
    triangle: TriangleId,
    calm: bool,
    geometry: Geometry,
    coefficients: Vec<f64>,
    /// The facet's energy parts, if known.
    energy: Option<[f64; 3]>,
}

/// What a tent wrote to the state, as its rank read it after the round's solves.
#[derive(serde::Serialize, serde::Deserialize)]
struct Footprint {
    time: f64,
    insist: bool,
    triangles: Vec<Cell>,
    /// The interface faces over the spokes, by edge.
    faces: Vec<(u32, FaceState)>,
}

/// One tent a rank solved: its place in the round and what it gave, its outcome `O` (an error
/// or a panic as its message).
#[derive(serde::Serialize, serde::Deserialize)]
struct Solved<O> {
    index: usize,
    result: Result<(O, Footprint), String>,
}

/// What a rank gives each round's all-gather.
#[derive(serde::Serialize, serde::Deserialize)]
struct Part<O> {
    solved: Vec<Solved<O>>,
    request: Request,
}

impl Split {
    /// Rank `transport.rank()` of `transport.ranks()`.
    pub(crate) fn new(transport: Box<dyn Transport + Send>) -> Self {
        Split {
            rank: transport.rank() as usize,
            ranks: transport.ranks(),
            transport: Mutex::new(transport),
            agreed: Mutex::new(None),
            carried: Mutex::new(Request::default()),
        }
    }

    /// Whether this is rank 0, the one that writes the run's files: the others hold copies of
    /// its state and write nothing.
    pub(crate) fn writes(&self) -> bool {
        self.rank == 0
    }

    /// The ranks the rounds are split over.
    pub(crate) fn ranks(&self) -> usize {
        self.ranks
    }

    /// Whether this rank solves the round's `index`-th tent.
    pub(crate) fn solves(&self, index: usize) -> bool {
        index % self.ranks == self.rank
    }

    /// True when the last all-gather agreed a pause (until [`Split::take_request`]).
    pub(crate) fn pause(&self) -> bool {
        self.agreed.lock().is_some()
    }

    /// The requests of the agreed pause, in place of `control`'s own: what `control` got since
    /// the all-gather goes to the next one.
    pub(crate) fn take_request(&self, control: &Control) -> Request {
        let late = control.take();
        self.carried.lock().merge(late);
        self.agreed.lock().take().unwrap_or_default()
    }
}

/// What `state` holds of the tent at `v`.
fn footprint(state: &Frontier, v: VertexId) -> Footprint {
    let (mesh, solution) = (&state.mesh, &state.solution);
    let triangles = (mesh.vertex_triangles(v).iter())
        .filter_map(|&t| {
            let element = solution.with_element(t as usize, |element| {
                element.map(|(geometry, coefficients)| (*geometry, coefficients.to_vec()))
            })?;
            Some(Cell {
                triangle: t,
                calm: state.calm(t),
                geometry: element.0,
                coefficients: element.1,
                energy: solution.energy(t as usize),
            })
        })
        .collect();
    let faces = (mesh.vertex_neighbors(v).iter())
        .filter_map(|&w| mesh.edge_between(v, w))
        .filter(|&e| (e as usize) < solution.edges())
        .filter_map(|e| solution.face(e as usize).map(|face| (e, face)))
        .collect();
    Footprint {
        time: state.front.time(v),
        insist: state.insist_flag(v),
        triangles,
        faces,
    }
}

/// Writes `print`, a tent at `v` on another rank, into `state`.
fn apply(state: &Frontier, v: VertexId, print: &Footprint) {
    state.front.set_time(v, print.time);
    state.set_insist_flag(v, print.insist);
    for cell in &print.triangles {
        state.set_calm(cell.triangle, cell.calm);
        let t = cell.triangle as usize;
        (state.solution).store(t, &cell.geometry, &cell.coefficients, cell.energy);
    }
    for (e, face) in &print.faces {
        state.solution.store_face(*e as usize, face);
    }
}

impl Split {
    /// [`sdg_scheduler::Work::exchange`] of tents whose outcomes are `O`, with `request`, what
    /// this rank's control asked since the last one.
    pub(crate) fn exchange<O: Serialize + DeserializeOwned>(
        &self,
        state: &Frontier,
        round: &[VertexId],
        results: &mut [Option<Tried<O, EngineError>>],
        request: Request,
    ) -> Result<(), EngineError> {
        let mut carried = std::mem::take(&mut *self.carried.lock());
        carried.merge(request);
        let mut part = Part {
            solved: Vec::new(),
            request: carried,
        };
        for (index, result) in results.iter_mut().enumerate() {
            let Some(tried) = result.take() else { continue };
            let v = round[index];
            let result = match tried {
                Ok(Ok(outcome)) => Ok((outcome, footprint(state, v))),
                Ok(Err(e)) => Err(e.to_string()),
                Err(panic) => Err(format!("internal error (a bug, please report it): {panic}")),
            };
            part.solved.push(Solved { index, result });
        }
        let rank = self.rank;
        let mut bytes = Vec::new();
        ciborium::into_writer(&part, &mut bytes)
            .map_err(|e| EngineError::Runtime(format!("rank {rank}: {e}")))?;
        let gathered = (self.transport.lock().all_gather(bytes))
            .map_err(|e| EngineError::Runtime(format!("rank {rank}: {e}")))?;
        let mut union = Request::default();
        for (from, bytes) in gathered.iter().enumerate() {
            let part: Part<O> = ciborium::from_reader(&bytes[..])
                .map_err(|e| EngineError::Runtime(format!("rank {rank}: from rank {from}: {e}")))?;
            union.merge(part.request);
            for Solved { index, result } in part.solved {
                let v = round[index];
                results[index] = Some(Ok(match result {
                    Ok((outcome, print)) => {
                        if from != rank {
                            apply(state, v, &print);
                        }
                        Ok(outcome)
                    }
                    Err(message) => Err(EngineError::Runtime(format!("rank {from}: {message}"))),
                }));
            }
        }
        if union.any() {
            *self.agreed.lock() = Some(union);
        }
        Ok(())
    }
}
