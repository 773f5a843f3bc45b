//! One tent's patch: the spacetime DG equations on its tetrahedra, assembled and solved at once.
//!
//! Weak form (see `docs/method.md`): on every element `K` of the patch, for every test function
//! `phi` in the complete polynomials of degree `p`,
//!
//! `int_K phi . (A0 q_tau + Ax q_x + Ay q_y) + sum over faces F of int_F phi . (F* - A_n q) = 0`
//!
//! with the target flux `F*`: the earlier side's flux `A_n q_prev` on the inflow (bottom) face,
//! the element's own `A_n q` on the outflow (top) face, and the Riemann flux `A_m q*` on the
//! vertical faces, which couple the ring of elements around the tent pole, or carry the boundary
//! data. The patch system is solved by block elimination around the ring of elements
//! ([`crate::ring`]).
//!
//! Above an interface edge the vertical faces take their targets from the interface's law
//! ([`crate::interface`]): bonded faces keep the linear path, free faces are traction-free on
//! both sides (still linear), and contact faces make the patch a Newton solve (`contact`).

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{Accum, MatMut, MatRef, Par};

use sdg_mesh::{EdgeId, Front, Mesh, TagId, Tent, TriangleId, VertexId};

use crate::basis::Basis;
use crate::boundary::{Boundary, Condition};
use crate::crack::Crossing;
use crate::element::{FrontSolution, Geometry, SpacePoint, evaluate};
use crate::exact::PlaneWave;
use crate::face::FaceState;
use crate::interface::{Contact, Interfaces, Law};
use crate::quadrature::{self, Rule};
use crate::riemann::{self, Side};
use crate::ring::BlockSystem;
use crate::system::{FrameTrace, MAX_FIELDS, Matrix, State, System};

mod contact;
pub(crate) mod tables;

use contact::{ContactFaces, FaceShape};
pub use contact::{Newton, NewtonFailure};
use tables::FaceTables;

/// Energy terms and diagnostics of one solved element, in scaled units (physical: times the
/// density; see [`crate::system`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ElementReport {
    /// Energy entering through the inflow face.
    pub energy_in: f64,
    /// Energy leaving through the outflow face (now part of the front).
    pub energy_out: f64,
    /// `energy_out` split as `[kinetic, strain, flux]` (see `norms::FrontEnergy`).
    pub energy_out_parts: [f64; 3],
    /// Net power entering through the vertical faces, integrated over them.
    pub vertical_work: f64,
    /// Part of `vertical_work` through the domain boundary.
    pub boundary_work: f64,
    /// Energy taken out of the element by interface faces (minus their part of
    /// `vertical_work`): summed over both sides of a face, the work absorbed by the interface.
    pub interface_work: f64,
    /// Part of `interface_work` done by tangential tractions on tangential velocity jumps of
    /// contact faces: friction.
    pub friction_dissipation: f64,
    /// Part of `interface_work` done on cohesive faces: the work of separation spent so far
    /// (fracture energy; for the reversible Xu-Needleman law, partly stored until the faces
    /// separate fully).
    pub fracture_work: f64,
    /// Numerical dissipation from the jumps against the targets: a sum of non-negative terms.
    pub dissipation: f64,
    /// Dissipation from the energy balance `energy_in - energy_out + vertical_work`; equal to
    /// `dissipation` to round-off when the element equations hold.
    pub dissipation_balance: f64,
    /// `|sum over faces of the momentum target flux|` (scaled units): zero to round-off when
    /// the element balances linear momentum.
    pub momentum_imbalance: f64,
    /// Sum over faces of the magnitude of the momentum target flux (scaled units).
    pub momentum_flux: f64,
    /// `momentum_imbalance / momentum_flux`: zero to round-off when the element balances
    /// linear momentum and its fluxes are not themselves round-off (an element at rest reads
    /// anything up to 1).
    pub momentum_residual: f64,
}

/// Totals over one patch.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct PatchReport {
    /// Elements solved.
    pub elements: usize,
    /// Unknowns of the linear system.
    pub dofs: usize,
    /// Sum of the element reports' fields.
    pub energy_in: f64,
    /// See [`ElementReport::energy_out`].
    pub energy_out: f64,
    /// See [`ElementReport::boundary_work`].
    pub boundary_work: f64,
    /// See [`ElementReport::interface_work`].
    pub interface_work: f64,
    /// See [`ElementReport::friction_dissipation`].
    pub friction_dissipation: f64,
    /// See [`ElementReport::fracture_work`].
    pub fracture_work: f64,
    /// See [`ElementReport::dissipation`].
    pub dissipation: f64,
    /// Largest [`ElementReport::momentum_residual`] of its elements.
    pub momentum_residual: f64,
    /// Largest [`ElementReport::momentum_imbalance`] of its elements.
    pub momentum_imbalance: f64,
    /// Largest [`ElementReport::momentum_flux`] of its elements.
    pub momentum_flux: f64,
    /// Newton iterations (linear solves) of a patch with nonlinear faces; zero for a linear
    /// patch.
    pub newton_iterations: usize,
    /// The cohesive indicator's measure: the work of the mismatch between the cohesive traction
    /// of the faces' separation and of the elements' displacement jump (see
    /// `ContactFaces::cohesive_mismatch`), scaled units like `dissipation`.
    pub cohesive_mismatch: f64,
    /// Wall time assembling the patch's system, s (measured: not the same from run to run).
    pub assembly_s: f64,
    /// Wall time solving it (the ring elimination, or the Newton iterations), s.
    pub solve_s: f64,
    /// Wall time evaluating the results (energies, displacements, interface states), s.
    pub evaluation_s: f64,
}

/// The state of a contact interface at one point, physical units, in the frame of the face
/// (normal, tangential; each value is the same whichever side the normal points from).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InterfaceSample {
    /// Time, s.
    pub time: f64,
    /// Target traction `s*`, Pa.
    pub traction: [f64; 2],
    /// Bonded Riemann traction `sI`, Pa.
    pub bonded_traction: [f64; 2],
    /// Normal separation, m.
    pub delta: f64,
    /// Tangential slip, m.
    pub slip: f64,
    /// Damage `D` in effect (the debonded fraction) with the damage law; 0 with other laws.
    pub damage: f64,
    /// Jump of the target velocities `[[v*]]`, m/s.
    pub velocity_jump: [f64; 2],
    /// Contact area fraction.
    pub eta: f64,
    /// Stick flag.
    pub gamma: f64,
    /// The mode with the largest area fraction.
    pub mode: crate::interface::Mode,
}

/// Initial data: the state at `t = 0`, a plane wave or rest.
#[derive(Clone, Copy, Debug)]
pub enum Initial<'a> {
    /// Zero velocity, stress and displacement.
    Rest,
    /// The exact solution at `t = 0`.
    Wave(&'a PlaneWave),
}

/// Per element of the patch being solved.
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    /// The front triangle the element's top face (`TOP`) becomes.
    triangle: TriangleId,
    vertices: [SpacePoint; 4],
    geometry: Geometry,
    /// Inflow faces, each with the index of the element below it in [`Inflow`]: one for a tent
    /// element.
    inflow: [(Face, usize); 2],
    inflow_count: usize,
    /// Vertical faces.
    sides: [Vertical; 2],
    side_count: usize,
}

/// A vertical face of a patch element.
#[derive(Clone, Copy, Debug, Default)]
struct Vertical {
    face: Face,
    /// The patch element across it (none on the domain boundary).
    neighbour: Option<usize>,
    /// Tag and id of its space edge.
    tag: Option<TagId>,
    edge: EdgeId,
    /// On a coarsening patch's face over the restored edge `ab` (then `edge` is the half `ma`):
    /// the other half `mb`.
    split: Option<EdgeId>,
    /// Its index among the patch's contact faces.
    contact: Option<usize>,
}

