//! The TOML run configuration: schema, command-line overrides and load-time validation.
//!
//! Every key is documented in `docs/config.md`. Units are SI. Unknown keys, wrong types and
//! unphysical values are rejected with an error naming the file and the key.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Deserializer, Serialize};

use sdg_solver::interface::{ContactParams, Law};
use sdg_solver::{Material, Plane};

/// A configuration error: where it came from, which key, and why.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{file}: {}{reason}", key.as_ref().map(|k| format!("{k}: ")).unwrap_or_default())]
pub struct ConfigError {
    /// The config file, or `--set KEY=VALUE` for an override.
    pub file: String,
    /// Dotted key path, when the error belongs to one key.
    pub key: Option<String>,
    /// What is wrong.
    pub reason: String,
}

/// The complete configuration of a run.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The space mesh at the initial time.
    pub mesh: MeshConfig,
    /// The bulk material.
    pub material: MaterialConfig,
    /// Time span.
    pub time: TimeConfig,
    /// Tent pitching.
    #[serde(default)]
    pub pitch: PitchConfig,
    /// Outputs.
    #[serde(default)]
    pub output: OutputConfig,
    /// The patch solver.
    #[serde(default)]
    pub solver: SolverConfig,
    /// Parallel execution.
    #[serde(default)]
    pub scheduler: SchedulerConfig,
    /// Adaptive refinement of the front.
    #[serde(default)]
    pub adapt: AdaptConfig,
    /// Boundary conditions, one entry per group of sides (`[[boundary]]`). Every boundary tag
    /// of the mesh must be named by one entry.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub boundary: Vec<BoundaryConfig>,
    /// Interface laws, one entry per group of interface tags (`[[interface]]`). Every interface
    /// tag of the mesh must be named by one entry.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub interface: Vec<InterfaceConfig>,
    /// An exact solution: initial data, `exact` boundaries and the error at the end time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exact: Option<ExactConfig>,
}

/// `[scheduler]`: parallel execution.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SchedulerConfig {
    /// Results depend only on the config, never on thread count or timing (rounds of independent
    /// tents instead of asynchronous claiming). Default false.
    #[serde(default)]
    pub deterministic: bool,
}

/// `[adapt]`: error-driven refinement of the front (see `docs/method.md`, "Adaptivity").
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AdaptConfig {
    /// Refine where patches are too dissipative. Default false.
    #[serde(default)]
    pub enabled: bool,
    /// Upper tolerance of the dissipation indicator: a patch above it is rejected and the front
    /// around its vertex refined. Dimensionless, see `docs/method.md`. Default 1e-3.
    #[serde(default = "default_tol")]
    pub tol: f64,
    /// Lower tolerance = `tol / coarsen_ratio`: elements accepted below it may be coarsened
    /// again. Must exceed 1. Default 16.
    #[serde(default = "default_coarsen_ratio")]
    pub coarsen_ratio: f64,
    /// No edge is split into halves shorter than this, m. Default: no limit below 1/1000 of the
    /// initial shortest edge.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_edge: Option<f64>,
    /// Edges longer than this, m, are split before the first tent. Default: no limit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_edge: Option<f64>,
}

fn default_tol() -> f64 {
    1e-3
}

fn default_coarsen_ratio() -> f64 {
    16.0
}

impl Default for AdaptConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            tol: default_tol(),
            coarsen_ratio: default_coarsen_ratio(),
            min_edge: None,
            max_edge: None,
        }
    }
}

/// `[solver]`: discretization and the Newton iterations of patches with contact faces.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SolverConfig {
    /// Complete polynomial order on each spacetime tetrahedron, 1 to 4. Default 2.
    #[serde(default = "default_order")]
    pub order: usize,
    /// Newton converges when the patch residual relative to the right-hand side is at most this,
    /// in (0, 1) (dimensionless). Default 1e-10.
    #[serde(default = "default_newton_tol")]
    pub newton_tol: f64,
    /// Newton iterations allowed per patch, at least 1. Default 30.
    #[serde(default = "default_newton_max_iter")]
    pub newton_max_iter: usize,
}

fn default_order() -> usize {
    2
}

fn default_newton_tol() -> f64 {
    1e-10
}

