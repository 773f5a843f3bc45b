//! Parameters of unilateral contact with Coulomb friction (seed 3.2.2, (3.25)-(3.39)).

use super::error::LawError;

/// Parameters of a contact interface, physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Coulomb friction coefficient `k` (>= 0).
    pub friction: f64,
    /// Separation at and below which the faces are fully in contact, `r_c <= 0` (m).
    pub r_c: f64,
    /// Separation at and above which the faces are fully separated, `r_s >= r_c` (m).
    pub r_s: f64,
    /// Normal bonded traction at and below which the faces are fully in contact, `s_c >= 0` (Pa).
    pub s_c: f64,
    /// Normal bonded traction at and above which the faces are fully separated, `s_s >= s_c`
    /// (Pa).
    pub s_s: f64,
}

impl ContactParams {
    /// Checks the seed's ranges: `k >= 0`, `r_c <= 0`, `r_c <= r_s`, `s_c >= 0`, `s_c <= s_s`,
    /// all finite.
    pub fn validate(&self) -> Result<(), LawError> {
        let err = |key, reason: &str| {
            Err(LawError {
                key,
                reason: reason.into(),
            })
        };
        for (key, value) in [
            ("friction", self.friction),
            ("r_c", self.r_c),
            ("r_s", self.r_s),
            ("s_c", self.s_c),
            ("s_s", self.s_s),
        ] {
            if !value.is_finite() {
                return err(key, "must be a finite number");
            }
        }
        if self.friction < 0.0 {
            return err("friction", "must be >= 0");
        }
        if self.r_c > 0.0 {
            return err(
                "r_c",
                "must be <= 0 (m): full contact at a separation of r_c or less",
            );
        }
        if self.r_c > self.r_s {
            return err("r_s", "must be >= r_c");
        }
        if self.s_c < 0.0 {
            return err("s_c", "must be >= 0 (Pa)");
        }
        if self.s_c > self.s_s {
            return err("s_s", "must be >= s_c");
        }
        Ok(())
    }
}