/// A face of a tetrahedron: its corners (indices into the element's vertices) and the opposite one.
type Face = ([usize; 3], usize);
const TOP: Face = ([1, 2, 3], 0);
/// Vertical face over the edge from the tent vertex to corner `a` (vertex 1), then to `b`.
const SIDE_A: Face = ([0, 1, 3], 2);
const SIDE_B: Face = ([0, 2, 3], 1);

impl Slot {
    fn inflows(&self) -> &[(Face, usize)] {
        &self.inflow[..self.inflow_count]
    }

    fn sides(&self) -> &[Vertical] {
        &self.sides[..self.side_count]
    }
}

/// A face quadrature rule and the reference tables at its points.
#[derive(Clone, Debug)]
struct FaceQuadrature {
    rule: Rule<2>,
    tables: FaceTables,
}

/// The inflow face of a tent element whose tent vertex is corner `corner` of its triangle, its
/// corners in the triangle's own vertex order: quadrature points on a front triangle are then the
/// same whichever vertex pitches it, so integrals of initial data match
/// [`crate::norms::front_energy`] exactly.
fn tent_bottom(corner: usize) -> Face {
    // Tetrahedron vertex k (k < 3) is triangle corner (corner + k) mod 3.
    ([0, 1, 2].map(|k| (k + 3 - corner) % 3), 3)
}

/// A face's first corner, its two edge vectors from there, its outward unit normal and twice
/// its area.
fn face_geometry(
    vertices: &[SpacePoint; 4],
    (corners, opposite): Face,
) -> (SpacePoint, [f64; 3], [f64; 3], [f64; 3], f64) {
    let [q0, q1, q2] = corners.map(|i| vertices[i]);
    let e1 = [0, 1, 2].map(|i| q1[i] - q0[i]);
    let e2 = [0, 1, 2].map(|i| q2[i] - q0[i]);
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let away = [0, 1, 2].map(|i| q0[i] - vertices[opposite][i]);
    let sign = if n[0] * away[0] + n[1] * away[1] + n[2] * away[2] < 0.0 {
        -1.0
    } else {
        1.0
    };
    (q0, e1, e2, n.map(|c| sign * c / norm), norm)
}

/// Visits the quadrature points of a face in physical coordinates with physical weights and the
/// outward unit normal.
fn face_points(
    rule: &Rule<2>,
    vertices: &[SpacePoint; 4],
    face: Face,
    mut visit: impl FnMut(SpacePoint, f64, [f64; 3]),
) {
    let (q0, e1, e2, n, area2) = face_geometry(vertices, face);
    for (p, &w) in rule.points.iter().zip(&rule.weights) {
        let x = [0, 1, 2].map(|i| q0[i] + p[0] * e1[i] + p[1] * e2[i]);
        visit(x, w * area2, n);
    }
}

/// Solves tent patches of one physical problem; holds all scratch memory, so solving a patch
/// allocates nothing.
pub struct PatchSolver {
    system: System,
    basis: Basis,
    /// Face rules: of degree `2p` for polynomial integrands (between solved elements), and
    /// `2p + 2` for boundary and initial data and nonlinear faces.
    exact: FaceQuadrature,
    data: FaceQuadrature,
    /// `H[r][k * n + l] = int_ref phi_k d(phi_l)/d(xi_r)`.
    h_ref: [Vec<f64>; 3],
    slots: Vec<Slot>,
    blocks: BlockSystem,
    order: Vec<usize>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    stack: MemBuffer,
    small: Vec<f64>,
    small_rhs: Vec<f64>,
    /// Basis values of another element at a face's points, when not tabulated (`points x n`),
    /// and its traces (`n x face_dim`).
    other_values: Vec<f64>,
    trace: Vec<f64>,
    /// The state and displacement below each inflow face at its rule points, from the
    /// assembly for the energy terms and the displacement: `2 x data points` per slot.
    below_states: Vec<(State, [f64; 2])>,
    phi: Vec<f64>,
    values: Vec<f64>,
    output: Vec<f64>,
    inflow: Inflow,
    reports: Vec<ElementReport>,
    used: usize,
    interfaces: Interfaces,
    newton: Newton,
    contact: ContactFaces,
    /// Newton iterate, `N(Q)` and residual: one value per patch unknown.
    iterate: Vec<f64>,
    nonlinear: Vec<f64>,
    residual: Vec<f64>,
    /// Interface states of the last patch's contact faces, stored by [`Self::commit`].
    faces: Vec<(EdgeId, FaceState)>,
}

impl std::fmt::Debug for PatchSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PatchSolver")
            .field("system", &self.system)
            .field("order", &self.basis.degree())
            .field("max_star", &self.slots.len())
            .finish_non_exhaustive()
    }
}

impl PatchSolver {
    /// A solver for polynomial order `order` (1 to 4) on meshes whose vertex stars have at most
    /// `max_star` triangles.
    pub fn new(system: System, order: usize, max_star: usize) -> Self {
        let basis = Basis::new(order);
        let n = basis.len();
        let fields = system.fields();
        let width = fields + system.displacement_components();
        let vol_rule = quadrature::tetrahedron(2 * order);
        let mut h_ref = [vec![0.0; n * n], vec![0.0; n * n], vec![0.0; n * n]];
        let mut phi = vec![0.0; n];
        let mut grads = vec![[0.0; 3]; n];
        for (xi, &w) in vol_rule.points.iter().zip(&vol_rule.weights) {
            basis.eval_with_gradient(*xi, &mut phi, &mut grads);
            for (r, h) in h_ref.iter_mut().enumerate() {
                for k in 0..n {
                    for l in 0..n {
                        h[k * n + l] += w * phi[k] * grads[l][r];
                    }
                }
            }
        }
        let lu = |m: usize| {
            StackReq::any_of(&[
                factor::lu_in_place_scratch::<usize, f64>(m, m, Par::Seq, Default::default()),
                solve::solve_in_place_scratch::<usize, f64>(m, 2, Par::Seq),
            ])
        };
        let [exact, data] = [2 * order, 2 * order + 2].map(|degree| {
            let rule = quadrature::triangle(degree);
            let tables = FaceTables::new(&basis, &rule);
            FaceQuadrature { rule, tables }
        });
        Self {
            other_values: vec![0.0; data.tables.points() * n],
            below_states: vec![([0.0; MAX_FIELDS], [0.0; 2]); max_star * 2 * data.tables.points()],
            trace: vec![0.0; n * data.tables.face_dim()],
            exact,
            data,
            h_ref,
            slots: vec![Slot::default(); max_star],
            blocks: BlockSystem::new(max_star, n * fields),
            order: Vec::with_capacity(max_star),
            perm: vec![0; n],
            perm_inv: vec![0; n],
            stack: MemBuffer::new(lu(n)),
            small: vec![0.0; n * n],
            small_rhs: vec![0.0; 2 * n],
            phi,
            values: vec![0.0; width],
            output: vec![0.0; max_star * n * width],
            inflow: Inflow {
                solved: vec![false; max_star],
                geometry: vec![Geometry::default(); max_star],
                coefficients: vec![0.0; max_star * n * width],
                size: n * width,
            },
            reports: vec![ElementReport::default(); max_star],
            used: 0,
            interfaces: Interfaces::default(),
            newton: Newton::default(),
            contact: ContactFaces::new(0, order, 0, n, 0),
            iterate: Vec::new(),
            nonlinear: Vec::new(),
            residual: Vec::new(),
            faces: Vec::new(),
            system,
            basis,
        }
    }

