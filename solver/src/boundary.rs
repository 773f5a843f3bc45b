//! Boundary conditions per tagged side, as Riemann problems with a prescribed side b.

use sdg_mesh::TagId;

use crate::exact::PlaneWave;
use crate::history::History;
use crate::material::Plane;
use crate::riemann::Side;
use crate::system::System;

/// A boundary condition on a side of the domain (physical units).
#[derive(Clone, Debug, PartialEq)]
pub enum Condition {
    /// Zero traction.
    Free,
    /// Zero normal velocity and zero tangential traction (anti-plane: zero traction).
    Roller,
    /// Prescribed traction `sigma n` (Pa): `[x, y]` in-plane, `[out-of-plane, unused]` anti-plane.
    Traction {
        /// Amplitude, Pa.
        value: [f64; 2],
        /// Multiplier in time.
        history: History,
    },
    /// Prescribed velocity (m/s), components as for `Traction`.
    Velocity {
        /// Amplitude, m/s.
        value: [f64; 2],
        /// Multiplier in time.
        history: History,
    },
    /// Prescribed incoming characteristic `w = s + Z v` of the exterior (Pa) in the side's frame:
    /// `[normal, tangential]` in-plane, `[out-of-plane, unused]` anti-plane. Zero absorbs
    /// outgoing waves; `w = 2 s` sends in a wave of stress `s` (seed 3.4.1).
    Transmitting {
        /// Amplitude, Pa.
        incoming: [f64; 2],
        /// Multiplier in time.
        history: History,
    },
    /// The exterior state is the configured exact solution.
    Exact,
}

/// Conditions per boundary tag; edges without a condition are free.
#[derive(Clone, Debug, Default)]
pub struct Boundary {
    by_tag: Vec<Option<Condition>>,
    exact: Option<PlaneWave>,
}

impl Boundary {
    /// Conditions indexed by tag id, and the exact solution for `Exact` sides.
    pub fn new(by_tag: Vec<Option<Condition>>, exact: Option<PlaneWave>) -> Self {
        Self { by_tag, exact }
    }

    /// The condition on edges tagged `tag`.
    pub fn condition(&self, tag: Option<TagId>) -> &Condition {
        tag.and_then(|t| self.by_tag.get(t as usize))
            .and_then(Option::as_ref)
            .unwrap_or(&Condition::Free)
    }

    /// Side b of the boundary Riemann problem at point `x` (m), time `t` (s), outward normal `m`,
    /// in scaled units. With `homogeneous`, the same kind of side with zero data.
    pub fn sides(
        &self,
        system: &System,
        condition: &Condition,
        x: [f64; 2],
        t: f64,
        m: [f64; 2],
        homogeneous: bool,
    ) -> [Side; 2] {
        let scale = |h: &History| if homogeneous { 0.0 } else { h.value(t) };
        let z = system.z_ref();
        match condition {
            Condition::Free => [Side::Traction(0.0); 2],
            Condition::Roller if system.plane() == Plane::Antiplane => [Side::Traction(0.0); 2],
            Condition::Roller => [Side::Velocity(0.0), Side::Traction(0.0)],
            Condition::Traction { value, history } => {
                let f = system.vector_in_frame(value.map(|s| s * scale(history) / z), m);
                f.map(Side::Traction)
            }
            Condition::Velocity { value, history } => {
                let f = system.vector_in_frame(value.map(|v| v * scale(history)), m);
                f.map(Side::Velocity)
            }
            Condition::Transmitting { incoming, history } => {
                incoming.map(|w| Side::Incoming(w * scale(history) / z))
            }
            Condition::Exact => {
                let frame = match (&self.exact, homogeneous) {
                    (Some(wave), false) => system.frame(&system.to_scaled(&wave.state(x, t)), m),
                    _ => Default::default(),
                };
                [0, 1].map(|k| Side::Trace {
                    v: frame.v[k],
                    s: frame.s[k],
                })
            }
        }
    }
}
