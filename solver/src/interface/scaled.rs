//! [`Contact`]: a nonlinear interface law in scaled units, giving side a's targets, their
//! derivatives and the rates of the interface state.

use super::cohesive::{CohesiveParams, XuNeedleman};
use super::contact::ContactParams;
use super::damage::{DamageLaw, DamageParams};
use super::registry::Law;
use super::targets::Targets;
use crate::crack::{Level, OPEN_DAMAGE, Tracking};
use crate::face::STATE_COMPONENTS;
use crate::system::{FrameTrace, System};

/// A contact law in scaled units: tractions over `Z_ref`, impedances over `rho c_ref`. The
/// separated part of the face carries the cohesive traction when there is one, else none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Scaled impedances per frame direction (normal, tangential).
    pub z: [f64; 2],
    /// Friction coefficient.
    pub k: f64,
    /// `r_c`, `r_s` (m).
    pub r: [f64; 2],
    /// `s_c`, `s_s` scaled.
    pub s: [f64; 2],
    /// The cohesive law of the separated part (scaled strength).
    pub cohesive: Option<XuNeedleman>,
    /// The damage law blending the bonded part with this one (scaled strength).
    pub damage: Option<DamageLaw>,
}

/// Cubic smoothstep `r(xi) = 3 xi^2 - 2 xi^3` of `xi = (hi - x) / (hi - lo)`, clamped: 1 at and
/// below `lo`, 0 at and above `hi` (a step at `lo` when `lo == hi`). Returns the value and its
/// derivative with respect to `x`.
fn fraction(x: f64, lo: f64, hi: f64) -> (f64, f64) {
    if x <= lo {
        (1.0, 0.0)
    } else if x >= hi {
        (0.0, 0.0)
    } else {
        let xi = (hi - x) / (hi - lo);
        (
            xi * xi * (3.0 - 2.0 * xi),
            -6.0 * xi * (1.0 - xi) / (hi - lo),
        )
    }
}

impl Contact {
    /// The scaled law of `params` for `system` (in-plane modes only), with the cohesive law
    /// `cohesive` on the separated part, or the whole blended with the bonded law by `damage`.
    pub fn new(
        system: &System,
        params: &ContactParams,
        cohesive: Option<&CohesiveParams>,
        damage: Option<&DamageParams>,
    ) -> Self {
        let z_ref = system.z_ref();
        Self {
            z: system.impedance(),
            k: params.friction,
            r: [params.r_c, params.r_s],
            s: [params.s_c / z_ref, params.s_s / z_ref],
            cohesive: cohesive.map(|c| XuNeedleman {
                strength: c.strength / z_ref,
                delta_c: c.critical_separation,
            }),
            damage: damage.map(|d| DamageLaw {
                strength: d.strength / z_ref,
                delay: d.delay,
                a: d.a,
                c0: d.c0,
                beta: d.beta,
                eps: d.eps,
                initial: d.initial,
            }),
        }
    }

    /// The scaled law of a nonlinear interface law; `None` for a linear one.
    pub fn of(system: &System, law: &Law) -> Option<Self> {
        match law {
            Law::Contact(params) => Some(Self::new(system, params, None, None)),
            Law::XuNeedleman(c) => Some(Self::new(system, &c.contact, Some(c), None)),
            Law::Damage(d) => Some(Self::new(system, &d.contact, None, Some(d))),
            Law::Bonded | Law::Free => None,
        }
    }

    /// Components of the interface state the law evolves: separation and slip, and damage.
    pub fn components(&self) -> usize {
        if self.damage.is_some() { 3 } else { 2 }
    }

    /// What crack tracking follows on the law's faces: the damage of a damage law (tip at
    /// [`OPEN_DAMAGE`], or `1 - eps` if lower; zone's leading edge at `eps`), the normal
    /// separation of a cohesive one (tip at `delta_c`, trailing edge at `delta_T`); `None` for
    /// plain contact.
    pub fn tracking(&self) -> Option<Tracking> {
        if let Some(d) = &self.damage {
            Some(Tracking {
                component: 2,
                levels: [
                    (Level::Tip, OPEN_DAMAGE.min(1.0 - d.eps)),
                    (Level::ZoneEnd, d.eps),
                ],
            })
        } else {
            self.cohesive.map(|c| Tracking {
                component: 0,
                levels: [
                    (Level::Tip, c.delta_c),
                    (Level::ZoneEnd, c.trailing_separation()),
                ],
            })
        }
    }

