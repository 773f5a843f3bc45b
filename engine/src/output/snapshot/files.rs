//! The snapshot files: VTU grids of the slices and crack segments, their pictures, the writer
//! thread that writes them off the solving threads, and the removal of an earlier run's.

use super::slicing::{InterfaceValues, PointValues, Segment, Triangle};
use crate::error::EngineError;
use crate::output::{CellType, Field, UnstructuredGrid};
use crate::plot::{FIELD_PNG_SIZE, FieldPlot, Values, VtuGrid};
use std::path::Path;

/// Removes from `dir` the snapshot files a run writes (`snapshot_NNNN.vtu` and `.png`,
/// `cracks_NNNN.vtu`, `snapshots.pvd`, and over ranks their `.pvtu` files and pieces
/// `snapshot_NNNN_R.vtu` and `cracks_NNNN_R.vtu`), so that a new run's folder holds no
/// snapshot of an earlier run that its collection does not list. Returns how many files were
/// removed.
pub(crate) fn remove_earlier(dir: &Path) -> Result<usize, EngineError> {
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
        // A piece of a run over ranks, `snapshot_NNNN_R.vtu` or `cracks_NNNN_R.vtu`.
        let piece = ["snapshot_", "cracks_"].iter().any(|prefix| {
            name.strip_prefix(prefix)
                .and_then(|rest| rest.split_once('_'))
                .is_some_and(|(index, rank)| {
                    numbered(&format!("{index}.vtu"), "", &["vtu"]) && numbered(rank, "", &["vtu"])
                })
        });
        if name == "snapshots.pvd"
            || piece
            || numbered(name, "snapshot_", &["vtu", "png", "pvtu"])
            || numbered(name, "cracks_", &["vtu", "pvtu"])
        {
            let path = entry.path();
            std::fs::remove_file(&path).map_err(|e| EngineError::io(&path, e))?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// Draws the velocity magnitude on `triangles` with the interface `segments` on top into the
/// PNG file `path`.
pub(super) fn draw_png(
    triangles: &[Triangle],
    segments: &[Segment],
    time: f64,
    path: &Path,
) -> Result<(), EngineError> {
    let points: Vec<[f64; 2]> = triangles.iter().flat_map(|t| t.xy).collect();
    let speed: Vec<f64> = triangles
        .iter()
        .flat_map(|t| t.values.iter().map(|v| magnitude(&v.velocity)))
        .collect();
    let lines: Vec<[[f64; 2]; 2]> = segments.iter().map(|s| s.xy).collect();
    draw_speed(points, speed, lines, time, path)
}

/// The Euclidean norm of `v`.
fn magnitude(v: &[f64]) -> f64 {
    v.iter().map(|c| c * c).sum::<f64>().sqrt()
}

/// Draws the snapshot `snapshot_NNNN.pvtu` of a run over ranks, at `time` (s), from its pieces
/// in `dir` (and those of `cracks_NNNN.pvtu` if there is one) into `snapshot_NNNN.png`: the
/// picture a run on threads draws of the same snapshot. Errors name the file that could not be
/// read or written.
pub(crate) fn draw_pieces_png(dir: &Path, pvtu: &str, time: f64) -> Result<(), EngineError> {
    let stem = pvtu.strip_suffix(".pvtu").unwrap_or(pvtu);
    let (mut points, mut speed, mut lines) = (Vec::new(), Vec::new(), Vec::new());
    for grid in piece_grids(dir, pvtu)? {
        let velocity = grid.point_data.iter().find(|f| f.name == "velocity");
        let velocity = velocity.ok_or_else(|| {
            EngineError::Input(format!(
                "{}: a piece without velocity",
                dir.join(pvtu).display()
            ))
        })?;
        for (corners, _) in grid.triangles() {
            for c in corners.map(|c| c as usize) {
                points.push([grid.points[c][0], grid.points[c][1]]);
                let n = velocity.components;
                speed.push(magnitude(&velocity.values[c * n..(c + 1) * n]));
            }
        }
    }
    let cracks = format!("{}.pvtu", stem.replacen("snapshot", "cracks", 1));
    if dir.join(&cracks).is_file() {
        for grid in piece_grids(dir, &cracks)? {
            let xy = |c: u32| [grid.points[c as usize][0], grid.points[c as usize][1]];
            lines.extend(grid.lines().into_iter().map(|[a, b]| [xy(a), xy(b)]));
        }
    }
    draw_speed(points, speed, lines, time, &dir.join(format!("{stem}.png")))
}

/// The pieces that the `.pvtu` file `name` in `dir` lists, read.
fn piece_grids(dir: &Path, name: &str) -> Result<Vec<VtuGrid>, EngineError> {
    let path = dir.join(name);
    let text = std::fs::read_to_string(&path).map_err(|e| EngineError::io(&path, e))?;
    text.split("<Piece Source=\"")
        .skip(1)
        .filter_map(|rest| rest.split_once('"'))
        .map(|(source, _)| VtuGrid::read(&dir.join(source)))
        .collect()
}

/// Draws the speeds (m/s) at the corners of the triangles of `points` (three each) with `lines`
/// on top into `path`. The triangles are drawn in the order of their centroids, so that the
/// picture does not depend on the order they come in (a run over ranks has them piece by piece).
fn draw_speed(
    points: Vec<[f64; 2]>,
    speed: Vec<f64>,
    mut lines: Vec<[[f64; 2]; 2]>,
    time: f64,
    path: &Path,
) -> Result<(), EngineError> {
    let centroid = |k: usize| {
        let p = &points[3 * k..3 * k + 3];
        [p[0][0] + p[1][0] + p[2][0], p[0][1] + p[1][1] + p[2][1]]
    };
    let mut order: Vec<usize> = (0..points.len() / 3).collect();
    order.sort_by(|&a, &b| {
        let (a, b) = (centroid(a), centroid(b));
        a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1]))
    });
    let corners = |k: usize| 3 * k..3 * k + 3;
    let drawn: Vec<[f64; 2]> = order
        .iter()
        .flat_map(|&k| points[corners(k)].iter().copied())
        .collect();
    let speed: Vec<f64> = order
        .iter()
        .flat_map(|&k| speed[corners(k)].iter().copied())
        .collect();
    let key = |l: &[[f64; 2]; 2]| l.map(|p| p.map(f64::to_bits));
    lines.sort_by_key(key);
    let triangles: Vec<[u32; 3]> = (0..order.len() as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    FieldPlot::new(&drawn, &triangles, Values::Points(&speed))
        .title("velocity magnitude (m/s)")
        .time(Some(time))
        .segments(&lines)
        .render(FIELD_PNG_SIZE)?
        .write_png(path)
}

/// The triangles as an unstructured grid with points `[x, y, 0]` (three per triangle: fields
/// are discontinuous), point fields `velocity`, `stress`, `displacement`,
/// `strain_energy_density` and cell field `area`.
pub(super) fn triangles_grid(triangles: &[Triangle]) -> UnstructuredGrid {
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
pub(super) fn segments_grid(segments: &[Segment]) -> UnstructuredGrid {
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

/// Writing one snapshot's files.
pub(super) type Job = Box<dyn FnOnce() -> Result<(), EngineError> + Send>;

/// A thread that runs [`Job`]s in the order they come, so that no worker waits for the disk
/// or for a picture being drawn. After the first error it runs no more jobs (a collection must
/// not list a file that failed) and keeps that error.
pub(super) struct Writer {
    pub(super) jobs: std::sync::mpsc::Sender<Job>,
    pub(super) thread: std::thread::JoinHandle<Result<(), EngineError>>,
    pub(super) failed: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Writer {
    pub(super) fn start() -> Self {
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

    pub(super) fn has_failed(&self) -> bool {
        self.failed.load(std::sync::atomic::Ordering::Acquire)
    }
}
