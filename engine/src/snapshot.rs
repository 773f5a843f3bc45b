//! Snapshots: the solution on planes `t = const`, cut from the spacetime elements as they are
//! solved and written as VTK triangle grids (`snapshot_NNNN.vtu`) with a ParaView collection
//! (`snapshots.pvd`). Crack surfaces (contact, cohesive and damage interfaces) are cut the same
//! way: their vertical faces give segments on the plane, written as `cracks_NNNN.vtu` (lines)
//! beside the triangles and listed in the collection as its part 1.
//!
//! # Slicing rule
//! A snapshot at `t_s` is the plane `tau = tau_s = c_ref t_s`. Each element vertex is classified
//! as below, on or above the plane, "on" meaning within `8 eps |tau_s|` of it (so that a front
//! time equal to `t_s` up to rounding counts as exactly on the plane). The plane is covered
//! exactly once by the slices of
//!
//! 1. the elements with a vertex below and a vertex on or above the plane, i.e.
//!    `min tau < tau_s <= max tau` ("taken from below"). An element whose top face lies in the
//!    plane contributes that face; one that touches the plane with a vertex or an edge
//!    contributes a degenerate polygon, which is dropped. This covers every `t_s` in
//!    `(t_start, t_end]`, including a flat front at `t_s` and the end time itself.
//! 2. Only when no element satisfies rule 1 — the plane is the initial front, `t_s = t_start` —
//!    the elements whose bottom face lies in the plane (three vertices on it, one above). Such
//!    faces are held as a fallback while rule 1 has produced nothing yet and dropped as soon as
//!    it does, whatever the order in which elements arrive.
//!
//! # Completeness
//! Every later element has all its vertices on or above the current front, so once the front's
//! minimum time reaches `t_s` no element can satisfy rule 1 any more: the snapshot is written
//! when `front_min_time >= t_s`. The start-time snapshot (rule 2) is complete only when the front
//! has left `t_s` everywhere, `front_min_time > t_s`. A snapshot later than the end time is never
//! written.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::config::VtuFormat;
use crate::error::EngineError;
use crate::output::{CellType, Field, UnstructuredGrid, write_atomic};
use crate::plot::{FIELD_PNG_SIZE, FieldPlot, Values};

/// Field values at a point of a slice, physical SI units.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointValues {
    /// Velocity, m/s.
    pub velocity: [f64; 3],
    /// Stress, Pa, in VTK symmetric-tensor order XX, YY, ZZ, XY, YZ, XZ.
    pub stress: [f64; 6],
    /// Displacement, m.
    pub displacement: [f64; 3],
    /// Strain energy density, J/m^3.
    pub strain_energy_density: f64,
}

/// Values on a contact interface at a point of a slice, physical SI units.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InterfaceValues {
    /// Normal separation, m.
    pub delta: f64,
    /// Tangential slip, m.
    pub slip: f64,
    /// Damage `D` in effect (damage law; 0 with other laws).
    pub damage: f64,
    /// Target traction (normal, tangential), Pa.
    pub traction: [f64; 2],
    /// Contact area fraction.
    pub eta: f64,
    /// Mode with the largest area fraction: 0 stick, 1 slip, 2 separation, 3 bonded (damage
    /// law).
    pub mode: f64,
}

/// A slice segment of an interface: ends `(x, y)`, metres, and the values there.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
struct Segment {
    xy: [[f64; 2]; 2],
    values: [InterfaceValues; 2],
}

/// A slice triangle: corners `(x, y)` counter-clockwise, metres, and the fields there.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
struct Triangle {
    xy: [[f64; 2]; 3],
    values: [PointValues; 3],
}

impl Triangle {
    fn area(&self) -> f64 {
        signed_area(self.xy[0], self.xy[1], self.xy[2])
    }
}

/// A snapshot not written yet.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Pending {
    /// Index in the sorted list of times, for the file name.
    index: usize,
    /// Time, s, on the run's clock (from its start).
    time: f64,
    /// The time the files are labelled with, s, on the config's clock (from `time.start`);
    /// `time` when absent (checkpoints written before labels, all of runs from 0).
    #[serde(default)]
    label: Option<f64>,
    /// `c_ref * time`, m.
    tau: f64,
    /// Half-width of the band around `tau` counted as on the plane, m.
    tol: f64,
    /// Slices of rule 1 (see the module docs).
    triangles: Vec<Triangle>,
    /// Bottom faces in the plane (rule 2), kept while `triangles` is empty.
    fallback: Vec<Triangle>,
    /// Interface segments (rule 1 on the interfaces' vertical faces).
    segments: Vec<Segment>,
}

impl Pending {
    /// Snapshot number `index` at `time` (s, run clock) labelled `label` (s), nothing collected.
    fn new(index: usize, time: f64, label: f64, c_ref: f64) -> Self {
        let tau = c_ref * time;
        Self {
            index,
            time,
            label: Some(label),
            tau,
            tol: 8.0 * f64::EPSILON * tau.abs(),
            triangles: Vec::new(),
            fallback: Vec::new(),
            segments: Vec::new(),
        }
    }

    /// The time the files are labelled with, s.
    fn label(&self) -> f64 {
        self.label.unwrap_or(self.time)
    }
}

/// Collects the t = const slices of spacetime elements as they are solved and writes each snapshot
/// as `snapshot_NNNN.vtu` plus a ParaView collection `snapshots.pvd` once it is complete.
///
/// Points are stored per triangle (no merging), which is exact for discontinuous fields.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Snapshots {
    c_ref: f64,
    dir: PathBuf,
    /// All snapshots in increasing time; those from `next` on are pending.
    snapshots: Vec<Pending>,
    next: usize,
    written: Vec<(f64, String)>,
    /// Interface files written: (time in s, file name).
    crack_files: Vec<(f64, String)>,
    /// Also draw each snapshot as `snapshot_NNNN.png`.
    png: bool,
    /// Encoding of the `.vtu` files; not saved, a restart takes the current `output.vtu`.
    #[serde(skip)]
    vtu: VtuFormat,
    /// The thread that writes the files, while it has work or until [`Snapshots::finish`].
    #[serde(skip)]
    writer: Option<Writer>,
    /// A write has failed (and was reported): nothing more is written, so that the collection
    /// on disk never lists the missing file.
    #[serde(skip)]
    failed: bool,
}