    /// The same solver with interface laws by tag (interior edges without one are bonded) and
    /// the Newton settings for patches with nonlinear faces. Contact laws need an in-plane
    /// system.
    pub fn with_interfaces(mut self, interfaces: Interfaces, newton: Newton) -> Self {
        if interfaces.any_nonlinear() {
            // Scratch of Newton patches, only for runs that have them.
            let (max_star, n) = (self.slots.len(), self.basis.len());
            let size = max_star * n * self.system.fields();
            let points = self.data.rule.points.len();
            let order = self.basis.degree();
            self.contact = ContactFaces::new(max_star, order, points, n, size / max_star);
            self.iterate = vec![0.0; size];
            self.nonlinear = vec![0.0; size];
            self.residual = vec![0.0; size];
            self.faces = Vec::with_capacity(max_star);
        }
        self.interfaces = interfaces;
        self.newton = newton;
        self
    }

    /// The system solved.
    pub fn system(&self) -> &System {
        &self.system
    }

    /// The basis of every element.
    pub fn basis(&self) -> &Basis {
        &self.basis
    }

    /// Values stored per basis function: the fields, then the displacement components.
    pub fn width(&self) -> usize {
        self.system.fields() + self.system.displacement_components()
    }

    /// Reports of the elements of the last patch, in the order of the vertex star.
    pub fn element_reports(&self) -> &[ElementReport] {
        &self.reports[..self.used]
    }

    /// Solves the patch of `tent` on `front` (only the times of the tent vertex's neighbours are
    /// read; the tent gives its own) with inflow from the elements in `solution`, which it does
    /// not change: [`Self::commit`] stores the result. The caller owns the star: no other thread
    /// touches these triangles, their edges or the neighbours' times meanwhile. Fails when the
    /// Newton iterations of a patch with contact faces do not converge. The same as
    /// [`Self::prepare`] then [`Self::solve_prepared`].
    pub fn solve(
        &mut self,
        mesh: &Mesh,
        front: &Front,
        tent: &Tent,
        boundary: &Boundary,
        initial: Initial,
        solution: &FrontSolution,
    ) -> Result<PatchReport, NewtonFailure> {
        self.prepare(mesh, front, tent, solution);
        self.solve_prepared(boundary, initial)
    }

    /// Copies everything the patch of `tent` reads from `mesh`, `front` and `solution` into the
    /// solver (the star's geometry, the inflow elements, the interface states below its contact
    /// faces), so that [`Self::solve_prepared`] can solve it while others change them.
    pub fn prepare(&mut self, mesh: &Mesh, front: &Front, tent: &Tent, solution: &FrontSolution) {
        let c = self.system.c_ref();
        let v = tent.vertex;
        let star = mesh.vertex_triangles(v);
        let d = star.len();
        assert!(
            d <= self.slots.len(),
            "vertex star larger than the solver was sized for"
        );
        self.used = d;
        let pv = mesh.vertex(v);
        for (i, (slot, &t)) in self.slots.iter_mut().zip(star).enumerate() {
            let tri = mesh.triangles()[t as usize];
            let corner = tri
                .iter()
                .position(|&w| w == v)
                .expect("star triangle contains v");
            let (a, b) = (tri[(corner + 1) % 3], tri[(corner + 2) % 3]);
            let at = |w: u32| {
                let p = mesh.vertex(w);
                [p[0], p[1], c * front.time(w)]
            };
            let vertices = [
                [pv[0], pv[1], c * tent.t_old],
                at(a),
                at(b),
                [pv[0], pv[1], c * tent.t_new],
            ];
            *slot = Slot {
                triangle: t,
                vertices,
                geometry: Geometry::new(&vertices),
                inflow: [(tent_bottom(corner), i), (TOP, usize::MAX)],
                inflow_count: 1,
                sides: vertical_faces(mesh, star, t, corner),
                side_count: 2,
            };
        }

        self.inflow.gather(star, solution);
        self.find_contact_faces(solution);
    }

    /// Solves the patch [`Self::prepare`] read, as [`Self::solve`] does.
    pub fn solve_prepared(
        &mut self,
        boundary: &Boundary,
        initial: Initial,
    ) -> Result<PatchReport, NewtonFailure> {
        self.solve_slots(boundary, initial)
    }

    /// Solves the coarsening patch that removes vertex `m`, the midpoint of edge `ends` (as
    /// [`Mesh::coarsenable`] reports it): one tetrahedron `(m, z, a, b)` per parent triangle
    /// `(z, a, b)` of `m`'s bisection, between the two children `(m, z, a)` and `(m, b, z)` on
    /// `front` (inflow, each from its own element in `solution`) and the parent's facet through
    /// `a`, `b`, `z` (outflow); the vertical face over `ab` couples the two parents, or carries
    /// the boundary condition. This is the tent at `m` raised onto edge `ab`, with one polynomial
    /// per parent (seed Fig. 4.6), so that every parent again lies on one element. The caller
    /// checks that `m` is below edge `ab` on the front and that the parents' facets are causal.
    /// [`Self::commit_to`] stores the result. On an interface with its own law, the face over
    /// `ab` inherits its separation from the faces over the halves `ma` and `mb` (two inflow
    /// segments): the interface state crosses the coarsening without projection, like the
    /// bulk; [`Self::interface_faces`] has it under the edge of the half `ma`. Returns `None`
    /// when `m` is not coarsenable or the patch's Newton iterations do not converge.
    pub fn solve_coarsening(
        &mut self,
        mesh: &Mesh,
        front: &Front,
        m: VertexId,
        boundary: &Boundary,
        initial: Initial,
        solution: &FrontSolution,
    ) -> Option<PatchReport> {
        let ends = mesh.coarsenable(m)?;
        let c = self.system.c_ref();
        let at = |w: VertexId| {
            let p = mesh.vertex(w);
            [p[0], p[1], c * front.time(w)]
        };
        // Children (m, z, a): the ones whose corner after m is an apex and before m an end.
        let mut sources = [0; 4];
        let mut parents = 0;
        for &t in mesh.vertex_triangles(m) {
            let tri = mesh.triangles()[t as usize];
            let k = tri
                .iter()
                .position(|&w| w == m)
                .expect("star triangle contains m");
            let (z, a) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
            if !ends.contains(&a) {
                continue;
            }
            let b = if a == ends[0] { ends[1] } else { ends[0] };
            let other = *mesh
                .vertex_triangles(m)
                .iter()
                .find(|&&u| {
                    let o = mesh.triangles()[u as usize];
                    o.contains(&b) && o.contains(&z)
                })
                .expect("the sibling child (m, b, z) is in the star");
            let e = mesh.triangle_edges(t)[(k + 1) % 3];
            let tag = mesh.edges()[e as usize].tag;
            // The half m b, for the interface face over the restored edge.
            let split = (self.interfaces.law(tag) != Law::Bonded).then(|| {
                *mesh
                    .triangle_edges(other)
                    .iter()
                    .find(|&&h| {
                        let ends = mesh.edges()[h as usize].vertices;
                        ends.contains(&m) && ends.contains(&b)
                    })
                    .expect("the sibling child has the half m b")
            });
            sources[2 * parents] = t;
            sources[2 * parents + 1] = other;
            let vertices = [at(m), at(z), at(a), at(b)];
            self.slots[parents] = Slot {
                triangle: t,
                vertices,
                geometry: Geometry::new(&vertices),
                inflow: [
                    (([0, 1, 2], 3), 2 * parents),
                    (([0, 3, 1], 2), 2 * parents + 1),
                ],
                inflow_count: 2,
                sides: [
                    Vertical {
                        face: ([0, 2, 3], 1),
                        tag,
                        edge: e,
                        split,
                        ..Default::default()
                    },
                    Vertical::default(),
                ],
                side_count: 1,
            };
            parents += 1;
        }
        if parents == 2 {
            self.slots[0].sides[0].neighbour = Some(1);
            self.slots[1].sides[0].neighbour = Some(0);
        }
        self.used = parents;
        self.inflow.gather(&sources[..2 * parents], solution);
        self.find_contact_faces(solution);
        self.solve_slots(boundary, initial).ok()
    }

