//! `[[interface]]`: the law of a group of interface tags, one variant per law with its own keys.
//!
//! An entry is read on its own ([`take_interfaces`]) so that every error names the key inside
//! the entry (`interface[0].strength`); its parameters are checked there, once, and the solver's
//! [`Law`] follows from a read entry without failing ([`LawConfig::law`]).

use serde::{Deserialize, Serialize};

use sdg_solver::interface::{CohesiveParams, ContactParams, DamageParams, Law, LawError};

/// The name of an interface law: the value of `law`.
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

/// The contact keys, in the order errors ask for them.
const CONTACT_KEYS: [&str; 5] = ["friction", "r_c", "r_s", "s_c", "s_s"];

impl LawName {
    /// True for laws that need a normal direction (not anti-plane shear).
    pub fn is_in_plane_only(self) -> bool {
        matches!(
            self,
            LawName::Contact | LawName::XuNeedleman | LawName::Damage
        )
    }

    /// The name as a config writes it.
    pub fn as_str(self) -> &'static str {
        match self {
            LawName::Bonded => "bonded",
            LawName::Free => "free",
            LawName::Contact => "contact",
            LawName::XuNeedleman => "xu_needleman",
            LawName::Damage => "damage",
        }
    }

    /// The law's keys besides `tags` and `law`: the required ones, then the optional ones.
    fn keys(self) -> (&'static [&'static str], &'static [&'static str]) {
        match self {
            LawName::Bonded | LawName::Free => (&[], &[]),
            LawName::Contact => (&CONTACT_KEYS, &[]),
            LawName::XuNeedleman => (&["strength", "critical_separation"], &CONTACT_KEYS),
            LawName::Damage => (
                &[
                    "strength", "delay", "a", "c0", "friction", "r_c", "r_s", "s_c", "s_s",
                ],
                &["beta", "damage_eps", "initial_damage"],
            ),
        }
    }
}

/// `[[interface]]`: one law on one or more interface tags.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct InterfaceConfig {
    /// Interface tags (`[[mesh.interface]]` tags, or Gmsh physical names on interior edges).
    pub tags: Vec<String>,
    /// The law and its parameters (`law = "..."` and the law's keys).
    #[serde(flatten)]
    pub law: LawConfig,
}

/// The law of an interface with its parameters as written; `law = "..."` names the variant, and
/// a key of another law is an error. Parameters are checked when the entry is read.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum LawConfig {
    /// Perfectly bonded.
    Bonded,
    /// Both faces traction-free.
    Free,
    /// Unilateral contact with Coulomb friction.
    Contact(ContactConfig),
    /// Xu-Needleman cohesive law, in contact under compression.
    XuNeedleman(CohesiveConfig),
    /// Delayed damage, the debonded part in contact.
    Damage(DamageConfig),
}

/// `law = "contact"`: unilateral contact with Coulomb friction (seed 3.2.1, 3.3.1); all keys
/// required.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ContactConfig {
    /// Coulomb friction coefficient `k`, >= 0 (dimensionless).
    pub friction: f64,
    /// Separation at and below which the faces are fully in contact, `r_c <= 0`, m.
    pub r_c: f64,
    /// Separation at and above which the faces are fully separated, `r_s >= r_c`, m.
    pub r_s: f64,
    /// Normal bonded traction at and below which the faces are fully in contact, `s_c >= 0`, Pa.
    pub s_c: f64,
    /// Normal bonded traction at and above which the faces are fully separated, `s_s >= s_c`,
    /// Pa.
    pub s_s: f64,
}

impl ContactConfig {
    fn params(&self) -> ContactParams {
        ContactParams {
            friction: self.friction,
            r_c: self.r_c,
            r_s: self.r_s,
            s_c: self.s_c,
            s_s: self.s_s,
        }
    }
}

