//! Output files: atomic writes, JSON summaries and VTK XML unstructured grids.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::EngineError;

/// Writes `bytes` to `dir/name` through a temporary file and a rename, so that a failed or
/// interrupted write never leaves a truncated file in place of an earlier complete one.
pub fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf, EngineError> {
    std::fs::create_dir_all(dir).map_err(|e| EngineError::io(dir, e))?;
    let path = dir.join(name);
    let tmp = dir.join(format!(".{name}.tmp"));
    std::fs::write(&tmp, bytes).map_err(|e| EngineError::io(&tmp, e))?;
    std::fs::rename(&tmp, &path).map_err(|e| EngineError::io(&path, e))?;
    Ok(path)
}

/// VTK cell types used here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellType {
    /// 2-node line (VTK 3).
    Line,
    /// 3-node triangle (VTK 5).
    Triangle,
    /// 4-node tetrahedron (VTK 10).
    Tetra,
}

impl CellType {
    fn vtk_id(self) -> u8 {
        match self {
            Self::Line => 3,
            Self::Triangle => 5,
            Self::Tetra => 10,
        }
    }

    fn nodes(self) -> usize {
        match self {
            Self::Line => 2,
            Self::Triangle => 3,
            Self::Tetra => 4,
        }
    }
}

/// A named field with `components` values per point or cell (1 for scalars, 3 for vectors, 6 for
/// symmetric tensors in VTK's order XX, YY, ZZ, XY, YZ, XZ).
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Array name.
    pub name: String,
    /// Values per point or cell.
    pub components: usize,
    /// `components` values per point or cell, flattened.
    pub values: Vec<f64>,
}

impl Field {
    /// A scalar field.
    pub fn scalar(name: &str, values: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            components: 1,
            values,
        }
    }
}

/// An unstructured grid of one cell type with named fields, written as VTK XML
/// (`.vtu`, ASCII, file version 1.0) that ParaView and meshio read.
#[derive(Clone, Debug)]
pub struct UnstructuredGrid {
    /// Cell type of every cell.
    pub cell_type: CellType,
    /// Point coordinates.
    pub points: Vec<[f64; 3]>,
    /// Point indices of each cell, `cell_type.nodes()` per cell, flattened.
    pub connectivity: Vec<u32>,
    /// Per-point fields.
    pub point_data: Vec<Field>,
    /// Per-cell fields.
    pub cell_data: Vec<Field>,
}

impl UnstructuredGrid {
    /// The grid as VTK XML text.
    pub fn to_vtu(&self) -> String {
        let nodes = self.cell_type.nodes();
        let cells = self.connectivity.len() / nodes;
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n",
        );
        let _ = writeln!(
            s,
            "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{cells}\">",
            self.points.len()
        );
        for (tag, data) in [
            ("PointData", &self.point_data),
            ("CellData", &self.cell_data),
        ] {
            let _ = writeln!(s, "<{tag}>");
            for f in data {
                let (name, components) = (&f.name, f.components);
                let attrs = match components {
                    1 => format!("Name=\"{name}\""),
                    _ => format!("Name=\"{name}\" NumberOfComponents=\"{components}\""),
                };
                let per_line = if components == 1 { 6 } else { components };
                data_array(&mut s, "Float64", &attrs, f.values.iter(), per_line);
            }
            let _ = writeln!(s, "</{tag}>");
        }
        s.push_str("<Points>\n");
        let points = self.points.iter().flatten();
        data_array(&mut s, "Float64", "NumberOfComponents=\"3\"", points, 3);
        s.push_str("</Points>\n<Cells>\n");
        let connectivity = self.connectivity.iter();
        data_array(
            &mut s,
            "Int64",
            "Name=\"connectivity\"",
            connectivity,
            nodes,
        );
        let offsets = (1..=cells).map(|c| c * nodes);
        data_array(&mut s, "Int64", "Name=\"offsets\"", offsets, 10);
        let types = std::iter::repeat_n(self.cell_type.vtk_id(), cells);
        data_array(&mut s, "UInt8", "Name=\"types\"", types, 20);
        s.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
        s
    }
}

/// Appends an ASCII `DataArray` of type `ty` with extra attributes `attrs`, `per_line` values to
/// a line. Floats use Rust's shortest round-trip form, so values read back exactly.
fn data_array<T: std::fmt::Display>(
    out: &mut String,
    ty: &str,
    attrs: &str,
    values: impl Iterator<Item = T>,
    per_line: usize,
) {
    let _ = writeln!(out, "<DataArray type=\"{ty}\" {attrs} format=\"ascii\">");
    let mut count = 0;
    for v in values {
        if count > 0 {
            out.push(if count % per_line == 0 { '\n' } else { ' ' });
        }
        let _ = write!(out, "{v}");
        count += 1;
    }
    if count > 0 {
        out.push('\n');
    }
    out.push_str("</DataArray>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vtu_lists_points_cells_and_fields() {
        let grid = UnstructuredGrid {
            cell_type: CellType::Tetra,
            points: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            connectivity: vec![0, 1, 2, 3],
            point_data: vec![Field::scalar("time", vec![0.0, 0.0, 0.0, 0.5])],
            cell_data: vec![Field {
                name: "tent".into(),
                components: 3,
                values: vec![7.0, 8.0, 9.0],
            }],
        };
        let text = grid.to_vtu();
        assert!(text.contains("NumberOfPoints=\"4\" NumberOfCells=\"1\""));
        assert!(text.contains("Name=\"time\""));
        assert!(text.contains("Name=\"tent\" NumberOfComponents=\"3\" format=\"ascii\">\n7 8 9\n"));
        assert!(text.contains("0 0 0 0.5\n"));
        assert!(text.contains("Name=\"offsets\" format=\"ascii\">\n4\n"));
        assert!(text.contains("Name=\"types\" format=\"ascii\">\n10\n"));
    }

    #[test]
    fn atomic_write_replaces_the_file() {
        let dir = tempfile::tempdir().unwrap();
        write_atomic(dir.path(), "a.json", b"1").unwrap();
        let path = write_atomic(dir.path(), "a.json", b"2").unwrap();
        assert_eq!(std::fs::read(path).unwrap(), b"2");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