    /// Assembles and solves the patch of the first `self.used` slots, whose inflow sources and
    /// contact faces are gathered, and computes the element reports.
    fn solve_slots(
        &mut self,
        boundary: &Boundary,
        initial: Initial,
    ) -> Result<PatchReport, NewtonFailure> {
        let started = Instant::now();
        let c = self.system.c_ref();
        let d = self.used;
        let n = self.basis.len();
        let fields = self.system.fields();
        let m = n * fields;
        self.blocks.reset(d, m);
        let a_mu = [
            self.system.a_n([1.0, 0.0, 0.0]),
            self.system.a_n([0.0, 1.0, 0.0]),
            self.system.a_n([0.0, 0.0, 1.0]),
        ];
        for i in 0..d {
            let slot = self.slots[i];
            // The diagonal block is a sum of Kronecker products, added at the end: 3 volume
            // terms, one per inflow face, one per vertical face.
            let mut diagonal: [(&[f64], Matrix); 7] = [(&[], [[0.0; MAX_FIELDS]; MAX_FIELDS]); 7];
            let mut terms = 0;
            // Volume: det * sum_r H_r (x) B_r with B_r = sum_mu inverse[r][mu] A_mu.
            let inv = slot.geometry.inverse();
            let det = slot.geometry.det();
            for (h, inv_r) in self.h_ref.iter().zip(inv) {
                let mut b = [[0.0; MAX_FIELDS]; MAX_FIELDS];
                for (a, &factor) in a_mu.iter().zip(inv_r) {
                    for (brow, arow) in b.iter_mut().zip(a) {
                        for (x, y) in brow.iter_mut().zip(arow) {
                            *x += det * factor * y;
                        }
                    }
                }
                diagonal[terms] = (h, b);
                terms += 1;
            }
            // Inflow faces: the target is the earlier side's trace.
            let stride = self.data.tables.points();
            for (f, &(face, source)) in slot.inflows().iter().enumerate() {
                let own = FaceTables::triple(face.0);
                let (_, _, _, nrm, area2) = face_geometry(&slot.vertices, face);
                let an = self.system.a_n(nrm);
                let kept = &mut self.below_states[(2 * i + f) * stride..][..stride];
                let (quadrature, under) = inflow_values(
                    [&self.exact, &self.data],
                    &self.basis,
                    &mut self.other_values,
                    &slot,
                    face,
                    self.inflow.below(source),
                );
                let (rule, tables) = (&quadrature.rule, &quadrature.tables);
                let system = &self.system;
                let mut points = tables.values(own).chunks_exact(n).enumerate();
                let rhs = self.blocks.rhs_mut(i);
                face_points(rule, &slot.vertices, face, |x, w, _| {
                    let (q, phi) = points.next().expect("one per rule point");
                    let under = under.map(|(v, c)| (&v[q * n..][..n], c));
                    let q_prev = inflow_state(system, under, initial, x);
                    kept[q] = (q_prev, inflow_displacement(system, under, initial, x));
                    let aq = system.apply(&an, &q_prev);
                    for (k, p) in phi.iter().enumerate() {
                        for (r, a) in rhs[k * fields..][..fields].iter_mut().zip(&aq) {
                            *r -= w * p * a;
                        }
                    }
                });
                diagonal[terms] = (tables.mass(own), an.map(|row| row.map(|x| -area2 * x)));
                terms += 1;
            }
            let system = &self.system;
            // Vertical faces: Riemann fluxes with the ring neighbour or the boundary data; free
            // interfaces are traction-free on each side. Contact faces are assembled bonded: the
            // Newton iterations add the difference of their targets from the bonded ones.
            for side in slot.sides() {
                let (face, tag) = (side.face, side.tag);
                let law = side.neighbour.map(|_| self.interfaces.law(tag));
                let (neighbour, condition) = match law {
                    Some(Law::Free) => (None, &Condition::Free),
                    _ => (side.neighbour, boundary.condition(tag)),
                };
                let own = FaceTables::triple(face.0);
                let (_, _, _, nrm, area2) = face_geometry(&slot.vertices, face);
                let normal = [nrm[0], nrm[1]];
                let a_m = system.a_n([normal[0], normal[1], 0.0]);
                let (m_a, m_b) =
                    face_matrices(system, boundary, condition, neighbour.is_some(), normal);
                let self_block: Matrix = std::array::from_fn(|r| {
                    std::array::from_fn(|c| area2 * (m_a[r][c] - a_m[r][c]))
                });
                diagonal[terms] = (self.exact.tables.mass(own), self_block);
                terms += 1;
                let Some(j) = neighbour else {
                    let mut points = self.data.tables.values(own).chunks_exact(n);
                    let rhs = self.blocks.rhs_mut(i);
                    face_points(&self.data.rule, &slot.vertices, face, |x, w, _| {
                        let phi = points.next().expect("one per rule point");
                        let sides = boundary.sides(
                            system,
                            condition,
                            [x[0], x[1]],
                            x[2] / c,
                            normal,
                            false,
                        );
                        let g = system.flux(
                            &riemann::solve(system, &FrameTrace::default(), &sides),
                            normal,
                        );
                        for (k, p) in phi.iter().enumerate() {
                            for (r, gc) in rhs[k * fields..][..fields].iter_mut().zip(&g) {
                                *r -= w * p * gc;
                            }
                        }
                    });
                    continue;
                };
                // Face mass (T_i T_j^T area2) (x) (L R^T): rank face_dim x rank(m_b).
                let trace_j = neighbour_trace(
                    &self.exact.tables,
                    &self.basis,
                    &mut self.other_values,
                    &mut self.trace,
                    &self.exact.rule,
                    (&slot, face),
                    &self.slots[j],
                );
                let (trace_i, nf) = (self.exact.tables.trace(own), self.exact.tables.face_dim());
                let (rank, l, r) = low_rank(&m_b, fields);
                let (u, v) = self.blocks.term_mut(nf * rank);
                for (k, (ti, tj)) in trace_i
                    .chunks_exact(nf)
                    .zip(trace_j.chunks_exact(nf))
                    .enumerate()
                {
                    for f in 0..nf {
                        for s in 0..rank {
                            let column = (f * rank + s) * m + k * fields;
                            for a in 0..fields {
                                u[column + a] = area2 * ti[f] * l[a][s];
                                v[column + a] = tj[f] * r[a][s];
                            }
                        }
                    }
                }
                self.blocks.add_term(i, j, nf * rank, 1.0);
            }
            kron_sum(
                self.blocks.new_block_mut(i, i),
                Accum::Replace,
                m,
                n,
                fields,
                &diagonal[..terms],
            );
        }

        ring_order(&self.slots[..d], &mut self.order);
        let assembled = Instant::now();
        let newton_iterations = if self.contact.faces().is_empty() {
            self.blocks.solve(&self.order[..d]);
            0
        } else {
            self.solve_newton()?
        };
        let solved = Instant::now();

        let mut report = PatchReport {
            elements: d,
            dofs: d * m,
            newton_iterations,
            assembly_s: (assembled - started).as_secs_f64(),
            solve_s: (solved - assembled).as_secs_f64(),
            ..Default::default()
        };
        for i in 0..d {
            let r = self.element_post(i, boundary);
            report.energy_in += r.energy_in;
            report.energy_out += r.energy_out;
            report.boundary_work += r.boundary_work;
            report.interface_work += r.interface_work;
            report.friction_dissipation += r.friction_dissipation;
            report.fracture_work += r.fracture_work;
            report.dissipation += r.dissipation;
            report.momentum_residual = report.momentum_residual.max(r.momentum_residual);
            report.momentum_imbalance = report.momentum_imbalance.max(r.momentum_imbalance);
            report.momentum_flux = report.momentum_flux.max(r.momentum_flux);
            self.reports[i] = r;
            self.displacement(i);
        }
        self.faces.clear();
        self.faces.extend(self.contact.finish());
        self.contact.find_crossings(c);
        let (fields, width, output) = (self.system.fields(), self.width(), &self.output);
        report.cohesive_mismatch = self.contact.cohesive_mismatch(|i, phi| {
            let mut u = [0.0; 2];
            for (k, ph) in phi.iter().enumerate() {
                let at = &output[(i * n + k) * width + fields..];
                u[0] += ph * at[0];
                u[1] += ph * at[1];
            }
            u
        });
        report.evaluation_s = solved.elapsed().as_secs_f64();
        Ok(report)
    }