/// Writing one snapshot's files.
type Job = Box<dyn FnOnce() -> Result<(), EngineError> + Send>;

/// A thread that runs [`Job`]s in the order they come, so that no worker waits for the disk
/// or for a picture being drawn. After the first error it runs no more jobs (a collection must
/// not list a file that failed) and keeps that error.
struct Writer {
    jobs: std::sync::mpsc::Sender<Job>,
    thread: std::thread::JoinHandle<Result<(), EngineError>>,
    failed: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Writer {
    fn start() -> Self {
        let (jobs, queue) = std::sync::mpsc::channel::<Job>();
        let failed = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let flag = failed.clone();
        let thread = std::thread::spawn(move || {
            for job in queue {
                if let Err(e) = job() {
                    flag.store(true, std::sync::atomic::Ordering::Release);
                    return Err(e);
                }
            }
            Ok(())
        });
        Self {
            jobs,
            thread,
            failed,
        }
    }

    fn has_failed(&self) -> bool {
        self.failed.load(std::sync::atomic::Ordering::Acquire)
    }
}

impl std::fmt::Debug for Snapshots {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Snapshots")
            .field("c_ref", &self.c_ref)
            .field("dir", &self.dir)
            .field(
                "pending_times",
                &self.snapshots[self.next..]
                    .iter()
                    .map(|s| s.time)
                    .collect::<Vec<_>>(),
            )
            .field(
                "pending_triangles",
                &self.snapshots[self.next..]
                    .iter()
                    .map(|s| s.triangles.len() + s.fallback.len())
                    .sum::<usize>(),
            )
            .field("written", &self.written)
            .finish()
    }
}

impl Snapshots {
    /// `times` in seconds (any order; sorted and deduplicated, non-finite times dropped; file
    /// numbers follow the sorted order), `c_ref` m/s (positive), output folder `dir`.
    pub fn new(times: &[f64], c_ref: f64, dir: PathBuf) -> Self {
        Self::on_clock(times, 0.0, c_ref, dir)
    }

    /// [`Snapshots::new`] for a run that starts at `start` (s, `time.start`): each of `times`
    /// (s, from the same origin as `start`) is cut at `time - start` on the run's clock and
    /// its files are labelled `time`.
    pub fn on_clock(times: &[f64], start: f64, c_ref: f64, dir: PathBuf) -> Self {
        assert!(
            c_ref.is_finite() && c_ref > 0.0,
            "c_ref must be positive, got {c_ref}"
        );
        let mut sorted: Vec<(f64, f64)> = (times.iter())
            .filter(|t| t.is_finite())
            .map(|&t| (t - start, t))
            .collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        sorted.dedup_by(|a, b| a.0 == b.0);
        let snapshots = sorted
            .into_iter()
            .enumerate()
            .map(|(index, (time, label))| Pending::new(index, time, label, c_ref))
            .collect();
        Self {
            c_ref,
            dir,
            snapshots,
            next: 0,
            written: Vec::new(),
            crack_files: Vec::new(),
            png: false,
            vtu: VtuFormat::default(),
            writer: None,
            failed: false,
        }
    }

    /// Makes `times` (s, from the origin of `start`, as [`Self::on_clock`] takes them) the
    /// snapshot times of a run resumed from a front whose latest time is `reached` (s, on the
    /// run's clock): snapshots written stay as they are, pending ones among `times` keep what
    /// they collected, other pending ones are dropped, and new times are numbered after every
    /// earlier snapshot. Fails, changing nothing, with the first new time at or before
    /// `reached`: elements solved before the restart crossed its plane uncollected.
    pub fn retime(&mut self, times: &[f64], start: f64, reached: f64) -> Result<(), f64> {
        let mut wanted: Vec<(f64, f64)> = (times.iter())
            .filter(|t| t.is_finite())
            .map(|&t| (t - start, t))
            .collect();
        wanted.sort_by(|a, b| a.0.total_cmp(&b.0));
        wanted.dedup_by(|a, b| a.0 == b.0);
        let known = |label: f64| self.snapshots.iter().any(|s| s.label() == label);
        if let Some(&(_, label)) = wanted
            .iter()
            .find(|&&(time, label)| !known(label) && time <= reached)
        {
            return Err(label);
        }
        let mut index = self
            .snapshots
            .iter()
            .map(|s| s.index + 1)
            .max()
            .unwrap_or(0);
        let mut earlier: Vec<Pending> = self.snapshots.drain(self.next..).collect();
        let mut pending = Vec::new();
        for (time, label) in wanted {
            if self.snapshots.iter().any(|s| s.label() == label) {
                continue;
            }
            match earlier.iter().position(|s| s.label() == label) {
                Some(k) => pending.push(earlier.swap_remove(k)),
                None => {
                    pending.push(Pending::new(index, time, label, self.c_ref));
                    index += 1;
                }
            }
        }
        pending.sort_by(|a, b| a.time.total_cmp(&b.time));
        self.snapshots.extend(pending);
        Ok(())
    }

    /// Also draw each snapshot as `snapshot_NNNN.png` (velocity magnitude, interfaces in red).
    pub fn with_png(mut self, png: bool) -> Self {
        self.png = png;
        self
    }

    /// Writes the `.vtu` files in `format` (default binary).
    pub fn with_vtu(mut self, format: VtuFormat) -> Self {
        self.vtu = format;
        self
    }

