//! The Xu-Needleman cohesive law (seed 2.2.5, (2.69)-(2.70)) and its parameters.

use super::contact::ContactParams;
use super::error::LawError;

/// Parameters of a Xu-Needleman cohesive interface (seed (2.69)-(2.70)), physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CohesiveParams {
    /// Cohesive strength `sigma_c` (Pa, > 0): the largest normal traction, at `delta = delta_c`.
    pub strength: f64,
    /// Critical separation `delta_c` (m, > 0), equal for the normal and tangential directions.
    pub critical_separation: f64,
    /// Contact of the faces in compression (and friction once they touch).
    pub contact: ContactParams,
}

impl CohesiveParams {
    /// Work of separation `phi = e sigma_c delta_c` (2.70), J/m^2.
    pub fn work_of_separation(&self) -> f64 {
        std::f64::consts::E * self.strength * self.critical_separation
    }

    /// The contact regularization used when a config gives none: full contact at a separation
    /// of `-delta_c / 100` or less (interpenetration is resisted first by the law's own
    /// stiffness `e sigma_c / delta_c`), separated at any opening; full contact at compressive
    /// bonded tractions, separated above `sigma_c / 100` of tension; no friction.
    pub fn default_contact(strength: f64, critical_separation: f64) -> ContactParams {
        ContactParams {
            friction: 0.0,
            r_c: -0.01 * critical_separation,
            r_s: 0.0,
            s_c: 0.0,
            s_s: 0.01 * strength,
        }
    }

    /// Checks `strength > 0`, `critical_separation > 0` (finite) and the contact parameters.
    pub fn validate(&self) -> Result<(), LawError> {
        for (key, value) in [
            ("strength", self.strength),
            ("critical_separation", self.critical_separation),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(LawError {
                    key,
                    reason: "must be a finite number > 0".into(),
                });
            }
        }
        self.contact.validate()
    }

    /// The Xu-Needleman traction (normal, tangential; Pa) at the separation `sep` (normal,
    /// tangential; m).
    pub fn traction(&self, sep: [f64; 2]) -> [f64; 2] {
        XuNeedleman {
            strength: self.strength,
            delta_c: self.critical_separation,
        }
        .traction(sep)
        .0
    }
}

/// The Xu-Needleman law (2.69) with equal normal and tangential critical separations: with
/// `D1 = delta / delta_c`, `D2 = slip / delta_c`, `T_n = sigma_c D1 exp(1 - D1 - D2^2)` and
/// `T_t = 2 sigma_c D2 (1 + D1) exp(1 - D1 - D2^2)`. For `D1 < 0` (interpenetration, which the
/// contact part of the law takes over) its linear continuation `exp(1 - D2^2)` replaces the
/// exponential and `1 + D1` is 1: continuous with continuous derivatives at `D1 = 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct XuNeedleman {
    /// `sigma_c`, in the units of the tractions returned.
    pub strength: f64,
    /// `delta_c`, m.
    pub delta_c: f64,
}

impl XuNeedleman {
    /// The trailing-edge separation `delta_T > delta_c` of the process zone (seed 2.4.2), m:
    /// where the normal traction has fallen to 1% of the strength (`D e^(1 - D) = 0.01`,
    /// `D = delta_T / delta_c ~ 7.64`).
    pub fn trailing_separation(&self) -> f64 {
        // Newton on ln D + 1 - D = ln 0.01, from beyond the root (the function is concave).
        let mut d: f64 = 10.0;
        for _ in 0..50 {
            let step = (d.ln() + 1.0 - d - 0.01f64.ln()) / (1.0 / d - 1.0);
            d -= step;
            if step.abs() < 1e-15 * d {
                break;
            }
        }
        d * self.delta_c
    }