/// `law = "xu_needleman"`: `strength` and `critical_separation` required, the contact keys
/// optional (defaults: [`CohesiveParams::default_contact`]).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CohesiveConfig {
    /// Cohesive strength `sigma_c`, Pa (> 0).
    pub strength: f64,
    /// Critical separation `delta_c`, m (> 0).
    pub critical_separation: f64,
    /// Coulomb friction coefficient, as [`ContactConfig::friction`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// Full contact separation, m, as [`ContactConfig::r_c`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub r_c: Option<f64>,
    /// Full separation, m, as [`ContactConfig::r_s`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub r_s: Option<f64>,
    /// Full contact normal traction, Pa, as [`ContactConfig::s_c`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_c: Option<f64>,
    /// Full separation normal traction, Pa, as [`ContactConfig::s_s`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_s: Option<f64>,
}

/// `law = "damage"`: `strength`, `delay`, `a`, `c0` and the contact keys (of the debonded part)
/// required, `beta`, `damage_eps` and `initial_damage` optional.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DamageConfig {
    /// Strength `sigma_c`, Pa (> 0).
    pub strength: f64,
    /// Delay time `tau`, s (> 0).
    pub delay: f64,
    /// Rate exponent `a` (> 0).
    pub a: f64,
    /// Threshold `c0` in (0, 1).
    pub c0: f64,
    /// Mixity factor `beta` (>= 0). Default [`DamageParams::DEFAULT_BETA`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// Damage at and above `1 - damage_eps` counts as full debonding. Default
    /// [`DamageParams::DEFAULT_EPS`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damage_eps: Option<f64>,
    /// Damage at t = 0 in [0, 1]. Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_damage: Option<f64>,
    /// Coulomb friction coefficient of the debonded part, as [`ContactConfig::friction`].
    pub friction: f64,
    /// Full contact separation, m, as [`ContactConfig::r_c`].
    pub r_c: f64,
    /// Full separation, m, as [`ContactConfig::r_s`].
    pub r_s: f64,
    /// Full contact normal traction, Pa, as [`ContactConfig::s_c`].
    pub s_c: f64,
    /// Full separation normal traction, Pa, as [`ContactConfig::s_s`].
    pub s_s: f64,
}

impl LawConfig {
    /// The name of the law.
    pub fn name(&self) -> LawName {
        match self {
            LawConfig::Bonded => LawName::Bonded,
            LawConfig::Free => LawName::Free,
            LawConfig::Contact(_) => LawName::Contact,
            LawConfig::XuNeedleman(_) => LawName::XuNeedleman,
            LawConfig::Damage(_) => LawName::Damage,
        }
    }

    /// The solver's law, defaults filled in.
    pub fn law(&self) -> Law {
        match self {
            LawConfig::Bonded => Law::Bonded,
            LawConfig::Free => Law::Free,
            LawConfig::Contact(c) => Law::Contact(c.params()),
            LawConfig::XuNeedleman(c) => {
                let default = CohesiveParams::default_contact(c.strength, c.critical_separation);
                Law::XuNeedleman(CohesiveParams {
                    strength: c.strength,
                    critical_separation: c.critical_separation,
                    contact: ContactParams {
                        friction: c.friction.unwrap_or(default.friction),
                        r_c: c.r_c.unwrap_or(default.r_c),
                        r_s: c.r_s.unwrap_or(default.r_s),
                        s_c: c.s_c.unwrap_or(default.s_c),
                        s_s: c.s_s.unwrap_or(default.s_s),
                    },
                })
            }
            LawConfig::Damage(d) => Law::Damage(DamageParams {
                strength: d.strength,
                delay: d.delay,
                a: d.a,
                c0: d.c0,
                beta: d.beta.unwrap_or(DamageParams::DEFAULT_BETA),
                eps: d.damage_eps.unwrap_or(DamageParams::DEFAULT_EPS),
                initial: d.initial_damage.unwrap_or(0.0),
                contact: ContactConfig {
                    friction: d.friction,
                    r_c: d.r_c,
                    r_s: d.r_s,
                    s_c: d.s_c,
                    s_s: d.s_s,
                }
                .params(),
            }),
        }
    }

