//! Side a's targets of a nonlinear face and the characteristics they are computed from.

use crate::face::STATE_COMPONENTS;
use crate::system::FrameTrace;

/// Which contact mode dominates at a point: the largest area fraction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// Bonded law.
    Bonded,
    /// Contact-stick.
    Stick,
    /// Contact-slip.
    Slip,
    /// Separation.
    Separation,
}

impl Mode {
    /// A short lowercase name for outputs.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Bonded => "bonded",
            Mode::Stick => "stick",
            Mode::Slip => "slip",
            Mode::Separation => "separation",
        }
    }
}

/// Side a's targets of a contact face and their derivatives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Targets {
    /// `v*_a` and `s*` in side a's frame (scaled).
    pub star: FrameTrace,
    /// `d star / d w_a[j]`, rows in the order `v[0], v[1], s[0], s[1]`.
    pub d_wa: [[f64; 2]; 4],
    /// `d star / d w_b[j]`.
    pub d_wb: [[f64; 2]; 4],
    /// `d star / d state[j]` for the interface state (normal separation, slip: per m; damage).
    pub d_sep: [[f64; STATE_COMPONENTS]; 4],
    /// Rates of the interface state: the separation rate `[[v*]] = v*_b - v*_a` (normal,
    /// tangential; m/s) and `dD/dt` (1/s), the same from both sides.
    pub rate: [f64; STATE_COMPONENTS],
    /// `d rate[k] / d w_a[j]`.
    pub rate_wa: [[f64; 2]; STATE_COMPONENTS],
    /// `d rate[k] / d w_b[j]`.
    pub rate_wb: [[f64; 2]; STATE_COMPONENTS],
    /// `d rate[k] / d state[j]`.
    pub rate_sep: [[f64; STATE_COMPONENTS]; STATE_COMPONENTS],
    /// Bonded Riemann tractions `sI` (normal, tangential; scaled).
    pub bonded_traction: [f64; 2],
    /// Contact area fraction `eta` of the debonded part.
    pub eta: f64,
    /// Stick flag `gamma` (0 or 1).
    pub gamma: f64,
    /// Damage `D` in effect: the debonded fraction (1 for laws without damage).
    pub damage: f64,
}

impl Targets {
    /// The mode with the largest area fraction: bonded `1 - D`, separation `D (1 - eta)`,
    /// stick `D eta gamma`, slip `D eta (1 - gamma)`.
    pub fn mode(&self) -> Mode {
        let d = self.damage;
        let fractions = [
            (Mode::Bonded, 1.0 - d),
            (Mode::Stick, d * self.eta * self.gamma),
            (Mode::Slip, d * self.eta * (1.0 - self.gamma)),
            (Mode::Separation, d * (1.0 - self.eta)),
        ];
        fractions
            .into_iter()
            .fold((Mode::Separation, -1.0), |best, f| {
                if f.1 > best.1 { f } else { best }
            })
            .0
    }
}

/// The characteristics arriving at a face from side a and side b, from their frame traces.
pub fn characteristics(z: [f64; 2], a: &FrameTrace, b: &FrameTrace) -> ([f64; 2], [f64; 2]) {
    (
        [a.s[0] - z[0] * a.v[0], a.s[1] - z[1] * a.v[1]],
        [b.s[0] + z[0] * b.v[0], b.s[1] + z[1] * b.v[1]],
    )
}
