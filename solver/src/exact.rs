//! Exact solutions for verification: plane P and S waves.

use crate::material::{Material, Plane};
use crate::system::{MAX_FIELDS, State};

/// Wave type of a plane wave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wave {
    /// Dilatational: velocity along the propagation direction, speed `c_d` (in-plane only).
    P,
    /// Shear: velocity across the propagation direction (out of plane in anti-plane shear),
    /// speed `c_s`.
    S,
}

/// Shape of a plane wave along its propagation coordinate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Profile {
    /// `sin(2 pi xi / wavelength)`: smooth and periodic.
    Sine,
    /// The compact C5 bump `(1 - 4 s^2)^6` for `|s| < 1/2`, `s = (xi - center) / wavelength`.
    Pulse,
}

/// Why a plane wave cannot be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ExactError {
    #[error("a P wave needs an in-plane mode (anti-plane shear carries S waves only)")]
    PInAntiplane,
    #[error("wavelength must be positive, got {0} m")]
    Wavelength(f64),
}

/// A plane wave `q(x, t) = f(d . x - c t) r` in an unbounded medium, with velocity amplitude
/// `amplitude` (m/s), propagation direction `d` and eigenvector `r` of its wave type.
#[derive(Clone, Debug, PartialEq)]
pub struct PlaneWave {
    direction: [f64; 2],
    speed: f64,
    wavelength: f64,
    amplitude: f64,
    profile: Profile,
    center: f64,
    /// Physical state per unit profile value.
    shape: State,
    /// Displacement direction (in-plane) or `[1, 0]` (anti-plane).
    polarization: [f64; 2],
}

impl PlaneWave {
    /// A wave of type `wave` travelling at `angle_deg` from the x axis.
    pub fn new(
        material: &Material,
        wave: Wave,
        angle_deg: f64,
        wavelength: f64,
        amplitude: f64,
        profile: Profile,
        center: f64,
    ) -> Result<Self, ExactError> {
        if !(wavelength > 0.0 && wavelength.is_finite()) {
            return Err(ExactError::Wavelength(wavelength));
        }
        let d = {
            let a = angle_deg.to_radians();
            [a.cos(), a.sin()]
        };
        let (mu, lambda) = (material.mu(), material.lambda());
        let mut shape = [0.0; MAX_FIELDS];
        let (speed, polarization) = match (material.plane(), wave) {
            (Plane::Antiplane, Wave::P) => return Err(ExactError::PInAntiplane),
            (Plane::Antiplane, Wave::S) => {
                let c = material.c_s();
                shape[0] = 1.0;
                shape[1] = -mu / c * d[0];
                shape[2] = -mu / c * d[1];
                (c, [1.0, 0.0])
            }
            (_, Wave::P) => {
                let c = material.c_d();
                shape[0] = d[0];
                shape[1] = d[1];
                shape[2] = -(lambda + 2.0 * mu * d[0] * d[0]) / c;
                shape[3] = -(lambda + 2.0 * mu * d[1] * d[1]) / c;
                shape[4] = -2.0 * mu * d[0] * d[1] / c;
                (c, d)
            }
            (_, Wave::S) => {
                let c = material.c_s();
                let p = [-d[1], d[0]];
                shape[0] = p[0];
                shape[1] = p[1];
                shape[2] = -2.0 * mu * p[0] * d[0] / c;
                shape[3] = -2.0 * mu * p[1] * d[1] / c;
                shape[4] = -mu * (p[0] * d[1] + p[1] * d[0]) / c;
                (c, p)
            }
        };
        Ok(Self {
            direction: d,
            speed,
            wavelength,
            amplitude,
            profile,
            center,
            shape,
            polarization,
        })
    }

