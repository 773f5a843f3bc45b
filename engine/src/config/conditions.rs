//! Conditions of the problem: boundary conditions and their time histories, interface laws
//! and the exact solution.

use serde::{Deserialize, Serialize};

use sdg_solver::interface::{CohesiveParams, ContactParams, DamageParams, Law};

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

/// The law of an interface.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LawName {
    /// Perfectly bonded.
    Bonded,
    /// Both faces traction-free.
    Free,
    /// Unilateral contact with Coulomb friction (in-plane modes only).
    Contact,
    /// Xu-Needleman cohesive law, in contact under compression (in-plane modes only).
    XuNeedleman,
    /// Delayed damage, the debonded part in contact (in-plane modes only).
    Damage,
}

impl LawName {
    /// True for laws that need a normal direction (not anti-plane shear).
    pub fn is_in_plane_only(self) -> bool {
        matches!(
            self,
            LawName::Contact | LawName::XuNeedleman | LawName::Damage
        )
    }
}

/// `[[interface]]`: one law on one or more interface tags. The contact parameters (seed 3.2.1,
/// 3.3.1) are required with `law = "contact"`; with `law = "xu_needleman"` `strength` and
/// `critical_separation` are required and the contact parameters optional (defaults:
/// [`CohesiveParams::default_contact`]); with `law = "damage"` `strength`, `delay`, `a`, `c0`
/// and the contact parameters (of the debonded part) are required, `beta`, `damage_eps` and
/// `initial_damage` optional. Parameters a law does not use are rejected.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InterfaceConfig {
    /// Interface tags (`[[mesh.interface]]` tags, or Gmsh physical names on interior edges).
    pub tags: Vec<String>,
    /// The law.
    pub law: LawName,
    /// Coulomb friction coefficient `k`, >= 0 (dimensionless).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// Separation at and below which the faces are fully in contact, `r_c <= 0`, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub r_c: Option<f64>,
    /// Separation at and above which the faces are fully separated, `r_s >= r_c`, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub r_s: Option<f64>,
    /// Normal bonded traction at and below which the faces are fully in contact, `s_c >= 0`, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_c: Option<f64>,
    /// Normal bonded traction at and above which the faces are fully separated, `s_s >= s_c`,
    /// Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_s: Option<f64>,
    /// Cohesive strength `sigma_c`, Pa (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength: Option<f64>,
    /// Critical separation `delta_c`, m (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub critical_separation: Option<f64>,
    /// Damage delay time `tau`, s (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay: Option<f64>,
    /// Damage rate exponent `a` (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<f64>,
    /// Damage threshold `c0` in (0, 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c0: Option<f64>,
    /// Damage mixity factor `beta` (>= 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// Damage at and above `1 - damage_eps` counts as full debonding.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damage_eps: Option<f64>,
    /// Damage at t = 0 in [0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_damage: Option<f64>,
}

