//! A reader of VTK XML unstructured grids (`.vtu`) as written by our snapshots, meshio and VTK.
//!
//! Supported: one `Piece`; `DataArray`s in `ascii`, inline `binary` (base64) and `appended`
//! (raw or base64) format, uncompressed or zlib-compressed (`vtkZLibDataCompressor`), with
//! `UInt32` or `UInt64` headers, little- or big-endian, of any integer or float type. Not
//! supported (an error naming the file): other compressors (LZMA, LZ4), several pieces, other
//! dataset types.

use std::path::Path;

use crate::error::EngineError;
use crate::output::Field;

/// The contents of a `.vtu` file, values converted to `f64`.
#[derive(Clone, Debug, Default)]
pub struct VtuGrid {
    /// Point coordinates.
    pub points: Vec<[f64; 3]>,
    /// Point indices of all cells, concatenated.
    pub connectivity: Vec<u32>,
    /// End of each cell in `connectivity`.
    pub offsets: Vec<usize>,
    /// VTK cell type of each cell.
    pub types: Vec<u8>,
    /// Per-point fields.
    pub point_data: Vec<Field>,
    /// Per-cell fields.
    pub cell_data: Vec<Field>,
}

/// File-wide encoding settings from the `VTKFile` tag.
#[derive(Clone, Copy, Debug)]
struct Encoding {
    big_endian: bool,
    header_u64: bool,
    zlib: bool,
}

/// A `DataArray` tag and where its data is.
#[derive(Debug)]
struct Array<'a> {
    attrs: Vec<(&'a str, &'a str)>,
    /// The text between the opening and closing tag.
    body: &'a [u8],
}

impl Array<'_> {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }
}

impl VtuGrid {
    /// Reads `path`; every error names the file.
    pub fn read(path: &Path) -> Result<Self, EngineError> {
        let bytes = std::fs::read(path)
            .map_err(|e| EngineError::Input(format!("{}: cannot read: {e}", path.display())))?;
        Self::parse(&bytes)
            .map_err(|reason| EngineError::Input(format!("{}: {reason}", path.display())))
    }

