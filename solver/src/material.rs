//! Isotropic linear elastic materials in the three 2D modes and their wave speeds.

/// Which 2D reduction of 3D elasticity is modelled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plane {
    /// Plane strain: `E_zz = 0`; uses the 3D Lame constant `lambda`.
    Strain,
    /// Plane stress: `sigma_zz = 0`; uses `lambda_hat = 2 mu lambda / (lambda + 2 mu)`.
    Stress,
    /// Anti-plane shear (mode III): one out-of-plane displacement, the scalar wave equation
    /// with speed `c_s`.
    Antiplane,
}

/// Why material parameters are not physical.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MaterialError {
    #[error("young: must be positive and finite, got {0} Pa")]
    Young(f64),
    #[error("poisson: must be in (-1, 0.5), got {0}")]
    Poisson(f64),
    #[error("density: must be positive and finite, got {0} kg/m^3")]
    Density(f64),
}

impl MaterialError {
    /// The parameter at fault: `young`, `poisson` or `density`.
    pub fn field(&self) -> &'static str {
        match self {
            Self::Young(_) => "young",
            Self::Poisson(_) => "poisson",
            Self::Density(_) => "density",
        }
    }
}

/// An isotropic linear elastic material (SI units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    young: f64,
    poisson: f64,
    density: f64,
    plane: Plane,
}

impl Material {
    /// A material with Young's modulus `young` (Pa), Poisson ratio `poisson` in (-1, 0.5) and
    /// mass density `density` (kg/m^3), in the 2D mode `plane`.
    pub fn new(
        young: f64,
        poisson: f64,
        density: f64,
        plane: Plane,
    ) -> Result<Self, MaterialError> {
        if !(young.is_finite() && young > 0.0) {
            return Err(MaterialError::Young(young));
        }
        if !(poisson > -1.0 && poisson < 0.5) {
            return Err(MaterialError::Poisson(poisson));
        }
        if !(density.is_finite() && density > 0.0) {
            return Err(MaterialError::Density(density));
        }
        Ok(Self {
            young,
            poisson,
            density,
            plane,
        })
    }

    /// The 2D mode.
    pub fn plane(&self) -> Plane {
        self.plane
    }

    /// Poisson ratio.
    pub fn poisson(&self) -> f64 {
        self.poisson
    }

    /// Mass density, kg/m^3.
    pub fn density(&self) -> f64 {
        self.density
    }

    /// Shear modulus `mu`, Pa.
    pub fn mu(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// The in-plane Lame constant of the mode, Pa: 3D `lambda` in plane strain, `lambda_hat` in
    /// plane stress (and the 3D value, unused by the equations, in anti-plane shear).
    pub fn lambda(&self) -> f64 {
        let nu = self.poisson;
        let lambda = self.young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        match self.plane {
            Plane::Stress => 2.0 * self.mu() * lambda / (lambda + 2.0 * self.mu()),
            Plane::Strain | Plane::Antiplane => lambda,
        }
    }

    /// Dilatational wave speed `c_d = sqrt((lambda + 2 mu) / rho)`, m/s.
    pub fn c_d(&self) -> f64 {
        ((self.lambda() + 2.0 * self.mu()) / self.density).sqrt()
    }

    /// Shear wave speed `c_s = sqrt(mu / rho)`, m/s.
    pub fn c_s(&self) -> f64 {
        (self.mu() / self.density).sqrt()
    }

    /// Rayleigh wave speed `c_R`, m/s: the root in `(0, c_s)` of
    /// `D = 4 a1 a2 - (1 + a2^2)^2` with `a1 = sqrt(1 - c^2/c_d^2)`, `a2 = sqrt(1 - c^2/c_s^2)`
    /// (seed 2.44d), found by bisection to round-off.
    pub fn c_r(&self) -> f64 {
        let k2 = (self.c_s() / self.c_d()).powi(2);
        // With x = (c / c_s)^2, D / x changes sign once on (0, 1): negative near 0, 1 at x = 1.
        let f = |x: f64| ((2.0 - x).powi(2) - 4.0 * ((1.0 - k2 * x) * (1.0 - x)).sqrt()) / x;
        let (mut lo, mut hi) = (1e-12, 1.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        self.c_s() * (0.5 * (lo + hi)).sqrt()
    }

    /// The fastest wave speed of the mode, m/s: `c_d` in plane strain and stress, `c_s` in
    /// anti-plane shear. Tent pitching keeps the front causal for this speed.
    pub fn max_wave_speed(&self) -> f64 {
        match self.plane {
            Plane::Antiplane => self.c_s(),
            Plane::Strain | Plane::Stress => self.c_d(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pmma(plane: Plane) -> Material {
        Material::new(3.24e9, 0.35, 1190.0, plane).unwrap()
    }

    #[test]
    fn pmma_plane_strain_speeds_match_the_seed() {
        let m = pmma(Plane::Strain);
        // The seed quotes 2090, 1004 and 938 m/s, truncated to whole m/s.
        assert!((m.c_d() - 2090.0).abs() < 1.0, "{}", m.c_d());
        assert!((m.c_s() - 1004.0).abs() < 1.0, "{}", m.c_s());
        assert!((m.c_r() - 938.0).abs() < 1.0, "{}", m.c_r());
        assert_eq!(m.max_wave_speed(), m.c_d());
    }

    #[test]
    fn plane_stress_uses_lambda_hat() {
        let (strain, stress) = (pmma(Plane::Strain), pmma(Plane::Stress));
        let nu: f64 = 0.35;
        // Plane stress c_d^2 = E / (rho (1 - nu^2)).
        let expected = (3.24e9 / (1190.0 * (1.0 - nu * nu))).sqrt();
        assert!((stress.c_d() - expected).abs() < 1e-9 * expected);
        assert!(stress.c_d() < strain.c_d());
        assert_eq!(stress.c_s(), strain.c_s());
        assert_eq!(pmma(Plane::Antiplane).max_wave_speed(), strain.c_s());
    }

    #[test]
    fn rayleigh_root_satisfies_the_dispersion_relation() {
        let m = pmma(Plane::Strain);
        let c = m.c_r();
        let a1 = (1.0 - (c / m.c_d()).powi(2)).sqrt();
        let a2 = (1.0 - (c / m.c_s()).powi(2)).sqrt();
        assert!((4.0 * a1 * a2 - (1.0 + a2 * a2).powi(2)).abs() < 1e-12);
    }

    #[test]
    fn rejects_unphysical_parameters() {
        assert_eq!(
            Material::new(1.0, 0.5, 1.0, Plane::Strain),
            Err(MaterialError::Poisson(0.5))
        );
        assert_eq!(
            Material::new(1.0, 0.2, -1.0, Plane::Strain),
            Err(MaterialError::Density(-1.0))
        );
        assert_eq!(
            Material::new(0.0, 0.2, 1.0, Plane::Strain),
            Err(MaterialError::Young(0.0))
        );
        assert!(Material::new(1.0, f64::NAN, 1.0, Plane::Strain).is_err());
    }
}
