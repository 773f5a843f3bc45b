//! Conditions of the problem: boundary conditions and their time histories, and the exact
//! solution.

use serde::{Deserialize, Serialize};

/// Kind of a boundary condition.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum BoundaryKind {
    /// Zero traction.
    Free,
    /// Zero normal velocity and zero tangential traction.
    Roller,
    /// Prescribed traction `value` (Pa) times `history`.
    Traction,
    /// Prescribed velocity `value` (m/s) times `history`.
    Velocity,
    /// Prescribed incoming characteristic `incoming` (Pa) times `history`; absorbing when zero.
    Transmitting,
    /// Exterior state from `[exact]`.
    Exact,
}

/// `[[boundary]]`: one condition on one or more tagged sides.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoundaryConfig {
    /// Boundary tags (`left`, `right`, `bottom`, `top`, or Gmsh physical names).
    pub sides: Vec<String>,
    /// The condition.
    pub kind: BoundaryKind,
    /// Traction (Pa) or velocity (m/s): `[x, y]` in-plane, `[z]` anti-plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<Vec<f64>>,
    /// Transmitting: incoming characteristic (Pa), `[normal, tangential]` in-plane, `[z]`
    /// anti-plane. Default zero (absorbing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub incoming: Option<Vec<f64>>,
    /// Time history multiplying `value` or `incoming`. Default constant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history: Option<HistoryConfig>,
}

/// Kind of a time history.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum HistoryKind {
    /// 1 at all times.
    Constant,
    /// Linear ramp to 1 over `ramp`.
    Linear,
    /// Cubic C1 ramp `3 r^2 - 2 r^3` to 1 over `ramp`.
    Smooth,
    /// Piecewise linear through `points`.
    Table,
    /// Through `points` with a C1 cubic ramp `3 r^2 - 2 r^3` on each piece.
    #[serde(rename = "smooth_table")]
    SmoothTable,
}

/// A time history: `{ kind = "smooth", ramp = 2e-6 }` or `{ kind = "table", points = [[0, 0],
/// [1e-6, 1]] }`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HistoryConfig {
    /// The shape.
    pub kind: HistoryKind,
    /// Ramp time, s (linear, smooth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp: Option<f64>,
    /// `[t (s), multiplier]` pairs with increasing `t` (table, smooth_table).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<[f64; 2]>>,
}

impl HistoryConfig {
    /// The history, or `(key, reason)` for a missing or invalid parameter.
    pub fn to_history(&self) -> Result<sdg_solver::history::History, (String, String)> {
        use sdg_solver::history::History;
        let ramp = || {
            self.ramp
                .ok_or_else(|| ("ramp".to_string(), "is required for this kind".to_string()))
        };
        let history = match self.kind {
            HistoryKind::Constant => History::Constant,
            HistoryKind::Linear => History::Linear { ramp: ramp()? },
            HistoryKind::Smooth => History::Smooth { ramp: ramp()? },
            HistoryKind::Table | HistoryKind::SmoothTable => {
                let points = self
                    .points
                    .as_ref()
                    .ok_or_else(|| ("points".to_string(), "is required for a table".to_string()))?;
                let points = points.iter().map(|p| (p[0], p[1])).collect();
                if self.kind == HistoryKind::Table {
                    History::Table(points)
                } else {
                    History::SmoothTable(points)
                }
            }
        };
        let key = match self.kind {
            HistoryKind::Table | HistoryKind::SmoothTable => "points",
            _ => "ramp",
        };
        history.validate().map_err(|r| (key.to_string(), r))?;
        Ok(history)
    }
}

/// Kind of exact solution.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ExactKind {
    /// A plane P or S wave.
    PlaneWave,
}

/// Wave type of a plane wave.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
pub enum WaveName {
    /// Dilatational.
    P,
    /// Shear.
    S,
}

/// Profile of a plane wave.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum ProfileName {
    /// Periodic sine.
    #[default]
    Sine,
    /// Compact smooth pulse.
    Pulse,
}

/// `[exact]`: an exact solution of the unbounded medium.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExactConfig {
    /// `"plane_wave"`.
    pub kind: ExactKind,
    /// `"P"` or `"S"`.
    pub wave: WaveName,
    /// Propagation direction from the x axis, degrees. Default 0.
    #[serde(default)]
    pub angle_deg: f64,
    /// Wavelength (sine) or pulse width, m.
    pub wavelength: f64,
    /// Velocity amplitude, m/s. Default 1.
    #[serde(default = "default_amplitude")]
    pub amplitude: f64,
    /// `"sine"` or `"pulse"`. Default sine.
    #[serde(default)]
    pub profile: ProfileName,
    /// Pulse centre at t = 0 along the propagation direction, m (`d . x`). Default 0.
    #[serde(default)]
    pub center: f64,
}

fn default_amplitude() -> f64 {
    1.0
}

#[cfg(test)]
mod tests {
    use crate::config::tests::{BASE, parse};

    #[test]
    fn smooth_table_history() {
        let text = format!(
            "{BASE}[[boundary]]\nsides = [\"top\"]\nkind = \"traction\"\nvalue = [0.0, -1e6]\n\
             history = {{ kind = \"smooth_table\", points = [[0.0, 0.0], [1e-7, 1.0]] }}\n"
        );
        let c = parse(&text, &[]).unwrap();
        let history = c.boundary[0]
            .history
            .as_ref()
            .unwrap()
            .to_history()
            .unwrap();
        assert_eq!(history.value(0.5e-7), 0.5);
    }
}
