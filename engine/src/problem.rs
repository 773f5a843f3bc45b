//! Problem setup: the space mesh, material, boundary conditions, interface laws, interface
//! probes and exact solution a configuration describes.

use sdg_mesh::{Mesh, TagId};
use sdg_solver::Material;
use sdg_solver::boundary::{Boundary, Condition};
use sdg_solver::exact::{PlaneWave, Profile, Wave};
use sdg_solver::history::History;
use sdg_solver::interface::{Interfaces, Law};
use sdg_solver::system::System;

use crate::config::{
    BoundaryConfig, BoundaryKind, Config, ConfigError, LoadScales, LoadedConfig, MeshKind,
    ProfileName, WaveName, rectangle_key,
};
use crate::error::EngineError;
use crate::fracture::criteria::Fracture;

/// Everything a run needs that is derived from the configuration.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The validated configuration and its file.
    pub loaded: LoadedConfig,
    /// The space mesh at the initial time.
    pub mesh: Mesh,
    /// The bulk material.
    pub material: Material,
    /// The scaled first-order system of the material.
    pub system: System,
    /// Boundary conditions per tag.
    pub boundary: Boundary,
    /// Interface laws per tag.
    pub interfaces: Interfaces,
    /// `output.interface_probes`, moved to interface edge midpoints.
    pub probes: Vec<Probe>,
    /// The exact solution, if configured.
    pub exact: Option<PlaneWave>,
    /// The scales of `[loading]`, if configured.
    pub loading: Option<Loading>,
    /// Crack propagation, if `[fracture]` is configured.
    pub fracture: Option<Fracture>,
}

/// The mode-I load of `[loading]` on the mesh.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Loading {
    /// Load ratio, amplitude, ramp time and the units of normalized time and length.
    #[serde(flatten)]
    pub scales: LoadScales,
    /// Time at which the waves reach the loaded interface, s: the distance from the loaded
    /// sides' vertices to its edges over `c_d`.
    pub arrival_time: f64,
}

/// A point where an interface is recorded over time: the midpoint of the interface edge of the
/// initial mesh nearest to the configured point.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// The configured point `[x, y]`, m.
    pub requested: [f64; 2],
    /// The interface edge midpoint it was moved to, m.
    pub at: [f64; 2],
    /// The tag of that edge.
    pub tag: String,
}

/// `(key, reason)` of an invalid setting.
type Invalid = (String, String);

impl Problem {
    /// Builds the mesh (generating it or reading the Gmsh file), the material, the boundary
    /// conditions, the interface laws, the probes and the exact solution. Checks that every
    /// `[[boundary]]` side tags boundary edges only, every `[[interface]]` tag interior edges
    /// only, and that every tag on an edge of the mesh is named by one of them.
    pub fn setup(loaded: LoadedConfig) -> Result<Self, EngineError> {
        let config = &loaded.config;
        let file = loaded.file.display().to_string();
        let invalid = |(key, reason): Invalid| ConfigError {
            file: file.clone(),
            key: Some(key),
            reason,
        };
        let material = config.material().map_err(|e| ConfigError {
            file: file.clone(),
            ..e
        })?;
        let mut mesh = match config.mesh.kind {
            MeshKind::Rectangle => config
                .rectangle()
                .build()
                .map_err(|e| invalid((rectangle_key(&e), e.reason)))?,
            MeshKind::Gmsh => {
                let path = config
                    .mesh
                    .path
                    .as_deref()
                    .expect("validated: gmsh has a path");
                sdg_mesh::read_msh(&loaded.resolve(path)).map_err(|source| EngineError::Mesh {
                    config: loaded.file.clone(),
                    source,
                })?
            }
        };
        let exact = config
            .exact
            .as_ref()
            .map(|e| {
                let wave = match e.wave {
                    WaveName::P => Wave::P,
                    WaveName::S => Wave::S,
                };
                let profile = match e.profile {
                    ProfileName::Sine => Profile::Sine,
                    ProfileName::Pulse => Profile::Pulse,
                };
                PlaneWave::new(
                    &material,
                    wave,
                    e.angle_deg,
                    e.wavelength,
                    e.amplitude,
                    profile,
                    e.center,
                )
                .map_err(|err| invalid(("exact".into(), err.to_string())))
            })
            .transpose()?;
        let fracture = config.fracture.as_ref().map(|f| {
            Fracture::new(f, &mut mesh, material.c_r(), |name| {
                config.law_of(name).unwrap_or(Law::Bonded)
            })
        });
        let sites = TagSites::of(&mesh);
        let boundary = conditions(config, &mesh, &sites).map_err(invalid)?;
        let interfaces = laws(config, &mesh, &sites, fracture.as_ref()).map_err(invalid)?;
        all_named(&mesh, &sites, &boundary, &interfaces).map_err(invalid)?;
        let probes = probes(&config.output.interface_probes, &mesh).map_err(invalid)?;
        let loading = config
            .load_scales()
            .map_err(invalid)?
            .map(|scales| Loading {
                scales,
                arrival_time: arrival_distance(config, &mesh) / material.c_d(),
            });
        Ok(Self {
            fracture,
            loading,
            system: System::new(&material),
            boundary: Boundary::new(boundary, exact.clone()),
            interfaces: Interfaces::new(interfaces),
            probes,
            exact,
            loaded,
            mesh,
            material,
        })
    }
}

