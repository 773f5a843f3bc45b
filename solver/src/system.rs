//! Linear elastodynamics as a symmetric hyperbolic system in scaled variables.
//!
//! Unknowns are velocity and stress, `q = (v, sigma)`; the equations are
//! `rho dv/dt - div sigma = 0` and `S dsigma/dt - sym grad v = 0` with the compliance `S`.
//! To keep every matrix entry of order one, the solver works in scaled variables:
//! - coordinates `(x, y, tau)` with `tau = c_ref t` (metres), `c_ref` the fastest wave speed;
//! - velocity `v` in m/s and stress `sigma / Z_ref` with `Z_ref = rho c_ref` (also m/s).
//!
//! The scaled system is `A0 dq/dtau + Ax dq/dx + Ay dq/dy = 0` with `A0 = diag(I, rho c_ref^2 S)`,
//! and the flux through a face with unit normal `n = (n_x, n_y, n_tau)` is `A_n q` with
//! `A_n = n_tau A0 + n_x Ax + n_y Ay`. Energy densities in these variables are `1 / rho` times
//! the physical ones.
//!
//! Field layout: in-plane `q = [v1, v2, s11, s22, s12]`; anti-plane `q = [v3, s31, s32]`.

use crate::material::{Material, Plane};

/// Largest number of fields (in-plane).
pub const MAX_FIELDS: usize = 5;
/// A state vector; only the first [`System::fields`] entries are used.
pub type State = [f64; MAX_FIELDS];
/// A square matrix on states; only the leading `fields x fields` block is used.
pub type Matrix = [[f64; MAX_FIELDS]; MAX_FIELDS];

/// Velocity and traction in a face frame: index 0 is the normal direction and 1 the tangential
/// one (in-plane), or index 0 the out-of-plane direction (anti-plane, index 1 unused).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTrace {
    /// Velocity components, m/s.
    pub v: [f64; 2],
    /// Traction components `(sigma m) . e`, scaled by `1 / Z_ref` (m/s).
    pub s: [f64; 2],
}

/// The scaled first-order system of one material.
#[derive(Clone, Debug)]
pub struct System {
    plane: Plane,
    fields: usize,
    c_ref: f64,
    z_ref: f64,
    a0: Matrix,
    a: [Matrix; 2],
    impedance: [f64; 2],
}

impl System {
    /// The system of `material`, scaled by its fastest wave speed.
    pub fn new(material: &Material) -> Self {
        let plane = material.plane();
        let c_ref = material.max_wave_speed();
        let rho = material.density();
        let (mu, lambda) = (material.mu(), material.lambda());
        let stiffness = rho * c_ref * c_ref;
        let mut a0 = [[0.0; MAX_FIELDS]; MAX_FIELDS];
        let mut a = [[[0.0; MAX_FIELDS]; MAX_FIELDS]; 2];
        let fields;
        let impedance;
        match plane {
            Plane::Strain | Plane::Stress => {
                fields = 5;
                a0[0][0] = 1.0;
                a0[1][1] = 1.0;
                // Compliance of [s11, s22, s12] -> [e11, e22, 2 e12], times rho c_ref^2.
                let det = 4.0 * mu * (lambda + mu);
                let diag = (lambda + 2.0 * mu) / det;
                let off = -lambda / det;
                a0[2][2] = stiffness * diag;
                a0[3][3] = stiffness * diag;
                a0[2][3] = stiffness * off;
                a0[3][2] = stiffness * off;
                a0[4][4] = stiffness / mu;
                // Ax: v1 <-> s11, v2 <-> s12; Ay: v1 <-> s12, v2 <-> s22.
                for (dir, pairs) in [[(0, 2), (1, 4)], [(0, 4), (1, 3)]].iter().enumerate() {
                    for &(i, j) in pairs {
                        a[dir][i][j] = -1.0;
                        a[dir][j][i] = -1.0;
                    }
                }
                impedance = [material.c_d() / c_ref, material.c_s() / c_ref];
            }
            Plane::Antiplane => {
                fields = 3;
                a0[0][0] = 1.0;
                a0[1][1] = stiffness / mu;
                a0[2][2] = stiffness / mu;
                for (dir, j) in [(0, 1), (1, 2)] {
                    a[dir][0][j] = -1.0;
                    a[dir][j][0] = -1.0;
                }
                impedance = [material.c_s() / c_ref, 0.0];
            }
        }
        Self {
            plane,
            fields,
            c_ref,
            z_ref: rho * c_ref,
            a0,
            a,
            impedance,
        }
    }