    /// Registers the vertical faces between patch elements whose edge has a contact law, once
    /// per face (from the element of smaller index, side a), and marks them on both elements.
    fn find_contact_faces(&mut self, solution: &FrontSolution) {
        self.contact.clear();
        for i in 0..self.used {
            for s in 0..self.slots[i].side_count {
                let side = self.slots[i].sides[s];
                let (Some(j), Some(law)) = (
                    side.neighbour,
                    Contact::of(&self.system, &self.interfaces.law(side.tag)),
                ) else {
                    continue;
                };
                if j < i {
                    continue;
                }
                assert!(
                    (side.edge as usize) < solution.edges(),
                    "contact faces need interface state on the front (FrontSolution::with_edges)"
                );
                let slot = self.slots[i];
                let corners = side.face.0.map(|k| slot.vertices[k]);
                let shape = match side.split {
                    None => FaceShape::tent(corners, side.edge),
                    Some(half) => FaceShape::coarsening(corners, [side.edge, half]),
                };
                let (rule, geometry_b) = (&self.data.rule, self.slots[j].geometry);
                let index = self.contact.add(
                    (i, j),
                    (&slot.geometry, &geometry_b),
                    law,
                    &shape,
                    &self.basis,
                    solution,
                    |visit| face_points(rule, &slot.vertices, side.face, visit),
                );
                self.slots[i].sides[s].contact = Some(index);
                let count = self.slots[j].side_count;
                let across = self.slots[j].sides[..count]
                    .iter_mut()
                    .find(|v| v.neighbour == Some(i))
                    .expect("a face's elements are each other's neighbours");
                across.contact = Some(index);
            }
        }
    }

    /// Solves the assembled patch with contact faces (assembled bonded) by Newton iterations
    /// from the bonded solution; leaves the solution where [`BlockSystem::rhs`] has it. Returns
    /// the number of linear solves.
    fn solve_newton(&mut self) -> Result<usize, NewtonFailure> {
        let d = self.used;
        let size = d * self.basis.len() * self.system.fields();
        let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
        let b_norm = norm(self.blocks.rhs());
        self.blocks.save();
        self.blocks.solve(&self.order[..d]);
        let (q, nl, r) = (
            &mut self.iterate[..size],
            &mut self.nonlinear[..size],
            &mut self.residual[..size],
        );
        q.copy_from_slice(self.blocks.rhs());
        let failure = |iterations, residual| NewtonFailure {
            iterations,
            residual,
        };
        let mut iterations = 1;
        loop {
            nl.fill(0.0);
            if !self.contact.evaluate(&self.system, q, nl) {
                return Err(failure(iterations, f64::NAN));
            }
            self.blocks.residual(q, r);
            for (ri, ni) in r.iter_mut().zip(nl.iter()) {
                *ri -= ni;
            }
            let scale = b_norm + norm(nl);
            let relative = if scale > 0.0 { norm(r) / scale } else { 0.0 };
            if !relative.is_finite() {
                return Err(failure(iterations, relative));
            }
            if relative <= self.newton.tol {
                break;
            }
            if iterations == self.newton.max_iter {
                return Err(failure(iterations, relative));
            }
            self.blocks.restore();
            self.contact.add_jacobians(&self.system, &mut self.blocks);
            let m = size / d;
            for i in 0..d {
                self.blocks
                    .rhs_mut(i)
                    .copy_from_slice(&r[i * m..(i + 1) * m]);
            }
            self.blocks.solve(&self.order[..d]);
            for (qi, dq) in q.iter_mut().zip(self.blocks.rhs()) {
                *qi += dq;
            }
            iterations += 1;
        }
        let m = size / d;
        for i in 0..d {
            self.blocks
                .rhs_mut(i)
                .copy_from_slice(&q[i * m..(i + 1) * m]);
        }
        Ok(iterations)
    }

    /// Replaces the elements under the star's front triangles in `solution` by the last patch
    /// solved: its tent is accepted. The caller still owns the star.
    pub fn commit(&self, solution: &FrontSolution) {
        self.commit_to(solution, |t| t);
    }

    /// Stores the elements of the last patch in `solution` under the triangles `id(t)`, where `t`
    /// is the triangle each element's top face was built for: the tent's star triangles, or for
    /// a coarsening patch the child `(m, z, a)` whose id the parent takes, moved by renumbering.
    pub fn commit_to(&self, solution: &FrontSolution, id: impl Fn(TriangleId) -> TriangleId) {
        for ((t, geometry, coefficients), report) in self.elements().zip(&self.reports) {
            let energy = Some(report.energy_out_parts);
            solution.store(id(t) as usize, geometry, coefficients, energy);
        }
        for (e, face) in &self.faces {
            solution.store_face(*e as usize, face);
        }
    }

    /// Where the last patch's cohesive faces crossed the crack-tracking levels
    /// ([`crate::crack`]).
    pub fn crack_crossings(&self) -> &[Crossing] {
        self.contact.crossings()
    }

    /// The interface faces of the last patch: per contact face, its edge and interface state.
    pub fn interface_faces(&self) -> &[(EdgeId, FaceState)] {
        &self.faces
    }

    /// The interface of the last patch at the point `x` (m) of edge `edge`, halfway up the
    /// contact face over it there; `None` when the patch has no contact face over `edge` or the
    /// face has no height at `x` (its far end).
    pub fn interface_sample(&mut self, edge: EdgeId, x: [f64; 2]) -> Option<InterfaceSample> {
        let f = self.contact.faces().iter().position(|f| f.edge == edge)?;
        let face = &self.contact.faces()[f];
        let [p0, p1, p2] = face.geometry.corners();
        let length = face.geometry.length();
        let along = ((x[0] - p0[0]) * (p1[0] - p0[0]) + (x[1] - p0[1]) * (p1[1] - p0[1]))
            / (length * length);
        let bottom = p0[2] + along * (p1[2] - p0[2]);
        let top = p2[2] + along * (p1[2] - p2[2]);
        if top - bottom <= 1e-9 * (p2[2] - p0[2]) {
            return None;
        }
        self.interface_sample_at(edge, [x[0], x[1], 0.5 * (bottom + top)])
    }

    /// The interface of the last patch at the point `point` (scaled spacetime) of the contact
    /// face over edge `edge`; `None` when the patch has no contact face over `edge`.
    pub fn interface_sample_at(
        &mut self,
        edge: EdgeId,
        point: SpacePoint,
    ) -> Option<InterfaceSample> {
        let f = self.contact.faces().iter().position(|f| f.edge == edge)?;
        let face = &self.contact.faces()[f];
        let (law, normal, sides) = (face.law, face.normal, [face.a, face.b]);
        let (n, width, fields) = (self.basis.len(), self.width(), self.system.fields());
        let [qa, qb] = sides.map(|i| {
            let coefficients = &self.output[i * n * width..(i + 1) * n * width];
            let geometry = &self.slots[i].geometry;
            evaluate(
                &self.basis,
                geometry,
                coefficients,
                point,
                &mut self.phi,
                &mut self.values,
            );
            let mut q = [0.0; MAX_FIELDS];
            q[..fields].copy_from_slice(&self.values[..fields]);
            q
        });
        let state = self.contact.state_at(f, point);
        let (w_a, w_b) = crate::interface::characteristics(
            law.z,
            &self.system.frame(&qa, normal),
            &self.system.frame(&qb, normal),
        );
        let (a, b) = (law.targets(w_a, w_b, state), law.targets(w_b, w_a, state));
        let z_ref = self.system.z_ref();
        Some(InterfaceSample {
            time: point[2] / self.system.c_ref(),
            traction: a.star.s.map(|s| s * z_ref),
            bonded_traction: a.bonded_traction.map(|s| s * z_ref),
            delta: state[0],
            slip: state[1],
            damage: if law.damage.is_some() { a.damage } else { 0.0 },
            // Side b's frame velocities flip with its normal.
            velocity_jump: [-b.star.v[0] - a.star.v[0], -b.star.v[1] - a.star.v[1]],
            eta: a.eta,
            gamma: a.gamma,
            mode: a.mode(),
        })
    }

