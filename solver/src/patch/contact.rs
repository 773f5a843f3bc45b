//! The nonlinear faces of a patch: vertical faces above interface edges with a contact or
//! cohesive law.
//!
//! A patch with such faces solves `K Q + N(Q) = b` by Newton iterations, where `K Q = b` is the
//! linear patch system with the nonlinear faces bonded, and `N(Q)` gathers
//! `int_F phi . (F*(q_a, q_b, sep) - F_bonded(q_a, q_b))` of those faces: how far the law's
//! target flux from the two sides' traces and the separation `sep` (normal, slip) on the face
//! departs from the bonded one. The iterations start from the bonded solution, which a face in
//! stick keeps. `sep` is itself the solution of the face's upwind DG in time
//! (see [`crate::face`]), a nonlinear function of the traces (the law's area fractions and
//! cohesive tractions depend on it); each iteration solves it exactly for the current traces
//! (inner Newton on the face, both components together), and the Jacobian carries its
//! dependence on the traces through the face system's implicit derivative, so the outer
//! iterations converge quadratically. The Jacobian keeps the ring structure: a nonlinear face
//! couples only the two elements beside it.

use sdg_mesh::EdgeId;

use crate::basis::Basis;
use crate::crack::{self, Crossing, Probe, SAMPLES};
use crate::element::{FrontSolution, Geometry};
use crate::face::{
    FaceBasis, FaceGeometry, FaceState, MAX_FACE_BASIS, STATE_COMPONENTS, solve_dense,
};
use crate::interface::{Contact, Targets};
use crate::quadrature::{self, Rule};
use crate::spacetime::SpacePoint;

/// One contact face of the patch, seen from its side a (normal `m` from a to b).
#[derive(Debug)]
pub(super) struct ContactFace {
    pub(super) a: usize,
    pub(super) b: usize,
    pub(super) edge: EdgeId,
    pub(super) law: Contact,
    pub(super) normal: [f64; 2],
    pub(super) geometry: FaceGeometry,
    /// Quadrature points on the face: weights (m^2), face basis values and `tau` derivatives,
    /// and the basis values of the elements on sides a and b.
    pub(super) weights: Vec<f64>,
    pub(super) psi: Vec<f64>,
    pub(super) psi_tau: Vec<f64>,
    pub(super) phi_a: Vec<f64>,
    pub(super) phi_b: Vec<f64>,
    /// The face system's constant part per component: `int psi_k dpsi_l/dtau +
    /// int_bottom L psi_k psi_l`, and the bottom edge's inflow of the interface state (normal
    /// separation components, then slip, then damage).
    pub(super) m0: Vec<f64>,
    pub(super) inflow: Vec<f64>,
    /// Coefficients of the interface state, component after component (`nf` each): normal
    /// `delta`, slip, and damage when the law evolves it.
    pub(super) sep: [f64; STATE_COMPONENTS * MAX_FACE_BASIS],
    /// The crack probe lines with the normal separation inherited from the faces below
    /// (cohesive faces).
    pub(super) probes: [Probe; SAMPLES],
    /// Per quadrature point: arriving characteristics and both sides' targets.
    pub(super) w_a: Vec<[f64; 2]>,
    pub(super) w_b: Vec<[f64; 2]>,
    pub(super) targets_a: Vec<Targets>,
    pub(super) targets_b: Vec<Targets>,
    /// The bottom edge's quadrature points (weights: spatial length, m; face basis values),
    /// the inflow's points.
    pub(super) bottom_weights: Vec<f64>,
    pub(super) bottom_psi: Vec<f64>,
    /// Where each bottom point lies along the edge: 0 below the top's first end, 1 below its
    /// second.
    pub(super) bottom_along: Vec<f64>,
    /// Cohesive faces: `P[p][q]` (points x sources) maps the law's traction at the sources (the
    /// face's points, then the bottom's) to its projection onto the face's polynomials at `p`
    /// (see [`ContactFace::project_matrix`]), the projected traction per point, and its derivatives
    /// `d T_k(p) / d d_(e, l)` with respect to the state's coefficients, at
    /// `((p 2 + k) 2 + e) nf + l`.
    pub(super) projection: Vec<f64>,
    pub(super) traction: Vec<[f64; 2]>,
    pub(super) slopes: Vec<f64>,
}