    /// Parses the bytes of a `.vtu` file.
    pub fn parse(bytes: &[u8]) -> Result<Self, String> {
        let mut tags = Tags { bytes, pos: 0 };
        let mut encoding = None;
        let mut section = "";
        let mut pieces = 0;
        let (mut n_points, mut n_cells) = (0, 0);
        let mut grid = Self::default();
        let mut arrays: Vec<(&str, Array)> = Vec::new();
        let mut appended: Option<(&[u8], bool)> = None;
        while let Some(tag) = tags.next_tag()? {
            match tag.name {
                "VTKFile" if !tag.closing => {
                    let attr = |k: &str| tag.attr(k);
                    if attr("type") != Some("UnstructuredGrid") {
                        return Err(format!(
                            "a VTK file of type {:?}, not UnstructuredGrid",
                            attr("type").unwrap_or("(none)")
                        ));
                    }
                    let zlib = match attr("compressor") {
                        None | Some("") => false,
                        Some("vtkZLibDataCompressor") => true,
                        Some(other) => {
                            return Err(format!(
                                "compressor {other} is not supported (only vtkZLibDataCompressor \
                                 or none; meshio: write with compression=\"zlib\" or None)"
                            ));
                        }
                    };
                    encoding = Some(Encoding {
                        big_endian: attr("byte_order") == Some("BigEndian"),
                        header_u64: attr("header_type") == Some("UInt64"),
                        zlib,
                    });
                }
                "Piece" if !tag.closing => {
                    pieces += 1;
                    if pieces > 1 {
                        return Err("several Pieces are not supported".into());
                    }
                    let count = |k: &str| -> Result<usize, String> {
                        tag.attr(k)
                            .and_then(|v| v.trim().parse().ok())
                            .ok_or_else(|| format!("Piece without a valid {k}"))
                    };
                    n_points = count("NumberOfPoints")?;
                    n_cells = count("NumberOfCells")?;
                }
                "PointData" | "CellData" | "Points" | "Cells" if !tag.closing => {
                    section = tag.name;
                }
                "PointData" | "CellData" | "Points" | "Cells" => section = "",
                "DataArray" if !tag.closing => {
                    let body = if tag.self_closing {
                        &[][..]
                    } else {
                        tags.body_until(b"</DataArray>")?
                    };
                    arrays.push((
                        section,
                        Array {
                            attrs: tag.attrs,
                            body,
                        },
                    ));
                }
                "AppendedData" if !tag.closing => {
                    let raw = tag.attr("encoding") != Some("base64");
                    let rest = &bytes[tags.pos..];
                    let start = rest
                        .iter()
                        .position(|&b| b == b'_')
                        .ok_or("AppendedData without its leading `_`")?;
                    appended = Some((&rest[start + 1..], raw));
                    break;
                }
                _ => {}
            }
        }
        let encoding = encoding.ok_or("not a VTK XML file (no VTKFile tag)")?;
        if pieces == 0 {
            return Err("no Piece in the UnstructuredGrid".into());
        }
        for (section, array) in &arrays {
            let values = decode(array, encoding, appended)?;
            let components: usize = array
                .attr("NumberOfComponents")
                .map_or(Ok(1), |c| c.trim().parse())
                .map_err(|_| "a DataArray with an invalid NumberOfComponents".to_string())?;
            let name = array.attr("Name").unwrap_or("");
            let expect = |count: usize, what: &str| {
                if values.len() == count * components {
                    Ok(())
                } else {
                    Err(format!(
                        "DataArray {name:?} has {} values, expected {} for {count} {what}",
                        values.len(),
                        count * components
                    ))
                }
            };
            match *section {
                "Points" => {
                    if components != 3 {
                        return Err("Points must have 3 components".into());
                    }
                    expect(n_points, "points")?;
                    grid.points = values.chunks(3).map(|p| [p[0], p[1], p[2]]).collect();
                }
                "Cells" => {
                    let ints = || values.iter().map(|&v| v as i64);
                    match name {
                        "connectivity" => {
                            grid.connectivity = ints()
                                .map(|i| {
                                    u32::try_from(i)
                                        .ok()
                                        .filter(|&i| (i as usize) < n_points)
                                        .ok_or_else(|| format!("cell point index {i} out of range"))
                                })
                                .collect::<Result<_, _>>()?;
                        }
                        "offsets" => {
                            expect(n_cells, "cells")?;
                            grid.offsets = ints().map(|i| i.max(0) as usize).collect();
                        }
                        "types" => {
                            expect(n_cells, "cells")?;
                            grid.types = ints().map(|i| i.clamp(0, 255) as u8).collect();
                        }
                        _ => {}
                    }
                }
                "PointData" | "CellData" => {
                    let (count, list) = if *section == "PointData" {
                        (n_points, &mut grid.point_data)
                    } else {
                        (n_cells, &mut grid.cell_data)
                    };
                    expect(
                        count,
                        if *section == "PointData" {
                            "points"
                        } else {
                            "cells"
                        },
                    )?;
                    list.push(Field {
                        name: name.to_string(),
                        components,
                        values,
                    });
                }
                _ => {}
            }
        }
        if grid.points.len() != n_points {
            return Err("no Points array".into());
        }
        if grid.offsets.len() != n_cells || grid.types.len() != n_cells {
            return Err("the Cells need connectivity, offsets and types arrays".into());
        }
        let mut previous = 0;
        for &end in &grid.offsets {
            if end < previous || end > grid.connectivity.len() {
                return Err(format!("cell offset {end} is out of order or out of range"));
            }
            previous = end;
        }
        Ok(grid)
    }

    /// The points of cell `c`.
    fn cell(&self, c: usize) -> &[u32] {
        let start = if c == 0 { 0 } else { self.offsets[c - 1] };
        &self.connectivity[start..self.offsets[c]]
    }

