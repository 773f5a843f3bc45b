//! The [`PatchSolver`]: its scratch memory and its public methods (preparing, solving and
//! committing patches, and reading their results).

use faer::Par;
use faer::dyn_stack::{MemBuffer, StackReq};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use sdg_mesh::{EdgeId, Front, Mesh, Tent, TriangleId, VertexId};

use super::contact::{ContactFaces, FaceShape};
use super::inflow::{Inflow, Initial};
use super::newton::{Newton, NewtonFailure};
use super::report::{ElementReport, FaceCut, InterfaceSample, PatchReport};
use super::slot::{FaceQuadrature, Slot, TOP, Vertical, face_points, tent_bottom, vertical_faces};
use super::tables::FaceTables;
use crate::basis::Basis;
use crate::boundary::Boundary;
use crate::crack::Crossing;
use crate::element::{FrontSolution, Geometry, evaluate};
use crate::face::FaceState;
use crate::interface::{Contact, Interfaces, Law};
use crate::quadrature;
use crate::ring::BlockSystem;
use crate::spacetime::{SpacePoint, cut_face};
use crate::system::{MAX_FIELDS, State, System};

/// Solves tent patches of one physical problem; holds all scratch memory, so solving a patch
/// allocates nothing.
pub struct PatchSolver {
    pub(super) system: System,
    pub(super) basis: Basis,
    /// Face rules: of degree `2p` for polynomial integrands (between solved elements), and
    /// `2p + 2` for boundary and initial data and nonlinear faces.
    pub(super) exact: FaceQuadrature,
    pub(super) data: FaceQuadrature,
    /// `H[r][k * n + l] = int_ref phi_k d(phi_l)/d(xi_r)`.
    pub(super) h_ref: [Vec<f64>; 3],
    pub(super) slots: Vec<Slot>,
    pub(super) blocks: BlockSystem,
    pub(super) order: Vec<usize>,
    pub(super) perm: Vec<usize>,
    pub(super) perm_inv: Vec<usize>,
    pub(super) stack: MemBuffer,
    pub(super) small: Vec<f64>,
    pub(super) small_rhs: Vec<f64>,
    /// Basis values of another element at a face's points, when not tabulated (`points x n`),
    /// and its traces (`n x face_dim`).
    pub(super) other_values: Vec<f64>,
    pub(super) trace: Vec<f64>,
    /// The state and displacement below each inflow face at its rule points, from the
    /// assembly for the energy terms and the displacement: `2 x data points` per slot.
    pub(super) below_states: Vec<(State, [f64; 2])>,
    pub(super) phi: Vec<f64>,
    pub(super) values: Vec<f64>,
    pub(super) output: Vec<f64>,
    pub(super) inflow: Inflow,
    pub(super) reports: Vec<ElementReport>,
    pub(super) used: usize,
    pub(super) interfaces: Interfaces,
    pub(super) newton: Newton,
    pub(super) contact: ContactFaces,
    /// Newton iterate, `N(Q)` and residual: one value per patch unknown.
    pub(super) iterate: Vec<f64>,
    pub(super) nonlinear: Vec<f64>,
    pub(super) residual: Vec<f64>,
    /// Interface states of the last patch's contact faces, stored by [`Self::commit`].
    pub(super) faces: Vec<(EdgeId, FaceState)>,
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

    /// Adds to `out` a sample of the last patch at each of the `probes` (points, m, in order)
    /// that lies on the edge of one of its contact faces on `mesh` ([`Self::interface_sample`]):
    /// `(probe index, sample)`.
    pub fn probe_samples(
        &mut self,
        mesh: &Mesh,
        probes: impl IntoIterator<Item = [f64; 2]>,
        out: &mut Vec<(usize, InterfaceSample)>,
    ) {
        for (i, at) in probes.into_iter().enumerate() {
            for k in 0..self.faces.len() {
                let e = self.faces[k].0;
                let [a, b] = mesh.edges()[e as usize].vertices.map(|v| mesh.vertex(v));
                if !on_segment(at, a, b) {
                    continue;
                }
                if let Some(sample) = self.interface_sample(e, at) {
                    out.push((i, sample));
                    break;
                }
            }
        }
    }

    /// Adds to `out` the cuts of the last patch's contact faces by the planes of the `times`
    /// (s, on the run's clock from 0) they cross, with the interface at both ends of each
    /// segment ([`Self::interface_sample_at`]). Allocates nothing when no plane crosses a face.
    pub fn snapshot_cuts(&mut self, times: &[f64], out: &mut Vec<FaceCut>) {
        let c_ref = self.system.c_ref();
        for k in 0..self.faces.len() {
            let (edge, corners) = (self.faces[k].0, self.faces[k].1.geometry.corners());
            let lo = corners.iter().map(|c| c[2]).fold(f64::INFINITY, f64::min);
            let hi = (corners.iter().map(|c| c[2])).fold(f64::NEG_INFINITY, f64::max);
            for &time in times {
                let tau = c_ref * time;
                if !(lo < tau && tau <= hi) {
                    continue;
                }
                let Some(ends) = cut_face(corners, tau) else {
                    continue;
                };
                out.push(FaceCut {
                    time,
                    ends: ends.map(|x| [x[0], x[1]]),
                    samples: ends.map(|x| self.interface_sample_at(edge, x)),
                });
            }
        }
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
}

/// True when `x` lies on the segment `ab` (to a relative tolerance of 1e-9).
fn on_segment(x: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    let d = [b[0] - a[0], b[1] - a[1]];
    let length2 = d[0] * d[0] + d[1] * d[1];
    let r = [x[0] - a[0], x[1] - a[1]];
    let along = (r[0] * d[0] + r[1] * d[1]) / length2;
    let across = (r[0] * d[1] - r[1] * d[0]).abs() / length2.sqrt();
    (-1e-9..=1.0 + 1e-9).contains(&along) && across <= 1e-9 * length2.sqrt()
}

#[cfg(test)]
mod tests {
    use super::on_segment;

    #[test]
    fn points_on_segments() {
        let (a, b) = ([0.0, 0.0], [2.0, 0.0]);
        assert!(on_segment([1.0, 0.0], a, b));
        assert!(on_segment([0.0, 0.0], a, b) && on_segment([2.0, 0.0], a, b));
        assert!(!on_segment([2.1, 0.0], a, b));
        assert!(!on_segment([1.0, 1e-6], a, b));
    }
}