fn default_newton_max_iter() -> usize {
    30
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            order: default_order(),
            newton_tol: default_newton_tol(),
            newton_max_iter: default_newton_max_iter(),
        }
    }
}

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
#[serde(rename_all = "lowercase")]
pub enum LawName {
    /// Perfectly bonded.
    Bonded,
    /// Both faces traction-free.
    Free,
    /// Unilateral contact with Coulomb friction (in-plane modes only).
    Contact,
}

/// `[[interface]]`: one law on one or more interface tags. The contact parameters (seed 3.2.1,
/// 3.3.1) are required with `law = "contact"` and rejected otherwise.
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
}

impl InterfaceConfig {
    /// The law, or `(key, reason)` for a missing, extra or invalid contact parameter.
    pub fn to_law(&self) -> Result<Law, (String, String)> {
        let params = [
            ("friction", self.friction),
            ("r_c", self.r_c),
            ("r_s", self.r_s),
            ("s_c", self.s_c),
            ("s_s", self.s_s),
        ];
        if self.law != LawName::Contact {
            return match params.iter().find(|(_, v)| v.is_some()) {
                Some((key, _)) => Err((
                    key.to_string(),
                    "is only used with law = \"contact\"".into(),
                )),
                None if self.law == LawName::Bonded => Ok(Law::Bonded),
                None => Ok(Law::Free),
            };
        }
        let [friction, r_c, r_s, s_c, s_s] = params.map(|(key, v)| {
            v.ok_or_else(|| (key.to_string(), "is required with law = \"contact\"".into()))
        });
        let params = ContactParams {
            friction: friction?,
            r_c: r_c?,
            r_s: r_s?,
            s_c: s_c?,
            s_s: s_s?,
        };
        params
            .validate()
            .map_err(|e| (e.key.to_string(), e.reason))?;
        Ok(Law::Contact(params))
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

fn default_interface_tag() -> String {
    "interface".into()
}

/// Reads one `[mesh.interface]` table or an `[[mesh.interface]]` array of tables. Errors keep
/// the key path (`mesh.interface.from`, `mesh.interface[1].from`).
fn one_or_many<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<SegmentConfig>, D::Error> {
    use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
    use serde::de::{MapAccess, SeqAccess, Visitor};

    struct OneOrMany;
    impl<'de> Visitor<'de> for OneOrMany {
        type Value = Vec<SegmentConfig>;

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a table or an array of tables")
        }

        fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
            SegmentConfig::deserialize(MapAccessDeserializer::new(map)).map(|s| vec![s])
        }

        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
            Vec::deserialize(SeqAccessDeserializer::new(seq))
        }
    }
    d.deserialize_any(OneOrMany)
}

/// The 2D mode of elasticity.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum PlaneName {
    /// Plane strain.
    Strain,
    /// Plane stress.
    Stress,
    /// Anti-plane shear.
    Antiplane,
}

/// `[material]`: an isotropic linear elastic material.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    /// Young's modulus, Pa.
    pub young: f64,
    /// Poisson ratio, in (-1, 0.5).
    pub poisson: f64,
    /// Mass density, kg/m^3.
    pub density: f64,
    /// `"strain"`, `"stress"` or `"antiplane"`.
    pub plane: PlaneName,
}

/// `[time]`: the simulated span, starting at 0.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeConfig {
    /// End time, s.
    pub end: f64,
}

/// `[pitch]`: tent pitching.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PitchConfig {
    /// Every front facet keeps `c_max |grad tau| < safety`, in (0, 1). Default 0.9.
    #[serde(default = "default_safety")]
    pub safety: f64,
}

fn default_safety() -> f64 {
    0.9
}

impl Default for PitchConfig {
    fn default() -> Self {
        Self {
            safety: default_safety(),
        }
    }
}

/// `[output]`: what is written where.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Output folder, relative to the working directory. Default `out`.
    #[serde(default = "default_output_dir")]
    pub dir: PathBuf,
    /// Write the spacetime mesh as `spacetime.vtu` (small runs only). Default false.
    #[serde(default)]
    pub spacetime_mesh: bool,
    /// Times (s) of solution snapshots (`snapshot_NNNN.vtu` and `snapshots.pvd`). Default none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub snapshot_times: Vec<f64>,
    /// Points `[x, y]` (m) near interface edges, each moved to the nearest interface edge
    /// midpoint of the initial mesh, where the interface is recorded over time. Default none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub interface_probes: Vec<[f64; 2]>,
}

