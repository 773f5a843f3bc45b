//! Know the cost before the run: tents, wall time and memory, estimated before any work and
//! checked against `[limits]`.
//!
//! # Tents
//! The pitcher itself is run on a copy of the initial front, always raising the vertex of least
//! time (a local minimum), for at most [`SAMPLE_TENTS`] tents or [`SAMPLE_SECONDS`] of wall
//! time. A front that reaches the end time within that gives the exact count. Otherwise each
//! vertex's count is extrapolated from its progress: `n_v t_end / tau_v` (a vertex advances by
//! about the same step at every tent, since its step is set by its star's budgets `B_T`).
//! Vertices not pitched yet get `gamma t_end / min_star B_T`, with `gamma` the mean of
//! `n_v min_star B_T / tau_v` over the pitched ones. Refinement and crack growth add tents the
//! initial mesh cannot show: with either on, the estimate is a lower bound.
//!
//! # Wall time
//! One patch solver (the run's own kind) solves the first tent of up to 64 vertices spread over
//! the mesh, without committing, within [`PATCH_SECONDS`]: the time per patch on one thread,
//! weighted by how often each vertex is pitched.
//! The wall time is `tents x seconds per patch / min(threads, cores)`. Patches with nonlinear
//! interfaces cost more once their interfaces are loaded (Newton iterations), which the first
//! tent, at rest, does not show. `sdg mesh` uses the pitching rate of the sample instead.
//!
//! # Memory
//! The resident memory after set-up (mesh, front, elements), plus per worker what creating and
//! using the timed patch solver added to it.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::time::{Duration, Instant};

use serde::Serialize;

use sdg_mesh::{Front, Mesh, Pitcher, Tent};
use sdg_solver::element::FrontSolution;
use sdg_solver::patch::{Initial, PatchSolver};

use crate::config::ConfigError;
use crate::problem::Problem;

/// Most tents the pitching sample raises.
pub const SAMPLE_TENTS: u64 = 2_000_000;
/// Most wall time the pitching sample takes, s.
pub const SAMPLE_SECONDS: f64 = 0.25;
/// Most wall time spent timing patch solves, s.
pub const PATCH_SECONDS: f64 = 0.2;
/// Wall time of untimed patch solves before the timed ones, s.
pub const WARM_UP_SECONDS: f64 = 0.03;
/// Timed solves of each sampled vertex's tent.
pub const REPEATS: usize = 3;

/// A run's estimated cost, written to `summary.json` beside the actual values.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Estimate {
    /// Tents to the end time (patches of `sdg run`; of a restarted run, from its checkpoint's
    /// front on).
    pub tents: f64,
    /// True when refinement or crack growth may add tents: `tents` is a lower bound.
    pub lower_bound: bool,
    /// True when the pitching sample reached the end time: `tents` is the exact count of the
    /// initial mesh.
    pub exact_tents: bool,
    /// Wall time of one tent on one thread (a patch solve, or a pitch for `sdg mesh`), s.
    pub seconds_per_tent: f64,
    /// Worker threads the wall time is for.
    pub threads: usize,
    /// Wall time of the run, s.
    pub wall_time_s: f64,
    /// Peak resident memory, bytes.
    pub memory_bytes: f64,
}

impl Estimate {
    /// The part of this estimate (of a whole run) still ahead of a run restarted from a front
    /// with vertex `times` (s on the run's clock, which ends at `t_end`): tents and wall time
    /// scaled by the share of the vertices' time still to go.
    pub(crate) fn remaining(self, times: &[f64], t_end: f64) -> Self {
        let to_go: f64 = times.iter().map(|&t| (t_end - t).clamp(0.0, t_end)).sum();
        let share = to_go / (times.len() as f64 * t_end).max(f64::MIN_POSITIVE);
        Self {
            tents: self.tents * share,
            exact_tents: false,
            wall_time_s: self.wall_time_s * share,
            ..self
        }
    }

    /// Tents per second on all threads.
    pub fn tents_per_second(&self) -> f64 {
        self.tents / self.wall_time_s.max(f64::MIN_POSITIVE)
    }

