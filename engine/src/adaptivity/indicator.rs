//! Error-driven refinement: the bulk dissipation indicator of a patch and its tolerance.
//!
//! A patch's numerical dissipation `D` (J/m, non-negative per element) is compared with the
//! dissipation a patch would be allowed if the whole domain lost a fraction `tol` of the
//! reference energy while a wave crosses it:
//!
//! `eta = D / (E_ref * (V / (A L / c)))`,
//!
//! where `V` is the patch's spacetime volume (m^2 s), `A` the domain area (m^2), `L` its diameter
//! (m), `c` the fastest wave speed (m/s) and `E_ref` the initial energy plus all work done
//! through the boundary so far (J/m). `eta` is dimensionless and independent of the load scale
//! (`D` and `E_ref` are both quadratic in it) and of the mesh size (`V / (A L / c)` is the
//! patch's share of one crossing of the domain): with every patch at `eta = tol`, a crossing
//! dissipates a fraction `tol` of the energy. A patch with `eta > tol` is rejected and the front
//! around its vertex refined; elements of patches with `eta < tol / coarsen_ratio` are calm, and
//! a bisection vertex whose elements are all calm is removed again by a coarsening patch.

use sdg_mesh::Mesh;

use crate::config::{AdaptConfig, ZoneConfig};

/// Refinement settings of a run.
#[derive(Clone, Debug)]
pub(crate) struct Adapt {
    /// Upper tolerance of `eta`.
    pub(crate) tol: f64,
    /// Lower tolerance of `eta`: elements accepted below it may be coarsened.
    pub(crate) lower: f64,
    /// No edge is halved into pieces shorter than this, m.
    pub(crate) min_edge: f64,
    /// Longest edge allowed before the first tent, m.
    pub(crate) max_edge: f64,
    /// Longest refinement edge in the star of an active crack tip, m (infinite: no rule).
    pub(crate) tip_edge: f64,
    /// Shortest piece the indicator makes away from interfaces and crack tips, m (0: no rule).
    pub(crate) far_edge: f64,
    /// Zones with a finer longest edge.
    zones: Vec<ZoneConfig>,
    /// Least reference energy, in the scaled units of the indicator's energies (J/m over the
    /// density).
    energy_floor: f64,
    /// The reference energy is `energy_floor` alone (`adapt.fixed_reference`).
    fixed: bool,
    /// `A L / c`, m^2 s: the spacetime volume of one crossing of the domain.
    crossing: f64,
}

impl Adapt {
    /// Settings for `mesh`, fastest wave speed `c_max` (m/s) and density `rho` (kg/m^3, which
    /// scales J/m to the indicator's energies), or `None` when disabled.
    pub(crate) fn new(config: &AdaptConfig, mesh: &Mesh, c_max: f64, rho: f64) -> Option<Self> {
        if !config.enabled {
            return None;
        }
        let area: f64 = (0..mesh.triangles().len() as u32)
            .map(|t| mesh.area(t))
            .sum();
        let (lo, hi) = mesh.vertices().iter().fold(
            ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            },
        );
        let diameter = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
        Some(Self {
            tol: config.tol,
            lower: config.tol / config.coarsen_ratio,
            min_edge: config.min_edge.unwrap_or(1e-3 * mesh.edge_length_range().0),
            max_edge: config.max_edge.unwrap_or(f64::INFINITY),
            tip_edge: config.tip_edge.unwrap_or(f64::INFINITY),
            far_edge: config.far_edge.unwrap_or(0.0),
            zones: config.zone.clone(),
            energy_floor: config.reference_energy.map_or(0.0, |e| e / rho),
            fixed: config.fixed_reference,
            crossing: area * diameter / c_max,
        })
    }

    /// The longest edge allowed at `x` (m): the finest zone containing it, else `max_edge`.
    pub(crate) fn max_edge_at(&self, x: [f64; 2]) -> f64 {
        self.zones
            .iter()
            .filter(|z| distance_to_segment(x, z.from, z.to) <= z.radius)
            .map(|z| z.max_edge)
            .fold(self.max_edge, f64::min)
    }

    /// `eta` of a patch that dissipated `dissipation` over spacetime volume `volume` (m^2 s),
    /// with reference energy `energy` (at least `adapt.reference_energy`, or that alone with
    /// `adapt.fixed_reference`; both energies in the same units); zero while the body holds no
    /// energy.
    pub(crate) fn indicator(&self, dissipation: f64, volume: f64, energy: f64) -> f64 {
        let energy = if self.fixed {
            self.energy_floor
        } else {
            energy.max(self.energy_floor)
        };
        if energy > 0.0 {
            dissipation * self.crossing / (energy * volume)
        } else {
            0.0
        }
    }
}

