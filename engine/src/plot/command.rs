//! `sdg plot` (a field of a VTU file as PNG) and `history.png` (energies against time).

use std::path::{Path, PathBuf};

use super::field::{FieldPlot, Values};
use super::line::{LineChart, LineStyle};
use super::vtu::VtuGrid;
use crate::error::EngineError;
use crate::output::Field;
use crate::output::table::{ReadTable, number};

/// Size of `sdg plot` pictures and run snapshots, pixels.
pub const FIELD_PNG_SIZE: (u32, u32) = (1000, 800);
/// Size of `history.png`, pixels.
pub const HISTORY_PNG_SIZE: (u32, u32) = (1000, 650);

/// What `sdg plot` draws.
#[derive(Clone, Debug)]
pub struct PlotRequest {
    /// The VTU file.
    pub vtu: PathBuf,
    /// A point or cell field, a component (`velocity_x`, `stress_xy`) or `von_mises`; `None`:
    /// the velocity magnitude.
    pub field: Option<String>,
    /// The PNG file; `None`: the VTU path with extension `png`.
    pub out: Option<PathBuf>,
    /// Overlay the mesh edges.
    pub edges: bool,
}

/// Component suffixes of vectors and of symmetric tensors in VTK order.
const VECTOR: [&str; 3] = ["x", "y", "z"];
const TENSOR: [&str; 6] = ["xx", "yy", "zz", "xy", "yz", "xz"];

/// A field to draw: its values (one per point or per cell) and its title.
struct Selected {
    values: Vec<f64>,
    per_point: bool,
    title: String,
}

/// The unit of a field written by `sdg run`, for titles.
fn unit(name: &str) -> Option<&'static str> {
    let base = name.rsplit_once('_').map_or(name, |(b, s)| {
        if VECTOR.contains(&s) || TENSOR.contains(&s) {
            b
        } else {
            name
        }
    });
    Some(match base {
        "velocity" => "m/s",
        "stress" | "von_mises" | "traction" => "Pa",
        "displacement" | "delta" | "slip" => "m",
        "strain_energy_density" => "J/m^3",
        "area" => "m^2",
        _ => return None,
    })
}

/// Every name [`select`] accepts for the arrays of `grid`.
fn names(grid: &VtuGrid) -> Vec<String> {
    let mut out = Vec::new();
    for f in grid.point_data.iter().chain(&grid.cell_data) {
        out.push(f.name.clone());
        let suffixes: &[&str] = match f.components {
            2 => &VECTOR[..2],
            3 => &VECTOR,
            6 => &TENSOR,
            _ => &[],
        };
        out.extend(suffixes.iter().map(|s| format!("{}_{s}", f.name)));
        if f.name == "stress" && f.components == 6 {
            out.push("von_mises".into());
        }
    }
    out
}

/// The field `name` of `grid`: an array (vectors as their magnitude, symmetric tensors as their
/// von Mises value), a component `NAME_x` / `NAME_xy`, or `von_mises` of `stress`.
fn select(grid: &VtuGrid, name: &str) -> Option<Selected> {
    let arrays = || {
        grid.point_data
            .iter()
            .map(|f| (f, true))
            .chain(grid.cell_data.iter().map(|f| (f, false)))
    };
    let with_unit = |title: String| match unit(name) {
        Some(u) => format!("{title} ({u})"),
        None => title,
    };
    let reduce = |f: &Field, per_point: bool, title: String, g: &dyn Fn(&[f64]) -> f64| Selected {
        values: f.values.chunks(f.components).map(g).collect(),
        per_point,
        title: with_unit(title),
    };
    if let Some((f, p)) = arrays().find(|(f, _)| f.name == name) {
        return Some(match f.components {
            1 => reduce(f, p, name.into(), &|v| v[0]),
            6 => reduce(f, p, format!("{name} (von Mises)"), &von_mises),
            _ => reduce(f, p, format!("{name} magnitude"), &|v| {
                v.iter().map(|x| x * x).sum::<f64>().sqrt()
            }),
        });
    }
    if name == "von_mises" {
        let (f, p) = arrays().find(|(f, _)| f.name == "stress" && f.components == 6)?;
        return Some(reduce(f, p, "von Mises stress".into(), &von_mises));
    }
    let (base, suffix) = name.rsplit_once('_')?;
    let (f, p) = arrays().find(|(f, _)| f.name == base)?;
    let k = match f.components {
        2 | 3 => VECTOR[..f.components].iter().position(|s| *s == suffix)?,
        6 => TENSOR.iter().position(|s| *s == suffix)?,
        _ => return None,
    };
    Some(reduce(f, p, name.into(), &|v| v[k]))
}