fn default_output_dir() -> PathBuf {
    PathBuf::from("out")
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self {
            dir: default_output_dir(),
            spacetime_mesh: false,
            snapshot_times: Vec::new(),
            interface_probes: Vec::new(),
        }
    }
}

/// A loaded, validated configuration and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedConfig {
    /// The validated configuration with overrides applied.
    pub config: Config,
    /// The config file.
    pub file: PathBuf,
}

impl LoadedConfig {
    /// Reads `file`, applies `overrides` (`key.path=value`, in order) and validates.
    pub fn load(file: &Path, overrides: &[String]) -> Result<Self, ConfigError> {
        let source = file.display().to_string();
        let text = std::fs::read_to_string(file).map_err(|e| ConfigError {
            file: source.clone(),
            key: None,
            reason: format!("cannot read: {e}"),
        })?;
        let config = Config::parse(&text, &source, overrides)?;
        Ok(Self {
            config,
            file: file.to_path_buf(),
        })
    }

    /// Resolves a path given in the config relative to the config file's folder.
    pub fn resolve(&self, path: &Path) -> PathBuf {
        match self.file.parent() {
            Some(dir) if path.is_relative() => dir.join(path),
            _ => path.to_path_buf(),
        }
    }
}

impl Config {
    /// Parses TOML `text` (named `source` in errors), applies `overrides` and validates.
    pub fn parse(text: &str, source: &str, overrides: &[String]) -> Result<Self, ConfigError> {
        let table: toml::Table = toml::from_str(text).map_err(|e| ConfigError {
            file: source.to_string(),
            key: None,
            reason: format!("invalid TOML: {}", e.message())
                .trim_end()
                .to_string()
                + &line_of(text, e.span()),
        })?;
        let mut root = toml::Value::Table(table);
        for spec in overrides {
            apply_override(&mut root, spec)?;
        }
        let config: Config = serde_path_to_error::deserialize(root).map_err(|e| {
            let path = e.path().to_string();
            ConfigError {
                file: source.to_string(),
                key: (path != ".").then_some(path),
                reason: e.into_inner().message().to_string(),
            }
        })?;
        config.validate().map_err(|(key, reason)| ConfigError {
            file: source.to_string(),
            key: Some(key),
            reason,
        })?;
        Ok(config)
    }

    /// The material, validated.
    pub fn material(&self) -> Result<Material, ConfigError> {
        let m = &self.material;
        let plane = match m.plane {
            PlaneName::Strain => Plane::Strain,
            PlaneName::Stress => Plane::Stress,
            PlaneName::Antiplane => Plane::Antiplane,
        };
        Material::new(m.young, m.poisson, m.density, plane).map_err(|e| ConfigError {
            file: String::new(),
            key: Some(format!("material.{}", e.field())),
            reason: e
                .to_string()
                .split_once(": ")
                .map_or(e.to_string(), |(_, r)| r.to_string()),
        })
    }

    /// Checks values that the schema's types cannot: returns `(key, reason)`.
    fn validate(&self) -> Result<(), (String, String)> {
        let fail = |key: &str, reason: String| Err((key.to_string(), reason));
        self.material()
            .map_err(|e| (e.key.unwrap_or_default(), e.reason))?;
        let end = self.time.end;
        if !(end.is_finite() && end > 0.0) {
            return fail(
                "time.end",
                format!("must be a positive time in s, got {end}"),
            );
        }
        let safety = self.pitch.safety;
        if !(safety > 0.0 && safety < 1.0) {
            return fail(
                "pitch.safety",
                format!(
                    "must be in (0, 1): a front facet at or above 1 is not causal, got {safety}"
                ),
            );
        }
        self.validate_physics()?;
        self.validate_adapt()?;
        let m = &self.mesh;
        let rectangle_keys = [
            ("mesh.width", m.width.is_some()),
            ("mesh.height", m.height.is_some()),
            ("mesh.nx", m.nx.is_some()),
            ("mesh.ny", m.ny.is_some()),
            ("mesh.diagonal", m.diagonal.is_some()),
            ("mesh.perturb", m.perturb.is_some()),
            ("mesh.seed", m.seed.is_some()),
            ("mesh.interface", !m.interface.is_empty()),
        ];
        match m.kind {
            MeshKind::Rectangle => {
                if m.path.is_some() {
                    return fail("mesh.path", "is only used with mesh.kind = \"gmsh\"".into());
                }
                for key in ["mesh.width", "mesh.height", "mesh.nx", "mesh.ny"] {
                    if !rectangle_keys.iter().any(|&(k, set)| k == key && set) {
                        return fail(key, "is required with mesh.kind = \"rectangle\"".into());
                    }
                }
                self.rectangle()
                    .build()
                    .map(drop)
                    .or_else(|e| fail(&rectangle_key(&e), e.reason))?;
            }
            MeshKind::Gmsh => {
                if m.path.is_none() {
                    return fail("mesh.path", "is required with mesh.kind = \"gmsh\"".into());
                }
                if let Some((key, _)) = rectangle_keys.iter().find(|(_, set)| *set) {
                    return fail(key, "is only used with mesh.kind = \"rectangle\"".into());
                }
            }
        }
        Ok(())
    }

