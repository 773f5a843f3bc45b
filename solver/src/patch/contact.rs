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

use faer::Accum;
use sdg_mesh::EdgeId;

use crate::basis::Basis;
use crate::crack::{self, Crossing, Probe, SAMPLES};
use crate::element::{FrontSolution, Geometry, SpacePoint};
use crate::face::{
    FaceBasis, FaceGeometry, FaceState, MAX_FACE_BASIS, STATE_COMPONENTS, solve_dense,
};
use crate::interface::{Contact, Targets, characteristics};
use crate::quadrature::{self, Rule};
use crate::ring::BlockSystem;
use crate::system::{FrameTrace, MAX_FIELDS, Matrix, System};

/// Settings of the Newton iterations of patches with nonlinear faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Newton {
    /// Converged when `|b - K Q - N(Q)| <= tol (|b| + |N(Q)|)` (Euclidean norms over the patch).
    pub tol: f64,
    /// Iterations allowed before the patch counts as not converged.
    pub max_iter: usize,
}

impl Default for Newton {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            max_iter: 30,
        }
    }
}

/// A patch whose Newton iterations did not converge.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "Newton iterations did not converge: relative residual {residual:.3e} after {iterations} \
     iterations"
)]
pub struct NewtonFailure {
    /// Iterations done.
    pub iterations: usize,
    /// Relative residual of the last iterate.
    pub residual: f64,
}

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
    weights: Vec<f64>,
    psi: Vec<f64>,
    psi_tau: Vec<f64>,
    phi_a: Vec<f64>,
    phi_b: Vec<f64>,
    /// The face system's constant part per component: `int psi_k dpsi_l/dtau +
    /// int_bottom L psi_k psi_l`, and the bottom edge's inflow of the interface state (normal
    /// separation components, then slip, then damage).
    m0: Vec<f64>,
    inflow: Vec<f64>,
    /// Coefficients of the interface state, component after component (`nf` each): normal
    /// `delta`, slip, and damage when the law evolves it.
    sep: [f64; STATE_COMPONENTS * MAX_FACE_BASIS],
    /// The crack probe lines with the normal separation inherited from the faces below
    /// (cohesive faces).
    probes: [Probe; SAMPLES],
    /// Per quadrature point: arriving characteristics and both sides' targets.
    w_a: Vec<[f64; 2]>,
    w_b: Vec<[f64; 2]>,
    pub(super) targets_a: Vec<Targets>,
    pub(super) targets_b: Vec<Targets>,
    /// The bottom edge's quadrature points (weights: spatial length, m; face basis values),
    /// the inflow's points.
    bottom_weights: Vec<f64>,
    bottom_psi: Vec<f64>,
    /// Where each bottom point lies along the edge: 0 below the top's first end, 1 below its
    /// second.
    bottom_along: Vec<f64>,
    /// Cohesive faces: `P[p][q]` (points x sources) maps the law's traction at the sources (the
    /// face's points, then the bottom's) to its projection onto the face's polynomials at `p`
    /// (see [`ContactFace::project_matrix`]), the projected traction per point, and its derivatives
    /// `d T_k(p) / d d_(e, l)` with respect to the state's coefficients, at
    /// `((p 2 + k) 2 + e) nf + l`.
    projection: Vec<f64>,
    traction: Vec<[f64; 2]>,
    slopes: Vec<f64>,
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

    /// The interface state (normal separation, slip: m; damage) at quadrature point `p` for
    /// coefficients `d`.
    fn separation_at(&self, nf: usize, p: usize, d: &[f64]) -> [f64; STATE_COMPONENTS] {
        state_from(&self.psi[p * nf..(p + 1) * nf], d)
    }

    /// `-G(d) = inflow - M0 d + int psi rate(state) / c` of the face's state system (the law's
    /// components) at the coefficients `d` into `g` (length `ns nf`), and with `jacobian` its
    /// derivative `M0 - int psi psi (d rate / d state) / c` (row-major, `ns nf` square);
    /// returns `|G|`.
    fn separation_residual(
        &mut self,
        c: f64,
        d: &[f64; STATE_COMPONENTS * MAX_FACE_BASIS],
        g: &mut [f64],
        mut jacobian: Option<&mut [f64]>,
    ) -> f64 {
        let n2 = g.len();
        let ns = self.law.components();
        let nf = n2 / ns;
        let projected = self.project_traction(nf, d, jacobian.is_some());
        for (row, gk) in g.iter_mut().enumerate() {
            let (comp, k) = (row / nf, row % nf);
            let md: f64 = (0..nf)
                .map(|l| self.m0[k * nf + l] * d[comp * nf + l])
                .sum();
            *gk = self.inflow[row] - md;
        }
        if let Some(jac) = jacobian.as_deref_mut() {
            jac.fill(0.0);
            for comp in 0..ns {
                for k in 0..nf {
                    let row = &mut jac[(comp * nf + k) * n2 + comp * nf..][..nf];
                    row.copy_from_slice(&self.m0[k * nf..(k + 1) * nf]);
                }
            }
        }
        for p in 0..self.weights.len() {
            let psi = &self.psi[p * nf..(p + 1) * nf];
            let t = self.targets_at(p, projected, self.separation_at(nf, p, d), false);
            let w = self.weights[p] / c;
            for comp in 0..ns {
                for k in 0..nf {
                    g[comp * nf + k] += w * psi[k] * t.rate[comp];
                }
            }
            if let Some(jac) = jacobian.as_deref_mut() {
                for (comp, e) in (0..ns).flat_map(|comp| (0..ns).map(move |e| (comp, e))) {
                    let r = w * t.rate_sep[comp][e];
                    if r == 0.0 {
                        continue;
                    }
                    for k in 0..nf {
                        let row = &mut jac[(comp * nf + k) * n2 + e * nf..][..nf];
                        for (x, &pl) in row.iter_mut().zip(psi) {
                            *x -= r * psi[k] * pl;
                        }
                    }
                }
                if projected {
                    self.add_projected_slopes(p, w, &t, jac, n2);
                }
            }
        }
        g.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    /// True for a cohesive face without damage: its target traction is the law's traction
    /// projected onto the face's polynomials (see [`Self::project_traction`]).
    fn projects(&self) -> bool {
        self.law.cohesive.is_some() && self.law.damage.is_none()
    }

    /// Side a's (or with `swap` side b's) targets at point `p` for the interface `state` there,
    /// with the projected traction when `projected`.
    fn targets_at(
        &self,
        p: usize,
        projected: bool,
        state: [f64; STATE_COMPONENTS],
        swap: bool,
    ) -> Targets {
        let (w_a, w_b) = if swap {
            (self.w_b[p], self.w_a[p])
        } else {
            (self.w_a[p], self.w_b[p])
        };
        if projected {
            self.law
                .targets_with_traction(w_a, w_b, state, self.traction[p])
        } else {
            self.law.targets(w_a, w_b, state)
        }
    }

    /// For a cohesive face, the law's traction at the state coefficients `d` projected onto
    /// the face's polynomials ([`Self::project_matrix`]), at every point (and with `slopes`
    /// its derivatives with respect to `d`). Testing the face's DG equation with the target
    /// traction gives its work as the law's potential gained over the face plus terms that
    /// vanish for `Pi T` (docs/method.md): with the pointwise `T`, `-(2 / Z) |T - Pi T|^2`
    /// (an L2 projection removes it), and `-int_bottom (T - Pi T) (delta+ - delta-)` on the
    /// bottom's jump (the bottom moments remove it). Returns whether the face projects.
    fn project_traction(&mut self, nf: usize, d: &[f64], slopes: bool) -> bool {
        if !self.projects() {
            return false;
        }
        let law = self.law.cohesive.expect("a cohesive face");
        let points = self.weights.len();
        if slopes {
            self.slopes[..points * 4 * nf].fill(0.0);
        }
        for p in 0..points {
            self.traction[p] = [0.0; 2];
        }
        let sources = points + self.bottom_weights.len();
        for q in 0..sources {
            let psi_q = if q < points {
                &self.psi[q * nf..(q + 1) * nf]
            } else {
                &self.bottom_psi[(q - points) * nf..(q - points + 1) * nf]
            };
            let state = state_from(psi_q, d);
            let (t, dt) = law.traction([state[0], state[1]]);
            for p in 0..points {
                let w = self.projection[p * sources + q];
                if w == 0.0 {
                    continue;
                }
                for (x, tk) in self.traction[p].iter_mut().zip(t) {
                    *x += w * tk;
                }
                if slopes {
                    for (k, e) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                        let f = w * dt[k][e];
                        let row = &mut self.slopes[((p * 2 + k) * 2 + e) * nf..][..nf];
                        for (x, &ps) in row.iter_mut().zip(psi_q) {
                            *x += f * ps;
                        }
                    }
                }
            }
        }
        true
    }

    /// Subtracts from the face system's Jacobian `jac` (`n2` square) the dependence of the
    /// rate at point `p` (weight `w`, scaled by `1 / c`; targets `t`) on the state through the
    /// projected traction: `d r_k / d T_k = -2 (1 - eta) / Z_k`.
    fn add_projected_slopes(&self, p: usize, w: f64, t: &Targets, jac: &mut [f64], n2: usize) {
        let nf = n2 / 2;
        let psi = &self.psi[p * nf..(p + 1) * nf];
        for comp in 0..2 {
            let r = w * -2.0 * (1.0 - t.eta) / self.law.z[comp];
            for e in 0..2 {
                let slope = &self.slopes[((p * 2 + comp) * 2 + e) * nf..][..nf];
                for k in 0..nf {
                    let row = &mut jac[(comp * nf + k) * n2 + e * nf..][..nf];
                    for (x, &sl) in row.iter_mut().zip(slope) {
                        *x -= r * psi[k] * sl;
                    }
                }
            }
        }
    }

    /// The projection of a cohesive face's traction (see [`Self::project_traction`]): the
    /// polynomial `Pi T` of the face's degree `p` whose moments against the polynomials of
    /// degree `p - 1` on the face (face rule) and against those of degree `p` along the bottom
    /// edge (bottom rule) are the traction's. The first makes `int Pi T d delta / d tau` the
    /// law's potential gained over the face; the second makes the work on the bottom's jump
    /// of the separation that of `T` itself. Fills `projection` (points x sources); `g`
    /// (`nf^2` for the face basis' `nf` functions) and `x` (`nf` per source) are scratch. Falls back to the pointwise traction
    /// if the moments do not determine `Pi T`.
    fn project_matrix(&mut self, basis: &FaceBasis, g: &mut [f64], x: &mut [f64]) {
        let (nf, degree) = (basis.len(), basis.degree());
        let points = self.weights.len();
        let bottom = self.bottom_weights.len();
        let sources = points + bottom;
        // The face basis is ordered by degree: its first `interior` functions span degree p - 1.
        let interior = nf - (degree + 1);
        let (g, x) = (&mut g[..nf * nf], &mut x[..nf * sources]);
        g.fill(0.0);
        x.fill(0.0);
        for q in 0..points {
            let psi = &self.psi[q * nf..(q + 1) * nf];
            let w = self.weights[q];
            for j in 0..interior {
                for k in 0..nf {
                    g[j * nf + k] += w * psi[j] * psi[k];
                }
                x[q * nf + j] = w * psi[j];
            }
        }
        for b in 0..bottom {
            let psi = &self.bottom_psi[b * nf..(b + 1) * nf];
            let (w, s) = (self.bottom_weights[b], self.bottom_along[b]);
            for i in 0..=degree {
                let row = interior + i;
                let moment = w * s.powi(i as i32);
                for k in 0..nf {
                    g[row * nf + k] += moment * psi[k];
                }
                x[(points + b) * nf + row] = moment;
            }
        }
        let projection = &mut self.projection[..points * sources];
        if solve_dense(g, nf, x, sources) {
            for p in 0..points {
                let psi = &self.psi[p * nf..(p + 1) * nf];
                for q in 0..sources {
                    let xq = &x[q * nf..(q + 1) * nf];
                    projection[p * sources + q] = psi.iter().zip(xq).map(|(a, b)| a * b).sum();
                }
            }
        } else {
            projection.fill(0.0);
            for p in 0..points {
                projection[p * sources + p] = 1.0;
            }
        }
    }
}