/// Distance from `x` to the segment `a`-`b`, m.
fn distance_to_segment(x: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let length2 = d[0] * d[0] + d[1] * d[1];
    let along = if length2 > 0.0 {
        (((x[0] - a[0]) * d[0] + (x[1] - a[1]) * d[1]) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (x[0] - a[0] - along * d[0]).hypot(x[1] - a[1] - along * d[1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use sdg_mesh::{Diagonal, Rectangle};

    #[test]
    fn zones_set_a_finer_longest_edge() {
        let config = AdaptConfig {
            enabled: true,
            max_edge: Some(0.5),
            zone: vec![
                ZoneConfig {
                    from: [0.0, 0.5],
                    to: [1.0, 0.5],
                    radius: 0.1,
                    max_edge: 0.05,
                },
                ZoneConfig {
                    from: [1.0, 0.5],
                    to: [1.0, 0.5],
                    radius: 0.2,
                    max_edge: 0.01,
                },
            ],
            ..AdaptConfig::default()
        };
        let a = Adapt::new(&config, &unit(4), 1.0, 1.0).unwrap();
        assert_eq!(a.max_edge_at([0.5, 0.59]), 0.05);
        assert_eq!(a.max_edge_at([0.5, 0.61]), 0.5);
        assert_eq!(
            a.max_edge_at([-0.05, 0.5]),
            0.05,
            "beyond the end, within the radius"
        );
        assert_eq!(a.max_edge_at([1.1, 0.6]), 0.01, "the finest zone wins");
        assert_eq!(a.max_edge_at([1.5, 0.5]), 0.5);
    }

    fn unit(n: u32) -> Mesh {
        Rectangle {
            width: 2.0,
            height: 1.0,
            nx: n,
            ny: n,
            diagonal: Diagonal::Right,
            interfaces: Vec::new(),
            sides: Vec::new(),
            perturb: 0.0,
            seed: 0,
        }
        .build()
        .unwrap()
    }

    #[test]
    fn indicator_is_the_dissipated_share_of_one_crossing() {
        let config = AdaptConfig {
            enabled: true,
            ..AdaptConfig::default()
        };
        let a = Adapt::new(&config, &unit(4), 2.0, 1.0).unwrap();
        // A = 2, L = sqrt(5), c = 2: one crossing is sqrt(5) m^2 s.
        let crossing = 5f64.sqrt();
        let eta = a.indicator(1e-3, 0.1 * crossing, 2.0);
        assert!((eta - 1e-3 / (2.0 * 0.1)).abs() < 1e-15);
        assert_eq!(a.indicator(1.0, 1.0, 0.0), 0.0);
        // The same loss at four times the energy and the same share is four times smaller.
        assert!((a.indicator(1e-3, 0.1 * crossing, 8.0) - eta / 4.0).abs() < 1e-15);
        assert!(Adapt::new(&AdaptConfig::default(), &unit(4), 2.0, 1.0).is_none());
        // A reference energy floor of 8 J/m at density 2 (4 in scaled units) replaces the 2.
        let floored = AdaptConfig {
            reference_energy: Some(8.0),
            ..config.clone()
        };
        let f = Adapt::new(&floored, &unit(4), 2.0, 2.0).unwrap();
        assert!((f.indicator(1e-3, 0.1 * crossing, 2.0) - eta / 2.0).abs() < 1e-15);
        assert!((f.indicator(1e-3, 0.1 * crossing, 8.0) - eta / 4.0).abs() < 1e-15);
        // A fixed reference ignores the energy held: 4 in scaled units whatever it is.
        let fixed = AdaptConfig {
            reference_energy: Some(8.0),
            fixed_reference: true,
            ..config
        };
        let x = Adapt::new(&fixed, &unit(4), 2.0, 2.0).unwrap();
        for held in [0.0, 2.0, 8.0, 1e6] {
            let got = x.indicator(1e-3, 0.1 * crossing, held);
            assert!((got - eta / 2.0).abs() < 1e-15, "held {held}: {got}");
        }
    }

    #[test]
    fn default_smallest_edge_follows_the_mesh() {
        let config = AdaptConfig {
            enabled: true,
            ..AdaptConfig::default()
        };
        let a = Adapt::new(&config, &unit(4), 1.0, 1.0).unwrap();
        assert!((a.min_edge - 1e-3 * 0.25).abs() < 1e-18);
        assert_eq!(a.max_edge, f64::INFINITY);
    }
}