    /// Checks the estimate against `[limits]`: exceeding one is a config error naming the
    /// estimate and what drives it (exit 2).
    pub fn check(&self, problem: &Problem) -> Result<(), ConfigError> {
        let config = &problem.loaded.config;
        if let Some(total) = machine_memory_bytes()
            && self.memory_bytes > total
        {
            let gib = |b: f64| b / (1024.0 * 1024.0 * 1024.0);
            return Err(ConfigError {
                file: format!("--threads {}", self.threads),
                key: None,
                reason: format!(
                    "the run needs about {:.1} GiB of memory with {} worker thread(s), more \
                     than this machine's {:.1} GiB: use fewer threads, or pass --force to `sdg run`",
                    gib(self.memory_bytes),
                    self.threads,
                    gib(total)
                ),
            });
        }
        let limits = &config.limits;
        let exceeded = if self.tents > limits.max_tents {
            Some((
                "limits.max_tents",
                format!(
                    "the run needs about {:.3e} tents, more than the limit {:.3e}",
                    self.tents, limits.max_tents
                ),
            ))
        } else if self.wall_time_s > limits.max_wall_time_s {
            Some((
                "limits.max_wall_time_s",
                format!(
                    "the run needs about {} on {} thread(s) ({:.3e} tents at {:.3e} s each), \
                     more than the limit {}",
                    duration(self.wall_time_s),
                    self.threads,
                    self.tents,
                    self.seconds_per_tent,
                    duration(limits.max_wall_time_s)
                ),
            ))
        } else {
            None
        };
        let Some((key, what)) = exceeded else {
            return Ok(());
        };
        let m = &config.material;
        let (min_edge, _) = problem.mesh.edge_length_range();
        Err(ConfigError {
            file: problem.loaded.file.display().to_string(),
            key: Some(key.into()),
            reason: format!(
                "{what}{}. It is driven by the fastest wave speed {:.3e} m/s (young = {:e} Pa, \
                 poisson = {}, density = {:e} kg/m^3, plane {}), the smallest edge {:.3e} m \
                 and the span {:e} s (time.end - time.start; tents per vertex about \
                 c span / (safety h)). Check \
                 the units, raise the limit, or pass --force to `sdg run`",
                if self.lower_bound {
                    " (a lower bound: refinement and crack growth add more)"
                } else {
                    ""
                },
                problem.material.max_wave_speed(),
                m.young,
                m.poisson,
                m.density,
                format!("{:?}", m.plane).to_lowercase(),
                min_edge,
                config.time.span()
            ),
        })
    }

    /// One line for people: tents, rate, wall time and memory.
    pub fn describe(&self) -> String {
        format!(
            "{}{:.3e} tents, {:.3e} tents/s per thread, {} on {} thread(s), {:.0} MiB",
            if self.lower_bound { "at least " } else { "" },
            self.tents,
            1.0 / self.seconds_per_tent.max(f64::MIN_POSITIVE),
            duration(self.wall_time_s),
            self.threads,
            self.memory_bytes / (1024.0 * 1024.0)
        )
    }
}

/// `s` as seconds, minutes, hours or days.
fn duration(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.3} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else if s < 172_800.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.3e} days", s / 86_400.0)
    }
}

/// What pitching the initial front for a while shows: the tents to the end time and the wall
/// time per pitch.
struct Sample {
    tents: f64,
    exact: bool,
    seconds_per_pitch: f64,
}

/// Pitches a copy of the flat front at time 0 on `mesh` with `pitcher`, least time first, for
/// at most `max_tents` tents and `max_seconds` of wall time, and extrapolates the tent count to
/// the pitcher's end time (module docs).
fn sample(mesh: &Mesh, pitcher: &Pitcher, max_tents: u64, max_seconds: f64) -> Sample {
    let start = Instant::now();
    let (per_vertex, pitched, exact) = tents_per_vertex(mesh, pitcher, max_tents, max_seconds);
    let seconds_per_pitch = start.elapsed().as_secs_f64() / pitched.max(1) as f64;
    Sample {
        tents: if exact {
            pitched as f64
        } else {
            per_vertex.iter().sum()
        },
        exact,
        seconds_per_pitch,
    }
}