    /// The state at t = 0 (before any face): no separation, the initial damage.
    pub fn initial_state(&self) -> [f64; STATE_COMPONENTS] {
        [0.0, 0.0, self.damage.map_or(0.0, |d| d.initial)]
    }

    /// Separations (m) of the order of the law's scales: its regularization band and the
    /// cohesive critical separation.
    pub fn separation_scale(&self) -> f64 {
        let c = self.cohesive.map_or(0.0, |x| x.delta_c);
        self.r[0].abs().max(self.r[1].abs()).max(c)
    }

    /// Side a's targets from the arriving characteristics `w_a`, `w_b` (normal, tangential) and
    /// the interface state (normal separation `delta`, tangential slip: m; damage).
    pub fn targets(&self, w_a: [f64; 2], w_b: [f64; 2], state: [f64; STATE_COMPONENTS]) -> Targets {
        self.targets_with(w_a, w_b, state, None)
    }

    /// [`Self::targets`] with the cohesive traction `traction` (scaled units) given instead of
    /// the law's at the separation; the derivatives then leave out its dependence on the state
    /// (`d star / d traction` is `1 - eta` for tractions, `(1 - eta) / Z` for velocities).
    pub fn targets_with_traction(
        &self,
        w_a: [f64; 2],
        w_b: [f64; 2],
        state: [f64; STATE_COMPONENTS],
        traction: [f64; 2],
    ) -> Targets {
        self.targets_with(w_a, w_b, state, Some(traction))
    }

    fn targets_with(
        &self,
        w_a: [f64; 2],
        w_b: [f64; 2],
        state: [f64; STATE_COMPONENTS],
        traction: Option<[f64; 2]>,
    ) -> Targets {
        let mut out = self.contact_targets(w_a, w_b, [state[0], state[1]], traction);
        if let Some(law) = &self.damage {
            law.blend(&mut out, self.z, w_a, w_b, state[2]);
        }
        // [[v*]] = v*_b - v*_a = (w_b - s*) / Z - (s* - w_a) / Z per direction.
        for k in 0..2 {
            let zk = self.z[k];
            out.rate[k] = (w_a[k] + w_b[k] - 2.0 * out.star.s[k]) / zk;
            for j in 0..2 {
                let unit = if j == k { 1.0 } else { 0.0 };
                out.rate_wa[k][j] = (unit - 2.0 * out.d_wa[2 + k][j]) / zk;
                out.rate_wb[k][j] = (unit - 2.0 * out.d_wb[2 + k][j]) / zk;
            }
            for j in 0..STATE_COMPONENTS {
                out.rate_sep[k][j] = -2.0 * out.d_sep[2 + k][j] / zk;
            }
        }
        if let Some(law) = &self.damage {
            law.evolution(&mut out, state[2]);
        }
        out
    }