/// The interface state (normal separation, slip: m; damage) at a point with face basis values
/// `psi`, for coefficients `d` (`psi.len()` per component).
fn state_from(psi: &[f64], d: &[f64]) -> [f64; STATE_COMPONENTS] {
    let nf = psi.len();
    std::array::from_fn(|c| psi.iter().zip(&d[c * nf..]).map(|(a, b)| a * b).sum())
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
    basis: FaceBasis,
    bottom_rule: Rule<1>,
    faces: Vec<ContactFace>,
    count: usize,
    psi: Vec<f64>,
    grad: Vec<[f64; 2]>,
    jacobian: Vec<f64>,
    columns: Vec<f64>,
    /// The right-hand sides of a cohesive face's projection, one per source point.
    moments: Vec<f64>,
    coupling: [Vec<f64>; 2],
    outer: Vec<f64>,
    block: Vec<f64>,
    crossings: Vec<Crossing>,
}

/// Linear maps of one side's state to a face frame: rows `v[0], v[1], s[0], s[1]`.
type FrameRows = [[f64; MAX_FIELDS]; 4];

fn frame_rows(system: &System, m: [f64; 2]) -> FrameRows {
    let mut rows = [[0.0; MAX_FIELDS]; 4];
    for j in 0..system.fields() {
        let mut e = [0.0; MAX_FIELDS];
        e[j] = 1.0;
        let f = system.frame(&e, m);
        for (row, value) in rows.iter_mut().zip([f.v[0], f.v[1], f.s[0], f.s[1]]) {
            row[j] = value;
        }
    }
    rows
}