impl ContactFace {
    /// The face's interface state for a face basis of `nf` functions.
    fn state(&self, nf: usize) -> FaceState {
        let mut coefficients = [[0.0; MAX_FACE_BASIS]; STATE_COMPONENTS];
        for (c, out) in coefficients.iter_mut().enumerate() {
            out[..nf].copy_from_slice(&self.sep[c * nf..(c + 1) * nf]);
        }
        FaceState {
            geometry: self.geometry,
            coefficients,
        }
    }
}

/// Where a nonlinear face lies: its corners and the segments of its boundary, in scaled
/// spacetime (m).
///
/// A tent's face over star edge `(v, w)` has corners `P0` (pole bottom), `P1` (`w`), `P2` (pole
/// top); its bottom `P0 P1` lies on the front over the edge, its top is `P2 P1`. A coarsening
/// patch's face over the restored edge `ab` has corners `m` (the removed vertex, below), `a`,
/// `b`; its bottom is the two halves `m a` and `m b` of the front, each over its own edge, and
/// its top `a b`.
#[derive(Clone, Copy, Debug)]
pub(super) struct FaceShape {
    /// Corners of the face's affine map.
    pub(super) corners: [SpacePoint; 3],
    /// The bottom segments, each with the edge whose face lies below it; one or two.
    pub(super) bottom: [(EdgeId, [SpacePoint; 2]); 2],
    pub(super) bottom_count: usize,
    /// The top segment, from one end of the edge to the other.
    pub(super) top: [SpacePoint; 2],
}

impl FaceShape {
    /// The face a tent builds: corners `P0` (pole bottom), `P1` (far end), `P2` (pole top) over
    /// `edge`.
    pub(super) fn tent(corners: [SpacePoint; 3], edge: EdgeId) -> Self {
        let [p0, p1, p2] = corners;
        Self {
            corners,
            bottom: [(edge, [p0, p1]); 2],
            bottom_count: 1,
            top: [p2, p1],
        }
    }

    /// The face a coarsening patch builds over the restored edge `ab`: corners `m` (below the
    /// edge's midpoint), `a`, `b`; `edges` are the halves `m a` and `m b`.
    pub(super) fn coarsening(corners: [SpacePoint; 3], edges: [EdgeId; 2]) -> Self {
        let [m, a, b] = corners;
        Self {
            corners,
            bottom: [(edges[0], [m, a]), (edges[1], [m, b])],
            bottom_count: 2,
            top: [a, b],
        }
    }

    /// The bottom segments.
    fn bottom(&self) -> &[(EdgeId, [SpacePoint; 2])] {
        &self.bottom[..self.bottom_count]
    }

    /// The point of the bottom below the space point `x` of the edge, and the edge of the
    /// segment it lies on.
    fn bottom_at(&self, x: [f64; 2]) -> (SpacePoint, EdgeId) {
        let along = |[p, q]: [SpacePoint; 2]| {
            let d = [q[0] - p[0], q[1] - p[1]];
            ((x[0] - p[0]) * d[0] + (x[1] - p[1]) * d[1]) / (d[0] * d[0] + d[1] * d[1])
        };
        let (edge, segment) = self
            .bottom()
            .iter()
            .copied()
            .find(|&(_, segment)| (0.0..=1.0).contains(&along(segment)))
            .unwrap_or(self.bottom[0]);
        let t = along(segment).clamp(0.0, 1.0);
        let [p, q] = segment;
        ([0, 1, 2].map(|i| p[i] + t * (q[i] - p[i])), edge)
    }
}