impl InterfaceConfig {
    /// The law, or `(key, reason)` for a missing, extra or invalid parameter.
    pub fn to_law(&self) -> Result<Law, (String, String)> {
        let contact = [
            ("friction", self.friction),
            ("r_c", self.r_c),
            ("r_s", self.r_s),
            ("s_c", self.s_c),
            ("s_s", self.s_s),
        ];
        let cohesive = [
            ("strength", self.strength),
            ("critical_separation", self.critical_separation),
        ];
        let damage = [
            ("delay", self.delay),
            ("a", self.a),
            ("c0", self.c0),
            ("beta", self.beta),
            ("damage_eps", self.damage_eps),
            ("initial_damage", self.initial_damage),
        ];
        let name = match self.law {
            LawName::Bonded => "bonded",
            LawName::Free => "free",
            LawName::Contact => "contact",
            LawName::XuNeedleman => "xu_needleman",
            LawName::Damage => "damage",
        };
        let unused = |keys: &[(&str, Option<f64>)]| match keys.iter().find(|(_, v)| v.is_some()) {
            Some((key, _)) => Err((
                key.to_string(),
                format!("is not a parameter of law = \"{name}\""),
            )),
            None => Ok(()),
        };
        let required = |(key, v): (&str, Option<f64>)| {
            v.ok_or_else(|| {
                (
                    key.to_string(),
                    format!("is required with law = \"{name}\""),
                )
            })
        };
        let invalid = |e: sdg_solver::interface::LawError| (e.key.to_string(), e.reason);
        match self.law {
            LawName::Bonded | LawName::Free => {
                unused(&contact)?;
                unused(&cohesive)?;
                unused(&damage)?;
                Ok(if self.law == LawName::Bonded {
                    Law::Bonded
                } else {
                    Law::Free
                })
            }
            LawName::Contact => {
                unused(&cohesive)?;
                unused(&damage)?;
                let [friction, r_c, r_s, s_c, s_s] = contact.map(required);
                let params = ContactParams {
                    friction: friction?,
                    r_c: r_c?,
                    r_s: r_s?,
                    s_c: s_c?,
                    s_s: s_s?,
                };
                params.validate().map_err(invalid)?;
                Ok(Law::Contact(params))
            }
            LawName::XuNeedleman => {
                unused(&damage)?;
                let [strength, critical_separation] = cohesive.map(required);
                let (strength, critical_separation) = (strength?, critical_separation?);
                let default = CohesiveParams::default_contact(strength, critical_separation);
                let params = CohesiveParams {
                    strength,
                    critical_separation,
                    contact: ContactParams {
                        friction: self.friction.unwrap_or(default.friction),
                        r_c: self.r_c.unwrap_or(default.r_c),
                        r_s: self.r_s.unwrap_or(default.r_s),
                        s_c: self.s_c.unwrap_or(default.s_c),
                        s_s: self.s_s.unwrap_or(default.s_s),
                    },
                };
                params.validate().map_err(invalid)?;
                Ok(Law::XuNeedleman(params))
            }
            LawName::Damage => {
                unused(&cohesive[1..])?;
                let [friction, r_c, r_s, s_c, s_s] = contact.map(required);
                let [delay, a, c0] = [damage[0], damage[1], damage[2]].map(required);
                let params = DamageParams {
                    strength: required(cohesive[0])?,
                    delay: delay?,
                    a: a?,
                    c0: c0?,
                    beta: self.beta.unwrap_or(DamageParams::DEFAULT_BETA),
                    eps: self.damage_eps.unwrap_or(DamageParams::DEFAULT_EPS),
                    initial: self.initial_damage.unwrap_or(0.0),
                    contact: ContactParams {
                        friction: friction?,
                        r_c: r_c?,
                        r_s: r_s?,
                        s_c: s_c?,
                        s_s: s_s?,
                    },
                };
                params.validate().map_err(invalid)?;
                Ok(Law::Damage(params))
            }
        }
    }
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
    use super::*;
    use crate::config::tests::{BASE, INTERFACES, parse};

    #[test]
    fn interfaces_and_their_laws() {
        let text = format!("{BASE}{INTERFACES}");
        let c = parse(&text, &["output.interface_probes=[[0.001, 0.005]]"]).unwrap();
        assert_eq!(c.mesh.interface.len(), 2);
        assert_eq!(c.rectangle().interfaces[1].tag, "joint");
        assert_eq!(
            c.interface[0].to_law().unwrap(),
            Law::Contact(ContactParams {
                friction: 0.25,
                r_c: -1e-6,
                r_s: 0.0,
                s_c: 0.0,
                s_s: 6e5,
            })
        );
        assert_eq!(c.interface[1].to_law().unwrap(), Law::Free);
        assert_eq!(c.output.interface_probes, vec![[0.001, 0.005]]);
        // Array entries are addressed by index in overrides.
        let c = parse(
            &text,
            &["interface.0.r_c=-1e-7", "mesh.interface.1.tag=other"],
        )
        .unwrap();
        assert_eq!(c.interface[0].r_c, Some(-1e-7));
        assert_eq!(c.mesh.interface[1].tag, "other");
        let e = parse(&text, &["interface.2.law=free"]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("interface"));
        assert!(e.reason.contains("not an index below 2"), "{e}");
    }

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