/// `d w / d q` of the characteristic arriving from side a (`sign = -1`: `s - Z v`) or side b
/// (`sign = 1`: `s + Z v`), rows normal and tangential.
fn characteristic_rows(rows: &FrameRows, z: [f64; 2], sign: f64) -> [[f64; MAX_FIELDS]; 2] {
    [0, 1].map(|k| std::array::from_fn(|j| rows[2 + k][j] + sign * z[k] * rows[k][j]))
}

/// The flux `A_m q*` as a linear map of the frame values `(v[0], v[1], s[0], s[1])`: columns.
fn flux_columns(system: &System, m: [f64; 2]) -> [[f64; MAX_FIELDS]; 4] {
    std::array::from_fn(|c| {
        let mut star = FrameTrace::default();
        if c < 2 {
            star.v[c] = 1.0;
        } else {
            star.s[c - 2] = 1.0;
        }
        system.flux(&star, m)
    })
}

/// `d flux / d w` (fields x 2) for targets with `d star / d w = dstar` and `d w / d q = dw`:
/// returns the `fields x fields` Jacobian `F dstar dw`.
fn chain(
    flux: &[[f64; MAX_FIELDS]; 4],
    dstar: &[[f64; 2]; 4],
    dw: &[[f64; MAX_FIELDS]; 2],
) -> Matrix {
    let mut out = [[0.0; MAX_FIELDS]; MAX_FIELDS];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..4)
                .map(|c| flux[c][i] * (dstar[c][0] * dw[0][j] + dstar[c][1] * dw[1][j]))
                .sum();
        }
    }
    out
}

