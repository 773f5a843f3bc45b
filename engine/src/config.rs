//! The TOML run configuration: schema, command-line overrides and load-time validation.
//!
//! Every key is documented in `docs/config.md`. Units are SI. Unknown keys, wrong types and
//! unphysical values are rejected with an error naming the file and the key.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

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
    /// Boundary conditions, one entry per group of sides (`[[boundary]]`). Sides without an
    /// entry are traction-free.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub boundary: Vec<BoundaryConfig>,
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

/// `[solver]`: discretization.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SolverConfig {
    /// Complete polynomial order on each spacetime tetrahedron, 1 to 4. Default 2.
    #[serde(default = "default_order")]
    pub order: usize,
}

fn default_order() -> usize {
    2
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            order: default_order(),
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
    /// `[t (s), multiplier]` pairs with increasing `t` (table).
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
    /// An interface segment on rectangle grid lines.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interface: Option<InterfaceConfig>,
}

/// `[mesh.interface]`: a straight interior segment on grid lines, tagged as an interface.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InterfaceConfig {
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
        let mut table: toml::Table = toml::from_str(text).map_err(|e| ConfigError {
            file: source.to_string(),
            key: None,
            reason: format!("invalid TOML: {}", e.message())
                .trim_end()
                .to_string()
                + &line_of(text, e.span()),
        })?;
        for spec in overrides {
            apply_override(&mut table, spec)?;
        }
        let config: Config =
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
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
            ("mesh.interface", m.interface.is_some()),
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
                    .or_else(|e| fail(&format!("mesh.{}", e.field), e.reason))?;
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

    /// Checks `[solver]`, `[[boundary]]`, `[exact]` and `output.snapshot_times`.
    fn validate_physics(&self) -> Result<(), (String, String)> {
        let order = self.solver.order;
        if !(1..=4).contains(&order) {
            return Err((
                "solver.order".into(),
                format!("must be 1 to 4, got {order}"),
            ));
        }
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
            interface: m.interface.as_ref().map(|i| sdg_mesh::GridSegment {
                from: i.from,
                to: i.to,
                tag: i.tag.clone(),
            }),
            perturb: m.perturb.unwrap_or(0.0),
            seed: m.seed.unwrap_or(0),
        }
    }
}

/// ` (line N)` for a TOML error span, or nothing.
fn line_of(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    span.map(|s| {
        let line = text[..s.start.min(text.len())].matches('\n').count() + 1;
        format!(" (line {line})")
    })
    .unwrap_or_default()
}

/// Applies one `key.path=value` override. The value is read as a TOML value (`3`, `1e-6`,
/// `true`, `"text"`, `[0.0, 1.0]`), or as a string when it is not one; the schema then checks
/// its type like any other key.
fn apply_override(table: &mut toml::Table, spec: &str) -> Result<(), ConfigError> {
    let source = format!("--set {spec}");
    let err = |key: Option<String>, reason: &str| ConfigError {
        file: source.clone(),
        key,
        reason: reason.to_string(),
    };
    let (path, raw) = spec
        .split_once('=')
        .ok_or_else(|| err(None, "expected KEY=VALUE"))?;
    let path = path.trim();
    let keys: Vec<&str> = path.split('.').collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(err(None, "the key path has an empty segment"));
    }
    let value = toml::from_str::<toml::Table>(&format!("v = {raw}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(raw.to_string()));
    let (last, parents) = keys.split_last().expect("split yields at least one key");
    let mut node = table;
    for (i, key) in parents.iter().enumerate() {
        let entry = node
            .entry(key.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        node = entry
            .as_table_mut()
            .ok_or_else(|| err(Some(keys[..=i].join(".")), "is a value, not a table"))?;
    }
    node.insert(last.to_string(), value);
    Ok(())
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
            HistoryKind::Table => {
                let points = self
                    .points
                    .as_ref()
                    .ok_or_else(|| ("points".to_string(), "is required for a table".to_string()))?;
                History::Table(points.iter().map(|p| (p[0], p[1])).collect())
            }
        };
        let key = if self.kind == HistoryKind::Table {
            "points"
        } else {
            "ramp"
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
        assert_eq!(c.mesh.interface.unwrap().tag, "interface");
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
