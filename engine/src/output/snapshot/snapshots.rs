//! Snapshots as a run makes them: the slices of its elements by each pending plane, collected
//! until the front has passed the plane, then written.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::config::VtuFormat;
use crate::error::EngineError;
use crate::output::write_output;

use super::files::{Job, Writer, draw_png, segments_grid, triangles_grid};
use super::slicing::{InterfaceValues, PointValues, Rule, Segment, Triangle, slice};

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
    /// In a run over ranks, this rank's part: its slices only, as pieces.
    #[serde(skip)]
    piece: Option<Piece>,
    /// In a run over ranks, the slices of the pieces written since the last checkpoint, by
    /// snapshot index: other ranks may not have written theirs yet, and a checkpoint keeps
    /// such a snapshot whole ([`Self::rewound`]).
    #[serde(skip)]
    kept: Vec<Kept>,
}

/// A piece written since the last checkpoint: the snapshot's index, the slices and the
/// interface segments.
type Kept = (usize, Vec<Triangle>, Vec<Segment>);

/// The piece files `STEM_R.vtu` of the snapshot `STEM.pvtu` in `dir`.
fn pieces_of(dir: &Path, stem: &str) -> Vec<String> {
    let prefix = format!("{stem}_");
    (std::fs::read_dir(dir).into_iter().flatten())
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| {
            n.strip_prefix(&prefix)
                .and_then(|rest| rest.strip_suffix(".vtu"))
                .is_some_and(|r| r.parse::<u32>().is_ok())
        })
        .collect()
}

