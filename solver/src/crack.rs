//! Crack-tip tracking on cohesive and damage faces: where and when a component of the interface
//! state first reaches the crack-tip level and the level of the process zone's other end.
//! - Xu-Needleman (seed 2.4.2): the normal separation reaches the nominal crack-tip level
//!   `delta_c`; the zone ends behind the tip at the trailing-edge level `delta_T` (the separation
//!   beyond `delta_c` at which the traction has fallen to 1% of the strength).
//! - Delayed damage (seed 4.2): the damage reaches [`OPEN_DAMAGE`] (the crack is open there, the
//!   tip); the zone ends ahead of the tip where the damage first reaches `eps`. Not `1 - eps`,
//!   where the law counts a face as fully debonded: `D` only approaches the target its stress
//!   sets, and behind a running tip the overstress decays, so on most crack edges of the
//!   branching plate `D` stalls between 0.99 and `1 - eps` (docs/verification.md), and a front
//!   at `1 - eps` skips them.
//!
//! Each cohesive face is probed on [`SAMPLES`] vertical lines above its edge, at the fractions
//! `(k + 1/2) / SAMPLES` of the edge, a set that does not depend on which end the tent's pole
//! stands at, so the faces stacked over an edge by the tents at either end probe the same lines.
//! A line crosses a level in a face when the separation the face inherits at its bottom (the
//! previous face's top value, DG upwind in time) is below the level and the face's top value is
//! not; the crossing time is the root on the face (its bottom when the upwind jump alone crossed).

use sdg_mesh::EdgeId;

use crate::face::{FaceBasis, FaceState};

/// Vertical probe lines per face.
pub const SAMPLES: usize = 4;

/// The damage from which a damage face counts as an open crack: it carries at most 1% of the
/// bonded traction. The crack tip of a damage law ([`Level::Tip`]), at most `1 - eps`.
pub const OPEN_DAMAGE: f64 = 0.99;

/// The levels tracked.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub enum Level {
    /// The crack tip: `delta = delta_c` (Xu-Needleman), `D = OPEN_DAMAGE` (damage).
    Tip,
    /// The process zone's other end: its trailing edge `delta = delta_T` (Xu-Needleman), its
    /// leading edge `D = eps` (damage).
    ZoneEnd,
}

/// What crack tracking follows on a law's faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tracking {
    /// The component of the interface state ([`crate::face::STATE_COMPONENTS`]).
    pub component: usize,
    /// The levels of that component (its units).
    pub levels: [(Level, f64); 2],
}

/// A point of a cohesive interface where the normal separation reached a level.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Crossing {
    /// The edge.
    pub edge: EdgeId,
    /// The point, m.
    pub point: [f64; 2],
    /// The time, s.
    pub time: f64,
    /// Which level.
    pub level: Level,
    /// Length of the edge, m: the scale to which the crossing places a crack tip.
    pub edge_length: f64,
}

/// The edge fraction of probe line `k` (from either end).
pub fn sample_fraction(k: usize) -> f64 {
    (k as f64 + 0.5) / SAMPLES as f64
}

/// One probe line of a face: vertical at `bottom`'s space point, from `bottom` (on the front
/// below the face, scaled spacetime, m) to the scaled time `top` (m, on the face's top), with the
/// tracked component's value `under` the face inherits there from the face below.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Probe {
    /// Bottom of the line.
    pub bottom: [f64; 3],
    /// Scaled time of the line's top.
    pub top: f64,
    /// Inherited value of the tracked component at the bottom.
    pub under: f64,
}