/// Von Mises stress of a symmetric tensor in VTK order XX, YY, ZZ, XY, YZ, XZ.
fn von_mises(s: &[f64]) -> f64 {
    let [xx, yy, zz, xy, yz, xz] = [s[0], s[1], s[2], s[3], s[4], s[5]];
    (0.5 * ((xx - yy).powi(2) + (yy - zz).powi(2) + (zz - xx).powi(2))
        + 3.0 * (xy * xy + yz * yz + xz * xz))
        .sqrt()
}

/// The time (s) of `vtu` from a ParaView collection (`*.pvd`) in its folder that lists it.
fn time_from_pvd(vtu: &Path) -> Option<f64> {
    let name = vtu.file_name()?.to_str()?;
    let dir = match vtu.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    for entry in std::fs::read_dir(dir).ok()?.flatten() {
        let path = entry.path();
        if path.extension().is_none_or(|e| e != "pvd") {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        for tag in text.split('<').filter(|t| t.starts_with("DataSet")) {
            let attr = |key: &str| {
                let start = tag.find(&format!("{key}=\""))? + key.len() + 2;
                let len = tag[start..].find('"')?;
                Some(&tag[start..start + len])
            };
            let listed = attr("file").and_then(|f| Path::new(f).file_name()?.to_str());
            if listed == Some(name)
                && let Some(t) = attr("timestep").and_then(|t| t.parse().ok())
            {
                return Some(t);
            }
        }
    }
    None
}

/// The interface segments of the slice `snapshot_NNNN.vtu`: the lines of `cracks_NNNN.vtu`
/// beside it, when there is one.
fn interface_segments(vtu: &Path) -> Result<Vec<[[f64; 2]; 2]>, EngineError> {
    let Some(index) = vtu
        .file_name()
        .and_then(|n| n.to_str())
        .and_then(|n| n.strip_prefix("snapshot_"))
    else {
        return Ok(Vec::new());
    };
    let path = vtu.with_file_name(format!("cracks_{index}"));
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let grid = VtuGrid::read(&path)?;
    let xy = |i: u32| {
        let p = grid.points[i as usize];
        [p[0], p[1]]
    };
    Ok(grid.lines().iter().map(|l| [xy(l[0]), xy(l[1])]).collect())
}

/// `sdg plot`: draws the requested field of a VTU file (see [`PlotRequest`]) as PNG, with the
/// time from a `.pvd` collection beside it and the interfaces of a snapshot's
/// `cracks_NNNN.vtu` on top. Returns the PNG's path. A file that cannot be read or has no
/// such field is an [`EngineError::Input`] naming the file (and the fields present).
pub fn plot_vtu(request: &PlotRequest) -> Result<PathBuf, EngineError> {
    let grid = VtuGrid::read(&request.vtu)?;
    let file = request.vtu.display();
    let name = request.field.as_deref().unwrap_or("velocity");
    let selected = select(&grid, name).ok_or_else(|| {
        let present = names(&grid);
        let present = if present.is_empty() {
            "none".to_string()
        } else {
            present.join(", ")
        };
        EngineError::Input(format!(
            "{file}: no field `{name}`; fields present: {present}"
        ))
    })?;
    let cells = grid.triangles();
    if cells.is_empty() {
        return Err(EngineError::Input(format!(
            "{file}: no triangles or quadrilaterals to draw (a cracks_NNNN.vtu holds the crack's \
             edges as lines: `crack_path.png` draws them, or open the file in ParaView)"
        )));
    }
    let triangles: Vec<[u32; 3]> = cells.iter().map(|c| c.0).collect();
    let per_cell: Vec<f64>;
    let values = if selected.per_point {
        Values::Points(&selected.values)
    } else {
        per_cell = cells.iter().map(|c| selected.values[c.1]).collect();
        Values::Cells(&per_cell)
    };
    let points: Vec<[f64; 2]> = grid.points.iter().map(|p| [p[0], p[1]]).collect();
    let segments = interface_segments(&request.vtu)?;
    let image = FieldPlot::new(&points, &triangles, values)
        .title(&selected.title)
        .time(time_from_pvd(&request.vtu))
        .edges(request.edges)
        .segments(&segments)
        .render(FIELD_PNG_SIZE)
        .map_err(|e| EngineError::Input(format!("{file}: {e}")))?;
    let out = request
        .out
        .clone()
        .unwrap_or_else(|| request.vtu.with_extension("png"));
    super::canvas::make_folder(&out)?;
    image.write_png(&out)?;
    Ok(out)
}

/// The chart of `history.csv` (as `sdg run` writes it): total, kinetic and strain energy,
/// boundary work and numerical dissipation (J/m) against time (us); interface work too when
/// any is recorded.
pub fn history_chart(csv: &str) -> Result<LineChart, EngineError> {
    let table = ReadTable::parse(csv, "history.csv")?;
    let column = |name: &str| {
        (table.column(name))
            .ok_or_else(|| EngineError::Plot(format!("history has no column {name}")))
    };
    let time = column("time_s")?;
    let series = |k: usize| -> Vec<(f64, f64)> {
        (table.rows())
            .map(|r| (number(r.get(time)) * 1e6, number(r.get(k))))
            .collect()
    };
    let mut chart = LineChart::new("Energy history", "time (us)", "energy (J/m)");
    for (name, key) in [
        ("total (on the front)", "front_energy_j"),
        ("kinetic", "kinetic_j"),
        ("strain", "strain_j"),
        ("boundary work", "boundary_work_j"),
        ("dissipation", "dissipation_j"),
        ("interface work", "interface_work_j"),
    ] {
        let points = series(column(key)?);
        if key == "interface_work_j" && points.iter().all(|p| p.1 == 0.0) {
            continue;
        }
        chart = chart.series(name, &points, LineStyle::Solid);
    }
    Ok(chart)
}

/// Draws `history.csv`'s text `csv` as `dir/history.png`; a picture that cannot be drawn is
/// logged as a warning, never an error of the run.
pub fn write_history_png(dir: &Path, csv: &str) {
    let path = dir.join("history.png");
    if let Err(e) = history_chart(csv).and_then(|c| c.write_png(&path, HISTORY_PNG_SIZE)) {
        tracing::warn!("{}: {e}", path.display());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> VtuGrid {
        VtuGrid {
            points: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            connectivity: vec![0, 1, 2],
            offsets: vec![3],
            types: vec![5],
            point_data: vec![
                Field {
                    name: "velocity".into(),
                    components: 3,
                    values: vec![3.0, 4.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
                },
                Field {
                    name: "stress".into(),
                    components: 6,
                    values: [[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]; 3].concat(),
                },
            ],
            cell_data: vec![Field::scalar("area", vec![0.5])],
        }
    }

    #[test]
    fn fields_by_name() {
        let g = grid();
        let v = select(&g, "velocity").unwrap();
        assert_eq!(v.values, [5.0, 0.0, 1.0]);
        assert_eq!(v.title, "velocity magnitude (m/s)");
        assert_eq!(select(&g, "velocity_y").unwrap().values, [4.0, 0.0, 0.0]);
        assert_eq!(select(&g, "stress_xx").unwrap().values, [1.0; 3]);
        // Uniaxial stress: von Mises equals it.
        assert_eq!(select(&g, "von_mises").unwrap().values, [1.0; 3]);
        let area = select(&g, "area").unwrap();
        assert!(!area.per_point && area.title == "area (m^2)");
        assert!(select(&g, "velocity_w").is_none() && select(&g, "pressure").is_none());
        assert!(names(&g).contains(&"stress_xz".to_string()));
    }

    #[test]
    fn history_columns() {
        let csv = "time_s,patches,front_energy_j,kinetic_j,strain_j,boundary_work_j,dissipation_j,\
                   interface_work_j\n0e0,0,1e0,5e-1,5e-1,0e0,0e0,0e0\n1e-6,10,1e0,4e-1,6e-1,0e0,1e-9,0e0\n";
        let image = history_chart(csv).unwrap().render((800, 500)).unwrap();
        let count = |rgb: [u8; 3]| image.rgb.chunks(3).filter(|p| *p == rgb).count();
        // Five series in the first five colours (Tableau 10); the interface work, zero
        // throughout, is left out, so the sixth colour is not drawn.
        let colours = [
            [31, 119, 180],
            [255, 127, 14],
            [44, 160, 44],
            [214, 39, 40],
            [148, 103, 189],
        ];
        for rgb in colours {
            assert!(count(rgb) > 0, "{rgb:?}");
        }
        assert_eq!(count([140, 86, 75]), 0);
        assert!(history_chart("time_s,x\n").is_err());
    }
}