/// Side a's targets minus the bonded ones, from the arriving characteristics.
fn departure(t: &Targets, z: [f64; 2], w_a: [f64; 2], w_b: [f64; 2]) -> FrameTrace {
    let mut star = t.star;
    for k in 0..2 {
        star.v[k] -= (w_b[k] - w_a[k]) / (2.0 * z[k]);
        star.s[k] -= 0.5 * (w_a[k] + w_b[k]);
    }
    star
}

/// `t` with the bonded targets' derivatives taken off `d_wa` and `d_wb` (see [`departure`]).
fn departure_derivatives(t: &Targets, z: [f64; 2]) -> Targets {
    let mut out = *t;
    for (k, zk) in z.iter().enumerate() {
        out.d_wa[k][k] += 0.5 / zk;
        out.d_wb[k][k] -= 0.5 / zk;
        out.d_wa[2 + k][k] -= 0.5;
        out.d_wb[2 + k][k] -= 0.5;
    }
    out
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

    /// Evaluates every face at the patch solution `q` (block rows of `m` unknowns): solves each
    /// face's separation and its targets and adds `N(q)` to `nl`. Returns false when a face's
    /// separation cannot be solved.
    pub(super) fn evaluate(&mut self, system: &System, q: &[f64], nl: &mut [f64]) -> bool {
        for f in 0..self.count {
            if !self.solve_face(system, f, q) {
                return false;
            }
            self.add_flux(system, f, nl);
        }
        true
    }

    /// Adds the Jacobian of `N` at the last evaluated solution to the block system.
    pub(super) fn add_jacobians(&mut self, system: &System, blocks: &mut BlockSystem) {
        for f in 0..self.count {
            self.add_jacobian(system, f, blocks);
        }
    }

    /// Traces, separation (face DG, inner Newton) and targets of face `f` at the solution `q`.
    fn solve_face(&mut self, system: &System, f: usize, q: &[f64]) -> bool {
        let fields = system.fields();
        let c = system.c_ref();
        let nf = self.basis.len();
        let face = &mut self.faces[f];
        let n = face.phi_a.len() / face.weights.len();
        let m = n * fields;
        let points = face.weights.len();
        let z = face.law.z;
        let (qa, qb) = (
            &q[face.a * m..(face.a + 1) * m],
            &q[face.b * m..(face.b + 1) * m],
        );
        for p in 0..points {
            let trace = |coefficients: &[f64], phi: &[f64]| {
                let mut s = [0.0; MAX_FIELDS];
                for (k, &ph) in phi.iter().enumerate() {
                    for (si, c) in s
                        .iter_mut()
                        .zip(&coefficients[k * fields..(k + 1) * fields])
                    {
                        *si += ph * c;
                    }
                }
                s
            };
            let ta = trace(qa, &face.phi_a[p * n..(p + 1) * n]);
            let tb = trace(qb, &face.phi_b[p * n..(p + 1) * n]);
            let (w_a, w_b) = characteristics(
                z,
                &system.frame(&ta, face.normal),
                &system.frame(&tb, face.normal),
            );
            face.w_a[p] = w_a;
            face.w_b[p] = w_b;
        }
        // Inner Newton on the face, G(d) = M0 d - inflow - int psi rate(state) / c = 0, with a
        // backtracking line search on |G|: the area fractions saturate (flat rate beyond r_c and
        // r_s), where plain Newton steps can cycle.
        let ns = face.law.components();
        // Per component, a size of the values: the separation's (both components, at least
        // the law's scale) and the damage's (at least 1).
        let scale = face.law.separation_scale();
        let sizes = |d: &[f64]| -> [f64; STATE_COMPONENTS] {
            let largest = |range: std::ops::Range<usize>, floor: f64| {
                d[range].iter().fold(floor, |m: f64, x| m.max(x.abs()))
            };
            let separation = largest(0..2 * nf, scale);
            [separation, separation, largest(2 * nf..3 * nf, 1.0)]
        };
        // The largest step of any component relative to its size.
        let relative = |step: &[f64], size: &[f64; STATE_COMPONENTS]| {
            (0..ns).fold(0.0f64, |m, comp| {
                step[comp * nf..(comp + 1) * nf]
                    .iter()
                    .fold(m, |m, s| m.max(s.abs() / size[comp]))
            })
        };
        let n2 = ns * nf;
        let (g, rest) = self.columns.split_at_mut(n2);
        let trial_g = &mut rest[..n2];
        let jac = &mut self.jacobian[..n2 * n2];
        let sep = face.sep;
        let mut norm = face.separation_residual(c, &sep, g, Some(jac));
        let mut converged = false;
        let mut previous = f64::INFINITY;
        for _ in 0..60 {
            if !solve_dense(jac, n2, g, 1) {
                return false;
            }
            // Trust region: steps of at most half the law's scale or of the state so far, per
            // component (the cohesive traction is not monotone; a long first step can land
            // beyond its peak, in another basin of |G|).
            let size = sizes(&face.sep);
            let largest = relative(g, &size);
            if largest > 0.5 {
                g.iter_mut().for_each(|s| *s *= 0.5 / largest);
            }
            let mut alpha = 1.0;
            let mut trial = face.sep;
            loop {
                for ((t, d), s) in trial.iter_mut().zip(&face.sep).zip(g.iter()) {
                    *t = d + alpha * s;
                }
                let trial_norm = face.separation_residual(c, &trial, trial_g, None);
                if trial_norm <= (1.0 - 1e-4 * alpha) * norm || alpha < 1e-6 {
                    break;
                }
                alpha *= 0.5;
            }
            face.sep = trial;
            let step = alpha * relative(g, &sizes(&face.sep));
            if !step.is_finite() {
                return false;
            }
            let sep = face.sep;
            norm = face.separation_residual(c, &sep, g, Some(jac));
            // Converged, or stalled at round-off (the step no longer halves).
            if step <= 1e-12 || (step <= 1e-9 && step >= 0.5 * previous) {
                converged = true;
                break;
            }
            previous = step;
        }
        let sep = face.sep;
        let projected = face.project_traction(nf, &sep, true);
        for p in 0..points {
            let state = face.separation_at(nf, p, &sep);
            face.targets_a[p] = face.targets_at(p, projected, state, false);
            face.targets_b[p] = face.targets_at(p, projected, state, true);
        }
        converged
    }

    /// Adds `int phi (F* - F_bonded)` of face `f` for both sides to `nl`.
    fn add_flux(&self, system: &System, f: usize, nl: &mut [f64]) {
        let fields = system.fields();
        let face = &self.faces[f];
        let n = face.phi_a.len() / face.weights.len();
        let m = n * fields;
        let minus = face.normal.map(|x| -x);
        for p in 0..face.weights.len() {
            let w = face.weights[p];
            let (z, w_a, w_b) = (face.law.z, face.w_a[p], face.w_b[p]);
            let fa = system.flux(&departure(&face.targets_a[p], z, w_a, w_b), face.normal);
            let fb = system.flux(&departure(&face.targets_b[p], z, w_b, w_a), minus);
            for (side, flux, phi) in [
                (face.a, fa, &face.phi_a[p * n..(p + 1) * n]),
                (face.b, fb, &face.phi_b[p * n..(p + 1) * n]),
            ] {
                let rows = &mut nl[side * m..(side + 1) * m];
                for (k, &ph) in phi.iter().enumerate() {
                    for (r, fl) in rows[k * fields..(k + 1) * fields].iter_mut().zip(&flux) {
                        *r += w * ph * fl;
                    }
                }
            }
        }
    }

    /// Adds the Jacobian of face `f`'s `int phi F*` with respect to both sides' coefficients,
    /// through the traces directly and through the face's interface state.
    fn add_jacobian(&mut self, system: &System, f: usize, blocks: &mut BlockSystem) {
        let fields = system.fields();
        let c = system.c_ref();
        let nf = self.basis.len();
        let face = &self.faces[f];
        let ns = face.law.components();
        let n2 = ns * nf;
        let n = face.phi_a.len() / face.weights.len();
        let m = n * fields;
        let z = face.law.z;
        let minus = face.normal.map(|x| -x);
        let rows = frame_rows(system, face.normal);
        let (dwa, dwb) = (
            characteristic_rows(&rows, z, -1.0),
            characteristic_rows(&rows, z, 1.0),
        );
        let (flux_a, flux_b) = (
            flux_columns(system, face.normal),
            flux_columns(system, minus),
        );
        let (a, b) = (face.a, face.b);
        let projects = face.projects();
        let [coupling_a, coupling_b] = &mut self.coupling;
        coupling_a.fill(0.0);
        coupling_b.fill(0.0);
        let columns = &mut self.columns[..n2 * 2 * m];
        columns.fill(0.0);
        let jac = &mut self.jacobian[..n2 * n2];
        jac.fill(0.0);
        for comp in 0..ns {
            for k in 0..nf {
                jac[(comp * nf + k) * n2 + comp * nf..][..nf]
                    .copy_from_slice(&face.m0[k * nf..(k + 1) * nf]);
            }
        }
        for p in 0..face.weights.len() {
            let w = face.weights[p];
            let (ta, tb) = (
                &departure_derivatives(&face.targets_a[p], z),
                &departure_derivatives(&face.targets_b[p], z),
            );
            let phi_a = &face.phi_a[p * n..(p + 1) * n];
            let phi_b = &face.phi_b[p * n..(p + 1) * n];
            let psi = &face.psi[p * nf..(p + 1) * nf];
            // Direct dependence on the traces: four blocks.
            for (row, col, phi_r, phi_c, j) in [
                (a, a, phi_a, phi_a, chain(&flux_a, &ta.d_wa, &dwa)),
                (a, b, phi_a, phi_b, chain(&flux_a, &ta.d_wb, &dwb)),
                (b, b, phi_b, phi_b, chain(&flux_b, &tb.d_wa, &dwb)),
                (b, a, phi_b, phi_a, chain(&flux_b, &tb.d_wb, &dwa)),
            ] {
                for (k, &pr) in phi_r.iter().enumerate() {
                    for (l, &pc) in phi_c.iter().enumerate() {
                        self.outer[k * n + l] = w * pr * pc;
                    }
                }
                super::kron_sum(
                    blocks.block_mut(row, col),
                    Accum::Add,
                    m,
                    n,
                    fields,
                    &[(&self.outer[..n * n], j)],
                );
            }
            // Dependence through the separation: d flux / d sep per side, and the face
            // system's derivative with respect to the traces.
            for (coupling, flux, t, phi) in [
                (&mut *coupling_a, &flux_a, ta, phi_a),
                (&mut *coupling_b, &flux_b, tb, phi_b),
            ] {
                for e in 0..ns {
                    let df: [f64; MAX_FIELDS] =
                        std::array::from_fn(|i| (0..4).map(|c| flux[c][i] * t.d_sep[c][e]).sum());
                    for (k, &ph) in phi.iter().enumerate() {
                        for (i, &d) in df[..fields].iter().enumerate() {
                            let row = &mut coupling[(k * fields + i) * n2 + e * nf..][..nf];
                            for (r, &ps) in row.iter_mut().zip(psi) {
                                *r += w * ph * d * ps;
                            }
                        }
                    }
                }
                if projects {
                    // Through the projected traction: d star / d T_k is (1 - eta) / Z_k for
                    // the velocity, 1 - eta for the traction.
                    for e in 0..2 {
                        for l in 0..nf {
                            let slope = |k: usize| face.slopes[((p * 2 + k) * 2 + e) * nf + l];
                            let dstar = [
                                (1.0 - t.eta) / z[0] * slope(0),
                                (1.0 - t.eta) / z[1] * slope(1),
                                (1.0 - t.eta) * slope(0),
                                (1.0 - t.eta) * slope(1),
                            ];
                            for (k, &ph) in phi.iter().enumerate() {
                                for i in 0..fields {
                                    let d: f64 = (0..4).map(|c| flux[c][i] * dstar[c]).sum();
                                    coupling[(k * fields + i) * n2 + e * nf + l] += w * ph * d;
                                }
                            }
                        }
                    }
                }
            }
            for comp in 0..ns {
                let drate: [[f64; MAX_FIELDS]; 2] =
                    [(&ta.rate_wa[comp], &dwa), (&ta.rate_wb[comp], &dwb)]
                        .map(|(r, dw)| std::array::from_fn(|j| r[0] * dw[0][j] + r[1] * dw[1][j]));
                for (side, phi) in [phi_a, phi_b].into_iter().enumerate() {
                    for (k, &ps) in psi.iter().enumerate() {
                        for (l, &ph) in phi.iter().enumerate() {
                            for (i, &dr) in drate[side][..fields].iter().enumerate() {
                                columns[(side * m + l * fields + i) * n2 + comp * nf + k] +=
                                    w / c * ps * ph * dr;
                            }
                        }
                    }
                }
                for e in 0..ns {
                    let r = w / c * ta.rate_sep[comp][e];
                    if r == 0.0 {
                        continue;
                    }
                    for k in 0..nf {
                        let row = &mut jac[(comp * nf + k) * n2 + e * nf..][..nf];
                        for (x, &pl) in row.iter_mut().zip(psi) {
                            *x -= r * psi[k] * pl;
                        }
                    }
                }
            }
            if projects {
                face.add_projected_slopes(p, w / c, ta, jac, n2);
            }
        }
        // d sep / d q = J^-1 (int psi (d rate / d q) / c), one column per side unknown.
        if !solve_dense(jac, n2, columns, 2 * m) {
            return;
        }
        for (row_side, coupling) in [(a, &*coupling_a), (b, &*coupling_b)] {
            for (col_side, offset) in [(a, 0), (b, m)] {
                let block = &mut self.block[..m * m];
                for col in 0..m {
                    let dd = &columns[(offset + col) * n2..][..n2];
                    for row in 0..m {
                        block[col * m + row] = coupling[row * n2..(row + 1) * n2]
                            .iter()
                            .zip(dd)
                            .map(|(x, y)| x * y)
                            .sum();
                    }
                }
                for (t, s) in blocks
                    .block_mut(row_side, col_side)
                    .iter_mut()
                    .zip(block.iter())
                {
                    *t += s;
                }
            }
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A cohesive face's projection keeps the traction's moments against degree `p - 1` on the
    /// face and against degree `p` along the bottom edge, and reproduces polynomials of degree
    /// `p`: what makes the face's work the law's potential plus the work of `T` itself on the
    /// bottom's jump.
    #[test]
    fn the_projected_traction_keeps_the_face_and_bottom_moments() {
        for p in 1..=4 {
            let rule = quadrature::triangle(2 * p + 2);
            let bottom_rule = quadrature::gauss_legendre(p + 2);
            let points = rule.points.len();
            let mut faces = ContactFaces::new(1, p, points, 1, 1);
            let nf = faces.basis.len();
            let basis = FaceBasis::new(p);
            let face = &mut faces.faces[0];
            // The reference triangle, its bottom the edge eta = 0 (twice as long as in `rule`).
            let mut psi = vec![0.0; nf];
            for (q, (x, &w)) in rule.points.iter().zip(&rule.weights).enumerate() {
                face.weights[q] = w;
                basis.eval(*x, &mut psi);
                face.psi[q * nf..(q + 1) * nf].copy_from_slice(&psi);
            }
            face.bottom_weights.clear();
            face.bottom_along.clear();
            for (b, (t, &w)) in bottom_rule
                .points
                .iter()
                .zip(&bottom_rule.weights)
                .enumerate()
            {
                basis.eval([t[0], 0.0], &mut psi);
                face.bottom_psi[b * nf..(b + 1) * nf].copy_from_slice(&psi);
                face.bottom_weights.push(2.0 * w);
                face.bottom_along.push(t[0]);
            }
            face.project_matrix(&faces.basis, &mut faces.jacobian, &mut faces.moments);
            let sources: Vec<[f64; 2]> = rule
                .points
                .iter()
                .copied()
                .chain(bottom_rule.points.iter().map(|t| [t[0], 0.0]))
                .collect();
            let projected = |f: &dyn Fn([f64; 2]) -> f64| -> Vec<f64> {
                (0..points)
                    .map(|q| {
                        let row = &face.projection[q * sources.len()..][..sources.len()];
                        row.iter().zip(&sources).map(|(w, &x)| w * f(x)).sum()
                    })
                    .collect()
            };
            // Degree p is reproduced.
            let poly =
                |x: [f64; 2]| 0.3 + x[0].powi(p as i32) - 2.0 * x[0] * x[1].powi(p as i32 - 1);
            for (q, value) in projected(&poly).into_iter().enumerate() {
                assert!((value - poly(rule.points[q])).abs() < 1e-11, "p = {p}");
            }
            // A smooth traction: the projection's polynomial, from its values at the face's
            // points, against the traction's moments.
            let traction =
                |x: [f64; 2]| (0.7 * x[0] - 1.3 * x[1]).exp() + (3.0 * x[0] * x[1]).sin();
            let values = projected(&traction);
            let (mut mass, mut c) = (vec![0.0; nf * nf], vec![0.0; nf]);
            for ((psi_q, &w), value) in face.psi.chunks_exact(nf).zip(&face.weights).zip(&values) {
                for k in 0..nf {
                    for l in 0..nf {
                        mass[k * nf + l] += w * psi_q[k] * psi_q[l];
                    }
                    c[k] += w * psi_q[k] * value;
                }
            }
            assert!(solve_dense(&mut mass, nf, &mut c, 1));
            let pi = |x: [f64; 2]| {
                let mut psi = vec![0.0; nf];
                basis.eval(x, &mut psi);
                psi.iter().zip(&c).map(|(a, b)| a * b).sum::<f64>()
            };
            let interior = p * (p + 1) / 2;
            for j in 0..interior {
                let moment: f64 = (0..points)
                    .map(|q| {
                        let x = rule.points[q];
                        face.weights[q] * face.psi[q * nf + j] * (pi(x) - traction(x))
                    })
                    .sum();
                assert!(moment.abs() < 1e-12, "p = {p}, face moment {j}: {moment:e}");
            }
            for i in 0..=p {
                let moment: f64 = bottom_rule
                    .points
                    .iter()
                    .zip(&bottom_rule.weights)
                    .map(|(t, w)| {
                        w * t[0].powi(i as i32) * (pi([t[0], 0.0]) - traction([t[0], 0.0]))
                    })
                    .sum();
                assert!(
                    moment.abs() < 1e-12,
                    "p = {p}, bottom moment {i}: {moment:e}"
                );
            }
        }
    }
}