    /// The 2D mode.
    pub fn plane(&self) -> Plane {
        self.plane
    }

    /// Number of fields: 5 in-plane, 3 anti-plane.
    pub fn fields(&self) -> usize {
        self.fields
    }

    /// Number of displacement components: 2 in-plane, 1 anti-plane.
    pub fn displacement_components(&self) -> usize {
        if self.plane == Plane::Antiplane { 1 } else { 2 }
    }

    /// Number of face-frame directions with a wave: 2 in-plane (normal, tangential), 1 anti-plane.
    pub fn directions(&self) -> usize {
        self.displacement_components()
    }

    /// The reference wave speed `c_ref` (m/s): `tau = c_ref t`.
    pub fn c_ref(&self) -> f64 {
        self.c_ref
    }

    /// The reference impedance `Z_ref = rho c_ref` (Pa s/m): scaled stress is `sigma / Z_ref`.
    pub fn z_ref(&self) -> f64 {
        self.z_ref
    }

    /// Scaled impedance per face-frame direction (`c_d / c_ref`, `c_s / c_ref`, or `c_s / c_ref`
    /// for anti-plane).
    pub fn impedance(&self) -> [f64; 2] {
        self.impedance
    }

    /// `A_n = n_tau A0 + n_x Ax + n_y Ay` for `n = [n_x, n_y, n_tau]`.
    pub fn a_n(&self, n: [f64; 3]) -> Matrix {
        let mut m = [[0.0; MAX_FIELDS]; MAX_FIELDS];
        for (i, row) in m.iter_mut().enumerate().take(self.fields) {
            for (j, entry) in row.iter_mut().enumerate().take(self.fields) {
                *entry = n[2] * self.a0[i][j] + n[0] * self.a[0][i][j] + n[1] * self.a[1][i][j];
            }
        }
        m
    }

    /// `M q` on the used fields.
    pub fn apply(&self, m: &Matrix, q: &State) -> State {
        let mut out = [0.0; MAX_FIELDS];
        for (i, o) in out.iter_mut().enumerate().take(self.fields) {
            *o = (0..self.fields).map(|j| m[i][j] * q[j]).sum();
        }
        out
    }

    /// `p . q` on the used fields.
    pub fn dot(&self, p: &State, q: &State) -> f64 {
        (0..self.fields).map(|i| p[i] * q[i]).sum()
    }

    /// Scaled energy density `q . A0 q / 2` (physical: times `rho`, J/m^3).
    pub fn energy_density(&self, q: &State) -> f64 {
        0.5 * self.dot(q, &self.apply(&self.a0, q))
    }

    /// Kinetic part of [`Self::energy_density`].
    pub fn kinetic_density(&self, q: &State) -> f64 {
        let n = self.displacement_components();
        0.5 * q[..n].iter().map(|v| v * v).sum::<f64>()
    }

    /// Physical `(velocity, stress)` to scaled.
    pub fn to_scaled(&self, q: &State) -> State {
        let mut out = *q;
        for s in &mut out[self.displacement_components()..self.fields] {
            *s /= self.z_ref;
        }
        out
    }

    /// Scaled state to physical `(velocity m/s, stress Pa)`.
    pub fn to_physical(&self, q: &State) -> State {
        let mut out = *q;
        for s in &mut out[self.displacement_components()..self.fields] {
            *s *= self.z_ref;
        }
        out
    }

    /// Velocity and traction of `q` in the frame of the face with unit normal `m = [m1, m2]`
    /// (tangent `[-m2, m1]`).
    pub fn frame(&self, q: &State, m: [f64; 2]) -> FrameTrace {
        match self.plane {
            Plane::Antiplane => FrameTrace {
                v: [q[0], 0.0],
                s: [q[1] * m[0] + q[2] * m[1], 0.0],
            },
            Plane::Strain | Plane::Stress => {
                let t = [-m[1], m[0]];
                let s = [q[2] * m[0] + q[4] * m[1], q[4] * m[0] + q[3] * m[1]];
                FrameTrace {
                    v: [q[0] * m[0] + q[1] * m[1], q[0] * t[0] + q[1] * t[1]],
                    s: [s[0] * m[0] + s[1] * m[1], s[0] * t[0] + s[1] * t[1]],
                }
            }
        }
    }

    /// A global vector `[x, y]` (or the out-of-plane scalar in entry 0) in the face frame of
    /// normal `m`.
    pub fn vector_in_frame(&self, w: [f64; 2], m: [f64; 2]) -> [f64; 2] {
        match self.plane {
            Plane::Antiplane => w,
            Plane::Strain | Plane::Stress => {
                [w[0] * m[0] + w[1] * m[1], -w[0] * m[1] + w[1] * m[0]]
            }
        }
    }