    /// The pending snapshot times (s) whose plane cuts a face spanning `tau` from `lo` to `hi`
    /// (m) by rule 1 (`lo < tau_s <= hi`), for [`Self::add_interface_segment`].
    pub fn crossing(&self, lo: f64, hi: f64) -> impl Iterator<Item = f64> + '_ {
        self.snapshots[self.next..]
            .iter()
            .filter(move |s| lo < s.tau - s.tol && s.tau - s.tol <= hi)
            .map(|s| s.time)
    }

    /// Records the segment `xy` (m) with `values` at its ends, the cut of an interface face by
    /// the plane of the pending snapshot at `time` (s, one of [`Self::crossing`]'s).
    pub fn add_interface_segment(
        &mut self,
        time: f64,
        xy: [[f64; 2]; 2],
        values: [InterfaceValues; 2],
    ) {
        if let Some(snap) = self.snapshots[self.next..]
            .iter_mut()
            .find(|s| s.time == time)
        {
            snap.segments.push(Segment { xy, values });
        }
    }

    /// False when no pending snapshot plane can cut an element whose vertices' times all lie in
    /// `[lo, hi]` (s), so that [`Snapshots::add_element`] would do nothing with it: callers may
    /// then skip loading the element. Conservative (a relative margin of 1e-9 on top of each
    /// plane's band), never false for an element `add_element` would slice.
    pub fn pending_within(&self, lo: f64, hi: f64) -> bool {
        let (lo, hi) = (self.c_ref * lo, self.c_ref * hi);
        let slack = 1e-9 * lo.abs().max(hi.abs());
        let pending = &self.snapshots[self.next..];
        let first = pending.partition_point(|s| s.tau + s.tol + slack < lo);
        pending
            .get(first)
            .is_some_and(|s| s.tau - s.tol - slack <= hi)
    }

    /// Cuts the element with vertices `vertices` ([x, y, tau]) by every pending snapshot plane it
    /// crosses and records the slice polygons (a triangle, or a quadrilateral split into two
    /// triangles), evaluating `eval` at each polygon corner (a point `[x, y, tau_s]` of the
    /// element). Cheap when no snapshot plane crosses the element: no allocation then.
    pub fn add_element(
        &mut self,
        vertices: &[[f64; 3]; 4],
        mut eval: impl FnMut([f64; 3]) -> PointValues,
    ) {
        let pending = &mut self.snapshots[self.next..];
        let (lo, hi) = vertices
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v[2]), hi.max(v[2]))
            });
        // A plane is relevant when some vertex is on or below it and some on or above it.
        let first = pending.partition_point(|s| s.tau + s.tol < lo);
        for snap in &mut pending[first..] {
            if snap.tau - snap.tol > hi {
                break;
            }
            let Some(corners) = slice(vertices, snap.tau, snap.tol) else {
                continue;
            };
            let fallback = match corners.rule {
                Rule::Crossing => {
                    if !snap.fallback.is_empty() {
                        snap.fallback = Vec::new();
                    }
                    false
                }
                Rule::BottomFace if snap.triangles.is_empty() => true,
                Rule::BottomFace => continue,
            };
            let values = corners.points[..corners.len].iter().map(|&p| eval(p));
            let mut v = [PointValues::default(); 4];
            for (slot, value) in v.iter_mut().zip(values) {
                *slot = value;
            }
            let xy = corners.points.map(|p| [p[0], p[1]]);
            let out = if fallback {
                &mut snap.fallback
            } else {
                &mut snap.triangles
            };
            // Fan triangulation of the convex, counter-clockwise polygon.
            let scale = (1..corners.len)
                .map(|i| (xy[i][0] - xy[0][0]).powi(2) + (xy[i][1] - xy[0][1]).powi(2))
                .fold(0.0, f64::max);
            for i in 1..corners.len - 1 {
                let tri = Triangle {
                    xy: [xy[0], xy[i], xy[i + 1]],
                    values: [v[0], v[i], v[i + 1]],
                };
                if tri.area() > 16.0 * f64::EPSILON * scale {
                    out.push(tri);
                }
            }
        }
    }

    /// Writes the snapshots still to come to `dir` in `vtu` (a run restored from a checkpoint).
    /// The files of snapshots written before into another folder are copied into `dir`, so that
    /// its collection finds them; a `.vtu` file that is not there any more is warned about.
    pub fn set_output(&mut self, dir: &Path, vtu: VtuFormat) -> Result<(), EngineError> {
        let earlier = std::mem::replace(&mut self.dir, dir.to_path_buf());
        self.vtu = vtu;
        let same = match (earlier.canonicalize(), dir.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => earlier == dir,
        };
        if same {
            return Ok(());
        }
        let files = (self.written.iter().chain(&self.crack_files)).flat_map(|(_, name)| {
            let picture = name
                .strip_suffix(".vtu")
                .filter(|stem| stem.starts_with("snapshot_"))
                .map(|stem| format!("{stem}.png"));
            std::iter::once(name.clone()).chain(picture)
        });
        for name in files {
            let (from, to) = (earlier.join(&name), dir.join(&name));
            if from.is_file() {
                // Over a same-named file of another run: the collection lists this run's.
                std::fs::copy(&from, &to).map_err(|e| EngineError::io(&to, e))?;
            } else if name.ends_with(".vtu") {
                let kept = if to.exists() {
                    "the file of that name there is kept and may be another run's"
                } else {
                    "snapshots.pvd lists it"
                };
                tracing::warn!(
                    "{}: not found, so not copied to {}; {kept}",
                    from.display(),
                    dir.display()
                );
            }
        }
        Ok(())
    }

    /// Hands `job` to the writer thread, started if need be.
    fn submit(&mut self, job: Job) {
        let writer = self.writer.get_or_insert_with(Writer::start);
        if let Err(std::sync::mpsc::SendError(job)) = writer.jobs.send(job) {
            // The thread is gone (it panicked): write here; finish() reports the panic.
            let _ = job();
        }
    }

    /// Waits until every file handed to the writer thread is written; returns the first error
    /// of a write. Files are complete on disk after it (before a checkpoint, at the end).
    pub fn finish(&mut self) -> Result<(), EngineError> {
        let Some(Writer { jobs, thread, .. }) = self.writer.take() else {
            return Ok(());
        };
        drop(jobs);
        let result = thread
            .join()
            .map_err(|_| EngineError::Runtime("the snapshot writer panicked".into()))
            .and_then(|written| written);
        self.failed |= result.is_err();
        result
    }

    /// Writes every pending snapshot whose time is `<= front_min_time` (s), except that the
    /// start-time snapshot waits for `front_min_time > t_s` (see the module docs), frees its
    /// triangles and rewrites `snapshots.pvd`. Returns how many are written: on a thread of
    /// their own, complete after [`Snapshots::finish`], which reports a failed write; a write
    /// that has failed already is reported here, once; after it nothing more is written.
    pub fn flush(&mut self, front_min_time: f64) -> Result<usize, EngineError> {
        if self.writer.as_ref().is_some_and(Writer::has_failed) {
            self.finish()?;
        }
        if self.failed {
            return Ok(0);
        }
        let mut count = 0;
        while let Some(snap) = self.snapshots.get_mut(self.next) {
            let tol = 4.0 * f64::EPSILON * snap.time.abs();
            let reached = front_min_time >= snap.time - tol;
            let passed = front_min_time > snap.time + tol;
            if !(passed || reached && !snap.triangles.is_empty()) {
                break;
            }
            let triangles = if snap.triangles.is_empty() {
                std::mem::take(&mut snap.fallback)
            } else {
                snap.fallback = Vec::new();
                std::mem::take(&mut snap.triangles)
            };
            let segments = std::mem::take(&mut snap.segments);
            let (index, time) = (snap.index, snap.label.unwrap_or(snap.time));
            let name = format!("snapshot_{index:04}.vtu");
            self.written.push((time, name.clone()));
            let cracks = format!("cracks_{index:04}.vtu");
            if !segments.is_empty() {
                self.crack_files.push((time, cracks.clone()));
            }
            let (dir, vtu, png) = (self.dir.clone(), self.vtu, self.png);
            self.submit(Box::new(move || {
                write_atomic(
                    &dir,
                    &name,
                    triangles_grid(&triangles).to_vtu(vtu).as_bytes(),
                )?;
                if png && !triangles.is_empty() {
                    let path = dir.join(format!("snapshot_{index:04}.png"));
                    // A picture that cannot be drawn must not end a run: warn and go on.
                    if let Err(e) = draw_png(&triangles, &segments, time, &path) {
                        tracing::warn!("{}: {e}", path.display());
                    }
                }
                if !segments.is_empty() {
                    let grid = segments_grid(&segments);
                    write_atomic(&dir, &cracks, grid.to_vtu(vtu).as_bytes())?;
                }
                Ok(())
            }));
            self.next += 1;
            count += 1;
        }
        if count > 0 {
            let (dir, pvd) = (self.dir.clone(), self.pvd());
            self.submit(Box::new(move || {
                write_atomic(&dir, "snapshots.pvd", pvd.as_bytes()).map(drop)
            }));
        }
        Ok(count)
    }

    /// Snapshot files written so far: (time in s, file name).
    pub fn written(&self) -> &[(f64, String)] {
        &self.written
    }

    /// The ParaView collection of the files written so far.
    fn pvd(&self) -> String {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" \
             byte_order=\"LittleEndian\">\n<Collection>\n",
        );
        for (part, files) in [&self.written, &self.crack_files].into_iter().enumerate() {
            for (time, name) in files {
                let _ = writeln!(
                    s,
                    "<DataSet timestep=\"{time}\" part=\"{part}\" file=\"{name}\"/>"
                );
            }
        }
        s.push_str("</Collection>\n</VTKFile>\n");
        s
    }
}