/// The tents of every vertex to the pitcher's end time: pitched as [`sample`] does, exact when
/// the front reaches the end time within `max_tents` and `max_seconds`, extrapolated otherwise
/// (module docs). Also the tents pitched and whether the counts are exact. With
/// `max_seconds` infinite the counts depend on the mesh and the pitcher alone.
pub(crate) fn tents_per_vertex(
    mesh: &Mesh,
    pitcher: &Pitcher,
    max_tents: u64,
    max_seconds: f64,
) -> (Vec<f64>, u64, bool) {
    let n = mesh.vertices().len();
    let t_end = pitcher.t_end();
    let front = Front::flat(n, 0.0);
    let mut counts = vec![0u64; n];
    // Times are non-negative, so their bits order like the times.
    let mut queue: BinaryHeap<Reverse<(u64, u32)>> = (0..n as u32)
        .map(|v| Reverse((0.0f64.to_bits(), v)))
        .collect();
    let start = Instant::now();
    let mut pitched = 0u64;
    let mut exact = false;
    while let Some(&Reverse((_, v))) = queue.peek() {
        if front.time(v) >= t_end {
            exact = true;
            break;
        }
        if pitched >= max_tents
            || (pitched.is_multiple_of(1024) && start.elapsed().as_secs_f64() > max_seconds)
        {
            break;
        }
        queue.pop();
        // The least time on the front is a local minimum: it can always be pitched.
        let Some(tent) = pitcher.pitch(mesh, &front, v) else {
            break;
        };
        counts[v as usize] += 1;
        pitched += 1;
        queue.push(Reverse((tent.t_new.to_bits(), v)));
    }
    let counts: Vec<f64> = counts.into_iter().map(|c| c as f64).collect();
    if exact || n == 0 {
        return (counts, pitched, true);
    }
    let least_budget = |v: u32| least_budget(mesh, pitcher, v);
    let (mut gamma, mut measured) = (0.0, 0usize);
    let mut tents = vec![0.0; n];
    for v in 0..n as u32 {
        let (count, time) = (counts[v as usize], front.time(v));
        if count > 0.0 {
            tents[v as usize] = count * t_end / time;
            gamma += count * least_budget(v) / time;
            measured += 1;
        }
    }
    let gamma = if measured > 0 {
        gamma / measured as f64
    } else {
        1.0
    };
    for v in 0..n as u32 {
        if counts[v as usize] == 0.0 {
            tents[v as usize] = gamma * t_end / least_budget(v);
        }
    }
    (tents, pitched, false)
}

/// Wall time of one patch solve on one thread, s: for up to 64 vertices spread over the mesh
/// by a low-discrepancy sequence (a stride would alias with a structured grid), the least of
/// [`REPEATS`] timed solves of the vertex's first tent (never committed), averaged with the
/// vertices' tent rates `1 / min_star B_T` as weights, within [`PATCH_SECONDS`]. The least of a
/// few solves leaves out page faults on fresh scratch memory and interruptions by other
/// processes, which vary from run to run.
fn seconds_per_patch(
    problem: &Problem,
    mesh: &Mesh,
    pitcher: &Pitcher,
    solver: &mut PatchSolver,
    solution: &FrontSolution,
    initial: Initial,
) -> f64 {
    let n = mesh.vertices().len();
    let front = Front::flat(n, 0.0);
    let golden = 0.5 * (5f64.sqrt() - 1.0);
    let tents = (0..64.min(n)).filter_map(|k| {
        let v = (((k as f64 * golden).fract() * n as f64) as usize).min(n - 1) as u32;
        let t_new = pitcher.pole_height(mesh, &front, v)?;
        Some(Tent {
            vertex: v,
            t_old: 0.0,
            t_new,
        })
    });
    let mut solve = |tent: &Tent| {
        let start = Instant::now();
        // A patch that does not converge costs its iterations all the same.
        let _ = solver.solve(mesh, &front, tent, &problem.boundary, initial, solution);
        start.elapsed().as_secs_f64()
    };
    // Untimed first: the first solves of a process run slower (fresh memory, clock ramp).
    let warm_up = Instant::now();
    for tent in tents.clone().cycle() {
        solve(&tent);
        if warm_up.elapsed().as_secs_f64() > WARM_UP_SECONDS {
            break;
        }
    }
    let limit = Duration::from_secs_f64(PATCH_SECONDS);
    let start = Instant::now();
    let (mut sum, mut weights) = (0.0, 0.0);
    for tent in tents {
        let v = tent.vertex;
        let least = (0..REPEATS)
            .map(|_| solve(&tent))
            .fold(f64::INFINITY, f64::min);
        let weight = 1.0 / least_budget(mesh, pitcher, v);
        sum += weight * least;
        weights += weight;
        if start.elapsed() > limit {
            break;
        }
    }
    if weights > 0.0 { sum / weights } else { 0.0 }
}

