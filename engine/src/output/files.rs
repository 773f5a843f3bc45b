//! Output files: atomic writes, JSON summaries and VTK XML unstructured grids.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::config::VtuFormat;
use crate::error::EngineError;

use super::fault::Fault;

/// Writes `bytes` to `dir/name` through a temporary file and a rename, so that a failed or
/// interrupted write never leaves a truncated file in place of an earlier complete one; makes
/// the folder first. An error names the file and the I/O error; the temporary file is removed.
pub fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf, EngineError> {
    std::fs::create_dir_all(dir).map_err(|e| EngineError::io(dir, e))?;
    write_whole(dir, name, bytes, false)
}

/// [`write_atomic`] into a run's output folder, which must exist: one removed under the
/// running job is an error naming the file, not made again empty.
pub(crate) fn write_output(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf, EngineError> {
    write_whole(dir, name, bytes, false)
}

/// [`write_output`], with the file synced before the rename and the folder after it, so that a
/// crash of the machine leaves the earlier file or the new one, whole (checkpoints).
pub(crate) fn write_synced(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf, EngineError> {
    let path = write_whole(dir, name, bytes, true)?;
    if let Ok(folder) = std::fs::File::open(dir) {
        // Not every file system syncs folders; the rename itself is atomic either way.
        let _ = folder.sync_all();
    }
    Ok(path)
}

/// Writes `bytes` to the temporary file `dir/.name.tmp`, syncs it if `sync`, and renames it to
/// `dir/name`; a fault of `SDG_FAULT` (see [`Fault`]) strikes on the way.
fn write_whole(dir: &Path, name: &str, bytes: &[u8], sync: bool) -> Result<PathBuf, EngineError> {
    let path = dir.join(name);
    let tmp = dir.join(format!(".{name}.tmp"));
    let fault = Fault::injected(name);
    let write = || -> std::io::Result<()> {
        fault.map_or(Ok(()), Fault::at_create)?;
        let mut file = std::fs::File::create(&tmp)?;
        let (head, tail) = bytes.split_at(bytes.len() / 2);
        file.write_all(head)?;
        fault.map_or(Ok(()), Fault::halfway)?;
        file.write_all(tail)?;
        if sync {
            file.sync_all()?;
        }
        std::fs::rename(&tmp, &path)
    };
    write().map_err(|e| discard(&path, &tmp, e))?;
    Ok(path)
}

/// Checks, before any work, that the folder `dir` can be made and written into: the nearest
/// part of it that exists must be a folder that takes a file. Creates nothing; `named` starts
/// the error (bad input, exit 2) with where the path came from, e.g. `--output out`.
pub fn check_writable(dir: &Path, named: &str) -> Result<(), EngineError> {
    let bad = |reason: String| EngineError::Input(format!("{named}: cannot write there: {reason}"));
    if dir.as_os_str().is_empty() {
        return Err(bad("an empty path; name a folder".into()));
    }
    let mut existing = dir;
    while !existing.exists() {
        match existing.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => existing = parent,
            _ => {
                existing = Path::new(".");
                break;
            }
        }
    }
    if !existing.is_dir() {
        return Err(bad(format!(
            "{} is a file, not a folder",
            existing.display()
        )));
    }
    let probe = existing.join(format!(".sdg_probe_{}", std::process::id()));
    std::fs::File::create(&probe)
        .map(drop)
        .map_err(|e| bad(format!("{}: {e}", existing.display())))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// The error of a failed write of `path` through the temporary file `tmp`, which is removed so
/// that it holds no space (a full disk is the usual cause).
fn discard(path: &Path, tmp: &Path, e: std::io::Error) -> EngineError {
    let _ = std::fs::remove_file(tmp);
    EngineError::Write {
        path: path.into(),
        source: e,
    }
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
/// (`.vtu`, file version 1.0) that ParaView and meshio read.
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
    /// The grid as VTK XML text with its arrays in `format`. Floats read back bit for bit in
    /// either format, and the same grid always gives the same text.
    pub fn to_vtu(&self, format: VtuFormat) -> String {
        let nodes = self.cell_type.nodes();
        let cells = self.connectivity.len() / nodes;
        let compressor = match format {
            VtuFormat::Binary => " compressor=\"vtkZLibDataCompressor\"",
            VtuFormat::Ascii => "",
        };
        let mut s = format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt64\"{compressor}>\n<UnstructuredGrid>\n"
        );
        let _ = writeln!(
            s,
            "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{cells}\">",
            self.points.len()
        );
        let mut out = ArrayWriter { s, format };
        for (tag, data) in [
            ("PointData", &self.point_data),
            ("CellData", &self.cell_data),
        ] {
            let _ = writeln!(out.s, "<{tag}>");
            for f in data {
                let (name, components) = (&f.name, f.components);
                let attrs = match components {
                    1 => format!("Name=\"{name}\""),
                    _ => format!("Name=\"{name}\" NumberOfComponents=\"{components}\""),
                };
                let per_line = if components == 1 { 6 } else { components };
                out.array(&attrs, f.values.iter().copied(), per_line);
            }
            let _ = writeln!(out.s, "</{tag}>");
        }
        out.s.push_str("<Points>\n");
        let points = self.points.iter().flatten().copied();
        out.array("NumberOfComponents=\"3\"", points, 3);
        out.s.push_str("</Points>\n<Cells>\n");
        let connectivity = self.connectivity.iter().map(|&i| i64::from(i));
        out.array("Name=\"connectivity\"", connectivity, nodes);
        let offsets = (1..=cells).map(|c| i64::try_from(c * nodes).expect("offset fits i64"));
        out.array("Name=\"offsets\"", offsets, 10);
        let types = std::iter::repeat_n(self.cell_type.vtk_id(), cells);
        out.array("Name=\"types\"", types, 20);
        out.s
            .push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
        out.s
    }
    /// A parallel VTK file (`.pvtu`) for grids with this grid's fields, whose pieces are the
    /// `.vtu` files `pieces` (names relative to the `.pvtu`). Every field is `Float64`.
    pub fn to_pvtu(&self, pieces: &[String]) -> String {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt64\">\n\
             <PUnstructuredGrid GhostLevel=\"0\">\n",
        );
        for (tag, data) in [
            ("PPointData", &self.point_data),
            ("PCellData", &self.cell_data),
        ] {
            let _ = writeln!(s, "<{tag}>");
            for f in data {
                let _ = writeln!(
                    s,
                    "<PDataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\"/>",
                    f.name, f.components
                );
            }
            let _ = writeln!(s, "</{tag}>");
        }
        s.push_str(
            "<PPoints>\n<PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n</PPoints>\n",
        );
        for piece in pieces {
            let _ = writeln!(s, "<Piece Source=\"{piece}\"/>");
        }
        s.push_str("</PUnstructuredGrid>\n</VTKFile>\n");
        s
    }
}