    /// The contact law's targets (star values and their derivatives, area fractions) for the
    /// separation `sep` (normal, slip; m), before any damage blending and rates.
    fn contact_targets(
        &self,
        w_a: [f64; 2],
        w_b: [f64; 2],
        sep: [f64; 2],
        traction: Option<[f64; 2]>,
    ) -> Targets {
        let delta = sep[0];
        let [z0, z1] = self.z;
        let si = [0.5 * (w_a[0] + w_b[0]), 0.5 * (w_a[1] + w_b[1])];
        let vi = [
            (w_b[0] - w_a[0]) / (2.0 * z0),
            (w_b[1] - w_a[1]) / (2.0 * z1),
        ];
        // Separated part: the cohesive traction tc (or none), side a's outgoing characteristic.
        let (tc, dtc) = match traction {
            Some(tc) => (tc, [[0.0; 2]; 2]),
            None => self
                .cohesive
                .map_or(([0.0; 2], [[0.0; 2]; 2]), |x| x.traction(sep)),
        };
        let v3 = [(tc[0] - w_a[0]) / z0, (tc[1] - w_a[1]) / z1];
        let (eta_d, deta_d) = fraction(delta, self.r[0], self.r[1]);
        let (eta_s, deta_s) = fraction(si[0], self.s[0], self.s[1]);
        let eta = eta_d * eta_s;
        // d eta / d w_x0 (either side: sI_n = (w_a0 + w_b0) / 2) and d eta / d delta.
        let eta_w = 0.5 * eta_d * deta_s;
        let eta_delta = deta_d * eta_s;

        // Tangential contact traction T and side a's velocity V: stick or slip.
        let bound = self.k * (-si[0]).max(0.0);
        let stick = si[1].abs() <= bound;
        let sign = if si[1] < 0.0 { -1.0 } else { 1.0 };
        // d bound / d w_x0.
        let bound_w = if si[0] < 0.0 { -0.5 * self.k } else { 0.0 };
        let (t, t_w0, t_wa1, t_wb1, v, v_w0, v_wa1, v_wb1);
        if stick {
            t = si[1];
            (t_w0, t_wa1, t_wb1) = (0.0, 0.5, 0.5);
            v = vi[1];
            (v_w0, v_wa1, v_wb1) = (0.0, -0.5 / z1, 0.5 / z1);
        } else {
            t = sign * bound;
            (t_w0, t_wa1, t_wb1) = (sign * bound_w, 0.0, 0.0);
            v = (t - w_a[1]) / z1;
            (v_w0, v_wa1, v_wb1) = (t_w0 / z1, -1.0 / z1, 0.0);
        }

        let mut out = Targets {
            bonded_traction: si,
            eta,
            gamma: if stick { 1.0 } else { 0.0 },
            damage: 1.0,
            ..Default::default()
        };
        out.star = FrameTrace {
            v: [
                eta * vi[0] + (1.0 - eta) * v3[0],
                eta * v + (1.0 - eta) * v3[1],
            ],
            s: [
                eta * si[0] + (1.0 - eta) * tc[0],
                eta * t + (1.0 - eta) * tc[1],
            ],
        };
        // Rows: v0, v1, s0, s1; columns: normal, tangential characteristic.
        let dv0 = eta_w * (vi[0] - v3[0]);
        out.d_wa[0] = [dv0 - eta * 0.5 / z0 - (1.0 - eta) / z0, 0.0];
        out.d_wb[0] = [dv0 + eta * 0.5 / z0, 0.0];
        let dv1 = eta_w * (v - v3[1]) + eta * v_w0;
        out.d_wa[1] = [dv1, eta * v_wa1 - (1.0 - eta) / z1];
        out.d_wb[1] = [dv1, eta * v_wb1];
        let ds0 = eta_w * (si[0] - tc[0]) + 0.5 * eta;
        out.d_wa[2] = [ds0, 0.0];
        out.d_wb[2] = [ds0, 0.0];
        let ds1 = eta_w * (t - tc[1]) + eta * t_w0;
        out.d_wa[3] = [ds1, eta * t_wa1];
        out.d_wb[3] = [ds1, eta * t_wb1];
        // d eta / d sep[j]: only the normal separation moves the contact fraction.
        for (j, e) in [eta_delta, 0.0].into_iter().enumerate() {
            out.d_sep[0][j] = e * (vi[0] - v3[0]) + (1.0 - eta) * dtc[0][j] / z0;
            out.d_sep[1][j] = e * (v - v3[1]) + (1.0 - eta) * dtc[1][j] / z1;
            out.d_sep[2][j] = e * (si[0] - tc[0]) + (1.0 - eta) * dtc[0][j];
            out.d_sep[3][j] = e * (t - tc[1]) + (1.0 - eta) * dtc[1][j];
        }

        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interface::damage::tests::damage_params;
    use crate::interface::targets::{Mode, characteristics};
    use crate::material::{Material, Plane};
    use crate::riemann;

    fn system() -> System {
        System::new(&Material::new(3.24e9, 0.35, 1190.0, Plane::Strain).unwrap())
    }

    fn law(sys: &System, friction: f64, r: [f64; 2], s: [f64; 2]) -> Contact {
        Contact::new(
            sys,
            &ContactParams {
                friction,
                r_c: r[0],
                r_s: r[1],
                s_c: s[0],
                s_s: s[1],
            },
            None,
            None,
        )
    }

    /// Independent characteristic computation of side a's targets for a pure mode, in terms of
    /// the traces (seed (3.22), (3.32), (3.34)), with impedances `z`.
    fn expected(z: [f64; 2], a: &FrameTrace, b: &FrameTrace, mode: Mode, k: f64) -> FrameTrace {
        let bonded = |j: usize| {
            let s = (a.s[j] * z[j] + b.s[j] * z[j]) / (2.0 * z[j]) + 0.5 * z[j] * (b.v[j] - a.v[j]);
            let v = (b.s[j] - a.s[j]) / (2.0 * z[j]) + 0.5 * (a.v[j] + b.v[j]);
            (v, s)
        };
        let (vn, sn) = bonded(0);
        let (vt, st) = bonded(1);
        match mode {
            Mode::Bonded | Mode::Stick => FrameTrace {
                v: [vn, vt],
                s: [sn, st],
            },
            Mode::Slip => {
                let t = k * (-sn).max(0.0) * st.signum();
                FrameTrace {
                    v: [vn, a.v[1] + (t - a.s[1]) / z[1]],
                    s: [sn, t],
                }
            }
            Mode::Separation => FrameTrace {
                v: [a.v[0] - a.s[0] / z[0], a.v[1] - a.s[1] / z[1]],
                s: [0.0, 0.0],
            },
        }
    }

    /// Checks `targets` against [`expected`] in every pure mode; returns the first mismatch.
    fn check_modes(
        targets: impl Fn(&Contact, [f64; 2], [f64; 2], f64) -> Targets,
    ) -> Result<(), String> {
        let sys = system();
        let z = sys.impedance();
        // Sharp regularization far from the states used, friction 0.3.
        let c = law(&sys, 0.3, [-1e-6, 1e-6], [1e3, 2e3]);
        let cases = [
            // (a, b, delta, mode)
            (
                FrameTrace {
                    v: [0.1, 0.02],
                    s: [-0.5, 0.05],
                },
                FrameTrace {
                    v: [-0.1, 0.01],
                    s: [-0.4, 0.04],
                },
                -2e-6,
                Mode::Stick,
            ),
            (
                FrameTrace {
                    v: [0.1, 0.3],
                    s: [-0.5, 0.6],
                },
                FrameTrace {
                    v: [-0.1, -0.2],
                    s: [-0.4, 0.7],
                },
                -2e-6,
                Mode::Slip,
            ),
            (
                FrameTrace {
                    v: [0.1, -0.3],
                    s: [-0.5, -0.6],
                },
                FrameTrace {
                    v: [-0.1, 0.2],
                    s: [-0.4, -0.7],
                },
                -2e-6,
                Mode::Slip,
            ),
            (
                FrameTrace {
                    v: [0.1, 0.02],
                    s: [0.5, 0.05],
                },
                FrameTrace {
                    v: [0.3, 0.01],
                    s: [0.4, 0.04],
                },
                0.0,
                Mode::Separation,
            ),
            (
                FrameTrace {
                    v: [0.1, 0.02],
                    s: [-0.5, 0.05],
                },
                FrameTrace {
                    v: [-0.1, 0.01],
                    s: [-0.4, 0.04],
                },
                5e-6,
                Mode::Separation,
            ),
        ];
        for (a, b, delta, mode) in cases {
            let (w_a, w_b) = characteristics(z, &a, &b);
            let got = targets(&c, w_a, w_b, delta);
            let want = expected(z, &a, &b, mode, c.k);
            if got.mode() != mode {
                return Err(format!("{mode:?}: got mode {:?}", got.mode()));
            }
            for j in 0..2 {
                if (got.star.v[j] - want.v[j]).abs() > 1e-14
                    || (got.star.s[j] - want.s[j]).abs() > 1e-14
                {
                    return Err(format!("{mode:?}: {:?} against {want:?}", got.star));
                }
            }
            // Side b from its own view: swapped characteristics, same tractions, velocities
            // of b; the separation rate is the jump of the normal velocities.
            let from_b = targets(&c, w_b, w_a, delta);
            let rate = -from_b.star.v[0] - got.star.v[0];
            if (from_b.star.s[0] - got.star.s[0]).abs() > 1e-14
                || (from_b.star.s[1] - got.star.s[1]).abs() > 1e-14
                || (rate - got.rate[0]).abs() > 1e-14
            {
                return Err(format!("{mode:?}: sides disagree"));
            }
        }
        Ok(())
    }

    #[test]
    fn every_mode_matches_the_characteristic_solution() {
        check_modes(|c, w_a, w_b, delta| c.targets(w_a, w_b, [delta, 0.0, 0.0])).unwrap();
    }

    #[test]
    fn a_sign_flip_in_the_solution_is_caught() {
        // The same check on a law whose slip traction points against the stick traction.
        let flipped = |c: &Contact, w_a: [f64; 2], w_b: [f64; 2], delta: f64| {
            let mut t = c.targets(w_a, w_b, [delta, 0.0, 0.0]);
            if t.mode() == Mode::Slip {
                t.star.s[1] = -t.star.s[1];
            }
            t
        };
        assert!(check_modes(flipped).is_err());
        // And one whose separation velocity takes the wrong characteristic sign.
        let wrong = |c: &Contact, w_a: [f64; 2], w_b: [f64; 2], delta: f64| {
            c.targets([-w_a[0], w_a[1]], w_b, [delta, 0.0, 0.0])
        };
        assert!(check_modes(wrong).is_err());
    }

    #[test]
    fn compressive_stick_is_the_bonded_solution() {
        let sys = system();
        let c = law(&sys, 0.5, [-1e-6, 0.0], [0.0, 1e3]);
        let a = FrameTrace {
            v: [0.2, -0.1],
            s: [-0.8, 0.1],
        };
        let b = FrameTrace {
            v: [-0.1, 0.05],
            s: [-0.7, 0.12],
        };
        let (w_a, w_b) = characteristics(sys.impedance(), &a, &b);
        let t = c.targets(w_a, w_b, [-2e-6, 0.0, 0.0]);
        let bonded = riemann::bonded(&sys, &a, &b);
        assert_eq!(t.mode(), Mode::Stick);
        for j in 0..2 {
            assert!((t.star.v[j] - bonded.v[j]).abs() < 1e-15);
            assert!((t.star.s[j] - bonded.s[j]).abs() < 1e-15);
        }
        assert_eq!(t.rate, [0.0; 3]);
    }

    #[test]
    fn outgoing_characteristic_is_kept_in_blended_modes() {
        let sys = system();
        let z = sys.impedance();
        let c = law(&sys, 0.25, [-1e-6, 1e-6], [0.0, 0.3]);
        for (i, delta) in [-5e-7, 0.0, 3e-7].into_iter().enumerate() {
            let w_a = [0.1 - 0.2 * i as f64, 0.3];
            let w_b = [-0.2, 0.1 + 0.1 * i as f64];
            let t = c.targets(w_a, w_b, [delta, 0.0, 0.0]);
            assert!(
                t.eta > 0.0 && t.eta < 1.0,
                "blend at {delta}: eta {}",
                t.eta
            );
            for j in 0..2 {
                assert!((t.star.s[j] - z[j] * t.star.v[j] - w_a[j]).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn blended_modes_are_area_weighted_averages() {
        // Independent computation of (3.36)-(3.39), (3.43)-(3.44): eta from the smoothsteps,
        // targets as eta (stick or slip) + (1 - eta) separation, from the traces.
        let sys = system();
        let z = sys.impedance();
        // The traction band in scaled units (the law takes Pa).
        let (r, s) = ([-1e-6, 1e-6], [0.0, 0.2]);
        let c = law(&sys, 0.25, r, s.map(|x| x * sys.z_ref()));
        let smooth = |x: f64, lo: f64, hi: f64| {
            let xi = ((hi - x) / (hi - lo)).clamp(0.0, 1.0);
            3.0 * xi * xi - 2.0 * xi.powi(3)
        };
        for (a, b, delta, contact) in [
            // Compressive stick, delta inside the regularization band.
            (
                FrameTrace {
                    v: [0.1, 0.0],
                    s: [-0.3, 0.01],
                },
                FrameTrace {
                    v: [-0.05, 0.0],
                    s: [-0.2, 0.02],
                },
                3e-7,
                Mode::Stick,
            ),
            // Slight tension inside the traction band, slip.
            (
                FrameTrace {
                    v: [0.02, 0.3],
                    s: [0.05, 0.2],
                },
                FrameTrace {
                    v: [0.01, -0.2],
                    s: [0.02, 0.25],
                },
                -2e-6,
                Mode::Slip,
            ),
        ] {
            let (w_a, w_b) = characteristics(z, &a, &b);
            let si_n = 0.5 * (a.s[0] + b.s[0]) + 0.5 * z[0] * (b.v[0] - a.v[0]);
            let eta = smooth(delta, r[0], r[1]) * smooth(si_n, s[0], s[1]);
            assert!(eta > 0.0 && eta < 1.0, "a blend: eta {eta}");
            let on = expected(z, &a, &b, contact, c.k);
            let off = expected(z, &a, &b, Mode::Separation, c.k);
            let got = c.targets(w_a, w_b, [delta, 0.0, 0.0]);
            assert!((got.eta - eta).abs() < 1e-14);
            for j in 0..2 {
                let v = eta * on.v[j] + (1.0 - eta) * off.v[j];
                let t = eta * on.s[j] + (1.0 - eta) * off.s[j];
                assert!((got.star.v[j] - v).abs() < 1e-14, "{contact:?} v{j}");
                assert!((got.star.s[j] - t).abs() < 1e-14, "{contact:?} s{j}");
            }
        }
    }

    /// Checks every analytic derivative of `c.targets` against central differences at
    /// `(w_a, w_b, state)`.
    fn check_derivatives(c: &Contact, w_a: [f64; 2], w_b: [f64; 2], state: [f64; 3]) {
        let values = |t: &Targets| {
            [
                t.star.v[0],
                t.star.v[1],
                t.star.s[0],
                t.star.s[1],
                t.rate[0],
                t.rate[1],
                t.rate[2],
            ]
        };
        let t = c.targets(w_a, w_b, state);
        let analytic = |r: usize, wrt: usize, j: usize| match (r, wrt) {
            (0..4, 0) => t.d_wa[r][j],
            (0..4, 1) => t.d_wb[r][j],
            (0..4, _) => t.d_sep[r][j],
            (_, 0) => t.rate_wa[r - 4][j],
            (_, 1) => t.rate_wb[r - 4][j],
            (_, _) => t.rate_sep[r - 4][j],
        };
        for (wrt, count) in [(0, 2), (1, 2), (2, 3)] {
            for j in 0..count {
                // Steps well inside the narrowest band of the law.
                let band = c
                    .cohesive
                    .map_or(f64::INFINITY, |x| x.delta_c)
                    .min(c.r[1] - c.r[0]);
                let h = match (wrt, j) {
                    (2, 2) => 1e-6,
                    (2, _) => 1e-4 * band,
                    _ => 1e-7,
                };
                let shifted = |sign: f64| {
                    let (mut a, mut b, mut d) = (w_a, w_b, state);
                    match wrt {
                        0 => a[j] += sign * h,
                        1 => b[j] += sign * h,
                        _ => d[j] += sign * h,
                    }
                    values(&c.targets(a, b, d))
                };
                let (f, g) = (shifted(1.0), shifted(-1.0));
                for r in 0..7 {
                    let fd = (f[r] - g[r]) / (2.0 * h);
                    let tol = if wrt == 2 { 1e-4 } else { 1e-6 };
                    let scale = match (wrt, r) {
                        (2, _) if j < 2 => 1.0 / c.separation_scale(),
                        (_, 6) => c.damage.map_or(1.0, |d| d.a / d.delay),
                        _ => 1.0,
                    };
                    assert!(
                        (analytic(r, wrt, j) - fd).abs() < tol * (scale + fd.abs()),
                        "row {r}, argument {wrt}[{j}] at {state:?}: {} vs {fd}",
                        analytic(r, wrt, j)
                    );
                }
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let sys = system();
        let c = law(&sys, 0.25, [-1e-6, 1e-6], [0.0, 0.3 * sys.z_ref()]);
        // Blended contact, slip and stick points away from kinks.
        for (w_a, w_b, delta) in [
            ([-0.1, 0.3], [-0.15, 0.1], -2e-7),
            ([-0.1, 0.01], [-0.15, 0.02], 4e-7),
            ([0.05, 0.01], [0.1, 0.02], 1e-7),
        ] {
            check_derivatives(&c, w_a, w_b, [delta, 3e-7, 0.0]);
        }
        // Cohesive: opening, slip and both, in tension and in compression.
        let x = cohesive(&sys);
        let dc = 4e-7;
        for (w_a, w_b, sep) in [
            ([0.2, 0.01], [0.25, 0.02], [0.5 * dc, 0.0]),
            ([0.2, 0.01], [0.25, -0.05], [2.5 * dc, 0.7 * dc]),
            ([-0.3, 0.01], [-0.2, 0.02], [-0.004 * dc, 0.1 * dc]),
            ([0.1, 0.3], [0.05, 0.2], [0.3 * dc, -1.3 * dc]),
        ] {
            check_derivatives(&x, w_a, w_b, [sep[0], sep[1], 0.0]);
        }
    }

    /// The seed's PMMA cohesive law (2.5.2) with its default contact part.
    fn cohesive(sys: &System) -> Contact {
        let (strength, delta_c) = (324e6, 4e-7);
        let params = CohesiveParams {
            strength,
            critical_separation: delta_c,
            contact: CohesiveParams::default_contact(strength, delta_c),
        };
        Contact::of(sys, &Law::XuNeedleman(params)).unwrap()
    }

    #[test]
    fn cohesive_faces_carry_the_law_when_open_and_bonded_targets_in_compression() {
        let sys = system();
        let z = sys.impedance();
        let x = cohesive(&sys);
        let law = x.cohesive.unwrap();
        // Opening under tension: separation with the cohesive traction, each side's velocity
        // from its own characteristic.
        let (a, b) = (
            FrameTrace {
                v: [0.1, 0.02],
                s: [0.5, 0.05],
            },
            FrameTrace {
                v: [0.3, 0.01],
                s: [0.4, 0.04],
            },
        );
        let sep = [1.5e-7, 0.2e-7];
        let (w_a, w_b) = characteristics(z, &a, &b);
        let t = x.targets(w_a, w_b, [sep[0], sep[1], 0.0]);
        let (tc, _) = law.traction(sep);
        assert_eq!(t.eta, 0.0);
        for j in 0..2 {
            assert!((t.star.s[j] - tc[j]).abs() < 1e-15);
            assert!((t.star.v[j] - (a.v[j] + (tc[j] - a.s[j]) / z[j])).abs() < 1e-15);
        }
        // In compression and closed: the bonded solution (friction 0 with zero shear).
        let (a, b) = (
            FrameTrace {
                v: [0.2, 0.0],
                s: [-0.8, 0.0],
            },
            FrameTrace {
                v: [-0.1, 0.0],
                s: [-0.7, 0.0],
            },
        );
        let (w_a, w_b) = characteristics(z, &a, &b);
        let t = x.targets(w_a, w_b, [-1e-8, 0.0, 0.0]);
        let bonded = riemann::bonded(&sys, &a, &b);
        assert_eq!(t.eta, 1.0);
        for j in 0..2 {
            assert!((t.star.v[j] - bonded.v[j]).abs() < 1e-15);
            assert!((t.star.s[j] - bonded.s[j]).abs() < 1e-15);
        }
    }

    #[test]
    fn damage_blends_the_bonded_and_the_contact_law() {
        let sys = system();
        let p = damage_params();
        let d = Contact::of(&sys, &Law::Damage(p)).unwrap();
        let c = Contact::of(&sys, &Law::Contact(p.contact)).unwrap();
        assert_eq!(d.components(), 3);
        let z = sys.impedance();
        let mut rng = 0.37f64;
        let mut next = || {
            rng = (rng * 9301.0 + 0.49297).fract();
            rng - 0.5
        };
        for _ in 0..50 {
            let (w_a, w_b) = ([next(), next()], [next(), next()]);
            let sep = [2e-7 * next(), 1e-7 * next()];
            // Undamaged: the bonded solution; fully debonded: the contact law, exactly.
            let bonded = d.targets(w_a, w_b, [sep[0], sep[1], 0.0]);
            for k in 0..2 {
                assert_eq!(bonded.star.s[k], 0.5 * (w_a[k] + w_b[k]));
                assert_eq!(bonded.star.v[k], (w_b[k] - w_a[k]) / (2.0 * z[k]));
                assert_eq!(bonded.rate[k], 0.0);
            }
            assert_eq!(bonded.mode(), Mode::Bonded);
            let contact = c.targets(w_a, w_b, [sep[0], sep[1], 0.0]);
            for full in [1.0, 1.0 - 0.5 * p.eps, 1.2] {
                let debonded = d.targets(w_a, w_b, [sep[0], sep[1], full]);
                assert_eq!(debonded.star, contact.star);
                assert_eq!(&debonded.rate[..2], &contact.rate[..2]);
                if full >= 1.0 {
                    assert_eq!(debonded.rate[2], 0.0, "no growth beyond 1");
                }
            }
            // In between: area-weighted, and the outgoing characteristic kept.
            let half = d.targets(w_a, w_b, [sep[0], sep[1], 0.3]);
            for k in 0..2 {
                let want = 0.7 * bonded.star.s[k] + 0.3 * contact.star.s[k];
                assert!((half.star.s[k] - want).abs() < 1e-14);
                assert!((half.star.s[k] - z[k] * half.star.v[k] - w_a[k]).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn damage_grows_at_the_seed_s_rate() {
        let sys = system();
        let p = damage_params();
        let d = Contact::of(&sys, &Law::Damage(p)).unwrap();
        let law = d.damage.unwrap();
        let s = |pa: f64| pa / sys.z_ref();
        // Below c0 sigma_c nothing grows; in compression nothing grows.
        let t = d.targets([s(0.7 * 62.1e6); 2], [s(0.7 * 62.1e6), 0.0], [0.0; 3]);
        assert!(t.bonded_traction[0] > 0.0 && t.rate[2] == 0.0);
        let t = d.targets([s(-2e8), 0.0], [s(-2e8), 0.0], [0.0; 3]);
        assert_eq!(t.rate[2], 0.0);
        // At y = 0.9 (f = 1/2) from D = 0.1: (1 - exp(-10 * 0.4)) / tau.
        let t = d.targets(
            [s(0.9 * 62.1e6), 0.0],
            [s(0.9 * 62.1e6), 0.0],
            [0.0, 0.0, 0.1],
        );
        assert!((law.target(0.9).0 - 0.5).abs() < 1e-12);
        let want = (1.0 - (-4.0f64).exp()) / 1e-8;
        assert!((t.rate[2] / want - 1.0).abs() < 1e-12, "{}", t.rate[2]);
        // Shear counts through beta: the same y from a pure shear traction.
        let t = d.targets(
            [0.0, s(0.9 * 62.1e6)],
            [0.0, s(0.9 * 62.1e6)],
            [0.0, 0.0, 0.1],
        );
        assert!((t.rate[2] / want - 1.0).abs() < 1e-12);
        // Derivatives, in growth and in blended contact.
        for (w_a, w_b, state) in [
            ([s(5.8e7), s(1e7)], [s(5.4e7), s(-0.4e7)], [5e-8, 1e-8, 0.2]),
            ([s(-3e7), s(2e7)], [s(-1e7), s(1e7)], [-3e-8, 2e-8, 0.6]),
            (
                [s(6.1e7), s(-2e7)],
                [s(5.7e7), s(-1e7)],
                [0.3e-7, -1e-8, 0.05],
            ),
            // Within the last 2 eps, where the damage in effect runs to 1.
            (
                [s(7.5e7), s(1e6)],
                [s(7.4e7), 0.0],
                [2e-7, 0.0, 1.0 - 1.5 * p.eps],
            ),
        ] {
            check_derivatives(&d, w_a, w_b, state);
        }
    }
}
