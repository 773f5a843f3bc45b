//! The ranks' results gathered on rank 0: the whole mesh's front, elements and interface faces,
//! every tent with its patch's report, and the ranks' message counts.
//!
//! A triangle's element is on every rank holding the triangle, all copies the same at the end
//! ([`crate::solving`]); each is gathered once, from the rank owning the triangle's first
//! corner, and each interface face from the rank owning its edge's first end. Each rank packs
//! what it owns into three [`Message::Update`]s (cells, tents, counts), which other ranks send
//! to rank 0 after the run, through the same transport; [`gather_threads`] packs and unpacks
//! the same messages (through their bytes) without sending them, so that the in-process path
//! checks the encoding the MPI path relies on.

use std::time::Duration;

use sdg_mesh::{Front, Mesh, Tent, VertexId};
use sdg_solver::element::{FrontSolution, GEOMETRY_VALUES, Geometry};
use sdg_solver::face::{FACE_GEOMETRY_VALUES, FaceGeometry, FaceState, MAX_FACE_BASIS};
use sdg_solver::patch::PatchReport;

use crate::partition::Rank;
use crate::pitching::{PitchingError, RankReport, SolvedPatch};
use crate::solving::RankSolution;
use crate::transport::{Cells, Message, Transport, Update};
use crate::view::LocalView;

/// The three messages a rank sends rank 0, told apart by [`Update::vertex`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    /// Elements (energy parts and coefficients) and interface faces the rank owns.
    Cells = 0,
    /// Tents (`[t_old, t_new, slope, report...]` by global vertex; those the rank kept,
    /// [`crate::Options::keep_tents`]) and owned front times.
    Tents = 1,
    /// The rank's message counts and its outputs ([`RankReport::outputs`]).
    Counts = 2,
}

const PARTS: usize = 3;

/// Values of the counts part before the rank's [`RankReport::outputs`].
const COUNTS: usize = 7;

/// Values of a [`PatchReport`] in a tent's cell.
const REPORT_VALUES: usize = 17;

/// What rank 0 gathers.
#[derive(Debug)]
pub struct Gathered {
    /// Front times by global vertex, s.
    pub front: Front,
    /// Elements by global triangle and interface faces by global edge.
    pub solution: FrontSolution,
    /// Every tent (global vertex ids) with its patch, by rank in the order each pitched them
    /// (those the ranks kept, [`crate::Options::keep_tents`]).
    pub tents: Vec<(Tent, SolvedPatch)>,
    /// Per rank, its report without tents or patches (those are in `tents`).
    pub reports: Vec<RankReport>,
    /// Per rank, how many tents it pitched ([`RankReport::pitched`]), kept or not.
    pub tents_by_rank: Vec<u64>,
}

impl Gathered {
    /// An empty gathering for `mesh` with elements of `basis_len` functions of `width` fields.
    fn new(mesh: &Mesh, basis_len: usize, width: usize, ranks: usize) -> Self {
        Self {
            front: Front::flat(mesh.vertices().len(), 0.0),
            solution: FrontSolution::new(mesh.triangles().len(), basis_len, width)
                .with_edges(mesh.edges().len()),
            tents: Vec::new(),
            reports: vec![RankReport::default(); ranks],
            tents_by_rank: vec![0; ranks],
        }
    }

    /// The tents with their patches in the serial reference order, `(t_old, global vertex)`.
    pub fn in_serial_order(&self) -> Vec<(Tent, SolvedPatch)> {
        let mut tents = self.tents.clone();
        tents.sort_by(|a, b| {
            a.0.t_old
                .total_cmp(&b.0.t_old)
                .then(a.0.vertex.cmp(&b.0.vertex))
        });
        tents
    }