/// Where the tags of a mesh lie, per tag id: on some boundary edge, on some interior edge.
struct TagSites {
    boundary: Vec<bool>,
    interior: Vec<bool>,
}

impl TagSites {
    fn of(mesh: &Mesh) -> Self {
        let n = mesh.tag_names().len();
        let (mut boundary, mut interior) = (vec![false; n], vec![false; n]);
        for e in mesh.edges() {
            if let Some(t) = e.tag {
                let on = if e.is_boundary() {
                    &mut boundary
                } else {
                    &mut interior
                };
                on[t as usize] = true;
            }
        }
        Self { boundary, interior }
    }

    /// The id of tag `name` when it is on some edge.
    fn find(&self, mesh: &Mesh, name: &str) -> Option<TagId> {
        mesh.tag_id(name)
            .filter(|&t| self.boundary[t as usize] || self.interior[t as usize])
    }

    /// The names of the tags on edges of one kind: `on` is [`Self::boundary`] or
    /// [`Self::interior`].
    fn names<'m>(mesh: &'m Mesh, on: &[bool]) -> Vec<&'m str> {
        mesh.tag_names()
            .iter()
            .zip(on)
            .filter(|&(_, &on)| on)
            .map(|(n, _)| n.as_str())
            .collect()
    }
}

/// The shortest distance from a vertex on a side of `[loading]` to an edge of its interface,
/// m; zero without `[loading]`.
fn arrival_distance(config: &Config, mesh: &Mesh) -> f64 {
    let Some(l) = &config.loading else {
        return 0.0;
    };
    let tagged = |names: &[String]| -> Vec<[[f64; 2]; 2]> {
        let tags: Vec<TagId> = names.iter().filter_map(|n| mesh.tag_id(n)).collect();
        mesh.edges()
            .iter()
            .filter(|e| e.tag.is_some_and(|t| tags.contains(&t)))
            .map(|e| e.vertices.map(|v| mesh.vertex(v)))
            .collect()
    };
    let crack = tagged(std::slice::from_ref(&l.interface));
    let sides = tagged(&l.sides);
    let to_segment = |p: [f64; 2], [a, b]: [[f64; 2]; 2]| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
    };
    sides
        .iter()
        .flatten()
        .flat_map(|&p| crack.iter().map(move |&s| to_segment(p, s)))
        .fold(f64::INFINITY, f64::min)
}

/// The `[[boundary]]` conditions by tag id; each side must tag boundary edges only.
fn conditions(
    config: &Config,
    mesh: &Mesh,
    sites: &TagSites,
) -> Result<Vec<Option<Condition>>, Invalid> {
    let mut by_tag = vec![None; mesh.tag_names().len()];
    for (prefix, b) in config.boundaries() {
        let key = || format!("{prefix}.sides");
        for side in &b.sides {
            let tag = sites.find(mesh, side).ok_or_else(|| {
                let known = TagSites::names(mesh, &sites.boundary);
                (
                    key(),
                    format!("no boundary side is tagged `{side}`; the mesh has {known:?}"),
                )
            })?;
            if sites.interior[tag as usize] {
                return Err((
                    key(),
                    format!(
                        "`{side}` tags interior edges: a boundary side lies on boundary edges \
                         only (interface laws go in [[interface]])"
                    ),
                ));
            }
            by_tag[tag as usize] = Some(condition(&b));
        }
    }
    Ok(by_tag)
}