    /// The triangles to draw, each with the index of the cell it comes from: triangles (VTK 5)
    /// and the corner triangles of quadratic ones (22), quadrilaterals (9) split in two; other
    /// cells are left out.
    pub fn triangles(&self) -> Vec<([u32; 3], usize)> {
        let mut out = Vec::new();
        for (c, &ty) in self.types.iter().enumerate() {
            let p = self.cell(c);
            match ty {
                5 | 22 if p.len() >= 3 => out.push(([p[0], p[1], p[2]], c)),
                9 if p.len() == 4 => {
                    out.push(([p[0], p[1], p[2]], c));
                    out.push(([p[0], p[2], p[3]], c));
                }
                _ => {}
            }
        }
        out
    }

    /// The line cells (VTK 3) as point index pairs.
    pub fn lines(&self) -> Vec<[u32; 2]> {
        (0..self.types.len())
            .filter(|&c| self.types[c] == 3 && self.cell(c).len() == 2)
            .map(|c| [self.cell(c)[0], self.cell(c)[1]])
            .collect()
    }
}

/// The values of a `DataArray`.
fn decode(
    array: &Array,
    encoding: Encoding,
    appended: Option<(&[u8], bool)>,
) -> Result<Vec<f64>, String> {
    let name = array.attr("Name").unwrap_or("");
    let ty = array.attr("type").unwrap_or("Float64");
    match array.attr("format").unwrap_or("ascii") {
        "ascii" => std::str::from_utf8(array.body)
            .map_err(|_| format!("DataArray {name:?}: ASCII data is not text"))?
            .split_ascii_whitespace()
            .map(|w| {
                w.parse::<f64>()
                    .map_err(|_| format!("DataArray {name:?}: `{w}` is not a number"))
            })
            .collect(),
        "binary" => {
            let bytes = base64(array.body).map_err(|e| format!("DataArray {name:?}: {e}"))?;
            binary(&bytes, ty, encoding).map_err(|e| format!("DataArray {name:?}: {e}"))
        }
        "appended" => {
            let (data, raw) =
                appended.ok_or_else(|| format!("DataArray {name:?} refers to no AppendedData"))?;
            let offset: usize = array
                .attr("offset")
                .and_then(|o| o.trim().parse().ok())
                .filter(|&o| o <= data.len())
                .ok_or_else(|| format!("DataArray {name:?}: missing or invalid offset"))?;
            let bytes = if raw {
                data[offset..].to_vec()
            } else {
                let end = data[offset..]
                    .iter()
                    .position(|&b| b == b'<' || b.is_ascii_whitespace())
                    .map_or(data.len(), |e| offset + e);
                base64(&data[offset..end]).map_err(|e| format!("DataArray {name:?}: {e}"))?
            };
            binary(&bytes, ty, encoding).map_err(|e| format!("DataArray {name:?}: {e}"))
        }
        other => Err(format!("DataArray {name:?}: unknown format {other:?}")),
    }
}

/// Decodes base64 four characters at a time, so that concatenated encodings (a compressed
/// array's header and blocks) decode to their concatenated bytes. Whitespace is skipped.
fn base64(text: &[u8]) -> Result<Vec<u8>, String> {
    let sextet = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let mut group = [0u8; 4];
    let mut n = 0;
    for &c in text.iter().filter(|c| !c.is_ascii_whitespace()) {
        group[n] = c;
        n += 1;
        if n < 4 {
            continue;
        }
        n = 0;
        let pad = group.iter().rev().take_while(|&&c| c == b'=').count();
        if pad > 2 {
            return Err("invalid base64 padding".into());
        }
        let mut bits = 0u32;
        for &c in &group[..4 - pad] {
            bits = bits << 6 | u32::from(sextet(c).ok_or("invalid base64 data")?);
        }
        bits <<= 6 * pad;
        out.extend_from_slice(&bits.to_be_bytes()[1..4 - pad]);
    }
    if n != 0 {
        return Err("base64 data of a length not a multiple of 4".into());
    }
    Ok(out)
}

