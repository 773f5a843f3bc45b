//! Reader for Gmsh MSH 4.1 ASCII files of planar triangulations.
//!
//! Contract:
//! - Only MSH 4.1 ASCII is read (`$MeshFormat` line `4.1 0 8`). `$MeshFormat`, `$PhysicalNames`,
//!   `$Entities`, `$Nodes` and `$Elements` are parsed; `$PartitionedEntities` is rejected; any
//!   other section is skipped. `$Entities` and `$Nodes` must precede `$Elements`, as Gmsh
//!   writes them.
//! - Coordinates are in metres. All nodes must share one z (up to 1e-9 of the xy extent); z is
//!   dropped.
//! - 3-node triangles (type 2) form the mesh. A 2-node line (type 1) on a curve entity with a
//!   physical tag tags its edge with that dimension-1 physical group: a boundary side, or an
//!   interface when the edge is interior. A curve with several physical tags uses the first;
//!   without `$Entities` no edge is tagged.
//!   Lines on curves without a physical tag and points (type 15) are ignored; any other
//!   element type, and elements on volume entities, are errors.
//! - Tag names are the dimension-1 physical groups (named in `$PhysicalNames` or used by a
//!   curve) in increasing physical-tag order; an unnamed group is named by its number. Groups
//!   with the same name share one tag.
//! - Nodes used by no triangle are dropped; the others become vertices `0..` in increasing
//!   node-tag order.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::path::Path;
use std::str::{FromStr, SplitWhitespace};

use crate::geometry::Point;
use crate::mesh::{Mesh, MeshError, TagId, VertexId};

/// Why an MSH file cannot be read: the file, the 1-based line (0 when the problem concerns no
/// single line, e.g. an I/O error or a missing section) and the reason.
#[derive(Debug, thiserror::Error)]
#[error("{file}{}: {reason}", line_suffix(*line))]
pub struct GmshError {
    /// File name as given to [`read_msh`] or [`parse_msh`].
    pub file: String,
    /// 1-based line number, or 0.
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

/// `:N` for line `N`, nothing for line 0 (the whole file).
fn line_suffix(line: usize) -> String {
    if line > 0 {
        format!(":{line}")
    } else {
        String::new()
    }
}

/// Reads a planar triangulation from the MSH 4.1 ASCII file at `path` (see the module docs).
pub fn read_msh(path: &Path) -> Result<Mesh, GmshError> {
    let file = path.display().to_string();
    // A device or pipe (`/dev/zero`) may never end.
    if let Ok(meta) = std::fs::metadata(path)
        && !meta.is_file()
        && !meta.is_dir()
    {
        return Err(GmshError {
            file,
            line: 0,
            reason: "not a regular file".into(),
        });
    }
    match std::fs::read(path) {
        Ok(bytes) => parse_msh(&String::from_utf8_lossy(&bytes), &file),
        Err(e) => Err(GmshError {
            file,
            line: 0,
            reason: format!("cannot read the file: {e}"),
        }),
    }
}

/// Parses a planar triangulation from MSH 4.1 ASCII `text` (see the module docs); `source`
/// names the file in error messages.
pub fn parse_msh(text: &str, source: &str) -> Result<Mesh, GmshError> {
    parse(text).map_err(|e| GmshError {
        file: source.to_owned(),
        ..e
    })
}

/// An error whose file name [`parse_msh`] fills in.
fn fail(line: usize, reason: impl Into<String>) -> GmshError {
    GmshError {
        file: String::new(),
        line,
        reason: reason.into(),
    }
}

/// The whitespace-separated fields of one line.
struct Fields<'a> {
    line: usize,
    tokens: SplitWhitespace<'a>,
}