/// The least budget `B_T` over the star of `v`, s: about its step per tent.
fn least_budget(mesh: &Mesh, pitcher: &Pitcher, v: u32) -> f64 {
    mesh.vertex_triangles(v)
        .iter()
        .map(|&t| pitcher.budget(t))
        .fold(f64::INFINITY, f64::min)
}

/// Resident memory of this process now, bytes (Linux; 0 elsewhere).
fn resident_bytes() -> f64 {
    memory_status("VmRSS:").unwrap_or(0.0)
}

/// Peak resident memory of this process so far, bytes (Linux only).
pub fn peak_resident_bytes() -> Option<f64> {
    memory_status("VmHWM:")
}

/// Memory this process may use, bytes (Linux only): the machine's, or its control group's
/// limit when lower (a batch job's allocation under Slurm's cgroups).
fn machine_memory_bytes() -> Option<f64> {
    let total = kb_line("/proc/meminfo", "MemTotal:")?;
    Some(cgroup_limit_bytes().map_or(total, |limit| limit.min(total)))
}

/// The memory limit of this process's control group (v2 `memory.max`, or v1
/// `memory.limit_in_bytes`), bytes; `None` when unlimited or unknown.
fn cgroup_limit_bytes() -> Option<f64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    groups.lines().find_map(|line| {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        let file = if controllers.is_empty() {
            format!("/sys/fs/cgroup{path}/memory.max")
        } else if controllers.split(',').any(|c| c == "memory") {
            format!("/sys/fs/cgroup/memory{path}/memory.limit_in_bytes")
        } else {
            return None;
        };
        std::fs::read_to_string(file)
            .ok()?
            .trim()
            .parse::<f64>()
            .ok()
    })
}

/// A `kB` line of `/proc/self/status`, in bytes.
fn memory_status(key: &str) -> Option<f64> {
    kb_line("/proc/self/status", key)
}

/// The line starting with `key` of the `kB` table at `path`, in bytes.
fn kb_line(path: &str, key: &str) -> Option<f64> {
    let status = std::fs::read_to_string(path).ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    let kb: f64 = line[key.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024.0)
}

/// Cores the threads can use.
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// What [`solve`] estimates from: the mesh, pitcher and elements as the run starts (zones
/// refined), and how the run's patch solvers are made.
pub(crate) struct Start<'a, F> {
    pub(crate) mesh: &'a Mesh,
    pub(crate) pitcher: &'a Pitcher,
    pub(crate) solution: &'a FrontSolution,
    pub(crate) initial: Initial<'a>,
    pub(crate) new_solver: F,
}

/// The estimate of `sdg run` on `threads`; `grows` when refinement or crack growth may add
/// tents.
pub(crate) fn solve(
    problem: &Problem,
    start: Start<'_, impl FnOnce() -> PatchSolver>,
    threads: usize,
    grows: bool,
) -> Estimate {
    let Start {
        mesh,
        pitcher,
        solution,
        initial,
        new_solver,
    } = start;
    let sampled = sample(mesh, pitcher, SAMPLE_TENTS, SAMPLE_SECONDS);
    let before = resident_bytes();
    let mut solver = new_solver();
    let seconds_per_tent =
        seconds_per_patch(problem, mesh, pitcher, &mut solver, solution, initial);
    let per_solver = (resident_bytes() - before).max(0.0);
    drop(solver);
    Estimate {
        tents: sampled.tents,
        lower_bound: grows,
        exact_tents: sampled.exact,
        seconds_per_tent,
        threads,
        wall_time_s: sampled.tents * seconds_per_tent / threads.min(cores()) as f64,
        memory_bytes: before + per_solver * threads as f64,
    }
}