    /// The elements of the last patch: the triangle each was built for (see
    /// [`Self::commit_to`]), its geometry and its coefficients.
    pub fn elements(&self) -> impl Iterator<Item = (TriangleId, &Geometry, &[f64])> {
        let size = self.basis.len() * self.width();
        self.slots[..self.used]
            .iter()
            .zip(self.output.chunks_exact(size))
            .map(|(slot, c)| (slot.triangle, &slot.geometry, c))
    }

    /// Energy terms and diagnostics of element `i` after the solve; also copies its field
    /// coefficients into the output buffer.
    fn element_post(&mut self, i: usize, boundary: &Boundary) -> ElementReport {
        let n = self.basis.len();
        let fields = self.system.fields();
        let nv = self.system.displacement_components();
        let m = n * fields;
        let width = self.width();
        let c = self.system.c_ref();
        let slot = self.slots[i];
        let solution = self.blocks.rhs();
        for k in 0..n {
            let out = &mut self.output[i * n * width + k * width..][..fields];
            out.copy_from_slice(&solution[i * m + k * fields..][..fields]);
        }
        let system = &self.system;
        // The element's state at point q of the rule of `tables` on its face `face`.
        let own = |tables: &FaceTables, face: Face, q: usize| {
            let phi = tables.at(FaceTables::triple(face.0), q);
            combine(&solution[i * m..(i + 1) * m], phi, fields)
        };
        let mut r = ElementReport::default();
        let mut momentum = [0.0; 2];
        let mut scale = 0.0;
        let mut add_momentum = |face: [f64; 2]| {
            for (a, b) in momentum.iter_mut().zip(face) {
                *a += b;
            }
            scale += face[0].hypot(face[1]);
        };
        let (exact, data) = (&self.exact, &self.data);
        let mut face_momentum = [0.0; 2];
        let mut point = 0..;
        face_points(&exact.rule, &slot.vertices, TOP, |_, w, nrm| {
            let q = own(&exact.tables, TOP, point.next().expect("unbounded"));
            let aq = system.apply(&system.a_n(nrm), &q);
            let out = 0.5 * w * system.dot(&q, &aq);
            let kinetic = w * nrm[2] * system.kinetic_density(&q);
            let strain = w * nrm[2] * system.energy_density(&q) - kinetic;
            r.energy_out += out;
            r.energy_out_parts[0] += kinetic;
            r.energy_out_parts[1] += strain;
            r.energy_out_parts[2] += out - kinetic - strain;
            for (f, a) in face_momentum.iter_mut().zip(&aq[..nv]) {
                *f += w * a;
            }
        });
        add_momentum(face_momentum);
        let stride = data.tables.points();
        for (f, &(face, source)) in slot.inflows().iter().enumerate() {
            // The rule and the states below of the assembly.
            let quadrature = if self.inflow.solved[source] {
                exact
            } else {
                data
            };
            let (rule, tables) = (&quadrature.rule, &quadrature.tables);
            let kept = &self.below_states[(2 * i + f) * stride..][..stride];
            face_momentum = [0.0; 2];
            let mut point = 0..;
            face_points(rule, &slot.vertices, face, |_, w, nrm| {
                let p = point.next().expect("unbounded");
                let an = system.a_n(nrm);
                let q_prev = kept[p].0;
                let q = own(tables, face, p);
                let aq_prev = system.apply(&an, &q_prev);
                r.energy_in -= 0.5 * w * system.dot(&q_prev, &aq_prev);
                let jump = std::array::from_fn(|k| q[k] - q_prev[k]);
                r.dissipation -= 0.5 * w * system.dot(&jump, &system.apply(&an, &jump));
                for (f, a) in face_momentum.iter_mut().zip(&aq_prev[..nv]) {
                    *f += w * a;
                }
            });
            add_momentum(face_momentum);
        }
        for side in slot.sides() {
            let condition = boundary.condition(side.tag);
            let law = side.neighbour.map(|_| self.interfaces.law(side.tag));
            let contact = side.contact.map(|f| {
                let face = &self.contact.faces()[f];
                if face.a == i {
                    &face.targets_a
                } else {
                    &face.targets_b
                }
            });
            // Polynomial integrands between linear elements; boundary data and nonlinear faces
            // (whose states the contact faces hold at the data rule's points) take the other.
            let polynomial = law.is_some_and(|law| !law.is_nonlinear());
            let quadrature = if polynomial { exact } else { data };
            let (rule, tables) = (&quadrature.rule, &quadrature.tables);
            let across = side.neighbour.map(|j| {
                let other = &self.slots[j];
                let (scratch, basis) = (&mut self.other_values, &self.basis);
                let at = (&slot, side.face);
                other_values(
                    tables,
                    basis,
                    scratch,
                    rule,
                    at,
                    &other.geometry,
                    &other.vertices,
                )
            });
            face_momentum = [0.0; 2];
            let mut point = 0;
            face_points(rule, &slot.vertices, side.face, |x, w, nrm| {
                let normal = [nrm[0], nrm[1]];
                let a = system.frame(&own(tables, side.face, point), normal);
                let star_trace = match (side.neighbour, law) {
                    (Some(_), Some(law)) if law.is_nonlinear() => {
                        contact.expect("contact faces are registered")[point].star
                    }
                    (Some(_), Some(Law::Free)) => {
                        riemann::solve(system, &a, &[Side::Traction(0.0); 2])
                    }
                    (Some(j), _) => {
                        let phi_j = &across.expect("a neighbour")[point * n..][..n];
                        let q_b = combine(&solution[j * m..(j + 1) * m], phi_j, fields);
                        riemann::bonded(system, &a, &system.frame(&q_b, normal))
                    }
                    (None, _) => {
                        let sides = boundary.sides(
                            system,
                            condition,
                            [x[0], x[1]],
                            x[2] / c,
                            normal,
                            false,
                        );
                        riemann::solve(system, &a, &sides)
                    }
                };
                let power = w
                    * (0..system.directions())
                        .map(|k| star_trace.v[k] * star_trace.s[k])
                        .sum::<f64>();
                point += 1;
                r.vertical_work += power;
                match law {
                    None => r.boundary_work += power,
                    Some(Law::Bonded) => {}
                    Some(law) => {
                        r.interface_work -= power;
                        if law.is_cohesive() {
                            r.fracture_work -= power;
                        } else {
                            r.friction_dissipation -= w * star_trace.v[1] * star_trace.s[1];
                        }
                    }
                }
                r.dissipation += w * riemann::dissipation(system, &a, &star_trace);
                let f = system.flux(&star_trace, normal);
                for (fm, a) in face_momentum.iter_mut().zip(&f[..nv]) {
                    *fm += w * a;
                }
            });
            add_momentum(face_momentum);
        }
        r.dissipation_balance = r.energy_in - r.energy_out + r.vertical_work;
        r.momentum_imbalance = momentum[0].hypot(momentum[1]);
        r.momentum_flux = scale;
        r.momentum_residual = r.momentum_imbalance / scale.max(f64::MIN_POSITIVE);
        r
    }