    /// Stores the part `message` of rank `from`.
    fn add(&mut self, from: Rank, message: &Message) -> Result<(), PitchingError> {
        let bad = |what: &str| PitchingError::Gather {
            rank: from,
            reason: what.to_string(),
        };
        let Message::Update(update) = message else {
            return Err(bad("not an update"));
        };
        let stride = self.solution.basis_len() * self.solution.width();
        match update.vertex {
            v if v == Part::Cells as u32 => {
                let cells = &update.elements;
                if cells.values.len() != cells.len() * (GEOMETRY_VALUES + 3 + stride) {
                    return Err(bad("elements of the wrong size"));
                }
                for i in 0..cells.len() {
                    let (t, _, values) = cells.get(i);
                    if t as usize >= self.solution.len() {
                        return Err(bad("an element of a triangle the mesh has not"));
                    }
                    let (geometry, rest) = values.split_at(GEOMETRY_VALUES);
                    let (energy, coefficients) = rest.split_at(3);
                    let geometry = Geometry::from_values(geometry.try_into().expect("split"));
                    let energy: [f64; 3] = energy.try_into().expect("split");
                    let energy = energy.iter().all(|x| !x.is_nan()).then_some(energy);
                    self.solution
                        .store(t as usize, &geometry, coefficients, energy);
                }
                let faces = &update.faces;
                if faces.values.len() != faces.len() * FACE_VALUES {
                    return Err(bad("interface faces of the wrong size"));
                }
                for i in 0..faces.len() {
                    let (e, _, values) = faces.get(i);
                    if e as usize >= self.solution.edges() {
                        return Err(bad("a face of an edge the mesh has not"));
                    }
                    self.solution.store_face(e as usize, &face_from(values));
                }
            }
            v if v == Part::Tents as u32 => {
                let tents = &update.elements;
                if tents.values.len() != tents.len() * (3 + REPORT_VALUES) {
                    return Err(bad("tents of the wrong size"));
                }
                for i in 0..tents.len() {
                    let (vertex, _, values) = tents.get(i);
                    let tent = Tent {
                        vertex,
                        t_old: values[0],
                        t_new: values[1],
                    };
                    let patch = SolvedPatch {
                        slope: values[2],
                        report: report_from(&values[3..]),
                    };
                    self.tents.push((tent, patch));
                }
                let times = &update.faces;
                for i in 0..times.len() {
                    let (v, _, time) = times.get(i);
                    if v as usize >= self.front.len() || time.len() != 1 {
                        return Err(bad("a front time of a vertex the mesh has not"));
                    }
                    self.front.set_time(v, time[0]);
                }
            }
            v if v == Part::Counts as u32 => {
                let values = &update.elements.values;
                let (Some(report), Some(pitched)) = (
                    self.reports.get_mut(from as usize),
                    self.tents_by_rank.get_mut(from as usize),
                ) else {
                    return Err(bad("counts of a rank the run has not"));
                };
                if values.len() < COUNTS {
                    return Err(bad("counts of the wrong size"));
                }
                *pitched = values[6] as u64;
                *report = RankReport {
                    rank: from,
                    updates_sent: values[0] as u64,
                    update_bytes: values[1] as u64,
                    updates_applied: values[2] as u64,
                    updates_stale: values[3] as u64,
                    boundary_vertices: values[4] as usize,
                    waited: Duration::from_secs_f64(values[5]),
                    pitched: values[6] as u64,
                    outputs: values[COUNTS..].to_vec(),
                    ..RankReport::default()
                };
            }
            _ => return Err(bad("an unknown part")),
        }
        Ok(())
    }
}

/// Values per interface face: its geometry's, then its coefficients.
const FACE_VALUES: usize =
    FACE_GEOMETRY_VALUES + sdg_solver::face::STATE_COMPONENTS * MAX_FACE_BASIS;

fn face_from(values: &[f64]) -> FaceState {
    let (geometry, coefficients) = values.split_at(FACE_GEOMETRY_VALUES);
    FaceState {
        geometry: FaceGeometry::from_values(geometry.try_into().expect("split")),
        coefficients: std::array::from_fn(|k| {
            std::array::from_fn(|j| coefficients[k * MAX_FACE_BASIS + j])
        }),
    }
}

fn report_values(r: &PatchReport) -> [f64; REPORT_VALUES] {
    [
        r.elements as f64,
        r.dofs as f64,
        r.energy_in,
        r.energy_out,
        r.boundary_work,
        r.interface_work,
        r.friction_dissipation,
        r.fracture_work,
        r.dissipation,
        r.momentum_residual,
        r.momentum_imbalance,
        r.momentum_flux,
        r.newton_iterations as f64,
        r.cohesive_mismatch,
        r.assembly_s,
        r.solve_s,
        r.evaluation_s,
    ]
}

fn report_from(v: &[f64]) -> PatchReport {
    PatchReport {
        elements: v[0] as usize,
        dofs: v[1] as usize,
        energy_in: v[2],
        energy_out: v[3],
        boundary_work: v[4],
        interface_work: v[5],
        friction_dissipation: v[6],
        fracture_work: v[7],
        dissipation: v[8],
        momentum_residual: v[9],
        momentum_imbalance: v[10],
        momentum_flux: v[11],
        newton_iterations: v[12] as usize,
        cohesive_mismatch: v[13],
        assembly_s: v[14],
        solve_s: v[15],
        evaluation_s: v[16],
    }
}