/// The contact faces of the patch being solved and their scratch memory.
#[derive(Debug)]
pub(super) struct ContactFaces {
    pub(super) basis: FaceBasis,
    pub(super) bottom_rule: Rule<1>,
    pub(super) faces: Vec<ContactFace>,
    pub(super) count: usize,
    pub(super) psi: Vec<f64>,
    pub(super) grad: Vec<[f64; 2]>,
    pub(super) jacobian: Vec<f64>,
    pub(super) columns: Vec<f64>,
    /// The right-hand sides of a cohesive face's projection, one per source point.
    pub(super) moments: Vec<f64>,
    pub(super) coupling: [Vec<f64>; 2],
    pub(super) outer: Vec<f64>,
    pub(super) block: Vec<f64>,
    pub(super) crossings: Vec<Crossing>,
}

impl ContactFaces {
    /// Scratch for up to `max_faces` faces, polynomial order `order`, `points` quadrature points
    /// per face, element basis length `n` and element unknowns `m`.
    pub(super) fn new(max_faces: usize, order: usize, points: usize, n: usize, m: usize) -> Self {
        let basis = FaceBasis::new(order);
        let nf = basis.len();
        let bottom_rule = quadrature::gauss_legendre(order + 2);
        // Two bottom segments at most (a coarsening patch's face).
        let bottom = 2 * bottom_rule.points.len();
        let face = || ContactFace {
            a: 0,
            b: 0,
            edge: 0,
            law: Contact {
                z: [1.0; 2],
                k: 0.0,
                r: [0.0; 2],
                s: [0.0; 2],
                cohesive: None,
                damage: None,
            },
            normal: [1.0, 0.0],
            geometry: FaceGeometry::default(),
            weights: vec![0.0; points],
            psi: vec![0.0; points * nf],
            psi_tau: vec![0.0; points * nf],
            phi_a: vec![0.0; points * n],
            phi_b: vec![0.0; points * n],
            m0: vec![0.0; nf * nf],
            inflow: vec![0.0; STATE_COMPONENTS * nf],
            sep: [0.0; STATE_COMPONENTS * MAX_FACE_BASIS],
            probes: [Probe::default(); SAMPLES],
            w_a: vec![[0.0; 2]; points],
            w_b: vec![[0.0; 2]; points],
            targets_a: vec![Targets::default(); points],
            targets_b: vec![Targets::default(); points],
            bottom_weights: Vec::with_capacity(bottom),
            bottom_psi: vec![0.0; bottom * nf],
            bottom_along: Vec::with_capacity(bottom),
            projection: vec![0.0; points * (points + bottom)],
            traction: vec![[0.0; 2]; points],
            slopes: vec![0.0; points * 4 * nf],
        };
        Self {
            moments: vec![0.0; nf * (points + bottom)],
            bottom_rule,
            faces: (0..max_faces).map(|_| face()).collect(),
            count: 0,
            psi: vec![0.0; nf],
            grad: vec![[0.0; 2]; nf],
            jacobian: vec![0.0; (STATE_COMPONENTS * nf).pow(2)],
            columns: vec![0.0; STATE_COMPONENTS * nf * (2 * m).max(2)],
            coupling: [
                vec![0.0; STATE_COMPONENTS * m * nf],
                vec![0.0; STATE_COMPONENTS * m * nf],
            ],
            outer: vec![0.0; n * n],
            block: vec![0.0; m * m],
            crossings: Vec::with_capacity(2 * SAMPLES * max_faces),
            basis,
        }
    }

    /// `[delta (m), slip (m), D]` of face `f` at the point `x` of its plane, after
    /// [`Self::finish`].
    pub(super) fn state_at(&mut self, f: usize, x: SpacePoint) -> [f64; STATE_COMPONENTS] {
        let state = self.faces[f].state(self.basis.len());
        state.evaluate(&self.basis, x, &mut self.psi)
    }

    /// Forgets the faces of the previous patch.
    pub(super) fn clear(&mut self) {
        self.count = 0;
        self.crossings.clear();
    }

    /// The faces of the current patch.
    pub(super) fn faces(&self) -> &[ContactFace] {
        &self.faces[..self.count]
    }