/// One rank's part of the snapshots of a run over `ranks` ranks: it writes the slices of the
/// elements it solved as `snapshot_NNNN_R.vtu` (`R` its rank), without pictures, and with
/// `cuts` the cuts of the interface faces of its patches as `cracks_NNNN_R.vtu` (empty where
/// none); rank 0 also writes `snapshot_NNNN.pvtu` and `cracks_NNNN.pvtu`, which list every
/// rank's pieces, and the collection `snapshots.pvd` of those.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Piece {
    /// This rank.
    pub rank: u32,
    /// Ranks of the run, at least 1.
    pub ranks: u32,
    /// The run has interface faces (nonlinear laws), so every snapshot has crack pieces.
    pub cuts: bool,
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
    #[cfg(test)]
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
            piece: None,
            kept: Vec::new(),
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

    /// Writes only `piece`'s part of each snapshot (a run over ranks).
    pub fn with_piece(mut self, piece: Piece) -> Self {
        self.piece = Some(piece);
        self
    }

    /// Writes the `.vtu` files in `format` (default binary).
    pub fn with_vtu(mut self, format: VtuFormat) -> Self {
        self.vtu = format;
        self
    }

    /// Records the segment `xy` (m) with `values` at its ends, the cut of an interface face by
    /// the plane of the pending snapshot at `time` (s).
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
            // A run over ranks lists the `.pvtu` of each snapshot; its pieces go with it.
            let pieces = name
                .strip_suffix(".pvtu")
                .map(|stem| pieces_of(&earlier, stem))
                .unwrap_or_default();
            std::iter::once(name.clone()).chain(picture).chain(pieces)
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
            if let Some(piece) = self.piece {
                self.write_piece(piece, index, time, (triangles, segments));
                self.next += 1;
                count += 1;
                continue;
            }
            let name = format!("snapshot_{index:04}.vtu");
            self.written.push((time, name.clone()));
            let cracks = format!("cracks_{index:04}.vtu");
            if !segments.is_empty() {
                self.crack_files.push((time, cracks.clone()));
            }
            let (dir, vtu, png) = (self.dir.clone(), self.vtu, self.png);
            self.submit(Box::new(move || {
                write_output(
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
                    write_output(&dir, &cracks, grid.to_vtu(vtu).as_bytes())?;
                }
                Ok(())
            }));
            self.next += 1;
            count += 1;
        }
        if count > 0 && self.piece.is_none_or(|p| p.rank == 0) {
            let (dir, pvd) = (self.dir.clone(), self.pvd());
            self.submit(Box::new(move || {
                write_output(&dir, "snapshots.pvd", pvd.as_bytes()).map(drop)
            }));
        }
        Ok(count)
    }

    /// Hands the writer `piece`'s part of snapshot number `index` at `time` (s): its
    /// `triangles`, and on rank 0 the `.pvtu` of every rank's part.
    fn write_piece(
        &mut self,
        piece: Piece,
        index: usize,
        time: f64,
        (triangles, segments): (Vec<Triangle>, Vec<Segment>),
    ) {
        let name = |stem: &str, rank: u32| format!("{stem}_{index:04}_{rank}.vtu");
        let pvtu = |stem: &str| format!("{stem}_{index:04}.pvtu");
        let rank0 = piece.rank == 0;
        let own = name("snapshot", piece.rank);
        self.written
            .push((time, if rank0 { pvtu("snapshot") } else { own.clone() }));
        if piece.cuts && rank0 {
            self.crack_files.push((time, pvtu("cracks")));
        }
        let (dir, vtu) = (self.dir.clone(), self.vtu);
        self.kept.push((index, triangles.clone(), segments.clone()));
        let pieces = |stem: &str| (0..piece.ranks).map(|r| name(stem, r)).collect::<Vec<_>>();
        let (snapshot_pieces, crack_pieces) = (pieces("snapshot"), pieces("cracks"));
        let (cracks, cracks_pvtu) = (name("cracks", piece.rank), pvtu("cracks"));
        let snapshot_pvtu = pvtu("snapshot");
        self.submit(Box::new(move || {
            let grid = triangles_grid(&triangles);
            write_output(&dir, &own, grid.to_vtu(vtu).as_bytes())?;
            if rank0 {
                let text = grid.to_pvtu(&snapshot_pieces);
                write_output(&dir, &snapshot_pvtu, text.as_bytes())?;
            }
            if piece.cuts {
                let grid = segments_grid(&segments);
                write_output(&dir, &cracks, grid.to_vtu(vtu).as_bytes())?;
                if rank0 {
                    let text = grid.to_pvtu(&crack_pieces);
                    write_output(&dir, &cracks_pvtu, text.as_bytes())?;
                }
            }
            Ok(())
        }));
    }

    /// What a checkpoint of a run over ranks gathers from this rank ([`Self::add_pending`]):
    /// the number of snapshots it has written, and as CBOR the slices of those it has not
    /// written and of the pieces it wrote since the last checkpoint.
    pub(crate) fn pending_cbor(&self) -> (usize, Vec<u8>) {
        let kept = self
            .kept
            .iter()
            .map(|(index, triangles, segments)| Pending {
                triangles: triangles.clone(),
                fallback: Vec::new(),
                segments: segments.clone(),
                ..self.snapshots[*index].clone()
            });
        let pending: Vec<Pending> = kept
            .chain(self.snapshots[self.next..].iter().cloned())
            .collect();
        let mut cbor = Vec::new();
        ciborium::into_writer(&pending, &mut cbor).expect("slices encode in memory");
        (self.next, cbor)
    }

    /// Adds another rank's slices, [`Self::pending_cbor`] of snapshots of the same times, to
    /// the snapshots not written yet (those of snapshots written already are left out).
    /// Errors: bytes that are not such slices.
    pub(crate) fn add_pending(&mut self, cbor: &[u8]) -> Result<(), String> {
        let other: Vec<Pending> =
            ciborium::from_reader(cbor).map_err(|e| format!("snapshot slices: {e}"))?;
        for o in other.into_iter().filter(|o| o.index >= self.next) {
            let Some(p) = self.snapshots.get_mut(o.index) else {
                return Err(format!(
                    "slices of snapshot {}, which there is not",
                    o.index
                ));
            };
            p.triangles.extend(o.triangles);
            p.fallback.extend(o.fallback);
            p.segments.extend(o.segments);
        }
        Ok(())
    }

    /// A copy for a checkpoint of a run over ranks in which every rank has written the first
    /// `next` snapshots: those after are pending again, with this rank's pieces written since
    /// the last checkpoint back among their slices. Then [`Self::add_pending`] the other
    /// ranks'.
    pub(crate) fn rewound(&self, next: usize) -> Self {
        let mut copy = self.to_stored();
        let next = next.min(self.next);
        for (index, triangles, segments) in self.kept.iter().filter(|k| k.0 >= next) {
            let p = &mut copy.snapshots[*index];
            p.triangles = triangles.clone();
            p.fallback.clear();
            p.segments = segments.clone();
        }
        copy.written.truncate(next.min(copy.written.len()));
        let written = &copy.written;
        (copy.crack_files).retain(|(time, _)| written.iter().any(|(t, _)| t == time));
        copy.next = next;
        copy
    }

    /// Forgets the kept slices of the first `next` snapshots, which every rank has written.
    pub(crate) fn forget_kept(&mut self, next: usize) {
        self.kept.retain(|k| k.0 >= next);
    }

    /// A copy of the schedule, the files written and the slices collected, without the writer
    /// or the piece: what a checkpoint stores.
    pub(crate) fn to_stored(&self) -> Self {
        let mut cbor = Vec::new();
        ciborium::into_writer(self, &mut cbor).expect("snapshots encode in memory");
        let mut copy: Self = ciborium::from_reader(&cbor[..]).expect("decoded as encoded");
        copy.vtu = self.vtu;
        copy
    }

    /// Forgets the slices collected and the files written, keeping which snapshots are still
    /// to come: the part of a rank other than 0 of a run over ranks resumed from a checkpoint
    /// (rank 0 keeps the slices and the collection).
    pub(crate) fn forget_collected(&mut self) {
        self.written.clear();
        self.crack_files.clear();
        for p in &mut self.snapshots[self.next..] {
            p.triangles.clear();
            p.fallback.clear();
            p.segments.clear();
        }
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

#[cfg(test)]
mod tests;