    /// Solves `du/dtau = v / c_ref` on element `i` (upwind in time from the element below) and
    /// stores the displacement coefficients in the output buffer.
    fn displacement(&mut self, i: usize) {
        let n = self.basis.len();
        let fields = self.system.fields();
        let nv = self.system.displacement_components();
        let width = self.width();
        let c = self.system.c_ref();
        let slot = self.slots[i];
        let det = slot.geometry.det();
        let inv_tau = [0, 1, 2].map(|r| slot.geometry.inverse()[r][2]);
        let small = &mut self.small[..n * n];
        let rhs = &mut self.small_rhs[..n * nv];
        for k in 0..n {
            for l in 0..n {
                small[l * n + k] = det
                    * (0..3)
                        .map(|r| self.h_ref[r][k * n + l] * inv_tau[r])
                        .sum::<f64>();
            }
            for d in 0..nv {
                rhs[d * n + k] = det * self.output[i * n * width + k * width + d] / c;
            }
        }
        let stride = self.data.tables.points();
        for (f, &(face, source)) in slot.inflows().iter().enumerate() {
            // The rule and the displacements below of the assembly.
            let quadrature = if self.inflow.solved[source] {
                &self.exact
            } else {
                &self.data
            };
            let (rule, tables) = (&quadrature.rule, &quadrature.tables);
            let kept = &self.below_states[(2 * i + f) * stride..][..stride];
            let (_, _, _, nrm, area2) = face_geometry(&slot.vertices, face);
            let own = FaceTables::triple(face.0);
            for (s, mass) in small.iter_mut().zip(tables.mass(own)) {
                // The mass is symmetric: row-major or column-major alike.
                *s -= area2 * nrm[2] * mass;
            }
            let mut points = tables.values(own).chunks_exact(n).enumerate();
            face_points(rule, &slot.vertices, face, |_, w, nrm| {
                let (q, phi) = points.next().expect("one per rule point");
                let u_prev = kept[q].1;
                for (k, p) in phi.iter().enumerate() {
                    for d in 0..nv {
                        rhs[d * n + k] -= w * nrm[2] * p * u_prev[d];
                    }
                }
            });
        }
        let stack = MemStack::new(&mut self.stack);
        let lu = MatMut::from_column_major_slice_mut(small, n, n);
        let (_, perm) = factor::lu_in_place(
            lu,
            &mut self.perm[..n],
            &mut self.perm_inv[..n],
            Par::Seq,
            stack,
            Default::default(),
        );
        let lu = MatRef::from_column_major_slice(&self.small[..n * n], n, n);
        let x = MatMut::from_column_major_slice_mut(&mut self.small_rhs[..n * nv], n, nv);
        solve::solve_in_place(lu, lu, perm, x, Par::Seq, stack);
        for k in 0..n {
            for d in 0..nv {
                self.output[i * n * width + k * width + fields + d] = self.small_rhs[d * n + k];
            }
        }
    }
}

/// Adds the sum of Kronecker products `sum_t scalar_t (x) block_t` to the column-major `m x m`
/// matrix `target` (`Accum::Add`), or stores it there (`Accum::Replace`, every entry written):
/// entry `(k, l)` of each `n x n` row-major `scalar_t` scales `block_t` at rows `k fields..`,
/// columns `l fields..`, with `m = n fields`. The blocks are combined per `(k, l)` first, so
/// `target` is written once whatever the number of terms.
fn kron_sum(
    target: &mut [f64],
    accum: Accum,
    m: usize,
    n: usize,
    fields: usize,
    terms: &[(&[f64], Matrix)],
) {
    for l in 0..n {
        for k in 0..n {
            let mut sum = [[0.0; MAX_FIELDS]; MAX_FIELDS];
            for (scalar, block) in terms {
                let s = scalar[k * n + l];
                for (row, b) in sum.iter_mut().zip(block) {
                    for (x, y) in row.iter_mut().zip(b) {
                        *x += s * y;
                    }
                }
            }
            for (b, col) in (l * fields..).take(fields).enumerate() {
                let column = &mut target[col * m + k * fields..][..fields];
                let values = column.iter_mut().zip(&sum);
                match accum {
                    Accum::Add => values.for_each(|(t, row)| *t += row[b]),
                    Accum::Replace => values.for_each(|(t, row)| *t = row[b]),
                }
            }
        }
    }
}

/// Orders the star's elements along the ring around the pole: each chain from its element
/// without a neighbour across its first side (`SIDE_A`, boundary tents), then closed rings,
/// walking across the second (`SIDE_B`, counter-clockwise). Elimination in this order fills only
/// blocks that couple to a ring's last element.
fn ring_order(slots: &[Slot], order: &mut Vec<usize>) {
    order.clear();
    let d = slots.len();
    let next = |i: usize| slots[i].sides[1].neighbour;
    let starts_chain = |i: usize| slots[i].sides[0].neighbour.is_none();
    for pass in [true, false] {
        for first in 0..d {
            if order.contains(&first) || (pass && !starts_chain(first)) {
                continue;
            }
            let mut i = first;
            loop {
                order.push(i);
                match next(i) {
                    Some(j) if !order.contains(&j) => i = j,
                    _ => break,
                }
            }
        }
    }
}

/// `matrix = L R^T` with `L`, `R` of `rank` columns (`l[a][s]`: row `a`, column `s`) on its
/// leading `fields x fields` part, by Gaussian elimination with full pivoting; pivots below
/// `1e-12` of the largest entry count as zero.
fn low_rank(matrix: &Matrix, fields: usize) -> (usize, Matrix, Matrix) {
    let mut rest = *matrix;
    let (mut l, mut r) = (
        [[0.0; MAX_FIELDS]; MAX_FIELDS],
        [[0.0; MAX_FIELDS]; MAX_FIELDS],
    );
    let largest = |m: &Matrix| {
        let mut best = (0, 0, 0.0f64);
        for (a, row) in m[..fields].iter().enumerate() {
            for (b, &x) in row[..fields].iter().enumerate() {
                if x.abs() > best.2 {
                    best = (a, b, x.abs());
                }
            }
        }
        best
    };
    let scale = largest(matrix).2;
    for s in 0..fields {
        let (p, q, size) = largest(&rest);
        if size <= 1e-12 * scale || size == 0.0 {
            return (s, l, r);
        }
        let pivot = rest[p][q];
        for a in 0..fields {
            l[a][s] = rest[a][q] / pivot;
            r[a][s] = rest[p][a];
        }
        for a in 0..fields {
            for b in 0..fields {
                rest[a][b] -= l[a][s] * r[b][s];
            }
        }
    }
    (fields, l, r)
}

/// The two vertical faces of the tent element over triangle `t`, whose tent vertex is its corner
/// `corner`, with the element across each (an index in the star; none on the domain boundary)
/// and its space edge.
fn vertical_faces(mesh: &Mesh, star: &[TriangleId], t: TriangleId, corner: usize) -> [Vertical; 2] {
    [(SIDE_A, 2), (SIDE_B, 1)].map(|(face, opposite_corner)| {
        let e = mesh.triangle_edges(t)[(corner + opposite_corner) % 3];
        let edge = mesh.edges()[e as usize];
        let neighbour = edge
            .triangles
            .iter()
            .flatten()
            .find(|&&u| u != t)
            .map(|&u| {
                star.iter()
                    .position(|&s| s == u)
                    .expect("edge neighbour is in the star")
            });
        Vertical {
            face,
            neighbour,
            tag: edge.tag,
            edge: e,
            split: None,
            contact: None,
        }
    })
}

/// Copies of the elements below a patch's elements, taken when the patch starts.
#[derive(Debug)]
struct Inflow {
    solved: Vec<bool>,
    geometry: Vec<Geometry>,
    coefficients: Vec<f64>,
    /// Values per element.
    size: usize,
}

impl Inflow {
    /// Copies the elements under `triangles` from `solution`: source `i` is `triangles[i]`.
    fn gather(&mut self, triangles: &[TriangleId], solution: &FrontSolution) {
        for (i, &t) in triangles.iter().enumerate() {
            let size = self.size;
            self.solved[i] = solution.load(
                t as usize,
                &mut self.geometry[i],
                &mut self.coefficients[i * size..(i + 1) * size],
            );
        }
    }