    /// Checks the parameters' ranges.
    fn validate(&self) -> Result<(), LawError> {
        match self.law() {
            Law::Bonded | Law::Free => Ok(()),
            Law::Contact(p) => p.validate(),
            Law::XuNeedleman(p) => p.validate(),
            Law::Damage(p) => p.validate(),
        }
    }
}

impl InterfaceConfig {
    /// Reads one `[[interface]]` entry and checks its parameters; `(key, reason)` for a missing,
    /// extra, mistyped or invalid key, the key inside the entry (empty for the entry itself).
    fn read(entry: toml::Value) -> Result<Self, (String, String)> {
        let fail = |key: &str, reason: String| Err((key.to_string(), reason));
        let toml::Value::Table(table) = entry else {
            return fail(
                "",
                format!("must be a table of keys (an [[interface]] entry), got {entry}"),
            );
        };
        let field = |key: &str| {
            table
                .get(key)
                .cloned()
                .ok_or_else(|| (key.to_string(), "is required".to_string()))
        };
        let tags: Vec<String> = field("tags")?
            .try_into()
            .map_err(|e: toml::de::Error| ("tags".to_string(), e.message().to_string()))?;
        let name: LawName = field("law")?
            .try_into()
            .map_err(|e: toml::de::Error| ("law".to_string(), e.message().to_string()))?;
        let law = name.as_str();
        let (required, optional) = name.keys();
        let keys: Vec<&str> = required.iter().chain(optional).copied().collect();
        for (key, value) in &table {
            if key == "tags" || key == "law" {
                continue;
            }
            if !keys.contains(&key.as_str()) {
                let takes = match keys.is_empty() {
                    true => "no parameters".to_string(),
                    false => keys.join(", "),
                };
                return fail(
                    key,
                    format!("is not a parameter of law = \"{law}\", which takes {takes}"),
                );
            }
            if !(value.is_float() || value.is_integer()) {
                return fail(key, format!("must be a number, got {value}"));
            }
        }
        if let Some(key) = required.iter().find(|k| !table.contains_key(**k)) {
            return fail(key, format!("is required with law = \"{law}\""));
        }
        let mut params = table;
        params.remove("tags");
        let law: LawConfig = toml::Value::Table(params)
            .try_into()
            .map_err(|e: toml::de::Error| (String::new(), e.message().to_string()))?;
        law.validate().map_err(|e| (e.key.to_string(), e.reason))?;
        Ok(Self { tags, law })
    }
}