    /// The traction (normal, tangential) at `sep` (m) and its derivatives `d T_k / d sep_j`.
    pub fn traction(&self, sep: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
        let (d1, d2) = (sep[0] / self.delta_c, sep[1] / self.delta_c);
        let open = d1.max(0.0);
        let e = (1.0 - open - d2 * d2).exp();
        let sigma = self.strength;
        let scale = sigma / self.delta_c;
        let tn = sigma * d1 * e;
        let tt = 2.0 * sigma * d2 * (1.0 + open) * e;
        let dtn = [scale * e * (1.0 - open), scale * d1 * e * (-2.0 * d2)];
        let dtt = [
            -2.0 * scale * d2 * open * e,
            2.0 * scale * (1.0 + open) * e * (1.0 - 2.0 * d2 * d2),
        ];
        ([tn, tt], [dtn, dtt])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xu_needleman_traction_peaks_at_the_strength() {
        let (strength, dc) = (324e6, 4e-7);
        let p = CohesiveParams {
            strength,
            critical_separation: dc,
            contact: CohesiveParams::default_contact(strength, dc),
        };
        // (2.69) written out: peak sigma_c at delta_c, 1% of it near 7.6 delta_c.
        let tn = |d: f64| strength * d / dc * (1.0 - d / dc).exp();
        for d in [0.1, 1.0, 3.0, 7.6] {
            let t = p.traction([d * dc, 0.0]);
            assert!((t[0] - tn(d * dc)).abs() < 1e-6 * strength && t[1] == 0.0);
        }
        assert!((p.traction([dc, 0.0])[0] - strength).abs() < 1e-6);
        let law = XuNeedleman {
            strength,
            delta_c: dc,
        };
        let trailing = law.traction([law.trailing_separation(), 0.0]).0[0];
        assert!((trailing / strength - 0.01).abs() < 1e-12);
        assert!(law.trailing_separation() > 7.0 * dc && law.trailing_separation() < 8.0 * dc);
        let tt = |d1: f64, d2: f64| 2.0 * strength * d2 * (1.0 + d1) * (1.0 - d1 - d2 * d2).exp();
        let t = p.traction([0.5 * dc, 0.3 * dc]);
        assert!((t[1] - tt(0.5, 0.3)).abs() < 1e-6 * strength);
        // Work of separation: the integral of T_n over the opening (2.70).
        let n = 200_000;
        let h = 60.0 * dc / n as f64;
        let work: f64 = (0..n)
            .map(|i| h * p.traction([(i as f64 + 0.5) * h, 0.0])[0])
            .sum();
        assert!((work / p.work_of_separation() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn invalid_parameters_are_named() {
        let ok = ContactParams {
            friction: 0.25,
            r_c: -1e-6,
            r_s: 0.0,
            s_c: 0.0,
            s_s: 6e5,
        };
        assert!(ok.validate().is_ok());
        let key = |p: ContactParams| p.validate().unwrap_err().key;
        assert_eq!(
            key(ContactParams {
                friction: -0.1,
                ..ok
            }),
            "friction"
        );
        assert_eq!(key(ContactParams { r_c: 1e-6, ..ok }), "r_c");
        assert_eq!(
            key(ContactParams {
                r_c: -1e-6,
                r_s: -2e-6,
                ..ok
            }),
            "r_s"
        );
        assert_eq!(key(ContactParams { s_c: 7e5, ..ok }), "s_s");
        assert_eq!(key(ContactParams { s_c: -1.0, ..ok }), "s_c");
        let cohesive = CohesiveParams {
            strength: 324e6,
            critical_separation: 4e-7,
            contact: ok,
        };
        assert!(cohesive.validate().is_ok());
        for (p, want) in [
            (
                CohesiveParams {
                    strength: 0.0,
                    ..cohesive
                },
                "strength",
            ),
            (
                CohesiveParams {
                    critical_separation: -4e-7,
                    ..cohesive
                },
                "critical_separation",
            ),
            (
                CohesiveParams {
                    strength: f64::NAN,
                    ..cohesive
                },
                "strength",
            ),
        ] {
            assert_eq!(p.validate().unwrap_err().key, want);
        }
    }
}