/// The values of binary array data (header, then data or compressed blocks).
fn binary(bytes: &[u8], ty: &str, encoding: Encoding) -> Result<Vec<f64>, String> {
    let header_size = if encoding.header_u64 { 8 } else { 4 };
    let mut cursor = 0;
    let mut header = || -> Result<usize, String> {
        let b = bytes
            .get(cursor..cursor + header_size)
            .ok_or("binary data shorter than its header")?;
        cursor += header_size;
        let v = match (header_size, encoding.big_endian) {
            (8, false) => u64::from_le_bytes(b.try_into().expect("8 bytes")),
            (8, true) => u64::from_be_bytes(b.try_into().expect("8 bytes")),
            (_, false) => u64::from(u32::from_le_bytes(b.try_into().expect("4 bytes"))),
            (_, true) => u64::from(u32::from_be_bytes(b.try_into().expect("4 bytes"))),
        };
        usize::try_from(v).map_err(|_| "a binary header value too large".to_string())
    };
    let data = if encoding.zlib {
        let blocks = header()?;
        let (_block_size, _last_size) = (header()?, header()?);
        let sizes = (0..blocks)
            .map(|_| header())
            .collect::<Result<Vec<_>, _>>()?;
        let mut start = header_size * (3 + blocks);
        let mut data = Vec::new();
        for size in sizes {
            let block = bytes
                .get(start..start + size)
                .ok_or("compressed data shorter than its header says")?;
            let inflated = miniz_oxide::inflate::decompress_to_vec_zlib(block)
                .map_err(|e| format!("zlib data does not decompress: {e:?}"))?;
            data.extend_from_slice(&inflated);
            start += size;
        }
        data
    } else {
        let len = header()?;
        bytes
            .get(header_size..header_size + len)
            .ok_or("binary data shorter than its header says")?
            .to_vec()
    };
    numbers(&data, ty, encoding.big_endian)
}

/// Bytes of VTK type `ty` as `f64`.
fn numbers(data: &[u8], ty: &str, big_endian: bool) -> Result<Vec<f64>, String> {
    macro_rules! convert {
        ($t:ty) => {{
            const N: usize = std::mem::size_of::<$t>();
            if !data.chunks_exact(N).remainder().is_empty() {
                return Err(format!(
                    "{} bytes are not a whole number of {ty}",
                    data.len()
                ));
            }
            data.chunks_exact(N)
                .map(|c| {
                    let b: [u8; N] = c.try_into().expect("chunk of N bytes");
                    let v = if big_endian {
                        <$t>::from_be_bytes(b)
                    } else {
                        <$t>::from_le_bytes(b)
                    };
                    v as f64
                })
                .collect()
        }};
    }
    Ok(match ty {
        "Float64" => convert!(f64),
        "Float32" => convert!(f32),
        "Int8" => convert!(i8),
        "UInt8" => convert!(u8),
        "Int16" => convert!(i16),
        "UInt16" => convert!(u16),
        "Int32" => convert!(i32),
        "UInt32" => convert!(u32),
        "Int64" => convert!(i64),
        "UInt64" => convert!(u64),
        other => return Err(format!("data type {other} is not supported")),
    })
}

/// An XML tag: name, attributes, whether it is `</name>` or `<name/>`.
#[derive(Debug)]
struct Tag<'a> {
    name: &'a str,
    attrs: Vec<(&'a str, &'a str)>,
    closing: bool,
    self_closing: bool,
}

impl Tag<'_> {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }
}