    /// The element of source `i`, or `None` for initial data.
    fn below(&self, i: usize) -> Option<(&Geometry, &[f64])> {
        let size = self.size;
        self.solved[i].then(|| {
            (
                &self.geometry[i],
                &self.coefficients[i * size..(i + 1) * size],
            )
        })
    }
}

/// The state `sum_k phi_k q_k` of coefficients stored `fields` per basis function.
fn combine(coefficients: &[f64], phi: &[f64], fields: usize) -> State {
    let mut q = [0.0; MAX_FIELDS];
    for (k, p) in phi.iter().enumerate() {
        for (qc, c) in q
            .iter_mut()
            .zip(&coefficients[k * fields..(k + 1) * fields])
        {
            *qc += p * c;
        }
    }
    q
}

/// The element below an inflow face: its basis values at the face's rule points (`n` per
/// point) and its coefficients.
type Below<'a> = (&'a [f64], &'a [f64]);

/// The quadrature of an inflow face (`exact` below a solved element, whose trace is a
/// polynomial, `data` on initial data) and, below a solved element, its basis values at the
/// rule's points of `face` (`points x n`, from the tables, or evaluated into `scratch` if its
/// vertices do not match) with its coefficients.
fn inflow_values<'a, 'q: 'a>(
    [exact, data]: [&'q FaceQuadrature; 2],
    basis: &Basis,
    scratch: &'a mut [f64],
    slot: &Slot,
    face: Face,
    below: Option<(&Geometry, &'a [f64])>,
) -> (&'q FaceQuadrature, Option<Below<'a>>) {
    let Some((geometry, coefficients)) = below else {
        return (data, None);
    };
    let vertices = geometry.vertices();
    let values = other_values(
        &exact.tables,
        basis,
        scratch,
        &exact.rule,
        (slot, face),
        geometry,
        &vertices,
    );
    (exact, Some((values, coefficients)))
}

/// The basis values at the rule points of `slot`'s `face` of the element with `geometry` and
/// `vertices` that shares the face: a table if the face's corners are among `vertices`, else
/// evaluated into `scratch`.
fn other_values<'a>(
    tables: &'a FaceTables,
    basis: &Basis,
    scratch: &'a mut [f64],
    rule: &Rule<2>,
    (slot, face): (&Slot, Face),
    geometry: &Geometry,
    vertices: &[SpacePoint; 4],
) -> &'a [f64] {
    match FaceTables::corners_in(face.0.map(|c| slot.vertices[c]), vertices) {
        Some(t) => tables.values(t),
        None => {
            let n = basis.len();
            let mut q = 0;
            face_points(rule, &slot.vertices, face, |x, _, _| {
                basis.eval(geometry.to_reference(x), &mut scratch[q * n..(q + 1) * n]);
                q += 1;
            });
            scratch
        }
    }
}

/// The traces on `slot`'s `face` of the patch element `other` across it ([`FaceTables::trace`]).
fn neighbour_trace<'a>(
    tables: &'a FaceTables,
    basis: &Basis,
    values: &mut [f64],
    trace: &'a mut [f64],
    rule: &Rule<2>,
    (slot, face): (&Slot, Face),
    other: &Slot,
) -> &'a [f64] {
    match FaceTables::corners_in(face.0.map(|c| slot.vertices[c]), &other.vertices) {
        Some(t) => tables.trace(t),
        None => {
            let values = other_values(
                tables,
                basis,
                values,
                rule,
                (slot, face),
                &other.geometry,
                &other.vertices,
            );
            tables.trace_of(values, trace);
            trace
        }
    }
}

/// `sum_k phi_k c_k` for coefficients of `width` values per basis function: value `index`.
fn value_at(phi: &[f64], coefficients: &[f64], index: usize) -> f64 {
    let width = coefficients.len() / phi.len();
    phi.iter()
        .zip(coefficients.chunks_exact(width))
        .map(|(p, c)| p * c[index])
        .sum()
}

/// The state below the front at `x`: from the element below (its basis values at `x` and
/// coefficients), or the initial data.
fn inflow_state(
    system: &System,
    under: Option<(&[f64], &[f64])>,
    initial: Initial,
    x: SpacePoint,
) -> State {
    match (under, initial) {
        (Some((phi, coefficients)), _) => std::array::from_fn(|k| {
            if k < system.fields() {
                value_at(phi, coefficients, k)
            } else {
                0.0
            }
        }),
        (None, Initial::Rest) => [0.0; MAX_FIELDS],
        (None, Initial::Wave(w)) => system.to_scaled(&w.state([x[0], x[1]], 0.0)),
    }
}

/// The displacement (m) below the front at `x`, like [`inflow_state`].
fn inflow_displacement(
    system: &System,
    under: Option<(&[f64], &[f64])>,
    initial: Initial,
    x: SpacePoint,
) -> [f64; 2] {
    match (under, initial) {
        (Some((phi, coefficients)), _) => {
            let f = system.fields();
            std::array::from_fn(|d| {
                if d < system.displacement_components() {
                    value_at(phi, coefficients, f + d)
                } else {
                    0.0
                }
            })
        }
        (None, Initial::Rest) => [0.0; 2],
        (None, Initial::Wave(w)) => w.displacement([x[0], x[1]], 0.0),
    }
}

/// The flux matrices of a vertical face with outward normal `m`: `F* = M_a q_a + M_b q_b + g`,
/// with `g` the boundary data's part (zero between elements).
fn face_matrices(
    system: &System,
    boundary: &Boundary,
    condition: &Condition,
    interior: bool,
    m: [f64; 2],
) -> (Matrix, Matrix) {
    let homogeneous = boundary.sides(system, condition, [0.0; 2], 0.0, m, true);
    let flux = |qa: &State, qb: &State| -> State {
        let a = system.frame(qa, m);
        let star = if interior {
            riemann::bonded(system, &a, &system.frame(qb, m))
        } else {
            riemann::solve(system, &a, &homogeneous)
        };
        system.flux(&star, m)
    };
    let mut m_a = [[0.0; MAX_FIELDS]; MAX_FIELDS];
    let mut m_b = [[0.0; MAX_FIELDS]; MAX_FIELDS];
    let zero = [0.0; MAX_FIELDS];
    for j in 0..system.fields() {
        let mut e = zero;
        e[j] = 1.0;
        let fa = flux(&e, &zero);
        let fb = if interior { flux(&zero, &e) } else { zero };
        for i in 0..system.fields() {
            m_a[i][j] = fa[i];
            m_b[i][j] = fb[i];
        }
    }
    (m_a, m_b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Material, Plane};

    #[test]
    fn the_coupling_through_a_face_passes_only_the_incoming_waves() {
        // The bonded flux's dependence on the other side has rank 2 in plane strain (P and S
        // waves) and 1 in anti-plane shear; L R^T gives it back.
        for (plane, waves) in [(Plane::Strain, 2), (Plane::Antiplane, 1)] {
            let system = System::new(&Material::new(3.24e9, 0.35, 1190.0, plane).expect("PMMA"));
            let boundary = Boundary::new(vec![None; 1], None);
            let normal = [0.6, -0.8];
            let (_, m_b) = face_matrices(&system, &boundary, &Condition::Free, true, normal);
            let fields = system.fields();
            let (rank, l, r) = low_rank(&m_b, fields);
            assert_eq!(rank, waves, "{plane:?}");
            let largest = m_b.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
            for a in 0..fields {
                for b in 0..fields {
                    let product: f64 = (0..rank).map(|s| l[a][s] * r[b][s]).sum();
                    assert!((product - m_b[a][b]).abs() <= 1e-14 * largest, "{plane:?}");
                }
            }
        }
    }
}