impl<'a> Fields<'a> {
    fn token(&mut self, what: &str) -> Result<&'a str, GmshError> {
        self.tokens
            .next()
            .ok_or_else(|| fail(self.line, format!("the line ends early: expected {what}")))
    }

    fn int<T: FromStr>(&mut self, what: &str) -> Result<T, GmshError> {
        let token = self.token(what)?;
        token.parse().map_err(|_| {
            fail(
                self.line,
                format!("expected {what} (an integer), found `{token}`"),
            )
        })
    }

    fn count(&mut self, what: &str) -> Result<usize, GmshError> {
        let token = self.token(what)?;
        token.parse().map_err(|_| {
            fail(
                self.line,
                format!("expected {what} (a non-negative integer), found `{token}`"),
            )
        })
    }

    fn float(&mut self, what: &str) -> Result<f64, GmshError> {
        let token = self.token(what)?;
        match token.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(_) => Err(fail(self.line, format!("{what} `{token}` is not finite"))),
            Err(_) => Err(fail(
                self.line,
                format!("expected {what} (a number), found `{token}`"),
            )),
        }
    }

    /// Reads `n` physical or bounding tags.
    fn tags(&mut self, n: usize, what: &str) -> Result<Vec<i32>, GmshError> {
        (0..n).map(|_| self.int(what)).collect()
    }

    fn finish(mut self) -> Result<(), GmshError> {
        match self.tokens.next() {
            Some(extra) => Err(fail(
                self.line,
                format!("unexpected extra field `{extra}` at the end of the line"),
            )),
            None => Ok(()),
        }
    }
}

/// Non-blank lines with their 1-based numbers.
struct Reader<'a> {
    lines: Vec<&'a str>,
    next: usize,
}

impl<'a> Reader<'a> {
    fn new(text: &'a str) -> Self {
        Self {
            lines: text.lines().collect(),
            next: 0,
        }
    }

    /// The next non-blank line, trimmed, with its number.
    fn line(&mut self) -> Option<(usize, &'a str)> {
        while self.next < self.lines.len() {
            self.next += 1;
            let text = self.lines[self.next - 1].trim();
            if !text.is_empty() {
                return Some((self.next, text));
            }
        }
        None
    }

    /// The fields of the next data line of `section`, which should hold `what`.
    fn data(&mut self, section: &str, what: &str) -> Result<Fields<'a>, GmshError> {
        let (line, text) = self.data_line(section, what)?;
        Ok(Fields {
            line,
            tokens: text.split_whitespace(),
        })
    }

    /// The next data line of `section`, which should hold `what`, with its number.
    fn data_line(&mut self, section: &str, what: &str) -> Result<(usize, &'a str), GmshError> {
        match self.line() {
            None => Err(fail(
                self.lines.len(),
                format!("unexpected end of file while reading section ${section}: expected {what}"),
            )),
            Some((line, text)) if text.starts_with('$') => Err(fail(
                line,
                format!("unexpected `{text}` in section ${section}: expected {what}"),
            )),
            Some(found) => Ok(found),
        }
    }

    /// Consumes the `$End{section}` line that must follow the section's content.
    fn end(&mut self, section: &str) -> Result<(), GmshError> {
        match self.line() {
            Some((_, text)) if text == format!("$End{section}") => Ok(()),
            Some((line, text)) => Err(fail(
                line,
                format!(
                    "expected `$End{section}` after the content its header declares, found `{text}`"
                ),
            )),
            None => Err(fail(
                self.lines.len(),
                format!("unexpected end of file: missing `$End{section}`"),
            )),
        }
    }

    /// Skips the lines of a section opened on line `start` up to its `$End{section}` line.
    fn skip(&mut self, section: &str, start: usize) -> Result<(), GmshError> {
        let end = format!("$End{section}");
        while let Some((_, text)) = self.line() {
            if text == end {
                return Ok(());
            }
        }
        Err(fail(
            start,
            format!("section ${section} has no `{end}` line"),
        ))
    }
}

/// Nodes of `$Nodes` in file order, indexed by tag.
struct Nodes {
    tags: Vec<u64>,
    points: Vec<Point>,
    index: HashMap<u64, usize>,
}

/// What `$Elements` contributes: triangles and physically tagged lines as indices into
/// [`Nodes`], each with the line it was read from.
struct Elements {
    line: usize,
    triangles: Vec<([usize; 3], usize)>,
    segments: Vec<([usize; 2], i32, usize)>,
}