/// A scanner over the tags of an XML document (enough of XML for VTK files).
struct Tags<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Tags<'a> {
    /// The next element tag, skipping text, comments and processing instructions.
    fn next_tag(&mut self) -> Result<Option<Tag<'a>>, String> {
        loop {
            let Some(open) = self.bytes[self.pos..].iter().position(|&b| b == b'<') else {
                return Ok(None);
            };
            let start = self.pos + open;
            let rest = &self.bytes[start..];
            if rest.starts_with(b"<!--") {
                let end = find(rest, b"-->").ok_or("an unterminated comment")?;
                self.pos = start + end + 3;
                continue;
            }
            let end = rest
                .iter()
                .position(|&b| b == b'>')
                .ok_or("an unterminated tag")?;
            self.pos = start + end + 1;
            if rest.starts_with(b"<?") || rest.starts_with(b"<!") {
                continue;
            }
            let inner = std::str::from_utf8(&rest[1..end]).map_err(|_| "a tag that is not text")?;
            let closing = inner.starts_with('/');
            let self_closing = inner.ends_with('/');
            let inner = inner.trim_start_matches('/').trim_end_matches('/');
            let name_end = inner
                .find(|c: char| c.is_ascii_whitespace())
                .unwrap_or(inner.len());
            return Ok(Some(Tag {
                name: &inner[..name_end],
                attrs: attributes(&inner[name_end..])?,
                closing,
                self_closing,
            }));
        }
    }

    /// The bytes up to `close`, moving past it.
    fn body_until(&mut self, close: &[u8]) -> Result<&'a [u8], String> {
        let rest = &self.bytes[self.pos..];
        let end = find(rest, close).ok_or("a DataArray without its closing tag")?;
        self.pos += end + close.len();
        Ok(&rest[..end])
    }
}

