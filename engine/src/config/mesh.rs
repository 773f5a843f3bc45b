//! `[mesh]`: the space triangulation, the interface segments on a rectangle's grid lines and
//! the parts of its sides tagged apart.

use std::path::PathBuf;

use serde::{Deserialize, Deserializer, Serialize};

/// Where the space mesh comes from.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum MeshKind {
    /// A structured rectangle mesh (`width`, `height`, `nx`, `ny`, ...).
    Rectangle,
    /// A Gmsh MSH 4.1 ASCII file (`path`).
    Gmsh,
}

/// Cell split pattern of a rectangle mesh.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum DiagonalName {
    /// Every cell split along `/`.
    Right,
    /// Every cell split along `\`.
    Left,
    /// Alternating `/` and `\`.
    #[default]
    Alternate,
}

/// `[mesh]`: the space triangulation. Rectangle keys and `path` are exclusive by `kind`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshConfig {
    /// `"rectangle"` or `"gmsh"`.
    pub kind: MeshKind,
    /// Gmsh file, relative to the config file's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// Rectangle extent in x, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    /// Rectangle extent in y, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
    /// Rectangle cells along x.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nx: Option<u32>,
    /// Rectangle cells along y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ny: Option<u32>,
    /// Rectangle cell split pattern (default `"alternate"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diagonal: Option<DiagonalName>,
    /// Random displacement of interior rectangle vertices, fraction of a cell, in [0, 0.25).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub perturb: Option<f64>,
    /// Seed of the perturbation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Interface segments on rectangle grid lines: `[[mesh.interface]]`, or one
    /// `[mesh.interface]` table.
    #[serde(
        default,
        deserialize_with = "one_or_many",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub interface: Vec<SegmentConfig>,
    /// Parts of a rectangle's sides tagged apart (a load on part of a side): `[[mesh.side]]`,
    /// or one `[mesh.side]` table.
    #[serde(
        default,
        deserialize_with = "one_or_many",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub side: Vec<SideConfig>,
}

/// `[[mesh.interface]]`: a straight interior segment on grid lines, tagged as an interface.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SegmentConfig {
    /// One end `[x, y]`, m.
    pub from: [f64; 2],
    /// The other end `[x, y]`, m.
    pub to: [f64; 2],
    /// Tag name (default `"interface"`).
    #[serde(default = "default_interface_tag")]
    pub tag: String,
}

/// `[[mesh.side]]`: a straight segment of a rectangle's side on grid nodes, whose boundary
/// edges get `tag` instead of their side's name.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SideConfig {
    /// One end `[x, y]`, m.
    pub from: [f64; 2],
    /// The other end `[x, y]`, m.
    pub to: [f64; 2],
    /// Tag name, for `[[boundary]]` `sides`.
    pub tag: String,
}

fn default_interface_tag() -> String {
    "interface".into()
}

/// Reads one `[mesh.interface]` (or `[mesh.side]`) table or an array of such tables. Errors
/// keep the key path (`mesh.interface.from`, `mesh.interface[1].from`).
fn one_or_many<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Vec<T>, D::Error> {
    use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
    use serde::de::{MapAccess, SeqAccess, Visitor};

    struct OneOrMany<T>(std::marker::PhantomData<T>);
    impl<'de, T: Deserialize<'de>> Visitor<'de> for OneOrMany<T> {
        type Value = Vec<T>;

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a table or an array of tables")
        }

        fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
            T::deserialize(MapAccessDeserializer::new(map)).map(|s| vec![s])
        }

        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
            Vec::deserialize(SeqAccessDeserializer::new(seq))
        }
    }
    d.deserialize_any(OneOrMany(std::marker::PhantomData))
}

/// The config key of a rectangle generator error: `mesh.nx`, `mesh.interface[k]` for the
/// k-th interface segment, `mesh.side[k]` for the k-th side segment.
pub(crate) fn rectangle_key(e: &sdg_mesh::RectangleError) -> String {
    let field = e.field.replacen("interfaces", "interface", 1);
    format!("mesh.{}", field.replacen("sides", "side", 1))
}