    /// The flux `A_m q*` through a vertical face of unit normal `m` of a state whose frame
    /// velocity and traction are `star`: it depends on nothing else.
    pub fn flux(&self, star: &FrameTrace, m: [f64; 2]) -> State {
        let mut f = [0.0; MAX_FIELDS];
        match self.plane {
            Plane::Antiplane => {
                f[0] = -star.s[0];
                f[1] = -star.v[0] * m[0];
                f[2] = -star.v[0] * m[1];
            }
            Plane::Strain | Plane::Stress => {
                let t = [-m[1], m[0]];
                let v = [0, 1].map(|i| star.v[0] * m[i] + star.v[1] * t[i]);
                let s = [0, 1].map(|i| star.s[0] * m[i] + star.s[1] * t[i]);
                f[0] = -s[0];
                f[1] = -s[1];
                f[2] = -v[0] * m[0];
                f[3] = -v[1] * m[1];
                f[4] = -(v[0] * m[1] + v[1] * m[0]);
            }
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn systems() -> Vec<System> {
        [Plane::Strain, Plane::Stress, Plane::Antiplane]
            .map(|p| System::new(&Material::new(3.24e9, 0.35, 1190.0, p).unwrap()))
            .into()
    }

    fn sample(fields: usize) -> State {
        let mut q = [0.0; MAX_FIELDS];
        for (i, x) in q.iter_mut().enumerate().take(fields) {
            *x = 0.3 + 0.7 * i as f64 - 0.2 * (i * i) as f64;
        }
        q
    }

    #[test]
    fn flux_from_frame_matches_a_n() {
        for s in systems() {
            let q = sample(s.fields());
            for angle in [0.0f64, 0.4, 2.0, -2.7] {
                let m = [angle.cos(), angle.sin()];
                let direct = s.apply(&s.a_n([m[0], m[1], 0.0]), &q);
                let via = s.flux(&s.frame(&q, m), m);
                for i in 0..s.fields() {
                    assert!((direct[i] - via[i]).abs() < 1e-14, "{:?} {i}", s.plane());
                }
            }
        }
    }

    #[test]
    fn wave_speeds_are_the_generalized_eigenvalues() {
        // det(Ax - lambda A0) = 0 at lambda = c/c_ref for each wave: apply (Ax - lambda A0) to
        // the known eigenvector of each wave running along +x, in every plane mode (stresses
        // scaled by rho c_ref, so the impedance of a wave of speed c reads c / c_ref).
        for plane in [Plane::Strain, Plane::Stress, Plane::Antiplane] {
            let m = Material::new(3.24e9, 0.35, 1190.0, plane).unwrap();
            let s = System::new(&m);
            let (p, sh) = (m.c_d() / s.c_ref(), m.c_s() / s.c_ref());
            let ratio = m.lambda() / (m.lambda() + 2.0 * m.mu());
            let state = |values: &[f64]| {
                let mut q = [0.0; MAX_FIELDS];
                q[..values.len()].copy_from_slice(values);
                q
            };
            let modes = if plane == Plane::Antiplane {
                // S wave: v3 = 1, s13 = -z_s.
                vec![(sh, state(&[1.0, -sh, 0.0]))]
            } else {
                vec![
                    // P wave: v1 = 1, s11 = -z_d, s22 = -z_d lambda / (lambda + 2 mu).
                    (p, state(&[1.0, 0.0, -p, -p * ratio, 0.0])),
                    // S wave: v2 = 1, s12 = -z_s.
                    (sh, state(&[0.0, 1.0, 0.0, 0.0, -sh])),
                ]
            };
            for (c, r) in modes {
                let lhs = s.apply(&s.a_n([1.0, 0.0, 0.0]), &r);
                let rhs = s.apply(&s.a_n([0.0, 0.0, 1.0]), &r);
                for i in 0..s.fields() {
                    assert!(
                        (lhs[i] - c * rhs[i]).abs() < 1e-12,
                        "{plane:?}, speed {c}, {i}: {lhs:?} vs {rhs:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn scaling_round_trips_and_energy_is_positive() {
        for s in systems() {
            let q = sample(s.fields());
            let back = s.to_physical(&s.to_scaled(&q));
            assert!((0..s.fields()).all(|i| (back[i] - q[i]).abs() < 1e-12 * q[i].abs().max(1.0)));
            assert!(s.energy_density(&q) > s.kinetic_density(&q));
        }
    }
}
