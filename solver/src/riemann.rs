//! Riemann solutions on vertical faces (seed 3.2.1): the velocity and traction `(v*, s*)` that
//! the two sides of a face, or a side and its boundary data, agree on.
//!
//! In the frame of a face with unit normal `m` from side a to side b, each direction (normal with
//! impedance `c_d`, tangential with `c_s`; scaled by `Z_ref`) carries one characteristic from each
//! side: `w_a = s_a - Z v_a` arrives from a, `w_b = s_b + Z v_b` from b. The solution keeps the
//! arriving characteristic of each side that is a material and replaces the other side by its
//! data. Bonded and contact-stick interfaces are the same "first kind" solution (3.21)-(3.23).

use crate::system::{FrameTrace, System};

/// What lies on side b of a face, per frame direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Side {
    /// Material with these trace values (bonded interface, or an exact exterior state).
    Trace {
        /// Velocity, m/s.
        v: f64,
        /// Scaled traction with the face normal from a to b.
        s: f64,
    },
    /// Prescribed traction (scaled), e.g. zero on a free side.
    Traction(f64),
    /// Prescribed velocity, m/s.
    Velocity(f64),
    /// Prescribed incoming characteristic `w_b = s_b + Z v_b` (scaled): a transmitting side.
    Incoming(f64),
}

/// Solves one direction: side a's trace `(v_a, s_a)` against `side`, impedance `z` on both
/// sides. Returns `(v*, s*)`.
pub fn solve_direction(z: f64, v_a: f64, s_a: f64, side: Side) -> (f64, f64) {
    let w_a = s_a - z * v_a;
    match side {
        Side::Trace { v, s } => {
            let w_b = s + z * v;
            ((w_b - w_a) / (2.0 * z), 0.5 * (w_a + w_b))
        }
        Side::Incoming(w_b) => ((w_b - w_a) / (2.0 * z), 0.5 * (w_a + w_b)),
        Side::Traction(s) => ((s - w_a) / z, s),
        Side::Velocity(v) => (v, w_a + z * v),
    }
}

/// Solves every direction of the system's frame: `sides[k]` is side b in direction `k`.
pub fn solve(system: &System, a: &FrameTrace, sides: &[Side; 2]) -> FrameTrace {
    let z = system.impedance();
    let mut star = FrameTrace::default();
    for k in 0..system.directions() {
        let (v, s) = solve_direction(z[k], a.v[k], a.s[k], sides[k]);
        star.v[k] = v;
        star.s[k] = s;
    }
    star
}

/// The bonded solution between two material traces in the same frame.
pub fn bonded(system: &System, a: &FrameTrace, b: &FrameTrace) -> FrameTrace {
    let sides = [0, 1].map(|k| Side::Trace {
        v: b.v[k],
        s: b.s[k],
    });
    solve(system, a, &sides)
}

/// Numerical energy dissipation density on a face from side a, `(v_a - v*) . (s_a - s*)` (scaled;
/// per unit face area): non-negative for every solution above.
pub fn dissipation(system: &System, a: &FrameTrace, star: &FrameTrace) -> f64 {
    (0..system.directions())
        .map(|k| (a.v[k] - star.v[k]) * (a.s[k] - star.s[k]))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Material, Plane};

    #[test]
    fn equal_traces_are_their_own_solution() {
        let (v, s) = solve_direction(0.7, 1.5, -2.0, Side::Trace { v: 1.5, s: -2.0 });
        assert!((v - 1.5).abs() < 1e-15 && (s + 2.0).abs() < 1e-15);
    }

    #[test]
    fn boundary_data_is_imposed_and_the_outgoing_characteristic_kept() {
        let (z, v_a, s_a) = (0.5, 0.3, 1.1);
        let w_a = s_a - z * v_a;
        for side in [
            Side::Traction(0.4),
            Side::Velocity(-0.2),
            Side::Incoming(0.9),
        ] {
            let (v, s) = solve_direction(z, v_a, s_a, side);
            assert!((s - z * v - w_a).abs() < 1e-15, "{side:?}");
            match side {
                Side::Traction(t) => assert_eq!(s, t),
                Side::Velocity(u) => assert_eq!(v, u),
                Side::Incoming(w) => assert!((s + z * v - w).abs() < 1e-15),
                Side::Trace { .. } => unreachable!(),
            }
            assert!((v_a - v) * (s_a - s) >= 0.0);
        }
    }

    #[test]
    fn bonded_solution_is_symmetric_under_swapping_sides() {
        let m = Material::new(3.24e9, 0.35, 1190.0, Plane::Strain).unwrap();
        let sys = System::new(&m);
        let a = FrameTrace {
            v: [0.2, -0.4],
            s: [0.1, 0.3],
        };
        let b = FrameTrace {
            v: [-0.5, 0.6],
            s: [0.7, -0.2],
        };
        let ab = bonded(&sys, &a, &b);
        // Seen from b the normal and tangent flip: frame velocities change sign, while the
        // frame tractions `(sigma m) . m` and `(sigma m) . t` do not.
        let flip = |f: &FrameTrace| FrameTrace {
            v: f.v.map(|x| -x),
            s: f.s,
        };
        let ba = bonded(&sys, &flip(&b), &flip(&a));
        for k in 0..2 {
            assert!((ab.v[k] + ba.v[k]).abs() < 1e-15 && (ab.s[k] - ba.s[k]).abs() < 1e-15);
        }
        assert!(dissipation(&sys, &a, &ab) + dissipation(&sys, &flip(&b), &ba) > 0.0);
    }
}