/// A value type of a `DataArray`: its VTK name, decimal form and little-endian bytes.
trait VtkValue: std::fmt::Display {
    const TYPE: &'static str;
    fn put_le(&self, out: &mut Vec<u8>);
}

macro_rules! vtk_value {
    ($t:ty, $name:literal) => {
        impl VtkValue for $t {
            const TYPE: &'static str = $name;
            fn put_le(&self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
        }
    };
}

vtk_value!(f64, "Float64");
vtk_value!(i64, "Int64");
vtk_value!(u8, "UInt8");

/// Uncompressed bytes per zlib block of a binary array (VTK's default).
const BLOCK: usize = 1 << 15;
/// zlib level of binary arrays: fast; floating-point bits compress little more at higher ones.
const LEVEL: u8 = 1;

/// Appends `DataArray` elements to VTK XML text.
struct ArrayWriter {
    s: String,
    format: VtuFormat,
}

impl ArrayWriter {
    /// Appends a `DataArray` of `values` with extra attributes `attrs`: in ASCII `per_line` values
    /// to a line, floats in Rust's shortest round-trip form; in binary the zlib-compressed
    /// little-endian bytes in VTK's block layout (UInt64 header `[blocks, block size, size of a
    /// partial last block or 0, compressed size of each block]`), header and blocks base64
    /// encoded one after the other.
    fn array<T: VtkValue>(
        &mut self,
        attrs: &str,
        values: impl Iterator<Item = T>,
        per_line: usize,
    ) {
        let out = &mut self.s;
        let ty = T::TYPE;
        match self.format {
            VtuFormat::Ascii => {
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
            }
            VtuFormat::Binary => {
                let _ = writeln!(out, "<DataArray type=\"{ty}\" {attrs} format=\"binary\">");
                let mut raw = Vec::new();
                values.for_each(|v| v.put_le(&mut raw));
                let blocks: Vec<Vec<u8>> = raw
                    .chunks(BLOCK)
                    .map(|b| miniz_oxide::deflate::compress_to_vec_zlib(b, LEVEL))
                    .collect();
                let mut header = Vec::with_capacity(8 * (3 + blocks.len()));
                let sizes = [blocks.len(), BLOCK, raw.len() % BLOCK]
                    .into_iter()
                    .chain(blocks.iter().map(Vec::len));
                sizes.for_each(|n| header.extend_from_slice(&(n as u64).to_le_bytes()));
                base64(out, &header);
                base64(out, &blocks.concat());
                out.push('\n');
            }
        }
        out.push_str("</DataArray>\n");
    }
}

/// Appends the standard base64 encoding of `bytes` (with `=` padding) to `out`.
pub(crate) fn base64(out: &mut String, bytes: &[u8]) {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    out.reserve(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let mut b = [0u8; 3];
        b[..chunk.len()].copy_from_slice(chunk);
        let bits = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            out.push(if k <= chunk.len() {
                char::from(ALPHABET[(bits >> (18 - 6 * k) & 63) as usize])
            } else {
                '='
            });
        }
    }
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
        let text = grid.to_vtu(VtuFormat::Ascii);
        assert!(text.contains("NumberOfPoints=\"4\" NumberOfCells=\"1\""));
        assert!(text.contains("Name=\"time\""));
        assert!(text.contains("Name=\"tent\" NumberOfComponents=\"3\" format=\"ascii\">\n7 8 9\n"));
        assert!(text.contains("0 0 0 0.5\n"));
        assert!(text.contains("Name=\"offsets\" format=\"ascii\">\n4\n"));
        assert!(text.contains("Name=\"types\" format=\"ascii\">\n10\n"));
    }

    #[test]
    fn base64_is_the_standard_encoding() {
        let encode = |bytes: &[u8]| {
            let mut s = String::from(">");
            base64(&mut s, bytes);
            s
        };
        assert_eq!(encode(b""), ">");
        assert_eq!(encode(b"Man"), ">TWFu");
        assert_eq!(encode(b"Ma"), ">TWE=");
        assert_eq!(encode(b"M"), ">TQ==");
        assert_eq!(encode(&[0xfb, 0xff, 0xbf]), ">+/+/");
    }

    #[test]
    fn atomic_write_replaces_the_file() {
        let dir = tempfile::tempdir().unwrap();
        write_atomic(dir.path(), "a.json", b"1").unwrap();
        let path = write_atomic(dir.path(), "a.json", b"2").unwrap();
        assert_eq!(std::fs::read(path).unwrap(), b"2");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_failed_atomic_write_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        // A folder that is not empty where the file should go: the rename fails.
        std::fs::create_dir_all(dir.path().join("a.json").join("inside")).unwrap();
        let err = write_atomic(dir.path(), "a.json", b"1").unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("a.json") && !text.contains(".a.json.tmp"),
            "{text}"
        );
        assert!(!dir.path().join(".a.json.tmp").exists());
    }

    #[test]
    fn a_folder_under_a_file_or_an_empty_path_is_refused_and_nothing_is_created() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("afile"), b"").unwrap();
        let under = dir.path().join("afile").join("sub");
        let err = check_writable(&under, "checkpoint.dir x").unwrap_err();
        assert!(matches!(err, EngineError::Input(_)), "{err}");
        let text = err.to_string();
        assert!(
            text.starts_with("checkpoint.dir ") && text.contains("is a file"),
            "{text}"
        );
        let err = check_writable(Path::new(""), "--trace").unwrap_err();
        assert!(err.to_string().contains("empty path"), "{err}");
        let fresh = dir.path().join("a").join("b");
        check_writable(&fresh, "--output a/b").unwrap();
        assert!(!dir.path().join("a").exists());
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "the probe file is removed");
    }
}