    /// Checks `[adapt]`.
    fn validate_adapt(&self) -> Result<(), (String, String)> {
        let a = &self.adapt;
        let fail = |key: &str, reason: String| Err((format!("adapt.{key}"), reason));
        if !(a.tol.is_finite() && a.tol > 0.0) {
            return fail("tol", format!("must be a positive number, got {}", a.tol));
        }
        if !(a.coarsen_ratio.is_finite() && a.coarsen_ratio > 1.0) {
            return fail(
                "coarsen_ratio",
                format!(
                    "must be a finite number above 1 (the lower tolerance is tol / ratio), got {}",
                    a.coarsen_ratio
                ),
            );
        }
        for (key, value) in [("min_edge", a.min_edge), ("max_edge", a.max_edge)] {
            if let Some(v) = value {
                if !(v.is_finite() && v > 0.0) {
                    return fail(key, format!("must be a positive length in m, got {v}"));
                }
            }
        }
        if let (Some(lo), Some(hi)) = (a.min_edge, a.max_edge) {
            if 2.0 * lo > hi {
                return fail(
                    "max_edge",
                    format!("must be at least twice adapt.min_edge ({lo} m), got {hi} m"),
                );
            }
        }
        Ok(())
    }

    /// Checks `[solver]`, `[[boundary]]`, `[[interface]]`, `[exact]` and `[output]` times and
    /// points.
    fn validate_physics(&self) -> Result<(), (String, String)> {
        let order = self.solver.order;
        if !(1..=4).contains(&order) {
            return Err((
                "solver.order".into(),
                format!("must be 1 to 4, got {order}"),
            ));
        }
        let tol = self.solver.newton_tol;
        if !(tol > 0.0 && tol < 1.0) {
            return Err((
                "solver.newton_tol".into(),
                format!("must be in (0, 1) (a relative residual), got {tol}"),
            ));
        }
        if self.solver.newton_max_iter == 0 {
            return Err(("solver.newton_max_iter".into(), "must be at least 1".into()));
        }
        self.validate_interfaces()?;
        let antiplane = self.material.plane == PlaneName::Antiplane;
        let components = if antiplane { 1 } else { 2 };
        let mut seen: Vec<&str> = Vec::new();
        for (i, b) in self.boundary.iter().enumerate() {
            let key = |k: &str| format!("boundary[{i}].{k}");
            if b.sides.is_empty() {
                return Err((key("sides"), "lists no side".into()));
            }
            for side in &b.sides {
                if seen.contains(&side.as_str()) {
                    return Err((
                        key("sides"),
                        format!("side `{side}` has a condition already"),
                    ));
                }
                seen.push(side);
            }
            let needs_value = matches!(b.kind, BoundaryKind::Traction | BoundaryKind::Velocity);
            let takes_history = needs_value || b.kind == BoundaryKind::Transmitting;
            match (&b.value, needs_value) {
                (None, true) => return Err((key("value"), "is required for this kind".into())),
                (Some(_), false) => {
                    return Err((key("value"), "is only used by traction and velocity".into()));
                }
                _ => {}
            }
            if b.incoming.is_some() && b.kind != BoundaryKind::Transmitting {
                return Err((key("incoming"), "is only used by transmitting".into()));
            }
            for (name, v) in [("value", &b.value), ("incoming", &b.incoming)] {
                if let Some(v) = v {
                    if v.len() != components || v.iter().any(|x| !x.is_finite()) {
                        let want = if antiplane {
                            "[z] in anti-plane"
                        } else {
                            "[x, y] (or [normal, tangential])"
                        };
                        return Err((
                            key(name),
                            format!("must be {components} finite numbers: {want}"),
                        ));
                    }
                }
            }
            if let Some(h) = &b.history {
                if !takes_history {
                    return Err((
                        key("history"),
                        "is only used by traction, velocity and transmitting".into(),
                    ));
                }
                h.to_history()
                    .map_err(|(k, r)| (key(&format!("history.{k}")), r))?;
            }
            if b.kind == BoundaryKind::Exact && self.exact.is_none() {
                return Err((key("kind"), "\"exact\" needs an [exact] section".into()));
            }
        }
        if let Some(e) = &self.exact {
            if e.wave == WaveName::P && antiplane {
                return Err((
                    "exact.wave".into(),
                    "anti-plane shear carries S waves only".into(),
                ));
            }
            if !(e.wavelength > 0.0 && e.wavelength.is_finite()) {
                return Err((
                    "exact.wavelength".into(),
                    format!("must be a positive length in m, got {}", e.wavelength),
                ));
            }
            for (k, v) in [
                ("angle_deg", e.angle_deg),
                ("amplitude", e.amplitude),
                ("center", e.center),
            ] {
                if !v.is_finite() {
                    return Err((format!("exact.{k}"), "must be finite".into()));
                }
            }
        }
        if let Some(t) = self
            .output
            .snapshot_times
            .iter()
            .find(|t| !(0.0..=self.time.end).contains(*t))
        {
            return Err((
                "output.snapshot_times".into(),
                format!("{t} s is outside [0, time.end]"),
            ));
        }
        if let Some(i) = self
            .output
            .interface_probes
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err((
                format!("output.interface_probes[{i}]"),
                "must be a point [x, y] of finite coordinates in m".into(),
            ));
        }
        Ok(())
    }

    /// Checks `[[interface]]`: tags named once, laws and their parameters.
    fn validate_interfaces(&self) -> Result<(), (String, String)> {
        let mut seen: Vec<&str> = Vec::new();
        for (i, entry) in self.interface.iter().enumerate() {
            let key = |k: &str| format!("interface[{i}].{k}");
            if entry.tags.is_empty() {
                return Err((key("tags"), "lists no tag".into()));
            }
            for tag in &entry.tags {
                if seen.contains(&tag.as_str()) {
                    return Err((key("tags"), format!("tag `{tag}` has a law already")));
                }
                seen.push(tag);
            }
            if entry.law == LawName::Contact && self.material.plane == PlaneName::Antiplane {
                return Err((
                    key("law"),
                    "\"contact\" needs a normal direction, which anti-plane shear \
                     (material.plane = \"antiplane\") has not; use \"bonded\" or \"free\""
                        .into(),
                ));
            }
            entry.to_law().map_err(|(k, r)| (key(&k), r))?;
        }
        Ok(())
    }

    /// The rectangle generator's parameters; missing keys read as zero (validation rejects them).
    pub fn rectangle(&self) -> sdg_mesh::Rectangle {
        let m = &self.mesh;
        sdg_mesh::Rectangle {
            width: m.width.unwrap_or(0.0),
            height: m.height.unwrap_or(0.0),
            nx: m.nx.unwrap_or(0),
            ny: m.ny.unwrap_or(0),
            diagonal: match m.diagonal.unwrap_or_default() {
                DiagonalName::Right => sdg_mesh::Diagonal::Right,
                DiagonalName::Left => sdg_mesh::Diagonal::Left,
                DiagonalName::Alternate => sdg_mesh::Diagonal::Alternate,
            },
            interfaces: m
                .interface
                .iter()
                .map(|i| sdg_mesh::GridSegment {
                    from: i.from,
                    to: i.to,
                    tag: i.tag.clone(),
                })
                .collect(),
            perturb: m.perturb.unwrap_or(0.0),
            seed: m.seed.unwrap_or(0),
        }
    }
}