/// Which rule of the module docs a slice comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Rule {
    Crossing,
    BottomFace,
}

/// Corners of the slice of one element, counter-clockwise in `(x, y)`; `points[len..]` unused.
#[derive(Clone, Copy, Debug)]
struct Corners {
    points: [[f64; 3]; 4],
    len: usize,
    rule: Rule,
}

/// The slice of the element `v` by the plane `tau = tau_s` (vertices within `tol` of it are on
/// it), or `None` when neither rule applies or the slice has fewer than three corners.
/// Removes from `dir` the snapshot files a run writes (`snapshot_NNNN.vtu` and `.png`,
/// `cracks_NNNN.vtu`, `snapshots.pvd`), so that a new run's folder holds no snapshot of an
/// earlier run that its collection does not list. Returns how many files were removed.
pub fn remove_earlier(dir: &Path) -> Result<usize, EngineError> {
    let numbered = |name: &str, prefix: &str, extensions: &[&str]| {
        name.strip_prefix(prefix)
            .and_then(|rest| rest.split_once('.'))
            .is_some_and(|(digits, extension)| {
                !digits.is_empty()
                    && digits.bytes().all(|b| b.is_ascii_digit())
                    && extensions.contains(&extension)
            })
    };
    let entries = std::fs::read_dir(dir).map_err(|e| EngineError::io(dir, e))?;
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        if !entry.file_type().is_ok_and(|t| t.is_file()) {
            continue;
        }
        if name == "snapshots.pvd"
            || numbered(name, "snapshot_", &["vtu", "png"])
            || numbered(name, "cracks_", &["vtu"])
        {
            let path = entry.path();
            std::fs::remove_file(&path).map_err(|e| EngineError::io(&path, e))?;
            removed += 1;
        }
    }
    Ok(removed)
}