/// Takes the `[[interface]]` entries out of the config's `root` table and reads them
/// ([`InterfaceConfig::read`]); `(key, reason)` names the entry, e.g. `interface[0].r_c`.
pub(super) fn take_interfaces(
    root: &mut toml::Value,
) -> Result<Vec<InterfaceConfig>, (String, String)> {
    let Some(value) = root.as_table_mut().and_then(|t| t.remove("interface")) else {
        return Ok(Vec::new());
    };
    let toml::Value::Array(entries) = value else {
        return Err((
            "interface".into(),
            format!("must be a list of [[interface]] entries, got {value}"),
        ));
    };
    (entries.into_iter().enumerate())
        .map(|(i, entry)| {
            InterfaceConfig::read(entry).map_err(|(key, reason)| match key.is_empty() {
                true => (format!("interface[{i}]"), reason),
                false => (format!("interface[{i}].{key}"), reason),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::tests::{BASE, INTERFACES, parse};

    /// `(key, reason)` of the error of `text` with `overrides`.
    fn error(text: &str, overrides: &[&str]) -> (String, String) {
        let e = parse(text, overrides).unwrap_err();
        (e.key.unwrap_or_default(), e.reason)
    }

    #[test]
    fn interfaces_and_their_laws() {
        let text = format!("{BASE}{INTERFACES}");
        let c = parse(&text, &["output.interface_probes=[[0.001, 0.005]]"]).unwrap();
        assert_eq!(c.mesh.interface.len(), 2);
        assert_eq!(c.rectangle().interfaces[1].tag, "joint");
        let contact = ContactParams {
            friction: 0.25,
            r_c: -1e-6,
            r_s: 0.0,
            s_c: 0.0,
            s_s: 6e5,
        };
        assert_eq!(c.interface[0].law.law(), Law::Contact(contact));
        assert_eq!(c.law_of("crack"), Some(Law::Contact(contact)));
        assert_eq!(c.law_of("joint"), Some(Law::Free));
        assert_eq!(c.law_of("elsewhere"), None);
        assert_eq!(c.output.interface_probes, vec![[0.001, 0.005]]);
        // Array entries are addressed by index in overrides.
        let c = parse(
            &text,
            &["interface.0.r_c=-1e-7", "mesh.interface.1.tag=other"],
        )
        .unwrap();
        let LawConfig::Contact(given) = c.interface[0].law else {
            panic!("{:?}", c.interface[0].law)
        };
        assert_eq!((given.r_c, given.friction), (-1e-7, 0.25));
        assert_eq!(c.mesh.interface[1].tag, "other");
        let e = parse(&text, &["interface.2.law=free"]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("interface"));
        assert!(e.reason.contains("not an index below 2"), "{e}");
    }

    #[test]
    fn a_key_of_another_law_or_a_missing_one_is_named() {
        let text = format!("{BASE}{INTERFACES}");
        let (key, reason) = error(&text, &["interface.0.strength=1e6"]);
        assert_eq!(key, "interface[0].strength");
        assert_eq!(
            reason,
            "is not a parameter of law = \"contact\", which takes friction, r_c, r_s, s_c, s_s"
        );
        let (key, reason) = error(&text, &["interface.1.delay=1e-6"]);
        assert_eq!(key, "interface[1].delay");
        assert!(reason.ends_with("law = \"free\", which takes no parameters"));
        // A key of no law at all reads the same.
        let (key, reason) = error(&text, &["interface.0.colour=1"]);
        assert_eq!(key, "interface[0].colour");
        assert!(reason.contains("not a parameter of law = \"contact\""));
        // The damage law takes the contact keys and its own, not the critical separation.
        let damage = "law = \"damage\"\nstrength = 1e6\ndelay = 1e-6\na = 2.0\nc0 = 0.5\n";
        let damage = text.replacen("law = \"contact\"\n", damage, 1);
        let c = parse(&damage, &["interface.0.beta=0.5"]).unwrap();
        let Some(Law::Damage(d)) = c.law_of("crack") else {
            panic!("{:?}", c.interface[0])
        };
        assert_eq!(
            (d.beta, d.eps, d.initial),
            (0.5, DamageParams::DEFAULT_EPS, 0.0)
        );
        assert_eq!((d.delay, d.contact.s_s), (1e-6, 6e5));
        let (key, _) = error(&damage, &["interface.0.critical_separation=1e-7"]);
        assert_eq!(key, "interface[0].critical_separation");
        for (missing, key) in [
            ("delay = 1e-6\n", "interface[0].delay"),
            ("s_s = 6e5\n", "interface[0].s_s"),
        ] {
            let (k, reason) = error(&damage.replacen(missing, "", 1), &[]);
            assert_eq!(
                (k.as_str(), reason.as_str()),
                (key, "is required with law = \"damage\"")
            );
        }
        let (key, reason) = error(&text.replacen("law = \"free\"\n", "", 1), &[]);
        assert_eq!(
            (key.as_str(), reason.as_str()),
            ("interface[1].law", "is required")
        );
        let (key, reason) = error(&text.replacen("tags = [\"joint\"]\n", "", 1), &[]);
        assert_eq!(
            (key.as_str(), reason.as_str()),
            ("interface[1].tags", "is required")
        );
    }

    #[test]
    fn a_mistyped_entry_or_key_is_named() {
        let text = format!("{BASE}{INTERFACES}");
        let (key, reason) = error(&text, &["interface.0.friction=\"high\""]);
        assert_eq!(key, "interface[0].friction");
        assert_eq!(reason, "must be a number, got \"high\"");
        let (key, reason) = error(&text, &["interface.0.tags=3"]);
        assert_eq!(key, "interface[0].tags");
        assert!(reason.contains("expected a sequence"), "{reason}");
        let (key, reason) = error(&format!("interface = [1]\n{BASE}"), &[]);
        assert_eq!(key, "interface[0]");
        assert!(reason.ends_with("entry), got 1"), "{reason}");
        let (key, _) = error(&format!("interface = 1\n{BASE}"), &[]);
        assert_eq!(key, "interface");
        // An integer is a number.
        assert!(parse(&text, &["interface.0.s_s=600000"]).is_ok());
    }

    /// The keys a law takes are the keys its variant writes, and its required keys suffice.
    #[test]
    fn the_keys_of_each_law_are_its_fields() {
        let contact = ContactConfig {
            friction: 0.0,
            r_c: 0.0,
            r_s: 0.0,
            s_c: 0.0,
            s_s: 0.0,
        };
        let laws = [
            LawConfig::Bonded,
            LawConfig::Free,
            LawConfig::Contact(contact),
            LawConfig::XuNeedleman(CohesiveConfig {
                strength: 1.0,
                critical_separation: 1.0,
                friction: Some(0.0),
                r_c: Some(0.0),
                r_s: Some(0.0),
                s_c: Some(0.0),
                s_s: Some(0.0),
            }),
            LawConfig::Damage(DamageConfig {
                strength: 1.0,
                delay: 1.0,
                a: 1.0,
                c0: 0.5,
                beta: Some(1.0),
                damage_eps: Some(0.1),
                initial_damage: Some(0.0),
                friction: 0.0,
                r_c: 0.0,
                r_s: 0.0,
                s_c: 0.0,
                s_s: 0.0,
            }),
        ];
        for law in laws {
            let name = law.name();
            let written = serde_json::to_value(law).unwrap();
            assert_eq!(written["law"], name.as_str());
            let mut keys: Vec<&str> = written
                .as_object()
                .unwrap()
                .keys()
                .map(|k| &k[..])
                .collect();
            keys.retain(|k| *k != "law");
            let (required, optional) = name.keys();
            let mut expected: Vec<&str> = required.iter().chain(optional).copied().collect();
            keys.sort();
            expected.sort();
            assert_eq!(keys, expected, "{name:?}");
            let only_required: toml::Table = (required.iter())
                .map(|k| (k.to_string(), toml::Value::Float(0.5)))
                .chain([("law".into(), toml::Value::String(name.as_str().into()))])
                .collect();
            let read: LawConfig = toml::Value::Table(only_required).try_into().unwrap();
            assert_eq!(read.name(), name);
        }
    }

    /// The entry writes the keys it was given, as checkpoints compare configurations by them.
    #[test]
    fn an_entry_writes_the_keys_it_was_given() {
        let text = format!("{BASE}{INTERFACES}");
        let cohesive = text.replacen(
            "law = \"contact\"\nfriction = 0.25\nr_c = -1e-6\nr_s = 0.0\ns_c = 0.0\ns_s = 6e5\n",
            "law = \"xu_needleman\"\nstrength = 324e6\ncritical_separation = 4e-7\nr_s = 0.0\n",
            1,
        );
        let c = parse(&cohesive, &[]).unwrap();
        let written = serde_json::to_value(&c.interface).unwrap();
        let expected = serde_json::json!([
            { "tags": ["crack"], "law": "xu_needleman", "strength": 324e6,
              "critical_separation": 4e-7, "r_s": 0.0 },
            { "tags": ["joint"], "law": "free" },
        ]);
        assert_eq!(written, expected);
    }
}
