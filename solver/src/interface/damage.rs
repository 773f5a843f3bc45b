//! The delayed-damage law (seed 4.2): its parameters and its scaled form, which blends the
//! bonded targets with the contact law's and evolves the damage.

use super::contact::ContactParams;
use super::error::LawError;
use super::targets::Targets;
use crate::face::STATE_COMPONENTS;
use crate::system::FrameTrace;

/// Parameters of the delayed-damage interface law (seed 4.2), physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DamageParams {
    /// Strength `sigma_c` (Pa, > 0) that scales the effective traction `y = s_eff / sigma_c`.
    pub strength: f64,
    /// Delay time `tau` (s, > 0): the damage rate is at most `1 / tau`.
    pub delay: f64,
    /// Rate exponent `a` (> 0): near its target `f(y)` the damage approaches it with the time
    /// constant `tau / a`.
    pub a: f64,
    /// Threshold `c0` in (0, 1): no damage grows while `y <= c0`.
    pub c0: f64,
    /// Mixity factor `beta` (>= 0) of the tangential traction in `s_eff`.
    pub beta: f64,
    /// A face counts as fully debonded (`D = 1` in its targets) once `D >= 1 - eps`; `eps` in
    /// (0, 1).
    pub eps: f64,
    /// Damage at t = 0 in [0, 1] (1: a pre-existing crack).
    pub initial: f64,
    /// Contact of the debonded part.
    pub contact: ContactParams,
}

impl DamageParams {
    /// Default `beta`: the tangential traction counts as much as the normal one.
    pub const DEFAULT_BETA: f64 = 1.0;
    /// Default `eps`.
    pub const DEFAULT_EPS: f64 = 1e-4;

    /// Checks the ranges above (all finite) and the contact parameters.
    pub fn validate(&self) -> Result<(), LawError> {
        let checks: [(&'static str, f64, bool, &str); 7] = [
            (
                "strength",
                self.strength,
                self.strength > 0.0,
                "must be > 0 (Pa)",
            ),
            ("delay", self.delay, self.delay > 0.0, "must be > 0 (s)"),
            ("a", self.a, self.a > 0.0, "must be > 0"),
            (
                "c0",
                self.c0,
                self.c0 > 0.0 && self.c0 < 1.0,
                "must be in (0, 1)",
            ),
            ("beta", self.beta, self.beta >= 0.0, "must be >= 0"),
            (
                "damage_eps",
                self.eps,
                self.eps > 0.0 && self.eps < 1.0,
                "must be in (0, 1)",
            ),
            (
                "initial_damage",
                self.initial,
                (0.0..=1.0).contains(&self.initial),
                "must be in [0, 1]",
            ),
        ];
        for (key, value, ok, reason) in checks {
            if !(value.is_finite() && ok) {
                return Err(LawError {
                    key,
                    reason: format!("{reason}, got {value}"),
                });
            }
        }
        self.contact.validate()
    }
}

/// The delayed-damage law in scaled units (tractions over `Z_ref`), for the scaled law `Contact`.
///
/// Evolution (4.8)-(4.14): `dD/dt = (1/tau) (1 - exp(-a <f(y) - D>_+))`, which only approaches
/// `D = 1`; `y = s_eff / sigma_c` with `s_eff = sqrt(<sI_n>_+^2 + beta^2 sI_t^2)` of the
/// bonded Riemann traction `sI`; `f` the cubic smoothstep from 0 at `y = c0` to 1 at `y = 1`.
/// Targets (4.20): `(1 - D)` times the bonded targets plus `D` times the contact law's, with
/// `D` clipped to [0, 1] and taken as 1 from `1 - eps` on (see [`DamageLaw::effective`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DamageLaw {
    /// `sigma_c`, scaled.
    pub strength: f64,
    /// `tau`, s.
    pub delay: f64,
    /// `a`.
    pub a: f64,
    /// `c0`.
    pub c0: f64,
    /// `beta`.
    pub beta: f64,
    /// `eps`.
    pub eps: f64,
    /// `D` at t = 0.
    pub initial: f64,
}

impl DamageLaw {
    /// The damage in effect for the state's `d`, and its derivative: `d` clipped to [0, 1],
    /// and 1 from `1 - eps` on, reached continuously (slope 2 from `1 - 2 eps`) so that the
    /// Newton iterations meet no jump.
    pub fn effective(&self, d: f64) -> (f64, f64) {
        let knee = 1.0 - 2.0 * self.eps;
        if d <= 0.0 {
            (0.0, 0.0)
        } else if d <= knee {
            (d, 1.0)
        } else if d < 1.0 - self.eps {
            (knee + 2.0 * (d - knee), 2.0)
        } else {
            (1.0, 0.0)
        }
    }