/// The parsed sections, each with the line of its header.
#[derive(Default)]
struct Sections {
    format: Option<usize>,
    physical_names: Option<(usize, BTreeMap<i32, String>)>,
    curves: Option<(usize, HashMap<i32, Option<i32>>)>,
    nodes: Option<(usize, Nodes)>,
    elements: Option<Elements>,
}

fn duplicate(line: usize, section: &str, first: usize) -> GmshError {
    fail(
        line,
        format!("duplicate section ${section} (the first one is on line {first})"),
    )
}

fn parse(text: &str) -> Result<Mesh, GmshError> {
    let mut reader = Reader::new(text);
    let mut s = Sections::default();
    while let Some((line, header)) = reader.line() {
        let Some(name) = header.strip_prefix('$') else {
            return Err(fail(
                line,
                format!("expected a section header such as `$Nodes`, found `{header}`"),
            ));
        };
        if s.format.is_none() && name != "MeshFormat" {
            return Err(fail(
                line,
                format!("expected `$MeshFormat` as the first section, found `{header}`"),
            ));
        }
        match name {
            "MeshFormat" => {
                if let Some(first) = s.format {
                    return Err(duplicate(line, name, first));
                }
                mesh_format(&mut reader)?;
                s.format = Some(line);
            }
            "PhysicalNames" => {
                if let Some((first, _)) = s.physical_names {
                    return Err(duplicate(line, name, first));
                }
                s.physical_names = Some((line, physical_names(&mut reader)?));
            }
            "Entities" => {
                if let Some((first, _)) = s.curves {
                    return Err(duplicate(line, name, first));
                }
                if let Some(elements) = &s.elements {
                    return Err(fail(
                        line,
                        format!(
                            "$Entities must come before $Elements (line {})",
                            elements.line
                        ),
                    ));
                }
                s.curves = Some((line, entities(&mut reader)?));
            }
            "Nodes" => {
                if let Some((first, _)) = s.nodes {
                    return Err(duplicate(line, name, first));
                }
                s.nodes = Some((line, nodes(&mut reader)?));
            }
            "Elements" => {
                if let Some(first) = &s.elements {
                    return Err(duplicate(line, name, first.line));
                }
                let Some((_, nodes)) = &s.nodes else {
                    return Err(fail(line, "$Elements comes before $Nodes"));
                };
                let curves = s.curves.as_ref().map(|(_, c)| c);
                s.elements = Some(elements(&mut reader, line, nodes, curves)?);
            }
            "PartitionedEntities" => {
                return Err(fail(
                    line,
                    "unsupported: partitioned mesh; save the mesh unpartitioned",
                ));
            }
            _ => reader.skip(name, line)?,
        }
    }
    if s.format.is_none() {
        return Err(fail(0, "not an MSH file: no $MeshFormat section"));
    }
    let Some((_, nodes)) = s.nodes else {
        return Err(fail(0, "missing $Nodes section"));
    };
    let Some(elements) = s.elements else {
        return Err(fail(0, "missing $Elements section"));
    };
    let names = s.physical_names.map(|(_, n)| n).unwrap_or_default();
    let curves = s.curves.map(|(_, c)| c).unwrap_or_default();
    build(&nodes, &elements, &names, &curves)
}

/// `$MeshFormat`: `version file-type data-size`; only `4.1` ASCII is accepted.
fn mesh_format(reader: &mut Reader) -> Result<(), GmshError> {
    let section = "MeshFormat";
    let mut f = reader.data(section, "`version file-type data-size`")?;
    let version = f.token("the version")?;
    if version != "4.1" {
        return Err(fail(
            f.line,
            format!(
                "MSH version {version} is not supported; save as MSH 4.1 (Mesh.MshFileVersion = 4.1)"
            ),
        ));
    }
    let file_type: u8 = f.int("the file type")?;
    match file_type {
        0 => {}
        1 => {
            return Err(fail(
                f.line,
                "binary MSH is not supported; save as ASCII (Mesh.Binary = 0)",
            ));
        }
        _ => {
            return Err(fail(
                f.line,
                format!("unknown file type {file_type} (0 is ASCII)"),
            ));
        }
    }
    f.count("the data size")?;
    f.finish()?;
    reader.end(section)
}