fn slice(v: &[[f64; 3]; 4], tau_s: f64, tol: f64) -> Option<Corners> {
    let side = |p: &[f64; 3]| {
        if p[2] < tau_s - tol {
            -1
        } else if p[2] > tau_s + tol {
            1
        } else {
            0
        }
    };
    let sides = v.each_ref().map(side);
    let below = sides.iter().filter(|&&s| s < 0).count();
    let on = sides.iter().filter(|&&s| s == 0).count();
    let rule = match (below, on) {
        (0, 3) => Rule::BottomFace,
        (0, _) | (4, _) => return None,
        _ => Rule::Crossing,
    };
    let mut points = [[0.0; 3]; 4];
    let mut len = 0;
    let mut push = |p: [f64; 3]| {
        points[len] = p;
        len += 1;
    };
    if below == 2 && on == 0 {
        // Quadrilateral: cut edges in cyclic order b0a0, b0a1, b1a1, b1a0 (consecutive ones share
        // a face of the tetrahedron).
        let (mut b, mut a) = ([0; 2], [0; 2]);
        let (mut nb, mut na) = (0, 0);
        for (i, &s) in sides.iter().enumerate() {
            if s < 0 {
                b[nb] = i;
                nb += 1;
            } else {
                a[na] = i;
                na += 1;
            }
        }
        for (i, j) in [(b[0], a[0]), (b[0], a[1]), (b[1], a[1]), (b[1], a[0])] {
            push(cut(v[i], v[j], tau_s));
        }
    } else {
        for i in 0..4 {
            match sides[i] {
                0 => push(v[i]),
                s if s < 0 => {
                    for j in 0..4 {
                        if sides[j] > 0 {
                            push(cut(v[i], v[j], tau_s));
                        }
                    }
                }
                _ => {}
            }
        }
    }
    if len < 3 {
        return None;
    }
    let xy = |p: [f64; 3]| [p[0], p[1]];
    let twice_area: f64 = (1..len - 1)
        .map(|i| signed_area(xy(points[0]), xy(points[i]), xy(points[i + 1])))
        .sum();
    if twice_area < 0.0 {
        points[..len].reverse();
    }
    Some(Corners { points, len, rule })
}

/// The point of the edge from `below` to `above` at `tau = tau_s`. Always interpolated from the
/// lower end, so the elements sharing an edge get the same point to the last bit.
fn cut(below: [f64; 3], above: [f64; 3], tau_s: f64) -> [f64; 3] {
    let w = (tau_s - below[2]) / (above[2] - below[2]);
    [
        below[0] + w * (above[0] - below[0]),
        below[1] + w * (above[1] - below[1]),
        tau_s,
    ]
}