/// The three parts of what rank `view.rank()` owns at the end of a run, as messages to rank 0.
fn parts(
    view: &LocalView,
    front: &Front,
    solution: &FrontSolution,
    report: &RankReport,
) -> [Message; PARTS] {
    let mesh = view.mesh();
    let owns = |v: VertexId| view.owner(v) == view.rank();
    let mut elements = Cells::default();
    for (t, corners) in mesh.triangles().iter().enumerate() {
        if !owns(corners[0]) {
            continue;
        }
        let energy = solution.energy(t).unwrap_or([f64::NAN; 3]);
        solution.with_element(t, |element| {
            if let Some((geometry, coefficients)) = element {
                elements.ids.push((view.global_triangle(t as u32), 0));
                elements.values.extend(geometry.to_values());
                elements.values.extend(energy);
                elements.values.extend_from_slice(coefficients);
            }
        });
    }
    let mut faces = Cells::default();
    for (e, edge) in mesh.edges().iter().enumerate() {
        if let Some(face) = solution.face(e).filter(|_| owns(edge.vertices[0])) {
            faces.ids.push((view.global_edge(e as u32), 0));
            faces.values.extend(face.geometry.to_values());
            faces.values.extend(face.coefficients.iter().flatten());
        }
    }
    let mut tents = Cells::default();
    for (tent, patch) in report.tents.iter().zip(&report.patches) {
        tents.ids.push((tent.vertex, 0));
        tents.values.extend([tent.t_old, tent.t_new, patch.slope]);
        tents.values.extend(report_values(&patch.report));
    }
    let mut times = Cells::default();
    for v in (0..mesh.vertices().len() as VertexId).filter(|&v| owns(v)) {
        times.ids.push((view.global(v), 0));
        times.values.push(front.time(v));
    }
    let counts = Cells {
        ids: vec![(view.rank(), 0)],
        values: vec![
            report.updates_sent as f64,
            report.update_bytes as f64,
            report.updates_applied as f64,
            report.updates_stale as f64,
            report.boundary_vertices as f64,
            report.waited.as_secs_f64(),
            report.pitched as f64,
        ]
        .into_iter()
        .chain(report.outputs.iter().copied())
        .collect(),
    };
    let update = |part: Part, elements, faces| {
        Message::Update(Update {
            vertex: part as u32,
            time: 0.0,
            generation: view.rank(),
            elements,
            faces,
            work: Vec::new(),
        })
    };
    [
        update(Part::Cells, elements, faces),
        update(Part::Tents, tents, times),
        update(Part::Counts, counts, Cells::default()),
    ]
}

/// Gathers the results of every rank of one process ([`crate::solve_threads`]) on `mesh`,
/// through the bytes of the messages [`gather`] sends.
pub fn gather_threads(mesh: &Mesh, ranks: &[RankSolution]) -> Result<Gathered, PitchingError> {
    let solution = &ranks.first().expect("at least one rank").solution;
    let mut gathered = Gathered::new(mesh, solution.basis_len(), solution.width(), ranks.len());
    let mut bytes = Vec::new();
    for rank in ranks {
        for message in parts(&rank.view, &rank.front, &rank.solution, &rank.report) {
            bytes.clear();
            message.encode(&mut bytes);
            let message = Message::decode(&bytes).map_err(|source| PitchingError::Transport {
                rank: rank.view.rank(),
                source,
            })?;
            gathered.add(rank.view.rank(), &message)?;
        }
    }
    Ok(gathered)
}

/// Gathers the results of the ranks of `transport` on rank 0, after [`crate::solve_rank`]
/// returned `report` on this rank with `front` and `solution` on `view`: every other rank
/// sends its parts and returns `None`; rank 0 waits up to `timeout` for each message and
/// returns what every rank owns on `mesh`. Call it only once every rank has returned from
/// `solve_rank` (after a barrier such as `MpiTransport::sum`): a part arriving on rank 0
/// while it still pitches would be taken for an update.
pub fn gather<T: Transport>(
    mesh: &Mesh,
    view: &LocalView,
    (front, solution, report): (&Front, &FrontSolution, &RankReport),
    transport: &mut T,
    timeout: Duration,
) -> Result<Option<Gathered>, PitchingError> {
    let rank = view.rank();
    let failed = |source| PitchingError::Transport { rank, source };
    if rank != 0 {
        for message in parts(view, front, solution, report) {
            transport.send(0, message).map_err(failed)?;
        }
        return Ok(None);
    }
    let ranks = transport.ranks();
    let mut gathered = Gathered::new(mesh, solution.basis_len(), solution.width(), ranks);
    for message in parts(view, front, solution, report) {
        gathered.add(0, &message)?;
    }
    for _ in 0..PARTS * (ranks - 1) {
        match transport.receive(timeout).map_err(failed)? {
            Some((from, Message::Abort)) => return Err(PitchingError::Aborted { rank, by: from }),
            Some((from, message)) => gathered.add(from, &message)?,
            None => {
                return Err(PitchingError::Gather {
                    rank,
                    reason: format!("no result came in {timeout:?}"),
                });
            }
        }
    }
    Ok(Some(gathered))
}