/// `$PhysicalNames`: the names of the dimension-1 physical groups by tag.
fn physical_names(reader: &mut Reader) -> Result<BTreeMap<i32, String>, GmshError> {
    let section = "PhysicalNames";
    let mut header = reader.data(section, "the number of physical names")?;
    let n = header.count("the number of physical names")?;
    header.finish()?;
    let mut names = BTreeMap::new();
    for _ in 0..n {
        let (line, text) = reader.data_line(section, "a physical name line `dim tag \"name\"`")?;
        let quoted = text
            .split_once('"')
            .and_then(|(head, rest)| Some((head, rest.strip_suffix('"')?)));
        let Some((head, name)) = quoted else {
            return Err(fail(
                line,
                format!(
                    "expected `dim tag \"name\"` with the name in double quotes, found `{text}`"
                ),
            ));
        };
        let mut f = Fields {
            line,
            tokens: head.split_whitespace(),
        };
        let dim: u8 = f.int("the physical group dimension")?;
        let tag: i32 = f.int("the physical tag")?;
        f.finish()?;
        if dim == 1 && names.insert(tag, name.to_owned()).is_some() {
            return Err(fail(
                line,
                format!("physical curve group {tag} is named twice"),
            ));
        }
    }
    reader.end(section)?;
    Ok(names)
}

/// `$Entities`: the first physical tag of each curve, by curve tag.
fn entities(reader: &mut Reader) -> Result<HashMap<i32, Option<i32>>, GmshError> {
    let section = "Entities";
    let mut header = reader.data(section, "`numPoints numCurves numSurfaces numVolumes`")?;
    let points = header.count("the number of points")?;
    let counts = [
        header.count("the number of curves")?,
        header.count("the number of surfaces")?,
        header.count("the number of volumes")?,
    ];
    header.finish()?;
    for _ in 0..points {
        let mut f = reader.data(section, "a point entity line")?;
        f.int::<i32>("the point tag")?;
        for what in ["x", "y", "z"] {
            f.float(what)?;
        }
        let n = f.count("the number of physical tags")?;
        f.tags(n, "a physical tag")?;
        f.finish()?;
    }
    let mut curves = HashMap::new();
    for (dim, count) in (1..).zip(counts) {
        for _ in 0..count {
            let mut f = reader.data(section, "an entity line")?;
            let tag: i32 = f.int("the entity tag")?;
            for what in ["minX", "minY", "minZ", "maxX", "maxY", "maxZ"] {
                f.float(what)?;
            }
            let n = f.count("the number of physical tags")?;
            let physical = f.tags(n, "a physical tag")?;
            let n = f.count("the number of bounding entities")?;
            f.tags(n, "a bounding entity tag")?;
            let line = f.line;
            f.finish()?;
            if dim == 1 && curves.insert(tag, physical.first().copied()).is_some() {
                return Err(fail(line, format!("curve entity {tag} is listed twice")));
            }
        }
    }
    reader.end(section)?;
    Ok(curves)
}