/// The config key of a rectangle generator error: `mesh.nx`, or `mesh.interface[k]` for the
/// k-th interface segment.
pub(crate) fn rectangle_key(e: &sdg_mesh::RectangleError) -> String {
    format!("mesh.{}", e.field.replacen("interfaces", "interface", 1))
}

/// ` (line N)` for a TOML error span, or nothing.
fn line_of(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    span.map(|s| {
        let line = text[..s.start.min(text.len())].matches('\n').count() + 1;
        format!(" (line {line})")
    })
    .unwrap_or_default()
}

/// Applies one `key.path=value` override to the config's `root` table. The value is read as a
/// TOML value (`3`, `1e-6`, `true`, `"text"`, `[0.0, 1.0]`), or as a string when it is not one;
/// the schema then checks its type like any other key. A number in the path selects an entry
/// of an array of tables: `interface.0.r_c`.
fn apply_override(root: &mut toml::Value, spec: &str) -> Result<(), ConfigError> {
    let source = format!("--set {spec}");
    let err = |key: &[&str], reason: String| ConfigError {
        file: source.clone(),
        key: (!key.is_empty()).then(|| key.join(".")),
        reason,
    };
    let (path, raw) = spec
        .split_once('=')
        .ok_or_else(|| err(&[], "expected KEY=VALUE".into()))?;
    let path = path.trim();
    let keys: Vec<&str> = path.split('.').collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(err(&[], "the key path has an empty segment".into()));
    }
    let value = toml::from_str::<toml::Table>(&format!("v = {raw}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(raw.to_string()));
    let mut node = root;
    for (i, key) in keys.iter().enumerate() {
        node = entry(node, key).map_err(|reason| err(&keys[..i], reason))?;
    }
    *node = value;
    Ok(())
}

/// The entry `key` of a table (a new empty table when missing) or of an array (`key` an index
/// below its length), or why `node` has none.
fn entry<'a>(node: &'a mut toml::Value, key: &str) -> Result<&'a mut toml::Value, String> {
    match node {
        toml::Value::Table(table) => Ok(table
            .entry(key.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))),
        toml::Value::Array(array) => {
            let len = array.len();
            key.parse::<usize>()
                .ok()
                .and_then(|k| array.get_mut(k))
                .ok_or_else(|| {
                    format!("is a list of {len} entries; `{key}` is not an index below {len}")
                })
        }
        _ => Err("is a value, not a table".into()),
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
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
"#;

    fn parse(text: &str, overrides: &[&str]) -> Result<Config, ConfigError> {
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Config::parse(text, "test.toml", &o)
    }

    fn key_of(text: &str, overrides: &[&str]) -> Option<String> {
        parse(text, overrides).unwrap_err().key
    }

    #[test]
    fn defaults_and_overrides() {
        let c = parse(BASE, &[]).unwrap();
        assert_eq!(c.pitch.safety, 0.9);
        assert_eq!(c.output.dir, PathBuf::from("out"));
        let c = parse(
            BASE,
            &[
                "mesh.nx=32",
                "pitch.safety=0.5",
                "output.dir=runs/a",
                "mesh.diagonal=right",
            ],
        )
        .unwrap();
        assert_eq!(c.mesh.nx, Some(32));
        assert_eq!(c.pitch.safety, 0.5);
        assert_eq!(c.output.dir, PathBuf::from("runs/a"));
        assert_eq!(c.mesh.diagonal, Some(DiagonalName::Right));
        let c = parse(
            BASE,
            &[
                "mesh.interface.from=[0.0, 0.005]",
                "mesh.interface.to=[0.002, 0.005]",
            ],
        )
        .unwrap();
        assert_eq!(c.mesh.interface.len(), 1);
        assert_eq!(c.mesh.interface[0].tag, "interface");
        assert_eq!(c.solver.newton_tol, 1e-10);
        assert_eq!(c.solver.newton_max_iter, 30);
        assert!(c.interface.is_empty() && c.output.interface_probes.is_empty());
    }

    /// Two interface segments and a contact law on one of them.
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
law = "free"
"#;

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
    fn bad_interface_settings_name_the_key() {
        let text = format!("{BASE}{INTERFACES}");
        let error = |overrides: &[&str]| {
            let e = parse(&text, overrides).unwrap_err();
            (e.key.unwrap_or_default(), e.reason)
        };
        for (set, key, words) in [
            ("interface.0.friction=-0.1", "interface[0].friction", ">= 0"),
            ("interface.0.r_c=1e-6", "interface[0].r_c", "<= 0"),
            ("interface.0.r_s=-2e-6", "interface[0].r_s", ">= r_c"),
            ("interface.0.s_c=7e5", "interface[0].s_s", ">= s_c"),
            (
                "interface.0.law=glued",
                "interface[0].law",
                "unknown variant `glued`",
            ),
            (
                "interface.1.r_c=0.0",
                "interface[1].r_c",
                "only used with law = \"contact\"",
            ),
            (
                "interface.1.tags=[\"crack\"]",
                "interface[1].tags",
                "has a law already",
            ),
            ("interface.1.tags=[]", "interface[1].tags", "lists no tag"),
            ("material.plane=antiplane", "interface[0].law", "anti-plane"),
            ("solver.newton_tol=0.0", "solver.newton_tol", "(0, 1)"),
            ("solver.newton_tol=1.5", "solver.newton_tol", "(0, 1)"),
            (
                "solver.newton_max_iter=0",
                "solver.newton_max_iter",
                "at least 1",
            ),
            (
                "output.interface_probes=[[nan, 0.0]]",
                "output.interface_probes[0]",
                "finite",
            ),
            (
                "mesh.interface.1.from=[0.008, 0.0001]",
                "mesh.interface[1]",
                "grid node",
            ),
        ] {
            let (k, reason) = error(&[set]);
            assert_eq!(k, key, "{set}");
            assert!(reason.contains(words), "{set}: {reason}");
        }
        let missing = parse(&text.replace("s_s = 6e5\n", ""), &[]).unwrap_err();
        assert_eq!(missing.key.as_deref(), Some("interface[0].s_s"));
        assert!(missing.reason.contains("required with law = \"contact\""));
        let typo = parse(&text.replace("to = [0.008", "too = [0.008"), &[]).unwrap_err();
        assert_eq!(typo.key.as_deref(), Some("mesh.interface[1].too"));
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

    #[test]
    fn errors_name_the_key() {
        assert_eq!(key_of(BASE, &["mesh.nx=abc"]).as_deref(), Some("mesh.nx"));
        assert_eq!(key_of(BASE, &["mesh.nx=1.5"]).as_deref(), Some("mesh.nx"));
        assert_eq!(
            key_of(BASE, &["material.density=-1"]).as_deref(),
            Some("material.density")
        );
        assert_eq!(
            key_of(BASE, &["material.poisson=0.5"]).as_deref(),
            Some("material.poisson")
        );
        assert_eq!(
            key_of(BASE, &["pitch.safety=1.0"]).as_deref(),
            Some("pitch.safety")
        );
        assert_eq!(key_of(BASE, &["time.end=0"]).as_deref(), Some("time.end"));
        assert_eq!(
            key_of(BASE, &["mesh.path=a.msh"]).as_deref(),
            Some("mesh.path")
        );
        assert_eq!(
            key_of(BASE, &["mesh.kind=gmsh", "mesh.path=a.msh"]).as_deref(),
            Some("mesh.width")
        );
        assert_eq!(
            key_of(BASE, &["mesh.perturb=0.3"]).as_deref(),
            Some("mesh.perturb")
        );
        assert_eq!(
            key_of(BASE, &["mesh.kind=tetra"]).as_deref(),
            Some("mesh.kind")
        );
        let unknown = parse(BASE, &["material.colour=1"]).unwrap_err();
        assert!(unknown.reason.contains("colour"), "{unknown}");
        let missing = parse(&BASE.replace("nx = 16\n", ""), &[]).unwrap_err();
        assert_eq!(missing.key.as_deref(), Some("mesh.nx"));
        let e = parse(BASE, &["mesh.nx.deep=1"]).unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.key.as_deref()),
            ("--set mesh.nx.deep=1", Some("mesh.nx"))
        );
        assert!(
            parse(BASE, &["novalue"])
                .unwrap_err()
                .reason
                .contains("KEY=VALUE")
        );
    }

    #[test]
    fn syntax_errors_give_the_line() {
        let e = parse(&format!("{BASE}\n[time\n"), &[]).unwrap_err();
        assert!(e.reason.contains("line 18"), "{e}");
        assert_eq!(e.to_string().split(':').next(), Some("test.toml"));
    }
}