/// The `[[interface]]` laws by tag id; each tag must tag interior edges only, and be on some
/// edge unless it is the tag of new crack edges.
fn laws(
    config: &Config,
    mesh: &Mesh,
    sites: &TagSites,
    fracture: Option<&Fracture>,
) -> Result<Vec<Option<Law>>, Invalid> {
    let mut by_tag = vec![None; mesh.tag_names().len()];
    for (i, entry) in config.interface.iter().enumerate() {
        let key = || format!("interface[{i}].tags");
        let law = entry.law.law();
        for name in &entry.tags {
            let new_cracks = fracture
                .map(|f| f.tag)
                .filter(|&t| mesh.tag_id(name) == Some(t));
            let tag = sites.find(mesh, name).or(new_cracks).ok_or_else(|| {
                let known = TagSites::names(mesh, &sites.interior);
                (
                    key(),
                    format!(
                        "no interior edge is tagged `{name}`; the mesh's interfaces are {known:?}"
                    ),
                )
            })?;
            if sites.boundary[tag as usize] {
                return Err((
                    key(),
                    format!(
                        "`{name}` tags boundary edges: an interface lies on interior edges only \
                         (boundary conditions go in [[boundary]])"
                    ),
                ));
            }
            by_tag[tag as usize] = Some(law);
        }
    }
    Ok(by_tag)
}

/// Checks that every tag on a boundary edge has a condition and every tag on an interior edge
/// a law.
fn all_named(
    mesh: &Mesh,
    sites: &TagSites,
    conditions: &[Option<Condition>],
    laws: &[Option<Law>],
) -> Result<(), Invalid> {
    for (t, name) in mesh.tag_names().iter().enumerate() {
        if sites.boundary[t] && conditions[t].is_none() {
            return Err((
                "boundary".into(),
                format!(
                    "the mesh's boundary side `{name}` has no [[boundary]] entry \
                     (kind = \"free\" for a traction-free side)"
                ),
            ));
        }
        if sites.interior[t] && laws[t].is_none() {
            return Err((
                "interface".into(),
                format!(
                    "the mesh's interface tag `{name}` has no [[interface]] entry \
                     (law = \"bonded\" for a perfectly bonded one)"
                ),
            ));
        }
    }
    Ok(())
}

/// Each of `points` (m) moved to the nearest midpoint of an interface edge (a tagged interior
/// edge); an error when the mesh has none or none is within the longest edge length.
fn probes(points: &[[f64; 2]], mesh: &Mesh) -> Result<Vec<Probe>, Invalid> {
    let midpoints: Vec<([f64; 2], TagId)> = mesh
        .edges()
        .iter()
        .filter(|e| e.is_interface())
        .map(|e| {
            let [a, b] = e.vertices.map(|v| mesh.vertex(v));
            let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            (mid, e.tag.expect("an interface edge has a tag"))
        })
        .collect();
    let longest = mesh.edge_length_range().1;
    let mut probes = Vec::with_capacity(points.len());
    for (i, &p) in points.iter().enumerate() {
        let key = || format!("output.interface_probes[{i}]");
        let distance = |q: [f64; 2]| (q[0] - p[0]).hypot(q[1] - p[1]);
        let &(at, tag) = midpoints
            .iter()
            .min_by(|a, b| distance(a.0).total_cmp(&distance(b.0)))
            .ok_or_else(|| (key(), "the mesh has no interface edge to probe".to_string()))?;
        let d = distance(at);
        if d > longest {
            return Err((
                key(),
                format!(
                    "{p:?} is {d:e} m from the nearest interface edge midpoint {at:?}, farther \
                     than the longest edge ({longest:e} m)"
                ),
            ));
        }
        probes.push(Probe {
            requested: p,
            at,
            tag: mesh.tag_names()[tag as usize].clone(),
        });
    }
    Ok(probes)
}