/// `$Nodes`: all node blocks; checks that the nodes lie in one plane z = const.
fn nodes(reader: &mut Reader) -> Result<Nodes, GmshError> {
    let section = "Nodes";
    let what = "`numEntityBlocks numNodes minNodeTag maxNodeTag`";
    let mut header = reader.data(section, what)?;
    let header_line = header.line;
    let blocks = header.count("the number of entity blocks")?;
    let declared = header.count("the number of nodes")?;
    header.count("the minimum node tag")?;
    header.count("the maximum node tag")?;
    header.finish()?;
    let mut nodes = Nodes {
        tags: Vec::new(),
        points: Vec::new(),
        index: HashMap::new(),
    };
    let mut z = Vec::new();
    for _ in 0..blocks {
        let what = "a block header `entityDim entityTag parametric numNodesInBlock`";
        let mut f = reader.data(section, what)?;
        let dim: usize = f.count("the entity dimension")?;
        f.int::<i32>("the entity tag")?;
        let parametric = f.count("the parametric flag")?;
        let n = f.count("the number of nodes in the block")?;
        let line = f.line;
        f.finish()?;
        if dim > 3 || parametric > 1 {
            return Err(fail(
                line,
                format!("invalid entity dimension {dim} or parametric flag {parametric}"),
            ));
        }
        let first = nodes.tags.len();
        for _ in 0..n {
            let mut f = reader.data(section, "a node tag")?;
            let tag: u64 = f.int("a node tag")?;
            let line = f.line;
            f.finish()?;
            if nodes.index.insert(tag, nodes.tags.len()).is_some() {
                return Err(fail(line, format!("node {tag} is defined twice")));
            }
            nodes.tags.push(tag);
        }
        for i in 0..n {
            let tag = nodes.tags[first + i];
            let mut f = reader.data(section, "node coordinates `x y z`")?;
            let point = [f.float("the x coordinate")?, f.float("the y coordinate")?];
            z.push((f.float("the z coordinate")?, f.line, tag));
            for _ in 0..parametric * dim {
                f.float("a parametric coordinate")?;
            }
            f.finish()?;
            nodes.points.push(point);
        }
    }
    if nodes.tags.len() != declared {
        return Err(fail(
            header_line,
            format!(
                "the header declares {declared} nodes, but the blocks hold {}",
                nodes.tags.len()
            ),
        ));
    }
    reader.end(section)?;
    let extent = |axis: usize| {
        let (lo, hi) = nodes
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[axis]), hi.max(p[axis]))
            });
        hi - lo
    };
    let tolerance = 1e-9 * extent(0).hypot(extent(1));
    let z0 = z.first().map_or(0.0, |&(z0, _, _)| z0);
    match z.iter().find(|(zi, _, _)| (zi - z0).abs() > tolerance) {
        Some(&(zi, line, tag)) => Err(fail(
            line,
            format!(
                "node {tag} has z = {zi}, but node {} has z = {z0}: the mesh must lie in a plane z = const",
                nodes.tags[0]
            ),
        )),
        None => Ok(nodes),
    }
}

/// `$Elements`: triangles and the lines of curves with a physical tag. `curves` is `None`
/// when the file has no `$Entities` section (then no line is tagged).
fn elements(
    reader: &mut Reader,
    section_line: usize,
    nodes: &Nodes,
    curves: Option<&HashMap<i32, Option<i32>>>,
) -> Result<Elements, GmshError> {
    let section = "Elements";
    let what = "`numEntityBlocks numElements minElementTag maxElementTag`";
    let mut header = reader.data(section, what)?;
    let header_line = header.line;
    let blocks = header.count("the number of entity blocks")?;
    let declared = header.count("the number of elements")?;
    header.count("the minimum element tag")?;
    header.count("the maximum element tag")?;
    header.finish()?;
    let mut out = Elements {
        line: section_line,
        triangles: Vec::new(),
        segments: Vec::new(),
    };
    let mut total = 0;
    for _ in 0..blocks {
        let what = "a block header `entityDim entityTag elementType numElementsInBlock`";
        let mut f = reader.data(section, what)?;
        let dim = f.count("the entity dimension")?;
        let entity: i32 = f.int("the entity tag")?;
        let element_type = f.count("the element type")?;
        let n = f.count("the number of elements in the block")?;
        let line = f.line;
        f.finish()?;
        if dim == 3 && n > 0 {
            return Err(fail(
                line,
                format!("3D meshes are not supported (volume {entity} has elements)"),
            ));
        }
        let (expected_dim, node_count) = match element_type {
            15 => (0, 1),
            1 => (1, 2),
            2 => (2, 3),
            _ => {
                return Err(fail(
                    line,
                    format!(
                        "unsupported element type {element_type} (only 3-node triangles and 2-node lines)"
                    ),
                ));
            }
        };
        if dim != expected_dim {
            return Err(fail(
                line,
                format!(
                    "element type {element_type} on an entity of dimension {dim} (expected {expected_dim})"
                ),
            ));
        }
        let physical = match (element_type, curves) {
            (1, Some(curves)) => *curves.get(&entity).ok_or_else(|| {
                fail(
                    line,
                    format!("the block refers to curve {entity}, which $Entities does not list"),
                )
            })?,
            _ => None,
        };
        for _ in 0..n {
            let mut f = reader.data(section, "an element line `elementTag nodeTag...`")?;
            f.int::<u64>("the element tag")?;
            let mut ids = [0; 3];
            for id in &mut ids[..node_count] {
                let tag: u64 = f.int("a node tag")?;
                *id = *nodes
                    .index
                    .get(&tag)
                    .ok_or_else(|| fail(f.line, format!("node {tag} is not defined in $Nodes")))?;
            }
            let line = f.line;
            f.finish()?;
            match (element_type, physical) {
                (2, _) => out.triangles.push((ids, line)),
                (1, Some(group)) => out.segments.push(([ids[0], ids[1]], group, line)),
                _ => {}
            }
        }
        total += n;
    }
    if total != declared {
        return Err(fail(
            header_line,
            format!("the header declares {declared} elements, but the blocks hold {total}"),
        ));
    }
    reader.end(section)?;
    Ok(out)
}