/// Signed area of the triangle `a, b, c`: positive when counter-clockwise.
fn signed_area(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// Draws the velocity magnitude on `triangles` with the interface `segments` on top into the
/// PNG file `path`.
fn draw_png(
    triangles: &[Triangle],
    segments: &[Segment],
    time: f64,
    path: &std::path::Path,
) -> Result<(), EngineError> {
    let points: Vec<[f64; 2]> = triangles.iter().flat_map(|t| t.xy).collect();
    let speed: Vec<f64> = triangles
        .iter()
        .flat_map(|t| {
            t.values
                .iter()
                .map(|v| v.velocity.iter().map(|c| c * c).sum::<f64>().sqrt())
        })
        .collect();
    let corners: Vec<[u32; 3]> = (0..triangles.len() as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    let lines: Vec<[[f64; 2]; 2]> = segments.iter().map(|s| s.xy).collect();
    FieldPlot::new(&points, &corners, Values::Points(&speed))
        .title("velocity magnitude (m/s)")
        .time(Some(time))
        .segments(&lines)
        .render(FIELD_PNG_SIZE)?
        .write_png(path)
}

/// The triangles as an unstructured grid with points `[x, y, 0]` (three per triangle: fields
/// are discontinuous), point fields `velocity`, `stress`, `displacement`,
/// `strain_energy_density` and cell field `area`.
fn triangles_grid(triangles: &[Triangle]) -> UnstructuredGrid {
    let values = || triangles.iter().flat_map(|t| t.values.iter());
    let field = |name: &str, components: usize, get: fn(&PointValues) -> &[f64]| Field {
        name: name.into(),
        components,
        values: values().flat_map(|p| get(p).iter().copied()).collect(),
    };
    UnstructuredGrid {
        cell_type: CellType::Triangle,
        points: triangles
            .iter()
            .flat_map(|t| t.xy.iter().map(|p| [p[0], p[1], 0.0]))
            .collect(),
        connectivity: (0..3 * triangles.len() as u32).collect(),
        point_data: vec![
            field("velocity", 3, |p| &p.velocity),
            field("stress", 6, |p| &p.stress),
            field("displacement", 3, |p| &p.displacement),
            field("strain_energy_density", 1, |p| {
                std::slice::from_ref(&p.strain_energy_density)
            }),
        ],
        cell_data: vec![Field::scalar(
            "area",
            triangles.iter().map(Triangle::area).collect(),
        )],
    }
}

/// The interface segments as an unstructured grid of lines with points `[x, y, 0]` (two per
/// segment) and point fields `delta`, `slip`, `damage`, `traction` (normal, tangential, 0), `eta`,
/// `mode`.
fn segments_grid(segments: &[Segment]) -> UnstructuredGrid {
    let values = || segments.iter().flat_map(|s| s.values.iter());
    let scalar = |name: &str, get: fn(&InterfaceValues) -> f64| {
        Field::scalar(name, values().map(get).collect())
    };
    UnstructuredGrid {
        cell_type: CellType::Line,
        points: segments
            .iter()
            .flat_map(|s| s.xy.iter().map(|p| [p[0], p[1], 0.0]))
            .collect(),
        connectivity: (0..2 * segments.len() as u32).collect(),
        point_data: vec![
            scalar("delta", |v| v.delta),
            scalar("slip", |v| v.slip),
            scalar("damage", |v| v.damage),
            Field {
                name: "traction".into(),
                components: 3,
                values: values()
                    .flat_map(|v| [v.traction[0], v.traction[1], 0.0])
                    .collect(),
            },
            scalar("eta", |v| v.eta),
            scalar("mode", |v| v.mode),
        ],
        cell_data: Vec::new(),
    }
}

/// The cut of the triangle `corners` (scaled spacetime, a vertical interface face) by the plane
/// `tau = tau_s`: its two ends, or `None` when the plane misses the triangle or touches it in a
/// point.
pub fn cut_face(corners: [[f64; 3]; 3], tau_s: f64) -> Option<[[f64; 3]; 2]> {
    let mut ends = [[0.0; 3]; 2];
    let mut count = 0;
    for i in 0..3 {
        let (p, q) = (corners[i], corners[(i + 1) % 3]);
        let on = p[2] == tau_s;
        let crosses = (p[2] - tau_s) * (q[2] - tau_s) < 0.0;
        for point in [on.then_some(p), crosses.then(|| cut(p, q, tau_s))]
            .into_iter()
            .flatten()
        {
            if count < 2 {
                ends[count] = point;
                count += 1;
            }
        }
    }
    let length = (ends[1][0] - ends[0][0]).hypot(ends[1][1] - ends[0][1]);
    (count == 2 && length > 0.0).then_some(ends)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_earlier_run_s_snapshot_files_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let removed = [
            "snapshot_0000.vtu",
            "snapshot_0012.png",
            "snapshot_12345.vtu",
            "cracks_0003.vtu",
            "snapshots.pvd",
        ];
        let kept = [
            "summary.json",
            "snapshot_notes.txt",
            "snapshot_.vtu",
            "snapshot_0001.vtu.bak",
            "cracks_0003.png",
            "my_snapshot_0001.vtu",
            "crack_path.png",
        ];
        for name in removed.iter().chain(&kept) {
            std::fs::write(dir.path().join(name), b"x").unwrap();
        }
        std::fs::create_dir(dir.path().join("snapshot_0002.vtu")).unwrap();
        assert_eq!(remove_earlier(dir.path()).unwrap(), removed.len());
        for name in removed {
            assert!(!dir.path().join(name).exists(), "{name} left");
        }
        for name in kept.iter().chain(&["snapshot_0002.vtu"]) {
            assert!(dir.path().join(name).exists(), "{name} removed");
        }
        assert_eq!(remove_earlier(dir.path()).unwrap(), 0);
    }

    /// Unit square: 4 vertices, 2 counter-clockwise triangles.
    const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    const TRIANGLES: [[usize; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

    /// Tetrahedra tiling the square times the layers between consecutive fronts (`fronts[k][v]`
    /// is the tau of vertex `v` on front `k`, increasing in `k`). Each prism is split into three
    /// tetrahedra by vertex index, which makes the splits of shared faces agree.
    fn tets(fronts: &[[f64; 4]]) -> Vec<[[f64; 3]; 4]> {
        let mut out = Vec::new();
        for layer in fronts.windows(2) {
            for tri in TRIANGLES {
                let mut t = tri;
                t.sort_unstable();
                let [a, b, c] = t;
                let lo = |v: usize| [SQUARE[v][0], SQUARE[v][1], layer[0][v]];
                let hi = |v: usize| [SQUARE[v][0], SQUARE[v][1], layer[1][v]];
                out.push([lo(a), lo(b), lo(c), hi(c)]);
                out.push([lo(a), lo(b), hi(b), hi(c)]);
                out.push([lo(a), hi(a), hi(b), hi(c)]);
            }
        }
        out
    }

    fn linear(p: [f64; 3]) -> PointValues {
        let [x, y, tau] = p;
        PointValues {
            velocity: [1.0 + 2.0 * x - y, 3.0 * y + tau, -tau],
            stress: [x, y, tau, x + y, y - tau, 2.0 * x + 0.5 * tau],
            displacement: [x * 0.25, -y, x + y + tau],
            strain_energy_density: 7.0 - x + 4.0 * tau,
        }
    }

    /// Reads `file`, checks that the corner values are `linear` at `tau` and returns the total
    /// triangle area and the number of triangles.
    fn check_file(dir: &std::path::Path, file: &str, tau: f64) -> (f64, usize) {
        let grid = crate::plot::VtuGrid::read(&dir.join(file)).unwrap();
        let field = |name: &str| {
            let mut fields = grid.point_data.iter().chain(&grid.cell_data);
            fields.find(|f| f.name == name).unwrap().values.clone()
        };
        let points: Vec<f64> = grid.points.iter().flatten().copied().collect();
        let velocity = field("velocity");
        let stress = field("stress");
        let displacement = field("displacement");
        let sed = field("strain_energy_density");
        let areas = field("area");
        let n = points.len() / 3;
        assert_eq!(n % 3, 0);
        assert_eq!(velocity.len(), 3 * n);
        assert_eq!(stress.len(), 6 * n);
        assert_eq!(areas.len(), n / 3);
        for k in 0..n {
            let p = [points[3 * k], points[3 * k + 1], tau];
            assert_eq!(points[3 * k + 2], 0.0);
            let want = linear(p);
            let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(a, b)| (a - b).abs() <= 1e-12);
            assert!(close(&velocity[3 * k..3 * k + 3], &want.velocity));
            assert!(close(&stress[6 * k..6 * k + 6], &want.stress));
            assert!(close(&displacement[3 * k..3 * k + 3], &want.displacement));
            assert!((sed[k] - want.strain_energy_density).abs() <= 1e-12);
        }
        let mut total = 0.0;
        for (c, &area) in areas.iter().enumerate() {
            let q = |i: usize| [points[9 * c + 3 * i], points[9 * c + 3 * i + 1]];
            let a = signed_area(q(0), q(1), q(2));
            assert!(a > 0.0, "triangle {c} of {file} is not counter-clockwise");
            assert_eq!(a, area);
            total += a;
        }
        (total, n / 3)
    }

    fn timesteps(pvd: &str) -> Vec<(f64, String)> {
        pvd.lines()
            .filter(|l| l.starts_with("<DataSet"))
            .map(|l| {
                let attr = |k: &str| {
                    let s = &l[l.find(k).unwrap() + k.len()..];
                    s[..s.find('"').unwrap()].to_string()
                };
                (attr("timestep=\"").parse().unwrap(), attr("file=\""))
            })
            .collect()
    }

    const TIMES: [f64; 5] = [0.0, 0.3, 1.0, 1.7, 2.0];

    #[test]
    fn elements_between_pending_planes_are_told_apart_from_those_they_cut() {
        let dir = tempfile::tempdir().unwrap();
        let mut snaps = Snapshots::new(&[0.3, 1.0], 2.0, dir.path().to_path_buf());
        assert!(snaps.pending_within(0.1, 0.3), "touches the first plane");
        assert!(snaps.pending_within(0.2, 0.5));
        assert!(snaps.pending_within(0.9, 1.2));
        assert!(!snaps.pending_within(0.0, 0.29));
        assert!(!snaps.pending_within(0.31, 0.99), "between the planes");
        assert!(!snaps.pending_within(1.01, 2.0));
        assert_eq!(snaps.flush(0.5).unwrap(), 1);
        assert!(!snaps.pending_within(0.1, 0.5), "the first is written");
        assert!(snaps.pending_within(0.5, 1.0));
    }

    /// Feeds `elements` in the given order and checks the five snapshots of `TIMES`.
    fn run(elements: &[[[f64; 3]; 4]]) {
        let dir = tempfile::tempdir().unwrap();
        // Unsorted, with a duplicate.
        let times = [1.7, 0.3, 2.0, 0.0, 1.0, 0.3];
        let mut snaps = Snapshots::new(&times, 1.0, dir.path().to_path_buf());
        assert_eq!(snaps.flush(0.0).unwrap(), 0, "start-time snapshot waits");
        for e in elements {
            snaps.add_element(e, linear);
        }
        assert_eq!(snaps.flush(0.5).unwrap(), 2);
        snaps.finish().unwrap();
        let names = ["snapshot_0000.vtu", "snapshot_0001.vtu"];
        assert_eq!(
            snaps.written(),
            &[(0.0, names[0].to_string()), (0.3, names[1].to_string())]
        );
        assert!(!dir.path().join("snapshot_0002.vtu").exists());
        let pvd = std::fs::read_to_string(dir.path().join("snapshots.pvd")).unwrap();
        assert_eq!(timesteps(&pvd).len(), 2);

        assert_eq!(snaps.flush(2.0).unwrap(), 3);
        assert_eq!(snaps.flush(2.0).unwrap(), 0);
        snaps.finish().unwrap();
        let pvd = std::fs::read_to_string(dir.path().join("snapshots.pvd")).unwrap();
        let listed = timesteps(&pvd);
        assert_eq!(listed.len(), 5);
        for (i, (time, file)) in listed.iter().enumerate() {
            assert_eq!(*time, TIMES[i]);
            assert_eq!(file, &format!("snapshot_{i:04}.vtu"));
            let (area, _) = check_file(dir.path(), file, TIMES[i]);
            assert!((area - 1.0).abs() <= 1e-12, "t = {time}: area {area}");
        }
        assert_eq!(snaps.written().len(), 5);
        assert!(snaps.snapshots.iter().all(|s| s.triangles.capacity() == 0));
    }

    #[test]
    fn retimed_snapshots_keep_what_is_written_and_collected() {
        let dir = tempfile::tempdir().unwrap();
        let mut snaps = Snapshots::new(&[0.3, 1.0, 1.7], 1.0, dir.path().to_path_buf());
        for e in tets(&[[0.0; 4], [1.2; 4]]) {
            snaps.add_element(&e, linear);
        }
        assert_eq!(snaps.flush(0.5).unwrap(), 1);
        snaps.finish().unwrap();
        let before = format!("{snaps:?}");
        // 0.5 is new and the front has reached 1.2: refused, nothing changed.
        assert_eq!(snaps.retime(&[0.3, 0.5, 1.0, 2.5], 0.0, 1.2), Err(0.5));
        assert_eq!(format!("{snaps:?}"), before);
        // 1.7 dropped, 1.0 kept with its slices, 2.5 and 3.0 new (numbered after 1.7's 2).
        snaps.retime(&[3.0, 1.0, 0.3, 2.5], 0.0, 1.2).unwrap();
        let pending: Vec<(usize, f64, usize)> = (snaps.snapshots[snaps.next..].iter())
            .map(|s| (s.index, s.time, s.triangles.len()))
            .collect();
        assert_eq!(pending, [(1, 1.0, 8), (3, 2.5, 0), (4, 3.0, 0)]);
        assert_eq!(snaps.written()[0].1, "snapshot_0000.vtu");
    }

    #[test]
    fn flat_layers_are_sliced_exactly_once() {
        let elements = tets(&[[0.0; 4], [1.0; 4], [2.0; 4]]);
        run(&elements);
        // Reversed order: the bottom faces of the upper layer at tau = 1 arrive first and must
        // be dropped once the top faces of the lower layer come.
        let reversed: Vec<_> = elements.into_iter().rev().collect();
        run(&reversed);
    }

    #[test]
    fn flat_front_slices_are_the_faces_in_the_plane() {
        let dir = tempfile::tempdir().unwrap();
        let mut snaps = Snapshots::new(&TIMES, 1.0, dir.path().to_path_buf());
        for e in tets(&[[0.0; 4], [1.0; 4], [2.0; 4]]) {
            snaps.add_element(&e, linear);
        }
        // tau = 0, 1, 2: the two square triangles (one face per prism); tau = 0.3: 4 per prism.
        let counts: Vec<usize> = snaps.snapshots.iter().map(|s| s.triangles.len()).collect();
        assert_eq!(counts, [0, 8, 2, 8, 2]);
        assert_eq!(snaps.snapshots[0].fallback.len(), 2);
        assert!(snaps.snapshots[2].fallback.is_empty());
    }

    #[test]
    fn curved_fronts_tile_every_plane() {
        // The middle front is not flat: planes at 0.95..1.15 cut both layers.
        let fronts = [[0.0; 4], [0.9, 1.2, 1.0, 1.1], [2.0; 4]];
        let elements = tets(&fronts);
        let times = [0.5, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1.2, 1.5];
        let dir = tempfile::tempdir().unwrap();
        // c_ref = 2: tau = 2 t.
        let times_s: Vec<f64> = times.iter().map(|t| t / 2.0).collect();
        let mut snaps =
            Snapshots::new(&times_s, 2.0, dir.path().to_path_buf()).with_vtu(VtuFormat::Ascii);
        for e in &elements {
            snaps.add_element(e, linear);
        }
        assert_eq!(snaps.flush(1.0).unwrap(), times.len());
        snaps.finish().unwrap();
        for (i, (time, file)) in snaps.written().iter().enumerate() {
            assert_eq!(*time, times_s[i]);
            let text = std::fs::read_to_string(dir.path().join(file)).unwrap();
            assert!(text.contains("format=\"ascii\"") && !text.contains("format=\"binary\""));
            let (area, _) = check_file(dir.path(), file, times[i]);
            assert!(
                (area - 1.0).abs() <= 1e-12,
                "tau = {}: area {area}",
                times[i]
            );
        }
    }

    #[test]
    fn files_are_written_off_the_caller_and_their_errors_come_at_finish() {
        let file = tempfile::NamedTempFile::new().unwrap();
        // A folder inside a file cannot be made: every write fails.
        let mut snaps = Snapshots::new(&[0.3], 1.0, file.path().join("out"));
        for e in tets(&[[0.0; 4], [1.0; 4]]) {
            snaps.add_element(&e, linear);
        }
        assert_eq!(snaps.flush(1.0).unwrap(), 1, "the caller does not wait");
        assert_eq!(snaps.written().len(), 1);
        let e = snaps.finish().unwrap_err();
        assert!(e.to_string().contains("out"), "{e}");
        assert!(snaps.finish().is_ok(), "reported once");
    }

    #[test]
    fn a_failed_snapshot_is_not_listed_and_the_next_flush_reports_it() {
        let dir = tempfile::tempdir().unwrap();
        // A folder that is not empty where the file should go: its rename fails.
        std::fs::create_dir_all(dir.path().join("snapshot_0000.vtu").join("x")).unwrap();
        let mut snaps = Snapshots::new(&[0.3, 0.6], 1.0, dir.path().to_path_buf());
        for e in tets(&[[0.0; 4], [1.0; 4]]) {
            snaps.add_element(&e, linear);
        }
        assert_eq!(snaps.flush(0.4).unwrap(), 1);
        let waited = std::time::Instant::now();
        while !snaps.writer.as_ref().is_some_and(Writer::has_failed) {
            assert!(waited.elapsed().as_secs() < 30, "the write never failed");
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        let e = snaps.flush(1.0).unwrap_err();
        assert!(e.to_string().contains("snapshot_0000.vtu"), "{e}");
        assert_eq!(
            snaps.flush(1.0).unwrap(),
            0,
            "reported once, then nothing written"
        );
        snaps.finish().unwrap();
        assert!(!dir.path().join("snapshots.pvd").exists());
        assert!(!dir.path().join("snapshot_0001.vtu").exists());
    }

    #[test]
    fn elements_away_from_the_planes_are_skipped() {
        let dir = tempfile::tempdir().unwrap();
        let mut snaps = Snapshots::new(&[5.0], 1.0, dir.path().to_path_buf());
        let mut calls = 0;
        for e in tets(&[[0.0; 4], [1.0; 4]]) {
            snaps.add_element(&e, |p| {
                calls += 1;
                linear(p)
            });
        }
        assert_eq!(calls, 0);
        assert_eq!(snaps.flush(1.0).unwrap(), 0);
        assert!(snaps.written().is_empty());
        assert!(!dir.path().join("snapshots.pvd").exists());
    }

    #[test]
    fn meshio_reads_a_snapshot() {
        let have_meshio = std::process::Command::new("python3")
            .args(["-c", "import meshio"])
            .output()
            .is_ok_and(|o| o.status.success());
        if !have_meshio {
            assert!(
                std::env::var_os("CI").is_none(),
                "meshio is required on CI (python3 -c 'import meshio' failed)"
            );
            eprintln!("skipping: python3 with meshio not available");
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let mut snaps = Snapshots::new(&[0.3], 1.0, dir.path().to_path_buf());
        for e in tets(&[[0.0; 4], [1.0; 4]]) {
            snaps.add_element(&e, linear);
        }
        snaps.flush(1.0).unwrap();
        snaps.finish().unwrap();
        let path = dir.path().join(&snaps.written()[0].1);
        let script = "import sys, meshio\n\
                      m = meshio.read(sys.argv[1])\n\
                      print(sum(len(b.data) for b in m.cells), m.cells[0].type)\n\
                      for k in ('velocity', 'stress', 'displacement', 'strain_energy_density'):\n    \
                          print(k, *m.point_data[k].shape)\n";
        let out = std::process::Command::new("python3")
            .args(["-c", script])
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "8 triangle");
        assert_eq!(lines[1], "velocity 24 3");
        assert_eq!(lines[2], "stress 24 6");
        assert_eq!(lines[3], "displacement 24 3");
        assert_eq!(lines[4], "strain_energy_density 24");
    }
}
