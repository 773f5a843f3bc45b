//! The run settings: time span, tent pitching, outputs, patch solver, scheduler and adaptivity.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// `[time]`: the simulated span, from `start` to `end`.
///
/// `start` only names the instant the run starts at: the initial front is flat there, and every
/// time a config gives (`end`, `output.snapshot_times`) or a run writes (CSV files, snapshots,
/// `summary.json`, messages) is on this clock. Everything that varies in time (boundary
/// histories, exact solutions) is a function of the time since `start`, and `checkpoint.every_sim_s`
/// counts from it, so that moving `start` changes no result, only the times written.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeConfig {
    /// Start time, s. Default 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub start: f64,
    /// End time, s, after `start`.
    pub end: f64,
}

fn is_zero(t: &f64) -> bool {
    *t == 0.0
}

impl TimeConfig {
    /// The simulated span `end - start`, s: the end on the run's own clock, which starts at 0.
    pub fn span(&self) -> f64 {
        self.end - self.start
    }

    /// The time `t` (s, on the config's clock) on the run's own clock: `t - start`.
    pub fn elapsed(&self, t: f64) -> f64 {
        t - self.start
    }

    /// The run's own time `tau` (s) on the config's clock, as outputs write it: `tau + start`,
    /// and `end` itself at the run's end, [`TimeConfig::span`] (which `end - start + start`
    /// may miss by a rounding).
    pub fn clock(&self, tau: f64) -> f64 {
        if tau == self.span() {
            self.end
        } else {
            tau + self.start
        }
    }
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

/// `[limits]`: the most a run may cost. Before any work `sdg run` and `sdg mesh` estimate the
/// run's tents and wall time and refuse (exit 2) a run whose estimate exceeds a limit, unless
/// given `--force`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LimitsConfig {
    /// Most tents. Default 1e10 (days on one node at the seed's resolution).
    #[serde(default = "default_max_tents")]
    pub max_tents: f64,
    /// Most wall time, s, on the threads of the run. Default 2.592e6 (30 days).
    #[serde(default = "default_max_wall_time_s")]
    pub max_wall_time_s: f64,
}

fn default_max_tents() -> f64 {
    1e10
}

fn default_max_wall_time_s() -> f64 {
    2.592e6
}

impl Default for LimitsConfig {
    fn default() -> Self {
        Self {
            max_tents: default_max_tents(),
            max_wall_time_s: default_max_wall_time_s(),
        }
    }
}

/// `[checkpoint]`: when a run saves its whole state, so that `sdg run --restart` can go on
/// from it. Whatever is set here, SIGTERM, SIGINT, SIGHUP, SIGUSR1 and `--max-wall-time`
/// write one.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CheckpointConfig {
    /// Wall time between checkpoints, s; default 1800 (half an hour), `inf` for none.
    #[serde(default = "default_every_wall_s")]
    pub every_wall_s: f64,
    /// Simulated time between checkpoints, s: one each time the whole front passes a
    /// multiple of it; none when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_sim_s: Option<f64>,
    /// Folder of the checkpoint files; default `checkpoints` in the output folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dir: Option<PathBuf>,
    /// How many checkpoints to keep, the newest; default 2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keep: Option<u32>,
    /// Also write a checkpoint when the front reaches the end time, so that a restart with a
    /// later `time.end` extends the finished run; default false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub at_end: bool,
}

fn default_every_wall_s() -> f64 {
    1800.0
}

impl Default for CheckpointConfig {
    fn default() -> Self {
        Self {
            every_wall_s: default_every_wall_s(),
            every_sim_s: None,
            dir: None,
            keep: None,
            at_end: false,
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
    /// `sdg run`: write `snapshot_NNNN.png` beside each snapshot (velocity magnitude) and
    /// `history.png` (energies against time). Default false.
    #[serde(default)]
    pub png: bool,
    /// Encoding of every `.vtu` file written. Default binary.
    #[serde(default)]
    pub vtu: VtuFormat,
}

/// `output.vtu`: how VTK XML files store their arrays; the values are the same either way.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum VtuFormat {
    /// Inline base64 of zlib-compressed little-endian bytes (`format="binary"`,
    /// `vtkZLibDataCompressor`, `UInt64` headers): compact and fast.
    #[default]
    Binary,
    /// Decimal text, shortest round-trip form: readable, larger and slower.
    Ascii,
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
            png: false,
            vtu: VtuFormat::default(),
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

/// `[scheduler]`: parallel execution.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SchedulerConfig {
    /// Results depend only on the config, never on thread count or timing (rounds of independent
    /// tents instead of asynchronous claiming). Default false.
    #[serde(default)]
    pub deterministic: bool,
}

/// `[adapt]`: error-driven refinement of the front (see `docs/theory/method.md`, "Adaptivity").
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AdaptConfig {
    /// Refine where patches are too dissipative. Default false.
    #[serde(default)]
    pub enabled: bool,
    /// Upper tolerance of the dissipation indicator: a patch above it is rejected and the front
    /// around its vertex refined. Dimensionless, see `docs/theory/method.md`. Default 1e-3.
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
    /// The patch of an active crack tip is rejected and its star refined while one of its
    /// elements has a refinement edge longer than this, m (down to `min_edge`), whatever the
    /// indicator says. Default: none (the indicator alone refines around tips).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip_edge: Option<f64>,
    /// Away from interfaces and crack tips the indicator halves no edge into pieces shorter
    /// than this, m: an element is near a crack when one of its corners is on an interface
    /// edge or is a crack tip. Default: none (`min_edge` everywhere).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub far_edge: Option<f64>,
    /// Zones with a finer `max_edge` (`[[adapt.zone]]`): refined before the first tent and
    /// never coarsened beyond it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub zone: Vec<ZoneConfig>,
    /// Least reference energy of the indicator, J/m. Default: none (the energy put in so far).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_energy: Option<f64>,
    /// The indicator's reference energy is `reference_energy` alone (which must be set), not the
    /// larger of it and the energy put in so far, so that a patch's verdict depends on the patch
    /// only. Default: false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fixed_reference: bool,
}

/// `[[adapt.zone]]`: the points within `radius` of the segment `from`-`to` keep edges no longer
/// than `max_edge`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ZoneConfig {
    /// One end of the segment `[x, y]`, m.
    pub from: [f64; 2],
    /// The other end `[x, y]`, m (may equal `from`: a disc).
    pub to: [f64; 2],
    /// Distance from the segment, m (>= 0).
    pub radius: f64,
    /// Longest edge in the zone, m (> 0).
    pub max_edge: f64,
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
            tip_edge: None,
            far_edge: None,
            zone: Vec::new(),
            reference_energy: None,
            fixed_reference: false,
        }
    }
}