/// Assembles the mesh: compact vertex numbering, tag names, tagged edges.
fn build(
    nodes: &Nodes,
    elements: &Elements,
    names: &BTreeMap<i32, String>,
    curves: &HashMap<i32, Option<i32>>,
) -> Result<Mesh, GmshError> {
    if elements.triangles.is_empty() {
        return Err(fail(
            elements.line,
            "no 3-node triangles (element type 2) in $Elements",
        ));
    }
    let used: BTreeSet<(u64, usize)> = elements
        .triangles
        .iter()
        .flat_map(|(ids, _)| ids.map(|i| (nodes.tags[i], i)))
        .collect();
    let mut vertex_of = HashMap::new();
    let mut vertices = Vec::with_capacity(used.len());
    let mut vertex_tags = Vec::with_capacity(used.len());
    for &(tag, i) in &used {
        vertex_of.insert(i, vertices.len() as VertexId);
        vertices.push(nodes.points[i]);
        vertex_tags.push(tag);
    }
    let triangles: Vec<[VertexId; 3]> = elements
        .triangles
        .iter()
        .map(|(ids, _)| ids.map(|i| vertex_of[&i]))
        .collect();

    let mut groups: BTreeMap<i32, String> = names.clone();
    for &group in curves.values().flatten() {
        groups.entry(group).or_insert_with(|| group.to_string());
    }
    let mut tag_names: Vec<String> = Vec::new();
    let mut tag_of = HashMap::new();
    for (group, name) in groups {
        let id = match tag_names.iter().position(|n| *n == name) {
            Some(id) => id,
            None => {
                tag_names.push(name);
                tag_names.len() - 1
            }
        };
        let id = TagId::try_from(id)
            .map_err(|_| fail(0, "too many physical curve groups for 16-bit tag ids"))?;
        tag_of.insert(group, id);
    }

    let edges: HashSet<[VertexId; 2]> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |i| sorted([t[i], t[(i + 1) % 3]])))
        .collect();
    let mut tagged = Vec::with_capacity(elements.segments.len());
    for &(ids, group, line) in &elements.segments {
        let edge = ids.map(|i| vertex_of.get(&i).copied());
        match edge {
            [Some(a), Some(b)] if edges.contains(&sorted([a, b])) => {
                tagged.push(([a, b], tag_of[&group]));
            }
            _ => {
                return Err(fail(
                    line,
                    format!(
                        "the line from node {} to node {} is not an edge of any triangle",
                        nodes.tags[ids[0]], nodes.tags[ids[1]]
                    ),
                ));
            }
        }
    }

    Mesh::new(vertices, triangles, tag_names, &tagged).map_err(|e| {
        let line_of = |t: usize| elements.triangles[t].1;
        match e {
            MeshError::DegenerateTriangle { triangle } => {
                fail(line_of(triangle), format!("invalid triangulation: {e}"))
            }
            MeshError::Overlap(_, t) => {
                fail(line_of(t as usize), format!("invalid triangulation: {e}"))
            }
            MeshError::NonManifoldEdge(a, b) => fail(
                elements.line,
                format!(
                    "invalid triangulation: {e} (vertices {a} and {b} are nodes {} and {})",
                    vertex_tags[a as usize], vertex_tags[b as usize]
                ),
            ),
            _ => fail(elements.line, format!("invalid triangulation: {e}")),
        }
    })
}