/// `key="value"` pairs (single or double quotes).
fn attributes(mut s: &str) -> Result<Vec<(&str, &str)>, String> {
    let mut out = Vec::new();
    loop {
        s = s.trim_start();
        if s.is_empty() {
            return Ok(out);
        }
        let eq = s
            .find('=')
            .ok_or_else(|| format!("a malformed attribute in `{s}`"))?;
        let key = s[..eq].trim();
        let rest = s[eq + 1..].trim_start();
        let quote = rest
            .chars()
            .next()
            .filter(|&c| c == '"' || c == '\'')
            .ok_or_else(|| format!("attribute {key} without quotes"))?;
        let close = rest[1..]
            .find(quote)
            .ok_or_else(|| format!("attribute {key} without its closing quote"))?;
        out.push((key, &rest[1..1 + close]));
        s = &rest[close + 2..];
    }
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::VtuFormat;
    use crate::output::{CellType, UnstructuredGrid};

    #[test]
    fn our_files_read_back_bit_for_bit() {
        // A strip of 2 n triangles: the binary arrays span several zlib blocks, the last one
        // partial; awkward floats.
        let n = 700;
        let points: Vec<[f64; 3]> = (0..2 * (n + 1))
            .map(|i| [(i / 2) as f64 / 3.0, (i % 2) as f64 * 0.1, -0.0])
            .collect();
        let connectivity = (0..n as u32)
            .flat_map(|c| [2 * c, 2 * c + 2, 2 * c + 1, 2 * c + 1, 2 * c + 2, 2 * c + 3])
            .collect();
        let special = [f64::MAX, f64::MIN_POSITIVE, 5e-324, -0.0, 0.1 + 0.2, -1e300];
        let velocity = (0..3 * points.len())
            .map(|i| special.get(i).copied().unwrap_or((i as f64).sqrt().sin()))
            .collect();
        let grid = UnstructuredGrid {
            cell_type: CellType::Triangle,
            points,
            connectivity,
            point_data: vec![Field {
                name: "velocity".into(),
                components: 3,
                values: velocity,
            }],
            cell_data: vec![Field::scalar(
                "area",
                (0..2 * n).map(|i| (i as f64).exp()).collect(),
            )],
        };
        let empty = UnstructuredGrid {
            cell_type: CellType::Line,
            points: Vec::new(),
            connectivity: Vec::new(),
            point_data: vec![Field::scalar("delta", Vec::new())],
            cell_data: Vec::new(),
        };
        let bits = |fields: &[Field]| -> Vec<(String, usize, Vec<u64>)> {
            fields
                .iter()
                .map(|f| {
                    let values = f.values.iter().map(|v| v.to_bits()).collect();
                    (f.name.clone(), f.components, values)
                })
                .collect()
        };
        for format in [VtuFormat::Ascii, VtuFormat::Binary] {
            let text = grid.to_vtu(format);
            assert_eq!(text, grid.to_vtu(format), "deterministic");
            let read = VtuGrid::parse(text.as_bytes()).unwrap();
            let flat = |p: &[[f64; 3]]| p.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(flat(&read.points), flat(&grid.points), "{format:?}");
            assert_eq!(read.connectivity, grid.connectivity);
            assert_eq!(bits(&read.point_data), bits(&grid.point_data), "{format:?}");
            assert_eq!(bits(&read.cell_data), bits(&grid.cell_data), "{format:?}");
            assert_eq!(read.triangles()[1], ([1, 2, 3], 1));
            assert!(read.lines().is_empty());
            let binary = text.contains("format=\"binary\"");
            assert_eq!(binary, format == VtuFormat::Binary);
            assert_eq!(binary, !text.contains("format=\"ascii\""));
            let read = VtuGrid::parse(empty.to_vtu(format).as_bytes()).unwrap();
            assert!(read.points.is_empty() && read.types.is_empty());
            assert_eq!(bits(&read.point_data), bits(&empty.point_data));
        }
    }

    #[test]
    fn base64_decodes_concatenated_streams() {
        assert_eq!(base64(b"TWFu").unwrap(), b"Man");
        assert_eq!(base64(b"TWE=").unwrap(), b"Ma");
        assert_eq!(base64(b"TQ==TWFu").unwrap(), b"MMan");
        assert!(base64(b"TQ=").is_err());
        assert!(base64(b"T*==").is_err());
    }

    /// A binary array as VTK writes it: header and data, base64, optionally zlib-compressed.
    fn binary_array(values: &[f64], zlib: bool) -> String {
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let encode = |bytes: &[u8]| {
            let mut s = String::new();
            crate::output::files::base64(&mut s, bytes);
            s
        };
        if zlib {
            let packed = miniz_oxide::deflate::compress_to_vec_zlib(&data, 6);
            let header: Vec<u8> = [1u32, 32768, data.len() as u32, packed.len() as u32]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect();
            encode(&header) + &encode(&packed)
        } else {
            let mut bytes = (data.len() as u32).to_le_bytes().to_vec();
            bytes.extend_from_slice(&data);
            encode(&bytes)
        }
    }

    #[test]
    fn binary_and_compressed_arrays() {
        for zlib in [false, true] {
            let compressor = if zlib {
                " compressor=\"vtkZLibDataCompressor\""
            } else {
                ""
            };
            let array = |name: &str, values: &[f64], comps: usize| {
                format!(
                    "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{comps}\" \
                     format=\"binary\">\n{}\n</DataArray>\n",
                    binary_array(values, zlib)
                )
            };
            let text = format!(
                "<?xml version=\"1.0\"?>\n<!-- a comment <with> brackets -->\n<VTKFile \
                 type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\"{compressor}>\n\
                 <UnstructuredGrid><Piece NumberOfPoints=\"3\" NumberOfCells=\"1\">\n<Points>\n{}\
                 </Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2\
                 </DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">3</DataArray>\n\
                 <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">5</DataArray>\n</Cells>\n\
                 <PointData>\n{}</PointData>\n<CellData>\n{}</CellData>\n</Piece></UnstructuredGrid>\n\
                 </VTKFile>\n",
                array("Points", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], 3),
                array("u", &[1.5, -2.0, 3.25], 1),
                array("c", &[7.0], 1),
            );
            let grid = VtuGrid::parse(text.as_bytes()).unwrap();
            assert_eq!(grid.points[2], [0.0, 1.0, 0.0]);
            assert_eq!(grid.point_data[0].values, [1.5, -2.0, 3.25], "zlib {zlib}");
            assert_eq!(grid.cell_data[0].values, [7.0]);
        }
    }

    #[test]
    fn unsupported_files_are_errors() {
        let err = |text: &str| VtuGrid::parse(text.as_bytes()).unwrap_err();
        assert!(err("hello").contains("not a VTK XML file"));
        assert!(err("<VTKFile type=\"PolyData\">").contains("PolyData"));
        assert!(
            err("<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkLZMADataCompressor\">")
                .contains("vtkLZMADataCompressor is not supported")
        );
        assert!(err("<VTKFile type=\"UnstructuredGrid\">").contains("no Piece"));
    }
}