    /// Adds the face between patch elements `a` and `b` with `shape`, known by the edge of its
    /// first bottom segment (its tent's star edge); `points` visits
    /// its quadrature points (the patch's face rule on side a's face) as `(x, weight, normal)`.
    /// Reads the faces below from `solution`. Returns the face's index.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add(
        &mut self,
        (a, b): (usize, usize),
        (geometry_a, geometry_b): (&Geometry, &Geometry),
        law: Contact,
        shape: &FaceShape,
        element_basis: &Basis,
        solution: &FrontSolution,
        points: impl FnOnce(&mut dyn FnMut(SpacePoint, f64, [f64; 3])),
    ) -> usize {
        let index = self.count;
        self.count += 1;
        let nf = self.basis.len();
        let n = element_basis.len();
        let (basis, psi, grad) = (&self.basis, &mut self.psi, &mut self.grad);
        let face = &mut self.faces[index];
        face.a = a;
        face.b = b;
        face.edge = shape.bottom[0].0;
        face.law = law;
        face.geometry = FaceGeometry::new(shape.corners);
        let d_tau = face.geometry.d_tau();
        let mut q = 0;
        points(&mut |x, w, nrm| {
            face.normal = [nrm[0], nrm[1]];
            face.weights[q] = w;
            basis.eval_with_gradient(face.geometry.to_reference(x), psi, grad);
            face.psi[q * nf..(q + 1) * nf].copy_from_slice(psi);
            for (t, g) in face.psi_tau[q * nf..(q + 1) * nf].iter_mut().zip(&*grad) {
                *t = g[0] * d_tau[0] + g[1] * d_tau[1];
            }
            element_basis.eval(
                geometry_a.to_reference(x),
                &mut face.phi_a[q * n..(q + 1) * n],
            );
            element_basis.eval(
                geometry_b.to_reference(x),
                &mut face.phi_b[q * n..(q + 1) * n],
            );
            q += 1;
        });
        let points = q;
        // Constant part of the face system and the inflow through the bottom edge P0 P1.
        let m0 = &mut face.m0[..nf * nf];
        m0.fill(0.0);
        for q in 0..points {
            let w = face.weights[q];
            for k in 0..nf {
                for l in 0..nf {
                    m0[k * nf + l] += w * face.psi[q * nf + k] * face.psi_tau[q * nf + l];
                }
            }
        }
        face.inflow.fill(0.0);
        face.bottom_weights.clear();
        face.bottom_along.clear();
        let [top_a, top_b] = shape.top;
        let span = [top_b[0] - top_a[0], top_b[1] - top_a[1]];
        let span2 = span[0] * span[0] + span[1] * span[1];
        let ns = law.components();
        let initial = law.initial_state();
        for &(under, [p, q]) in shape.bottom() {
            let below = solution.face(under as usize);
            let length = (q[0] - p[0]).hypot(q[1] - p[1]);
            for (t, &wg) in self
                .bottom_rule
                .points
                .iter()
                .zip(&self.bottom_rule.weights)
            {
                let x = [0, 1, 2].map(|i| p[i] + t[0] * (q[i] - p[i]));
                let state = below
                    .as_ref()
                    .map_or(initial, |f| f.evaluate(basis, x, psi));
                basis.eval(face.geometry.to_reference(x), psi);
                let w = wg * length;
                let b = face.bottom_weights.len();
                face.bottom_weights.push(w);
                face.bottom_along
                    .push(((x[0] - top_a[0]) * span[0] + (x[1] - top_a[1]) * span[1]) / span2);
                face.bottom_psi[b * nf..(b + 1) * nf].copy_from_slice(psi);
                for k in 0..nf {
                    for l in 0..nf {
                        m0[k * nf + l] += w * psi[k] * psi[l];
                    }
                    for (c, value) in state[..ns].iter().enumerate() {
                        face.inflow[c * nf + k] += w * psi[k] * value;
                    }
                }
            }
        }
        if let Some(tracking) = law.tracking() {
            let component = tracking.component;
            let [a, b] = shape.top;
            for (k, probe) in face.probes.iter_mut().enumerate() {
                let f = crack::sample_fraction(k);
                let (bottom, under) =
                    shape.bottom_at([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]);
                let below = solution.face(under as usize);
                *probe = Probe {
                    bottom,
                    top: a[2] + f * (b[2] - a[2]),
                    under: below.map_or(initial[component], |s| {
                        s.evaluate(basis, bottom, psi)[component]
                    }),
                };
            }
        }
        if face.projects() {
            face.project_matrix(&self.basis, &mut self.jacobian, &mut self.moments);
        }
        // First guess: the inherited state carried up the face (no rate), `M0 d = inflow`.
        let (guess, matrix) = (&mut self.columns[..ns * nf], &mut self.jacobian[..nf * nf]);
        guess.copy_from_slice(&face.inflow[..ns * nf]);
        matrix.copy_from_slice(&face.m0[..nf * nf]);
        if !solve_dense(matrix, nf, guess, ns) {
            guess.fill(0.0);
        }
        face.sep = [0.0; STATE_COMPONENTS * MAX_FACE_BASIS];
        face.sep[..ns * nf].copy_from_slice(guess);
        index
    }

    /// Finds the crack-tracking crossings of the last patch's cohesive faces (after the solve);
    /// `c_ref` converts scaled time to s.
    pub(super) fn find_crossings(&mut self, c_ref: f64) {
        self.crossings.clear();
        let nf = self.basis.len();
        for face in &self.faces[..self.count] {
            let Some(tracking) = face.law.tracking() else {
                continue;
            };
            crack::find_crossings(
                &face.state(nf),
                &self.basis,
                (face.edge, &face.probes),
                tracking,
                c_ref,
                &mut self.psi,
                &mut self.crossings,
            );
        }
    }

    /// The cohesive indicator's measure of the last patch (seed 2.5.2, 4.4.2): on the cohesive
    /// faces, the work rate of the mismatch between the law's traction at the face's separation
    /// (the target) and at the separation of the two elements' displacement traces, on the
    /// separated fraction, `int (1 - eta) |(T(sep) - T([[u]])) . [[v*]]|` (scaled units, like the
    /// numerical dissipation). `displacement(i, phi)` gives patch element `i`'s displacement
    /// (m) at a point from its basis values `phi` there.
    pub(super) fn cohesive_mismatch(
        &self,
        displacement: impl Fn(usize, &[f64]) -> [f64; 2],
    ) -> f64 {
        let nf = self.basis.len();
        let mut total = 0.0;
        for face in &self.faces[..self.count] {
            let Some(law) = face.law.cohesive else {
                continue;
            };
            let n = face.phi_a.len() / face.weights.len();
            let m = face.normal;
            for p in 0..face.weights.len() {
                let ua = displacement(face.a, &face.phi_a[p * n..(p + 1) * n]);
                let ub = displacement(face.b, &face.phi_b[p * n..(p + 1) * n]);
                let du = [ub[0] - ua[0], ub[1] - ua[1]];
                let traced = [du[0] * m[0] + du[1] * m[1], -du[0] * m[1] + du[1] * m[0]];
                let (at_traces, _) = law.traction(traced);
                let [delta, slip, _] = face.separation_at(nf, p, &face.sep);
                let (at_face, _) = law.traction([delta, slip]);
                let t = &face.targets_a[p];
                let power: f64 = (0..2)
                    .map(|k| (at_face[k] - at_traces[k]) * t.rate[k])
                    .sum();
                total += face.weights[p] * (1.0 - t.eta) * power.abs();
            }
        }
        total
    }

    /// The crossings found by [`Self::find_crossings`].
    pub(super) fn crossings(&self) -> &[Crossing] {
        &self.crossings
    }

    /// Per face of the last patch, the edge and the interface state to store on the front.
    pub(super) fn finish(&self) -> impl Iterator<Item = (EdgeId, FaceState)> + '_ {
        let nf = self.basis.len();
        self.faces[..self.count]
            .iter()
            .map(move |face| (face.edge, face.state(nf)))
    }
}