fn sorted([a, b]: [VertexId; 2]) -> [VertexId; 2] {
    [a.min(b), a.max(b)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device that never ends is refused before it is read.
    #[cfg(target_os = "linux")]
    #[test]
    fn devices_are_not_read() {
        let e = read_msh(Path::new("/dev/zero")).unwrap_err();
        assert_eq!((e.file.as_str(), e.line), ("/dev/zero", 0));
        assert_eq!(e.reason, "not a regular file");
    }

    /// A unit square of 2 triangles: physical curves "left" (1, plus 7 on the same curve),
    /// "bottom" (2), "right" (3), "top" (4), an unnamed interior diagonal (6), an unused node 5
    /// and a skipped `$Comments` section. Line numbers in the tests refer to this text.
    const SQUARE: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
5
1 1 "left"
1 2 "bottom"
1 3 "right"
1 4 "top"
2 9 "square"
$EndPhysicalNames
$Entities
4 5 1 0
1 0 0 0 0
2 1 0 0 0
3 1 1 0 0
4 0 1 0 0
1 0 0 0 1 0 0 1 2 2 1 -2
2 1 0 0 1 1 0 1 3 2 2 -3
3 0 1 0 1 1 0 1 4 2 3 -4
4 0 0 0 0 1 0 2 1 7 2 4 -1
5 0 0 0 1 1 0 1 6 2 1 -3
1 0 0 0 1 1 0 1 9 4 1 2 3 4
$EndEntities
$Nodes
2 5 1 5
0 1 0 1
5
0.5 0.25 0
2 1 1 4
3
1
4
2
1 1 0 0.1 0.2
0 0 0 0 0
0 1 0 0 1
1 0 0 1 0
$EndNodes
$Elements
7 8 1 8
0 1 15 1
8 5
1 1 1 1
1 1 2
1 2 1 1
2 2 3
1 3 1 1
3 3 4
1 4 1 1
4 4 1
1 5 1 1
5 1 3
2 1 2 2
6 1 2 3
7 1 3 4
$EndElements
$Comments
anything
$EndComments
"#;

    /// `SQUARE` with lines replaced: `(n, text)` replaces line `n` (1-based) by `text`.
    fn with_lines(edits: &[(usize, &str)]) -> String {
        let mut lines: Vec<&str> = SQUARE.lines().collect();
        for &(n, text) in edits {
            lines[n - 1] = text;
        }
        lines.join("\n")
    }

    fn with_line(n: usize, text: &str) -> String {
        with_lines(&[(n, text)])
    }

    /// Parses `text`, expecting an error on `line` whose reason contains `reason`.
    fn assert_error(text: &str, line: usize, reason: &str) {
        let e = parse_msh(text, "test.msh").unwrap_err();
        assert_eq!(e.file, "test.msh");
        assert_eq!(e.line, line, "{e}");
        assert!(e.reason.contains(reason), "{e}");
    }

    fn tag_name(mesh: &Mesh, tag: Option<TagId>) -> Option<&str> {
        tag.map(|t| mesh.tag_names()[t as usize].as_str())
    }

    #[test]
    fn reads_unit_square_with_boundary_tags() {
        let m = parse_msh(SQUARE, "square.msh").unwrap();
        assert_eq!(
            m.vertices(),
            &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
        );
        assert_eq!(m.triangles().len(), 2);
        let area: f64 = (0..2).map(|t| m.area(t)).sum();
        assert!((area - 1.0).abs() < 1e-15);
        assert_eq!(m.tag_names(), &["left", "bottom", "right", "top", "6"]);
        for e in m.edges().iter().filter(|e| e.is_boundary()) {
            let [a, b] = e.vertices.map(|v| m.vertex(v));
            let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            let expected = match mid {
                [0.0, _] => "left",
                [1.0, _] => "right",
                [_, 0.0] => "bottom",
                _ => "top",
            };
            assert_eq!(tag_name(&m, e.tag), Some(expected));
        }
    }

    #[test]
    fn interior_physical_line_is_an_interface() {
        let m = parse_msh(SQUARE, "square.msh").unwrap();
        let interfaces: Vec<_> = m.edges().iter().filter(|e| e.is_interface()).collect();
        assert_eq!(interfaces.len(), 1);
        assert_eq!(interfaces[0].vertices, [0, 2]);
        assert_eq!(tag_name(&m, interfaces[0].tag), Some("6"));
    }

    #[test]
    fn reports_malformed_input_with_its_line() {
        let truncated: String = SQUARE.lines().take(50).collect::<Vec<_>>().join("\n");
        assert_error(
            &truncated,
            50,
            "unexpected end of file while reading section $Elements",
        );
        assert_error(&with_line(2, "4.1 1 8"), 2, "binary MSH is not supported");
        assert_error(
            &with_line(2, "2.2 0 8"),
            2,
            "MSH version 2.2 is not supported",
        );
        assert_error(&with_line(37, "0 one 0 0 1"), 37, "found `one`");
        assert_error(&with_line(55, "6 1 2 9"), 55, "node 9 is not defined");
        assert_error(&with_line(54, "2 1 3 1"), 54, "unsupported element type 3");
        assert_error(&with_line(35, "1 1 0.5 0.1 0.2"), 35, "z = 0.5");
        assert_error(&with_line(54, "3 1 4 2"), 54, "3D meshes are not supported");
        assert_error(&with_line(26, "2 6 1 5"), 26, "declares 6 nodes");
        assert_error(&with_line(37, "0 1 0 0 1 7"), 37, "extra field `7`");
        assert_error(&with_line(39, "$Elements"), 39, "expected `$EndNodes`");
        assert_error(&with_line(53, "5 2 4"), 53, "not an edge of any triangle");
        assert_error(
            &with_line(58, "$PartitionedEntities"),
            58,
            "partitioned mesh",
        );
        assert_error(&with_line(60, "$EndPhysicalNames"), 58, "no `$EndComments`");
        let collinear = [
            (29, "0.5 0.5 0"),
            (41, "7 9 1 9"),
            (54, "2 1 2 3"),
            (57, "9 1 5 3\n$EndElements"),
        ];
        assert_error(&with_lines(&collinear), 57, "triangle 2 is degenerate");
        assert_error(&with_line(6, "1 1 left"), 6, "double quotes");
        assert_error(&with_line(1, "$Nodes"), 1, "expected `$MeshFormat`");
        let no_elements: String = SQUARE.lines().take(39).collect::<Vec<_>>().join("\n");
        assert_error(&no_elements, 0, "missing $Elements");
    }

    #[test]
    fn reads_plate_with_hole() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../tests/data/plate_with_hole.msh"
        );
        let m = read_msh(Path::new(path)).unwrap();
        let area: f64 = (0..m.triangles().len() as u32).map(|t| m.area(t)).sum();
        let exact = 16e-6 - std::f64::consts::PI * 1e-6;
        assert!((area - exact).abs() < 0.01 * exact, "area {area}");
        for side in ["left", "right", "bottom", "top", "hole"] {
            assert!(m.tag_id(side).is_some(), "no tag {side}");
        }
        let hole = m.tag_id("hole");
        let mut hole_edges = 0;
        for e in m.edges().iter().filter(|e| e.is_boundary()) {
            assert!(e.tag.is_some(), "untagged boundary edge {:?}", e.vertices);
            if e.tag == hole {
                hole_edges += 1;
                for v in e.vertices {
                    let p = m.vertex(v);
                    let r = (p[0] - 2e-3).hypot(p[1] - 2e-3);
                    assert!((r - 1e-3).abs() < 1e-12, "hole vertex at radius {r}");
                }
            }
        }
        assert!(hole_edges > 8);
        assert_eq!(m.edges().iter().filter(|e| e.is_interface()).count(), 0);
    }

    #[test]
    fn truncated_file_names_a_line() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/truncated.msh");
        let e = read_msh(Path::new(path)).unwrap_err();
        assert!(e.line > 0, "{e}");
        assert!(e.file.ends_with("truncated.msh"));
        assert!(e.reason.contains("unexpected end of file"), "{e}");
        let missing = read_msh(Path::new("no/such/file.msh")).unwrap_err();
        assert_eq!(missing.line, 0);
    }
}