/// The solver's condition for a validated `[[boundary]]` entry.
fn condition(b: &BoundaryConfig) -> Condition {
    let pair = |v: &Option<Vec<f64>>| {
        let v = v.as_deref().unwrap_or(&[]);
        [
            v.first().copied().unwrap_or(0.0),
            v.get(1).copied().unwrap_or(0.0),
        ]
    };
    let history = || {
        b.history.as_ref().map_or(History::Constant, |h| {
            h.to_history().expect("validated history")
        })
    };
    match b.kind {
        BoundaryKind::Free => Condition::Free,
        BoundaryKind::Roller => Condition::Roller,
        BoundaryKind::Exact => Condition::Exact,
        BoundaryKind::Traction => Condition::Traction {
            value: pair(&b.value),
            history: history(),
        },
        BoundaryKind::Velocity => Condition::Velocity {
            value: pair(&b.value),
            history: history(),
        },
        BoundaryKind::Transmitting => Condition::Transmitting {
            incoming: pair(&b.incoming),
            history: history(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16 mm x 10 mm rectangle in 1 mm cells, free on every side.
    const PLAIN: &str = r#"
[mesh]
kind = "rectangle"
width = 0.016
height = 0.01
nx = 16
ny = 10

[material]
young = 3.24e9
poisson = 0.35
density = 1190.0
plane = "strain"

[time]
end = 1e-6

[[boundary]]
sides = ["left", "right", "bottom", "top"]
kind = "free"
"#;

    /// A horizontal `crack` in contact and a vertical bonded `joint`.
    const INTERFACES: &str = r#"
[[mesh.interface]]
from = [0.0, 0.005]
to = [0.004, 0.005]
tag = "crack"

[[mesh.interface]]
from = [0.008, 0.0]
to = [0.008, 0.004]
tag = "joint"

[[interface]]
tags = ["crack"]
law = "contact"
friction = 0.25
r_c = -1e-6
r_s = 0.0
s_c = 0.0
s_s = 6e5

[[interface]]
tags = ["joint"]
law = "bonded"
"#;

    fn setup(text: &str, overrides: &[&str]) -> Result<Problem, EngineError> {
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        let config = Config::parse(text, "case.toml", &overrides).expect("valid config");
        Problem::setup(LoadedConfig {
            config,
            file: "case.toml".into(),
            overrides,
        })
    }

    /// The key and reason of a setup error; checks that it names the file.
    fn error(text: &str, overrides: &[&str]) -> (String, String) {
        match setup(text, overrides) {
            Err(EngineError::Config(e)) => {
                assert_eq!(e.file, "case.toml");
                (e.key.unwrap_or_default(), e.reason)
            }
            other => panic!("expected a config error, got {other:?}"),
        }
    }

    #[test]
    fn laws_by_tag_and_probes_on_edge_midpoints() {
        let p = setup(
            &format!("{PLAIN}{INTERFACES}"),
            &["output.interface_probes=[[0.0012, 0.0053], [0.0081, 0.0021]]"],
        )
        .unwrap();
        let tag = |name| p.mesh.tag_id(name);
        assert!(matches!(
            p.interfaces.law(tag("crack")),
            Law::Contact(c) if c.friction == 0.25
        ));
        assert_eq!(p.interfaces.law(tag("joint")), Law::Bonded);
        let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-15;
        assert_eq!(p.probes.len(), 2);
        assert_eq!(p.probes[0].requested, [0.0012, 0.0053]);
        assert!(close(p.probes[0].at, [0.0015, 0.005]), "{:?}", p.probes[0]);
        assert_eq!(p.probes[0].tag, "crack");
        assert!(close(p.probes[1].at, [0.008, 0.0025]), "{:?}", p.probes[1]);
        assert_eq!(p.probes[1].tag, "joint");
        assert!(setup(PLAIN, &[]).unwrap().probes.is_empty());
    }

    #[test]
    fn every_tag_is_named_on_the_right_kind_of_edge() {
        let text = format!("{PLAIN}{INTERFACES}");
        for (set, key, words) in [
            (
                r#"interface.1.tags=["joint", "top"]"#,
                "interface[1].tags",
                "`top` tags boundary edges",
            ),
            (
                r#"interface.1.tags=["seam"]"#,
                "interface[1].tags",
                "no interior edge is tagged `seam`",
            ),
            (
                r#"boundary.0.sides=["left", "right", "bottom", "top", "joint"]"#,
                "boundary[0].sides",
                "`joint` tags interior edges",
            ),
            (
                r#"boundary.0.sides=["left", "right", "bottom", "top", "seam"]"#,
                "boundary[0].sides",
                "no boundary side is tagged `seam`",
            ),
            (
                r#"boundary.0.sides=["left", "right", "bottom"]"#,
                "boundary",
                "`top` has no [[boundary]] entry",
            ),
            (
                r#"interface=[{ tags = ["crack"], law = "bonded" }]"#,
                "interface",
                "`joint` has no [[interface]] entry",
            ),
            (
                "output.interface_probes=[[0.012, 0.009]]",
                "output.interface_probes[0]",
                "farther than the longest edge",
            ),
        ] {
            let (k, reason) = error(&text, &[set]);
            assert_eq!(k, key, "{set}: {reason}");
            assert!(reason.contains(words), "{set}: {reason}");
        }
        let (k, reason) = error(PLAIN, &["output.interface_probes=[[0.001, 0.005]]"]);
        assert_eq!(k, "output.interface_probes[0]");
        assert!(reason.contains("no interface edge"), "{reason}");
    }
}