/// The estimate of `sdg mesh` (pitching only) on `threads`.
pub(crate) fn mesh(mesh: &Mesh, pitcher: &Pitcher, threads: usize) -> Estimate {
    let sampled = sample(mesh, pitcher, SAMPLE_TENTS, SAMPLE_SECONDS);
    Estimate {
        tents: sampled.tents,
        lower_bound: false,
        exact_tents: sampled.exact,
        seconds_per_tent: sampled.seconds_per_pitch,
        threads,
        wall_time_s: sampled.tents * sampled.seconds_per_pitch / threads.min(cores()) as f64,
        memory_bytes: resident_bytes() + 16.0 * mesh.vertices().len() as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sdg_mesh::{Diagonal, Rectangle};

    fn mesh(nx: u32, ny: u32, perturb: f64) -> Mesh {
        Rectangle {
            width: 2.0,
            height: 1.0,
            nx,
            ny,
            diagonal: Diagonal::Alternate,
            interfaces: Vec::new(),
            sides: Vec::new(),
            perturb,
            seed: 3,
        }
        .build()
        .unwrap()
    }

    #[test]
    fn a_restart_is_estimated_for_the_time_its_front_has_still_to_go() {
        let whole = Estimate {
            tents: 1000.0,
            lower_bound: true,
            exact_tents: true,
            seconds_per_tent: 1e-3,
            threads: 2,
            wall_time_s: 0.5,
            memory_bytes: 1e6,
        };
        // Vertices at a quarter, half and three quarters of the way, one past the end.
        let rest = whole.remaining(&[0.25, 0.5, 0.75, 1.5], 1.0);
        assert!((rest.tents - 1000.0 * 1.5 / 4.0).abs() < 1e-9, "{rest:?}");
        assert!((rest.wall_time_s - 0.5 * 1.5 / 4.0).abs() < 1e-12);
        assert!(!rest.exact_tents && rest.lower_bound);
        assert_eq!(rest.memory_bytes, whole.memory_bytes);
    }

    /// The tents of pitching the whole front, least time first.
    fn all_tents(mesh: &Mesh, pitcher: &Pitcher) -> u64 {
        let s = sample(mesh, pitcher, u64::MAX, f64::INFINITY);
        assert!(s.exact);
        s.tents as u64
    }

    #[test]
    fn a_sample_that_reaches_the_end_counts_exactly() {
        let mesh = mesh(6, 3, 0.0);
        let pitcher = Pitcher::new(&mesh, 1.0, 0.9, 0.5).unwrap();
        let total = all_tents(&mesh, &pitcher);
        let front = Front::flat(mesh.vertices().len(), 0.0);
        let pitched = crate::job::pitch_to_end(&mesh, &pitcher, &front, |_, _| {}).unwrap();
        assert_eq!(total, pitched);
    }

    #[test]
    fn extrapolated_counts_match_the_whole_run() {
        for (nx, ny, perturb, end) in [(16, 8, 0.0, 4.0), (20, 10, 0.24, 3.0), (12, 12, 0.2, 6.0)] {
            let mesh = mesh(nx, ny, perturb);
            let pitcher = Pitcher::new(&mesh, 2.0, 0.8, end).unwrap();
            let total = all_tents(&mesh, &pitcher) as f64;
            for fraction in [0.05, 0.2] {
                let s = sample(&mesh, &pitcher, (fraction * total) as u64, f64::INFINITY);
                assert!(!s.exact);
                let ratio = s.tents / total;
                assert!((0.9..1.1).contains(&ratio), "{nx}x{ny} {fraction}: {ratio}");
            }
            // Fewer tents than vertices: most are extrapolated from their budgets.
            let few = sample(
                &mesh,
                &pitcher,
                mesh.vertices().len() as u64 / 3,
                f64::INFINITY,
            );
            let ratio = few.tents / total;
            assert!((0.5..2.0).contains(&ratio), "{nx}x{ny} few: {ratio}");
        }
    }
}