    /// Wave speed, m/s.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    fn phase(&self, x: [f64; 2], t: f64) -> f64 {
        self.direction[0] * x[0] + self.direction[1] * x[1] - self.speed * t
    }

    /// Profile value and its antiderivative (in `xi`) at phase `xi`.
    fn profile(&self, xi: f64) -> (f64, f64) {
        let lw = self.wavelength;
        match self.profile {
            Profile::Sine => {
                let k = 2.0 * std::f64::consts::PI / lw;
                ((k * xi).sin(), -(k * xi).cos() / k)
            }
            Profile::Pulse => {
                let s = ((xi - self.center) / lw).clamp(-0.5, 0.5);
                let value = if s.abs() < 0.5 {
                    (1.0 - 4.0 * s * s).powi(6)
                } else {
                    0.0
                };
                // Antiderivative of the expanded polynomial sum_k C(6,k) (-4)^k s^(2k) from -1/2.
                let mut integral = 0.0;
                let mut binom = 1.0;
                for k in 0..=6 {
                    let c = binom * (-4.0f64).powi(k) / (2 * k + 1) as f64;
                    integral += c * (s.powi(2 * k + 1) + 0.5f64.powi(2 * k + 1));
                    binom = binom * (6 - k) as f64 / (k + 1) as f64;
                }
                (value, lw * integral)
            }
        }
    }

    /// Physical state (velocity m/s, stress Pa) at `x` (m) and `t` (s).
    pub fn state(&self, x: [f64; 2], t: f64) -> State {
        let f = self.amplitude * self.profile(self.phase(x, t)).0;
        self.shape.map(|r| f * r)
    }

    /// Displacement (m) at `x` and `t`: the time integral of the velocity with zero mean for the
    /// sine and zero ahead of the pulse.
    pub fn displacement(&self, x: [f64; 2], t: f64) -> [f64; 2] {
        let u = -self.amplitude * self.profile(self.phase(x, t)).1 / self.speed;
        self.polarization.map(|p| p * u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks that `wave` satisfies momentum balance and the constitutive law in `material`
    /// (Young's modulus `young`, Poisson ratio `nu`) at one point, by central differences:
    /// each equation's residual within `1e-6` of the sum of its terms' sizes (the differences
    /// are good to about `1e-9` of them), and the terms not all zero.
    fn check_pde(material: &Material, (young, nu): (f64, f64), wave: Wave, profile: Profile) {
        let pw = PlaneWave::new(material, wave, 30.0, 0.01, 0.5, profile, 0.001).unwrap();
        let (x, t, h) = ([0.0031, -0.0017], 1.3e-6, 1e-7);
        let dt = |i: usize| {
            let ht = h / pw.speed();
            (pw.state(x, t + ht)[i] - pw.state(x, t - ht)[i]) / (2.0 * ht)
        };
        let dx = |k: usize, i: usize| {
            let mut xp = x;
            let mut xm = x;
            xp[k] += h;
            xm[k] -= h;
            (pw.state(xp, t)[i] - pw.state(xm, t)[i]) / (2.0 * h)
        };
        // Each equation as its terms, which sum to zero.
        let rho = material.density();
        let mu = young / (2.0 * (1.0 + nu));
        let lambda3 = young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let equations: Vec<Vec<f64>> = match material.plane() {
            Plane::Antiplane => vec![
                vec![rho * dt(0), -dx(0, 1), -dx(1, 2)],
                vec![dt(1), -mu * dx(0, 0)],
                vec![dt(2), -mu * dx(1, 0)],
            ],
            plane => {
                let lambda = if plane == Plane::Stress {
                    2.0 * mu * lambda3 / (lambda3 + 2.0 * mu)
                } else {
                    lambda3
                };
                let (vx_x, vy_y) = (dx(0, 0), dx(1, 1));
                vec![
                    vec![rho * dt(0), -dx(0, 2), -dx(1, 4)],
                    vec![rho * dt(1), -dx(0, 4), -dx(1, 3)],
                    vec![dt(2), -(lambda + 2.0 * mu) * vx_x, -lambda * vy_y],
                    vec![dt(3), -lambda * vx_x, -(lambda + 2.0 * mu) * vy_y],
                    vec![dt(4), -mu * (dx(1, 0) + dx(0, 1))],
                ]
            }
        };
        for (i, terms) in equations.iter().enumerate() {
            let residual: f64 = terms.iter().sum();
            let size: f64 = terms.iter().map(|t| t.abs()).sum();
            assert!(
                residual.abs() <= 1e-6 * size,
                "{:?} {wave:?} {profile:?}, equation {i}: {terms:?}",
                material.plane()
            );
        }
        let momentum: f64 = equations[0].iter().map(|t| t.abs()).sum();
        assert!(momentum > 0.0, "the point lies outside the wave");
        // Displacement rate equals velocity.
        let u = |t| pw.displacement(x, t);
        let ht = 1e-10;
        let du = (u(t + ht)[0] - u(t - ht)[0]) / (2.0 * ht);
        let pol = if material.plane() == Plane::Antiplane {
            1.0
        } else {
            pw.polarization[0]
        };
        let v = pw.state(x, t)[0] / pol;
        assert!((du / pol - v).abs() < 1e-5 * v.abs().max(1e-3), "{du} {v}");
    }

    #[test]
    fn plane_waves_solve_the_equations_of_motion() {
        let (young, nu) = (3.24e9, 0.35);
        for plane in [Plane::Strain, Plane::Stress, Plane::Antiplane] {
            let m = Material::new(young, nu, 1190.0, plane).unwrap();
            for profile in [Profile::Sine, Profile::Pulse] {
                if plane != Plane::Antiplane {
                    check_pde(&m, (young, nu), Wave::P, profile);
                }
                check_pde(&m, (young, nu), Wave::S, profile);
            }
        }
    }

    #[test]
    fn p_waves_need_an_in_plane_mode() {
        let m = Material::new(3.24e9, 0.35, 1190.0, Plane::Antiplane).unwrap();
        let e = PlaneWave::new(&m, Wave::P, 0.0, 1.0, 1.0, Profile::Sine, 0.0);
        assert_eq!(e, Err(ExactError::PInAntiplane));
    }
}