    /// `f(y)` and `f'(y)`.
    pub fn target(&self, y: f64) -> (f64, f64) {
        let xi = (y - self.c0) / (1.0 - self.c0);
        if xi <= 0.0 {
            (0.0, 0.0)
        } else if xi >= 1.0 {
            (1.0, 0.0)
        } else {
            (
                xi * xi * (3.0 - 2.0 * xi),
                6.0 * xi * (1.0 - xi) / (1.0 - self.c0),
            )
        }
    }

    /// Blends the contact targets `t` (of the debonded part) with the bonded ones for the
    /// damage `d`: star values and their derivatives, and `d star / d D`.
    pub(super) fn blend(&self, t: &mut Targets, z: [f64; 2], w_a: [f64; 2], w_b: [f64; 2], d: f64) {
        let (de, dde) = self.effective(d);
        let si = t.bonded_traction;
        let vi = [0, 1].map(|k| (w_b[k] - w_a[k]) / (2.0 * z[k]));
        let bonded = [vi[0], vi[1], si[0], si[1]];
        let contact = [t.star.v[0], t.star.v[1], t.star.s[0], t.star.s[1]];
        // d bonded row r / d w_a[j], d w_b[j]: diagonal in the frame direction.
        let bonded_d = |r: usize, j: usize| -> (f64, f64) {
            let k = r % 2;
            match (r < 2, j == k) {
                (_, false) => (0.0, 0.0),
                (true, true) => (-0.5 / z[k], 0.5 / z[k]),
                (false, true) => (0.5, 0.5),
            }
        };
        let mut star = [0.0; 4];
        for r in 0..4 {
            star[r] = (1.0 - de) * bonded[r] + de * contact[r];
            for j in 0..2 {
                let (ba, bb) = bonded_d(r, j);
                t.d_wa[r][j] = (1.0 - de) * ba + de * t.d_wa[r][j];
                t.d_wb[r][j] = (1.0 - de) * bb + de * t.d_wb[r][j];
                t.d_sep[r][j] *= de;
            }
            t.d_sep[r][2] = dde * (contact[r] - bonded[r]);
        }
        t.star = FrameTrace {
            v: [star[0], star[1]],
            s: [star[2], star[3]],
        };
        t.damage = de;
    }

    /// `dD/dt` (1/s) for the damage `d` and its derivatives into `t` (`rate[2]`, `rate_wa[2]`,
    /// `rate_wb[2]`, `rate_sep[2]`); `strength` and the bonded traction are scaled alike.
    pub(super) fn evolution(&self, t: &mut Targets, d: f64) {
        t.rate[2] = 0.0;
        t.rate_wa[2] = [0.0; 2];
        t.rate_wb[2] = [0.0; 2];
        t.rate_sep[2] = [0.0; STATE_COMPONENTS];
        let si = t.bonded_traction;
        let tension = si[0].max(0.0);
        let s_eff = (tension * tension + self.beta * self.beta * si[1] * si[1]).sqrt();
        let (f, df) = self.target(s_eff / self.strength);
        let g = f - d;
        if g <= 0.0 {
            return;
        }
        let e = (-self.a * g).exp();
        t.rate[2] = (1.0 - e) / self.delay;
        let rate_g = self.a * e / self.delay;
        t.rate_sep[2][2] = -rate_g;
        if s_eff > 0.0 {
            // sI = (w_a + w_b) / 2 per direction.
            let dy = [
                tension / (self.strength * s_eff),
                self.beta * self.beta * si[1] / (self.strength * s_eff),
            ];
            let r = dy.map(|x| 0.5 * rate_g * df * x);
            t.rate_wa[2] = r;
            t.rate_wb[2] = r;
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// The seed's damage law (4.5, first set) for PMMA with frictional contact when debonded.
    pub(crate) fn damage_params() -> DamageParams {
        DamageParams {
            strength: 62.1e6,
            delay: 1e-8,
            a: 10.0,
            c0: 0.8,
            beta: 1.0,
            eps: DamageParams::DEFAULT_EPS,
            initial: 0.0,
            contact: ContactParams {
                friction: 0.3,
                r_c: -1e-7,
                r_s: 1e-7,
                s_c: 0.0,
                s_s: 1e6,
            },
        }
    }

    #[test]
    fn invalid_damage_parameters_are_named() {
        let ok = damage_params();
        assert!(ok.validate().is_ok());
        for (p, want) in [
            (DamageParams { delay: 0.0, ..ok }, "delay"),
            (DamageParams { c0: 1.0, ..ok }, "c0"),
            (DamageParams { c0: 0.0, ..ok }, "c0"),
            (DamageParams { initial: 1.5, ..ok }, "initial_damage"),
            (
                DamageParams {
                    strength: -1.0,
                    ..ok
                },
                "strength",
            ),
            (DamageParams { a: f64::NAN, ..ok }, "a"),
            (DamageParams { eps: 1.0, ..ok }, "damage_eps"),
        ] {
            assert_eq!(p.validate().unwrap_err().key, want);
        }
    }
}