/// Adds to `out` the crossings of `tracking`'s levels on the face `state` over `edge`, on its
/// probe lines `probes`; `c_ref` converts the face's scaled time (m) to s, and `psi` is scratch
/// of the face basis length.
pub fn find_crossings(
    state: &FaceState,
    basis: &FaceBasis,
    (edge, probes): (EdgeId, &[Probe; SAMPLES]),
    tracking: Tracking,
    c_ref: f64,
    psi: &mut [f64],
    out: &mut Vec<Crossing>,
) {
    let component = tracking.component;
    for probe in probes {
        let bottom = probe.bottom;
        let at = |tau: f64, psi: &mut [f64]| {
            state.evaluate(basis, [bottom[0], bottom[1], tau], psi)[component]
        };
        let top_value = at(probe.top, psi);
        for (level, value) in tracking.levels {
            if !(probe.under < value && top_value >= value) {
                continue;
            }
            // Bisection on the face's polynomial between the bottom and the top of the line.
            let (mut lo, mut hi) = (bottom[2], probe.top);
            if at(lo, psi) < value {
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if at(mid, psi) < value {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
            } else {
                hi = lo;
            }
            out.push(Crossing {
                edge,
                point: [bottom[0], bottom[1]],
                time: hi / c_ref,
                level,
                edge_length: state.geometry.length(),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::face::{FaceGeometry, MAX_FACE_BASIS};

    /// A face over the edge from (0, 0) to (1, 0) with its pole at the origin, rising from
    /// tau = 0 to 2 there; the far end at tau = 1.
    fn face(delta: impl Fn([f64; 2]) -> f64) -> FaceState {
        let geometry = FaceGeometry::new([[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 0.0, 2.0]]);
        // Linear separation in (xi, eta): interpolate the corner values.
        let mut coefficients = [0.0; MAX_FACE_BASIS];
        let c0 = delta([0.0, 0.0]);
        coefficients[0] = c0;
        coefficients[1] = delta([1.0, 0.0]) - c0;
        coefficients[2] = delta([0.0, 1.0]) - c0;
        let mut state = FaceState {
            geometry,
            coefficients: [[0.0; MAX_FACE_BASIS]; 3],
        };
        state.coefficients[0] = coefficients;
        state
    }

    /// The probe lines of [`face`] with inherited separation `under`.
    fn probes(under: f64) -> [Probe; SAMPLES] {
        std::array::from_fn(|k| {
            let f = sample_fraction(k);
            Probe {
                bottom: [f, 0.0, f],
                top: 2.0 - f,
                under,
            }
        })
    }

    #[test]
    fn crossings_are_found_on_the_probe_lines_at_the_level() {
        let basis = FaceBasis::new(1);
        // delta = 3 eta (the pole direction): 0 at the bottom edge, 3 at the pole top.
        let state = face(|x| 3.0 * x[1]);
        let mut out = Vec::new();
        let mut psi = vec![0.0; basis.len()];
        let levels = Tracking {
            component: 0,
            levels: [(Level::Tip, 1.0), (Level::ZoneEnd, 2.5)],
        };
        find_crossings(
            &state,
            &basis,
            (7, &probes(0.0)),
            levels,
            1.0,
            &mut psi,
            &mut out,
        );
        for c in &out {
            // Check against the face's own value at the reported point and time.
            let value = state.evaluate(&basis, [c.point[0], c.point[1], c.time], &mut psi)[0];
            let want = if c.level == Level::Tip { 1.0 } else { 2.5 };
            assert!((value - want).abs() < 1e-12, "{c:?}: {value}");
            assert_eq!(c.edge, 7);
        }
        // On the line at fraction f the top value is 3 (1 - f): 2.625, 1.875, 1.125, 0.375 for
        // f = 1/8 ... 7/8; three lines reach 1, one reaches 2.5.
        assert_eq!(out.iter().filter(|c| c.level == Level::Tip).count(), 3);
        assert_eq!(out.iter().filter(|c| c.level == Level::ZoneEnd).count(), 1);
        // Already above the level below: no new crossing.
        out.clear();
        find_crossings(
            &state,
            &basis,
            (7, &probes(1.5)),
            levels,
            1.0,
            &mut psi,
            &mut out,
        );
        assert!(out.iter().all(|c| c.level != Level::Tip));
        // An upwind jump across the level: the crossing is at the bottom of the line.
        let state = face(|_| 1.2);
        out.clear();
        find_crossings(
            &state,
            &basis,
            (7, &probes(0.5)),
            levels,
            2.0,
            &mut psi,
            &mut out,
        );
        assert_eq!(out.len(), SAMPLES);
        for (k, c) in out.iter().enumerate() {
            let f = sample_fraction(k);
            assert!((c.point[0] - f).abs() < 1e-15 && (c.time - f / 2.0).abs() < 1e-15);
        }
    }

    #[test]
    fn the_tracked_component_is_the_one_crossing() {
        let basis = FaceBasis::new(1);
        // The damage rises to 3 at the pole top (as the separation above); no separation.
        let mut state = face(|x| 3.0 * x[1]);
        state.coefficients[2] = state.coefficients[0];
        state.coefficients[0] = [0.0; MAX_FACE_BASIS];
        let mut psi = vec![0.0; basis.len()];
        let count = |component: usize, psi: &mut [f64]| {
            let mut out = Vec::new();
            let tracking = Tracking {
                component,
                levels: [(Level::Tip, 1.0), (Level::ZoneEnd, 2.5)],
            };
            find_crossings(
                &state,
                &basis,
                (7, &probes(0.0)),
                tracking,
                1.0,
                psi,
                &mut out,
            );
            out.len()
        };
        assert_eq!(count(2, &mut psi), 4);
        assert_eq!(count(0, &mut psi), 0);
    }
}
