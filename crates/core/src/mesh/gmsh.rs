//! Gmsh MSH import and export: ASCII MSH 2.2 and MSH 4.1, 3-node triangles in the plane
//! `z = 0`, phases named by physical surface groups.
//!
//! # Format facts this module relies on
//!
//! Both versions (see the Gmsh reference manual, section "MSH file format"):
//!
//! * A file is a sequence of sections `$Name` ... `$EndName`. The first one is
//!   `$MeshFormat`, whose single line is `version file-type data-size`; `file-type` is `0`
//!   for ASCII and `1` for binary. Sections we do not need (`$NodeData`, `$Periodic`, ...)
//!   are skipped.
//! * `$PhysicalNames`: a count, then one `dimension physical-tag "name"` line per group.
//!   The name is quoted and may contain spaces.
//! * Element type `15` is a 1-node point, `1` a 2-node line, `2` a 3-node triangle. Points
//!   and lines (boundary groups, corners) are skipped; every other type (quadrangles `3`,
//!   second-order elements, 3D elements, ...) is rejected, because the RVE is made of
//!   linear triangles only.
//! * Node coordinates are `x y z`; Gmsh writes them with 16 significant digits, so the
//!   same mesh written in both versions has bit-identical coordinates.
//!
//! MSH 2.2:
//!
//! * `$Nodes`: a count, then `node-tag x y z` lines.
//! * `$Elements`: a count, then `element-tag type number-of-tags tag... node-tag...` lines.
//!   The first tag is the physical group (`0`: none), the second the elementary entity.
//! * An element in several physical groups is written once per group, under different
//!   element tags. The reader therefore merges triangles with the same three nodes and
//!   takes the union of their physical groups.
//!
//! MSH 4.1:
//!
//! * `$Entities`: `numPoints numCurves numSurfaces numVolumes`, then one line per entity.
//!   A surface line is `tag minX minY minZ maxX maxY maxZ numPhysicalTags physicalTag...
//!   numBoundingCurves curveTag...`. Elements carry no physical tag of their own: a
//!   triangle is in the physical groups of its surface entity.
//! * `$Nodes`: `numEntityBlocks numNodes minNodeTag maxNodeTag`, then per block
//!   `entityDim entityTag parametric numNodesInBlock`, the block's node tags (one per
//!   line), then its coordinate lines `x y z`, followed by `entityDim` parametric
//!   coordinates when `parametric` is `1`.
//! * `$Elements`: `numEntityBlocks numElements minElementTag maxElementTag`, then per
//!   block `entityDim entityTag elementType numElementsInBlock` and one
//!   `elementTag nodeTag...` line per element.
//! * Partitioned files (`$PartitionedEntities`) are rejected.
//!
//! The reader is line-oriented: every record sits on its own line, as Gmsh writes it, so
//! that an error can name the line. Blank lines are ignored; `\r\n` line ends are accepted.
//!
//! # What the reader guarantees
//!
//! [`parse_msh`] returns a [`PhaseMesh`] whose nodes are exactly the nodes used by the
//! triangles, numbered `0..n` in increasing order of their Gmsh node tags (tags may be
//! non-contiguous), and whose triangles are in increasing order of their Gmsh element
//! tags, counter-clockwise and non-degenerate. Anything it cannot turn into such a mesh is
//! an [`Error::Gmsh`] naming the line and the reason; no input makes it panic.
//!
//! **Orientation.** In a plane mesh the sign of the signed area is the only orientation
//! information a triangle has, so a clockwise triangle *is* an inverted element
//! (negative Jacobian). The reader rejects it instead of silently reordering its nodes:
//! a flipped element usually means a tangled mesh or a surface meshed with its normal
//! along `-z`, and either deserves the user's attention. Gmsh orients the triangles of a
//! surface along the surface's normal: OpenCASCADE rectangles and disks, and built-in
//! `Plane Surface`s on counter-clockwise curve loops, give counter-clockwise triangles,
//! but a built-in `Plane Surface` on a clockwise `Curve Loop` gives clockwise ones
//! (checked with Gmsh 4.15; `tests/data/gmsh/clockwise_v22.msh`). Such a surface is fixed
//! in Gmsh with `ReverseMesh Surface{...};` in the `.geo` file or
//! `gmsh.model.mesh.reverse()`; the error counts the clockwise triangles, so that a
//! reversed surface (all its triangles) is easy to tell from a tangled element.
//!
//! # Writing
//!
//! [`write_msh22`] and [`write_msh41`] write a [`PhaseMesh`] with the physical surface
//! groups [`MATRIX_GROUP`] (physical tag 1) and [`AGGREGATE_GROUP`] (physical tag 2),
//! one elementary surface per phase with the same tag. Node `i` gets
//! tag `i + 1` and triangle `k` tag `k + 1`, so reading the output back with
//! `parse_msh(text, path, "matrix", &["aggregate".into()])` gives the same mesh, and
//! Gmsh itself opens and re-saves it.

use std::collections::{HashMap, HashSet};
use std::fs;
use std::io::{self, Write};
use std::path::Path;
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::mesh::{Phase, PhaseMesh, Triangle, MAX_TRIANGLES};

/// Name of the physical surface group of the matrix in files we write.
pub const MATRIX_GROUP: &str = "matrix";
/// Physical (and elementary) tag of the matrix in files we write. (Not `pub`: cbindgen
/// would export it into the C header.)
const MATRIX_TAG: i64 = 1;
/// Name of the physical surface group of the inclusions in files we write.
pub const AGGREGATE_GROUP: &str = "aggregate";
/// Physical (and elementary) tag of the inclusions in files we write.
const AGGREGATE_TAG: i64 = 2;

/// A triangle is degenerate when twice its area is at most this fraction of the square
/// of its longest edge, i.e. when its height is below `1e-10` times its longest edge.
const DEGENERATE_RELATIVE_AREA: f64 = 1e-10;

/// A node is off the plane `z = 0` when `|z|` exceeds this fraction of the mesh extent
/// in `x` and `y` (round-off from CAD kernels stays far below it).
const PLANAR_RELATIVE_Z: f64 = 1e-10;

/// Largest MSH file read, in bytes: a mesh at the scene limit of
/// [`MAX_TRIANGLES`] triangles takes about 150 MB in either
/// version, and the reader holds the text and an index of its lines.
pub const MAX_FILE_BYTES: u64 = 512 << 20;

/// Largest node or element count a file may declare (in a header or a 4.1 block): twice
/// the scene limit on triangles, room for the lines and points Gmsh adds.
pub const MAX_DECLARED_ITEMS: usize = 2 * MAX_TRIANGLES;

/// Element types (Gmsh numbering) the reader understands.
const POINT: i64 = 15;
const LINE: i64 = 1;
const TRIANGLE: i64 = 2;

/// Reads a Gmsh MSH 2.2 or 4.1 ASCII file; see [`parse_msh`].
///
/// The file is read as bytes and decoded leniently, so that a binary file is reported as
/// such (from its `$MeshFormat` line) rather than as invalid UTF-8.
pub fn read_msh(path: &Path, matrix_group: &str, inclusion_groups: &[String]) -> Result<PhaseMesh> {
    let io_error = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let size = fs::metadata(path).map_err(io_error)?.len();
    if size > MAX_FILE_BYTES {
        return Err(Error::Gmsh {
            path: path.to_path_buf(),
            line: 1,
            reason: format!(
                "the file has {size} bytes, more than the limit of {MAX_FILE_BYTES} bytes for \
                 an RVE mesh (at most {} triangles)",
                MAX_TRIANGLES
            ),
        });
    }
    let bytes = fs::read(path).map_err(io_error)?;
    let text = String::from_utf8_lossy(&bytes);
    parse_msh(&text, path, matrix_group, inclusion_groups)
}

/// Parses the text of a Gmsh MSH 2.2 or 4.1 ASCII file into a phase-labelled mesh.
///
/// Triangles in the physical surface group named `matrix_group` become
/// [`Phase::Matrix`], those in any of `inclusion_groups` [`Phase::Inclusion`]. Every
/// requested group must be a surface group of `$PhysicalNames`, and every triangle must be
/// in exactly one of the two phases. `path_for_errors` only labels the errors.
///
/// See the [module documentation](self) for the format facts, the node and triangle
/// numbering of the result, and why clockwise triangles are rejected.
pub fn parse_msh(
    text: &str,
    path_for_errors: &Path,
    matrix_group: &str,
    inclusion_groups: &[String],
) -> Result<PhaseMesh> {
    let mut reader = Reader::new(text, path_for_errors);
    let raw = match read_mesh_format(&mut reader)? {
        Version::V22 => read_v22(&mut reader)?,
        Version::V41 => read_v41(&mut reader)?,
    };
    assemble(raw, &reader, matrix_group, inclusion_groups)
}

// ---------------------------------------------------------------------------------------
// Line reader
// ---------------------------------------------------------------------------------------

/// The non-blank lines of the file with their 1-based line numbers.
struct Reader<'a> {
    path: &'a Path,
    lines: Vec<(usize, &'a str)>,
    next: usize,
    /// Number of the file's last line, for errors at the end of the file.
    last_line: usize,
}

impl<'a> Reader<'a> {
    fn new(text: &'a str, path: &'a Path) -> Self {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut last_line = 0;
        let mut lines = Vec::new();
        for (i, line) in text.lines().enumerate() {
            last_line = i + 1;
            let line = line.trim();
            if !line.is_empty() {
                lines.push((i + 1, line));
            }
        }
        Reader {
            path,
            lines,
            next: 0,
            last_line,
        }
    }

    fn error(&self, line: usize, reason: impl Into<String>) -> Error {
        Error::Gmsh {
            path: self.path.to_path_buf(),
            line,
            reason: reason.into(),
        }
    }

    /// The next line, or `None` at the end of the file.
    fn try_next(&mut self) -> Option<Record<'a>> {
        let &(number, text) = self.lines.get(self.next)?;
        self.next += 1;
        Some(Record {
            path: self.path,
            number,
            text,
            rest: text,
            is_last: self.next == self.lines.len(),
        })
    }

    /// The next line; the end of the file is an error ("truncated file") that says what
    /// was expected.
    fn next(&mut self, expected: &str) -> Result<Record<'a>> {
        self.try_next().ok_or_else(|| {
            self.error(
                self.last_line,
                format!("file ends while reading {expected} (truncated file?)"),
            )
        })
    }

    /// Expects the line `$End<section>`.
    fn expect_end(&mut self, section: &str) -> Result<()> {
        let end = format!("$End{section}");
        let line = self.next(&format!("`{end}`"))?;
        if line.text == end {
            Ok(())
        } else {
            Err(line.error(format!(
                "expected `{end}`, found `{}` (wrong count or extra lines in ${section})",
                truncate(line.text, 40)
            )))
        }
    }

    /// Skips a section we do not read, up to and including its `$End` line.
    fn skip_section(&mut self, section: &str) -> Result<()> {
        let end = format!("$End{section}");
        loop {
            if self.next(&format!("`{end}`"))?.text == end {
                return Ok(());
            }
        }
    }

    /// Reads the sections after `$MeshFormat`, handing each one to `read` with its name
    /// and its `$Name` header line. `read` returns `Ok(false)` for a section it does not
    /// know, which is then skipped; a known section that appears twice is an error.
    fn sections(
        &mut self,
        mut read: impl FnMut(&mut Self, &str, &Record<'a>) -> Result<bool>,
    ) -> Result<()> {
        let mut read_before = HashSet::new();
        while let Some(header) = self.try_next() {
            let Some(name) = header.text.strip_prefix('$') else {
                return Err(header.error(format!(
                    "expected a section header such as `$Nodes`, found `{}`",
                    truncate(header.text, 40)
                )));
            };
            if name.starts_with("End") {
                return Err(header.error(format!(
                    "`{}` without a matching section start",
                    truncate(header.text, 40)
                )));
            }
            if read_before.contains(name) {
                return Err(header.error(format!("second `{}` section", header.text)));
            }
            if read(self, name, &header)? {
                read_before.insert(name);
            } else {
                self.skip_section(name)?;
            }
        }
        Ok(())
    }
}

/// One line of the file, consumed field by field.
struct Record<'a> {
    path: &'a Path,
    number: usize,
    text: &'a str,
    /// The fields not read yet.
    rest: &'a str,
    is_last: bool,
}

impl<'a> Record<'a> {
    fn error(&self, reason: impl Into<String>) -> Error {
        Error::Gmsh {
            path: self.path.to_path_buf(),
            line: self.number,
            reason: reason.into(),
        }
    }

    /// The next whitespace-separated field, named `what` in the error when it is missing.
    fn field(&mut self, what: &str) -> Result<&'a str> {
        let rest = self.rest.trim_start();
        if rest.is_empty() {
            let hint = if self.is_last {
                " (truncated file?)"
            } else {
                ""
            };
            return Err(self.error(format!("line ends before the {what}{hint}")));
        }
        let (field, tail) = rest.split_at(rest.find(char::is_whitespace).unwrap_or(rest.len()));
        self.rest = tail;
        Ok(field)
    }

    /// The rest of the line, unsplit.
    fn remainder(&self) -> &'a str {
        self.rest.trim()
    }

    fn parse<T: FromStr>(&mut self, what: &str) -> Result<T> {
        let field = self.field(what)?;
        field
            .parse()
            .map_err(|_| self.error(format!("`{field}` is not a valid {what}")))
    }

    /// A count or a tag: a non-negative integer.
    fn count(&mut self, what: &str) -> Result<usize> {
        self.parse(what)
    }

    /// A node or element count, at most [`MAX_DECLARED_ITEMS`]: a larger one is refused
    /// before anything is read for it.
    fn declared(&mut self, what: &str) -> Result<usize> {
        let count = self.count(what)?;
        if count > MAX_DECLARED_ITEMS {
            return Err(self.error(format!(
                "{what} {count} is more than the limit of {MAX_DECLARED_ITEMS} (RVE meshes \
                 have at most {} triangles)",
                MAX_TRIANGLES
            )));
        }
        Ok(count)
    }

    fn tag(&mut self, what: &str) -> Result<u64> {
        self.parse(what)
    }

    fn int(&mut self, what: &str) -> Result<i64> {
        self.parse(what)
    }

    /// A finite floating-point number (`nan` and `inf` parse as `f64` but are rejected).
    fn real(&mut self, what: &str) -> Result<f64> {
        let field = self.field(what)?;
        match field.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(self.error(format!("`{field}` is not a valid (finite) {what}"))),
        }
    }

    /// Checks that every field was read.
    fn end(&self) -> Result<()> {
        match self.remainder().split_whitespace().next() {
            None => Ok(()),
            Some(extra) => Err(self.error(format!(
                "unexpected extra field `{}` in `{}`",
                truncate(extra, 40),
                truncate(self.text, 80)
            ))),
        }
    }
}

// ---------------------------------------------------------------------------------------
// What both versions deliver before the shared post-processing
// ---------------------------------------------------------------------------------------

struct PhysicalName {
    dim: i64,
    tag: i64,
    name: String,
}

struct RawNode {
    tag: u64,
    xyz: [f64; 3],
    line: usize,
}

struct RawTriangle {
    tag: u64,
    nodes: [u64; 3],
    /// Physical tags of the triangle (several when it is in several groups).
    physicals: Vec<i64>,
    line: usize,
}

#[derive(Default)]
struct RawMesh {
    physical_names: Vec<PhysicalName>,
    /// Line of the `$PhysicalNames` header, if the section is present.
    physical_names_line: Option<usize>,
    nodes: Vec<RawNode>,
    triangles: Vec<RawTriangle>,
}

#[derive(Clone, Copy)]
enum Version {
    V22,
    V41,
}

/// Reads the `$MeshFormat` section, which must open the file.
fn read_mesh_format(r: &mut Reader) -> Result<Version> {
    let Some(header) = r.try_next() else {
        return Err(r.error(r.last_line.max(1), "empty file: no `$MeshFormat` header"));
    };
    if header.text != "$MeshFormat" {
        return Err(header.error(format!(
            "not a Gmsh MSH 2.2/4.1 file: expected `$MeshFormat` first, found `{}`",
            truncate(header.text, 40)
        )));
    }
    let mut line = r.next("the `$MeshFormat` line")?;
    let version_text = line.field("MSH version")?;
    let version = match version_text {
        "2.2" => Version::V22,
        "4.1" => Version::V41,
        other => {
            return Err(line.error(format!(
                "unsupported MSH version `{other}`: only 2.2 and 4.1 (ASCII) are read; \
                 re-save the mesh with Gmsh in one of these versions"
            )))
        }
    };
    match line.int("file type (0 ASCII, 1 binary)")? {
        0 => {}
        1 => {
            return Err(line.error(format!(
                "binary MSH {version_text} files are not supported; \
                 re-save the mesh as ASCII (Gmsh option Mesh.Binary = 0)"
            )))
        }
        other => {
            return Err(line.error(format!("unknown file type {other} (expected 0 for ASCII)")))
        }
    }
    line.count("data size")?;
    line.end()?;
    r.expect_end("MeshFormat")?;
    Ok(version)
}

/// `$PhysicalNames`, identical in both versions.
fn read_physical_names(r: &mut Reader, raw: &mut RawMesh, header: &Record) -> Result<()> {
    raw.physical_names_line = Some(header.number);
    let mut count_line = r.next("the number of physical names")?;
    let count = count_line.count("number of physical names")?;
    count_line.end()?;
    for _ in 0..count {
        let mut line = r.next("a physical name")?;
        let dim = line.int("physical group dimension")?;
        let tag = line.int("physical tag")?;
        let quoted = line.remainder();
        let name = quoted
            .strip_prefix('"')
            .and_then(|rest| rest.strip_suffix('"'))
            .filter(|name| !name.contains('"'))
            .ok_or_else(|| line.error(format!("expected a quoted group name, found `{quoted}`")))?;
        raw.physical_names.push(PhysicalName {
            dim,
            tag,
            name: name.to_string(),
        });
    }
    r.expect_end("PhysicalNames")
}

/// A node line `[tag] x y z` (the tag is read by the caller).
fn read_xyz(line: &mut Record) -> Result<[f64; 3]> {
    Ok([
        line.real("x coordinate")?,
        line.real("y coordinate")?,
        line.real("z coordinate")?,
    ])
}

/// Number of nodes of the element types we accept, `None` for the others.
fn nodes_per_element(element_type: i64) -> Option<usize> {
    match element_type {
        POINT => Some(1),
        LINE => Some(2),
        TRIANGLE => Some(3),
        _ => None,
    }
}

/// The error for an element type we do not read.
fn unsupported_element(line: &Record, element_type: i64) -> Error {
    let name = match element_type {
        3 => "4-node quadrangle",
        4 => "4-node tetrahedron",
        5 => "8-node hexahedron",
        6 => "6-node prism",
        7 => "5-node pyramid",
        8 => "3-node second-order line",
        9 => "6-node second-order triangle",
        10 => "9-node second-order quadrangle",
        16 => "8-node second-order quadrangle",
        _ => "element",
    };
    line.error(format!(
        "unsupported element type {element_type} ({name}): only 3-node triangles (type 2) \
         are read, besides points (15) and lines (1), which are skipped"
    ))
}

// ---------------------------------------------------------------------------------------
// MSH 2.2
// ---------------------------------------------------------------------------------------

fn read_v22(r: &mut Reader) -> Result<RawMesh> {
    let mut raw = RawMesh::default();
    let (mut has_nodes, mut has_elements) = (false, false);
    r.sections(|r, name, header| {
        match name {
            "PhysicalNames" => read_physical_names(r, &mut raw, header)?,
            "Nodes" => {
                has_nodes = true;
                read_v22_nodes(r, &mut raw)?
            }
            "Elements" => {
                has_elements = true;
                read_v22_elements(r, &mut raw)?
            }
            _ => return Ok(false),
        }
        Ok(true)
    })?;
    require_sections(r, has_nodes, has_elements)?;
    Ok(raw)
}

fn read_v22_nodes(r: &mut Reader, raw: &mut RawMesh) -> Result<()> {
    let mut count_line = r.next("the number of nodes")?;
    let count = count_line.declared("number of nodes")?;
    count_line.end()?;
    for _ in 0..count {
        let mut line = r.next("a node")?;
        let tag = line.tag("node tag")?;
        let xyz = read_xyz(&mut line)?;
        line.end()?;
        raw.nodes.push(RawNode {
            tag,
            xyz,
            line: line.number,
        });
    }
    r.expect_end("Nodes")
}

fn read_v22_elements(r: &mut Reader, raw: &mut RawMesh) -> Result<()> {
    let mut count_line = r.next("the number of elements")?;
    let count = count_line.declared("number of elements")?;
    count_line.end()?;
    // Triangles already seen, by sorted node tags: Gmsh writes a triangle that is in
    // several physical groups once per group.
    let mut by_nodes: HashMap<[u64; 3], usize> = HashMap::new();
    for _ in 0..count {
        let mut line = r.next("an element")?;
        let tag = line.tag("element tag")?;
        let element_type = line.int("element type")?;
        let Some(node_count) = nodes_per_element(element_type) else {
            return Err(unsupported_element(&line, element_type));
        };
        let tag_count = line.count("number of element tags")?;
        let mut physical = None;
        for i in 0..tag_count {
            let value = line.int("element tag value")?;
            if i == 0 {
                physical = Some(value);
            }
        }
        let mut nodes = [0; 3];
        for node in nodes.iter_mut().take(node_count) {
            *node = line.tag("node tag")?;
        }
        line.end()?;
        if element_type != TRIANGLE {
            continue;
        }
        // Physical tag 0 means "in no physical group".
        let physicals: Vec<i64> = physical.into_iter().filter(|&p| p != 0).collect();
        let mut key = nodes;
        key.sort_unstable();
        match by_nodes.get(&key) {
            Some(&first) => raw.triangles[first].physicals.extend(physicals),
            None => {
                by_nodes.insert(key, raw.triangles.len());
                raw.triangles.push(RawTriangle {
                    tag,
                    nodes,
                    physicals,
                    line: line.number,
                });
            }
        }
    }
    r.expect_end("Elements")
}

// ---------------------------------------------------------------------------------------
// MSH 4.1
// ---------------------------------------------------------------------------------------

/// A block of triangles of one surface entity, whose physical groups are filled in once
/// the whole file (and so `$Entities`) has been read.
struct TriangleBlock {
    entity: i64,
    triangles: std::ops::Range<usize>,
}

fn read_v41(r: &mut Reader) -> Result<RawMesh> {
    let mut raw = RawMesh::default();
    let mut surfaces: HashMap<i64, Vec<i64>> = HashMap::new();
    let mut blocks = Vec::new();
    let (mut has_nodes, mut has_elements) = (false, false);
    r.sections(|r, name, header| {
        match name {
            "PhysicalNames" => read_physical_names(r, &mut raw, header)?,
            "Entities" => read_v41_entities(r, &mut surfaces)?,
            "Nodes" => {
                has_nodes = true;
                read_v41_nodes(r, &mut raw)?
            }
            "Elements" => {
                has_elements = true;
                read_v41_elements(r, &mut raw, &mut blocks)?
            }
            "PartitionedEntities" => {
                let reason = "partitioned MSH files are not supported; save the mesh unpartitioned";
                return Err(header.error(reason));
            }
            _ => return Ok(false),
        }
        Ok(true)
    })?;
    require_sections(r, has_nodes, has_elements)?;
    for block in blocks {
        let physicals = surfaces.get(&block.entity).cloned().unwrap_or_default();
        for triangle in &mut raw.triangles[block.triangles] {
            triangle.physicals.clone_from(&physicals);
        }
    }
    Ok(raw)
}

/// Reads `$Entities`, keeping the physical tags of each surface.
fn read_v41_entities(r: &mut Reader, surfaces: &mut HashMap<i64, Vec<i64>>) -> Result<()> {
    let mut counts = r.next("the entity counts")?;
    let points = counts.count("number of points")?;
    let curves = counts.count("number of curves")?;
    let surface_count = counts.count("number of surfaces")?;
    let volumes = counts.count("number of volumes")?;
    counts.end()?;
    for _ in 0..points.saturating_add(curves) {
        r.next("a point or curve entity")?;
    }
    for _ in 0..surface_count {
        let mut line = r.next("a surface entity")?;
        let tag = line.int("surface tag")?;
        for what in ["minX", "minY", "minZ", "maxX", "maxY", "maxZ"] {
            line.real(what)?;
        }
        let physical_count = line.count("number of physical tags")?;
        let mut physicals = Vec::new();
        for _ in 0..physical_count {
            physicals.push(line.int("physical tag")?);
        }
        let curve_count = line.count("number of bounding curves")?;
        for _ in 0..curve_count {
            line.int("bounding curve tag")?;
        }
        if surfaces.insert(tag, physicals).is_some() {
            return Err(line.error(format!("surface entity {tag} is defined twice")));
        }
        line.end()?;
    }
    for _ in 0..volumes {
        r.next("a volume entity")?;
    }
    r.expect_end("Entities")
}

/// Reads the header line of `$Nodes` or `$Elements`: the block count and the item count.
fn read_block_header(r: &mut Reader, items: &str) -> Result<(usize, usize, usize)> {
    let mut line = r.next(&format!("the {items} header"))?;
    let blocks = line.count("number of entity blocks")?;
    let count = line.declared(&format!("number of {items}"))?;
    line.tag(&format!("minimum {items} tag"))?;
    line.tag(&format!("maximum {items} tag"))?;
    line.end()?;
    Ok((blocks, count, line.number))
}

fn read_v41_nodes(r: &mut Reader, raw: &mut RawMesh) -> Result<()> {
    let (blocks, declared, header_line) = read_block_header(r, "nodes")?;
    let mut total = 0usize;
    for _ in 0..blocks {
        let mut block = r.next("a node block header")?;
        let dim = block.int("entity dimension")?;
        block.int("entity tag")?;
        let parametric = block.int("parametric flag")?;
        let count = block.declared("number of nodes in the block")?;
        block.end()?;
        let extra = match (parametric, dim) {
            (0, _) => 0,
            (1, 0..=3) => dim as usize,
            _ => {
                return Err(r.error(
                    block.number,
                    format!("bad node block: parametric flag {parametric}, entity dimension {dim}"),
                ))
            }
        };
        let first = raw.nodes.len();
        for _ in 0..count {
            let mut line = r.next("a node tag")?;
            let tag = line.tag("node tag")?;
            line.end()?;
            raw.nodes.push(RawNode {
                tag,
                xyz: [0.0; 3],
                line: line.number,
            });
        }
        for node in &mut raw.nodes[first..] {
            let mut line = r.next("node coordinates")?;
            node.xyz = read_xyz(&mut line)?;
            node.line = line.number;
            for _ in 0..extra {
                line.real("parametric coordinate")?;
            }
            line.end()?;
        }
        total = total.saturating_add(count);
    }
    if total != declared {
        return Err(r.error(
            header_line,
            format!("the header declares {declared} nodes but the blocks hold {total}"),
        ));
    }
    r.expect_end("Nodes")
}

fn read_v41_elements(
    r: &mut Reader,
    raw: &mut RawMesh,
    blocks: &mut Vec<TriangleBlock>,
) -> Result<()> {
    let (block_count, declared, header_line) = read_block_header(r, "elements")?;
    let mut total = 0usize;
    for _ in 0..block_count {
        let mut block = r.next("an element block header")?;
        let dim = block.int("entity dimension")?;
        let entity = block.int("entity tag")?;
        let element_type = block.int("element type")?;
        let count = block.declared("number of elements in the block")?;
        let Some(node_count) = nodes_per_element(element_type) else {
            return Err(unsupported_element(&block, element_type));
        };
        block.end()?;
        if element_type == TRIANGLE && dim != 2 {
            let reason = format!("triangles in an entity of dimension {dim} (expected 2)");
            return Err(block.error(reason));
        }
        let first = raw.triangles.len();
        for _ in 0..count {
            let mut line = r.next("an element")?;
            let tag = line.tag("element tag")?;
            let mut nodes = [0; 3];
            for node in nodes.iter_mut().take(node_count) {
                *node = line.tag("node tag")?;
            }
            line.end()?;
            if element_type == TRIANGLE {
                raw.triangles.push(RawTriangle {
                    tag,
                    nodes,
                    physicals: Vec::new(),
                    line: line.number,
                });
            }
        }
        if element_type == TRIANGLE {
            blocks.push(TriangleBlock {
                entity,
                triangles: first..raw.triangles.len(),
            });
        }
        total = total.saturating_add(count);
    }
    if total != declared {
        return Err(r.error(
            header_line,
            format!("the header declares {declared} elements but the blocks hold {total}"),
        ));
    }
    r.expect_end("Elements")
}

fn require_sections(r: &Reader, has_nodes: bool, has_elements: bool) -> Result<()> {
    let missing = match (has_nodes, has_elements) {
        (true, true) => return Ok(()),
        (false, _) => "$Nodes",
        (true, false) => "$Elements",
    };
    Err(r.error(r.last_line, format!("the file has no {missing} section")))
}

// ---------------------------------------------------------------------------------------
// Shared post-processing: groups, renumbering, geometry checks
// ---------------------------------------------------------------------------------------

/// Turns what either version read into a [`PhaseMesh`]: phases from the physical groups,
/// renumbered nodes, geometric checks.
fn assemble(
    mut raw: RawMesh,
    r: &Reader,
    matrix_group: &str,
    inclusion_groups: &[String],
) -> Result<PhaseMesh> {
    let mut triangles = std::mem::take(&mut raw.triangles);
    let groups = Groups::new(&raw, r, matrix_group, inclusion_groups)?;
    let node_of_tag = node_indices(&raw.nodes, r)?;
    sort_triangles(&mut triangles, r)?;
    let labelled = label_triangles(&triangles, &groups, &node_of_tag, r)?;

    // Keep the used nodes, numbered in increasing tag order.
    let mut used: Vec<usize> = labelled.iter().flat_map(|(nodes, _)| *nodes).collect();
    used.sort_unstable_by_key(|&i| raw.nodes[i].tag);
    used.dedup();
    check_planar(&raw.nodes, &used, r)?;
    let mut new_index = vec![0; raw.nodes.len()];
    for (new, &old) in used.iter().enumerate() {
        new_index[old] = new;
    }

    let mut mesh = PhaseMesh {
        nodes: used
            .iter()
            .map(|&i| [raw.nodes[i].xyz[0], raw.nodes[i].xyz[1]])
            .collect(),
        triangles: Vec::with_capacity(labelled.len()),
    };
    // Orientation: see the module documentation.
    let mut clockwise = Vec::new();
    for (t, (nodes, phase)) in triangles.iter().zip(labelled) {
        let triangle = Triangle {
            nodes: nodes.map(|i| new_index[i]),
            phase,
        };
        let twice_area = twice_signed_area(&mesh.nodes, &triangle, t, r)?;
        if twice_area < 0.0 {
            clockwise.push((t, twice_area));
        }
        mesh.triangles.push(triangle);
    }
    match clockwise.first() {
        Some(&(t, twice_area)) => Err(inverted(t, twice_area, clockwise.len(), triangles.len(), r)),
        None => Ok(mesh),
    }
}

/// The index of each node tag in `nodes`; a tag that appears twice is an error.
fn node_indices(nodes: &[RawNode], r: &Reader) -> Result<HashMap<u64, usize>> {
    let mut node_of_tag: HashMap<u64, usize> = HashMap::with_capacity(nodes.len());
    for (i, node) in nodes.iter().enumerate() {
        if node_of_tag.insert(node.tag, i).is_some() {
            return Err(r.error(node.line, format!("node tag {} appears twice", node.tag)));
        }
    }
    Ok(node_of_tag)
}

/// Sorts the triangles by tag; a tag that appears twice, no triangle, or more than
/// [`MAX_TRIANGLES`] are errors.
fn sort_triangles(triangles: &mut [RawTriangle], r: &Reader) -> Result<()> {
    triangles.sort_by_key(|t| t.tag);
    if let Some(pair) = triangles.windows(2).find(|w| w[0].tag == w[1].tag) {
        let reason = format!("element tag {} appears twice", pair[1].tag);
        return Err(r.error(pair[1].line, reason));
    }
    if triangles.is_empty() {
        return Err(r.error(
            r.last_line,
            "the file contains no triangles (element type 2)",
        ));
    }
    if triangles.len() > MAX_TRIANGLES {
        let reason = format!(
            "the file holds {} triangles, more than the limit of {} for an RVE mesh",
            triangles.len(),
            MAX_TRIANGLES
        );
        return Err(r.error(r.last_line, reason));
    }
    Ok(())
}

/// Phase and raw node indices of each triangle; a node tag not in `$Nodes` is an error.
fn label_triangles(
    triangles: &[RawTriangle],
    groups: &Groups,
    node_of_tag: &HashMap<u64, usize>,
    r: &Reader,
) -> Result<Vec<([usize; 3], Phase)>> {
    let mut labelled = Vec::with_capacity(triangles.len());
    for t in triangles {
        let phase = groups.phase(t, r)?;
        let mut nodes = [0; 3];
        for (slot, tag) in nodes.iter_mut().zip(t.nodes) {
            *slot = *node_of_tag.get(&tag).ok_or_else(|| {
                let reason = format!(
                    "triangle {} references node {tag}, which is not in $Nodes",
                    t.tag
                );
                r.error(t.line, reason)
            })?;
        }
        labelled.push((nodes, phase));
    }
    Ok(labelled)
}

/// The requested physical groups and the phase of each of their physical tags.
struct Groups<'a> {
    matrix: &'a str,
    inclusions: &'a [String],
    names: &'a [PhysicalName],
    phase_of: HashMap<i64, Phase>,
}

impl<'a> Groups<'a> {
    /// Looks the requested groups up among the surface groups of `$PhysicalNames`.
    fn new(
        raw: &'a RawMesh,
        r: &Reader,
        matrix: &'a str,
        inclusions: &'a [String],
    ) -> Result<Self> {
        let line = raw.physical_names_line.unwrap_or(1);
        let requests = std::iter::once((matrix, Phase::Matrix))
            .chain(inclusions.iter().map(|g| (g.as_str(), Phase::Inclusion)));
        let mut phase_of = HashMap::new();
        for (group, phase) in requests {
            let mut found = false;
            for name in raw
                .physical_names
                .iter()
                .filter(|n| n.name == group && n.dim == 2)
            {
                found = true;
                if phase_of
                    .insert(name.tag, phase)
                    .is_some_and(|old| old != phase)
                {
                    let reason = format!(
                        "physical group `{group}` is requested both as matrix and as inclusion group"
                    );
                    return Err(r.error(line, reason));
                }
            }
            if !found {
                return Err(r.error(line, missing_group_reason(raw, group, phase)));
            }
        }
        Ok(Groups {
            matrix,
            inclusions,
            names: &raw.physical_names,
            phase_of,
        })
    }

    /// The phase of a triangle: its physical groups must include requested ones of
    /// exactly one phase (other groups are allowed and ignored).
    fn phase(&self, t: &RawTriangle, r: &Reader) -> Result<Phase> {
        let mut phases = t
            .physicals
            .iter()
            .filter_map(|p| self.phase_of.get(p).copied());
        let Some(phase) = phases.next() else {
            let reason = format!(
                "triangle {} is in {}, which is neither the matrix group `{}` nor an inclusion \
                 group ({})",
                t.tag,
                self.describe(&t.physicals),
                self.matrix,
                quoted_list(self.inclusions.iter().map(String::as_str)),
            );
            return Err(r.error(t.line, reason));
        };
        if phases.any(|other| other != phase) {
            let reason = format!(
                "triangle {} is in both the matrix group and an inclusion group: {}",
                t.tag,
                self.describe(&t.physicals)
            );
            return Err(r.error(t.line, reason));
        }
        Ok(phase)
    }

    /// "no physical group", or "physical group `name` (tag 2), unnamed tag 7".
    fn describe(&self, physicals: &[i64]) -> String {
        if physicals.is_empty() {
            return "no physical group".to_string();
        }
        let groups: Vec<String> = physicals
            .iter()
            .map(
                |&p| match self.names.iter().find(|n| n.tag == p && n.dim == 2) {
                    Some(n) => format!("`{}` (tag {p})", n.name),
                    None => format!("unnamed tag {p}"),
                },
            )
            .collect();
        format!("physical group {}", groups.join(", "))
    }
}

fn missing_group_reason(raw: &RawMesh, group: &str, phase: Phase) -> String {
    let role = match phase {
        Phase::Matrix => "matrix",
        Phase::Inclusion => "inclusion",
    };
    if raw.physical_names_line.is_none() {
        return format!(
            "the {role} group `{group}` is requested, but the file has no $PhysicalNames section"
        );
    }
    if let Some(other) = raw.physical_names.iter().find(|n| n.name == group) {
        return format!(
            "the {role} group `{group}` is a dimension-{} physical group; a surface \
             (dimension-2) group is needed",
            other.dim
        );
    }
    let surfaces = raw
        .physical_names
        .iter()
        .filter(|n| n.dim == 2)
        .map(|n| n.name.as_str());
    format!(
        "the {role} group `{group}` is not in $PhysicalNames (surface groups in the file: {})",
        quoted_list(surfaces)
    )
}

/// "`a`, `b`", or "none".
fn quoted_list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let quoted: Vec<String> = names.map(|n| format!("`{n}`")).collect();
    if quoted.is_empty() {
        "none".to_string()
    } else {
        quoted.join(", ")
    }
}

/// Rejects used nodes off the plane `z = 0` (relative to the mesh extent).
fn check_planar(nodes: &[RawNode], used: &[usize], r: &Reader) -> Result<()> {
    let (lo, hi) = bounding_box(used.iter().map(|&i| [nodes[i].xyz[0], nodes[i].xyz[1]]));
    let tolerance = PLANAR_RELATIVE_Z * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    match used
        .iter()
        .map(|&i| &nodes[i])
        .find(|n| n.xyz[2].abs() > tolerance)
    {
        None => Ok(()),
        Some(node) => Err(r.error(
            node.line,
            format!(
                "node {} has z = {}: only plane meshes in z = 0 are supported",
                node.tag, node.xyz[2]
            ),
        )),
    }
}

/// Twice the signed area of a triangle (positive when counter-clockwise); a degenerate
/// triangle is an error.
fn twice_signed_area(
    nodes: &[[f64; 2]],
    triangle: &Triangle,
    raw: &RawTriangle,
    r: &Reader,
) -> Result<f64> {
    let [p, q, s] = triangle.nodes.map(|i| nodes[i]);
    let twice_area = (q[0] - p[0]) * (s[1] - p[1]) - (s[0] - p[0]) * (q[1] - p[1]);
    let longest_squared = [(p, q), (q, s), (s, p)]
        .iter()
        .map(|(a, b)| (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2))
        .fold(0.0, f64::max);
    if twice_area.abs() <= DEGENERATE_RELATIVE_AREA * longest_squared {
        let reason = format!(
            "triangle {} is degenerate (area {:e}, its nodes are collinear or coincide)",
            raw.tag,
            0.5 * twice_area
        );
        return Err(r.error(raw.line, reason));
    }
    Ok(twice_area)
}

/// The error for the first clockwise triangle; the count tells a flipped surface (all of
/// its triangles) from a tangled element (one or a few).
fn inverted(
    raw: &RawTriangle,
    twice_area: f64,
    clockwise: usize,
    total: usize,
    r: &Reader,
) -> Error {
    let reason = format!(
        "triangle {} is inverted: its nodes are clockwise (signed area {:e}); {clockwise} of \
         the {total} triangles in the file are clockwise. Triangles must be counter-clockwise \
         in the xy plane. A surface whose triangles are all clockwise was meshed with its \
         normal along -z (e.g. a clockwise Curve Loop in a .geo file): reverse it in Gmsh \
         with `ReverseMesh Surface{{...}};` or gmsh.model.mesh.reverse()",
        raw.tag,
        0.5 * twice_area
    );
    r.error(raw.line, reason)
}

/// The first `max` characters of `text`, for error messages about garbage input.
fn truncate(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((end, _)) => format!("{}...", &text[..end]),
        None => text.to_string(),
    }
}

// ---------------------------------------------------------------------------------------
// Writers
// ---------------------------------------------------------------------------------------

/// Writes `mesh` as a Gmsh MSH 2.2 ASCII file; see the [module documentation](self).
///
/// Each triangle line is `tag 2 2 physical elementary n0 n1 n2`, with physical and
/// elementary tag 1 (matrix) or 2 (aggregate).
///
/// Coordinates are written in Rust's shortest round-trip form (`{:?}`), so reading the
/// file back gives bit-identical coordinates.
pub fn write_msh22(mesh: &PhaseMesh, w: &mut impl Write) -> io::Result<()> {
    write_header(w, "2.2")?;
    writeln!(w, "$Nodes\n{}", mesh.nodes.len())?;
    for (i, [x, y]) in mesh.nodes.iter().enumerate() {
        writeln!(w, "{} {x:?} {y:?} 0", i + 1)?;
    }
    writeln!(w, "$EndNodes\n$Elements\n{}", mesh.triangles.len())?;
    for (k, t) in mesh.triangles.iter().enumerate() {
        let tag = phase_tag(t.phase);
        let [a, b, c] = t.nodes.map(|i| i + 1);
        writeln!(w, "{} {TRIANGLE} 2 {tag} {tag} {a} {b} {c}", k + 1)?;
    }
    writeln!(w, "$EndElements")
}

/// Writes `mesh` as a Gmsh MSH 4.1 ASCII file; see the [module documentation](self).
///
/// The two phases are the surface entities 1 (matrix) and 2 (aggregate), each in
/// the physical group of the same tag. A node is written in the aggregate entity's block
/// when only inclusion triangles use it, otherwise in the matrix entity's block.
pub fn write_msh41(mesh: &PhaseMesh, w: &mut impl Write) -> io::Result<()> {
    let [in_matrix, in_aggregate] = PHASES.map(|phase| used_by(mesh, phase));
    // Every node is written once, in the block of one entity.
    let entity_of_node = |i: usize| {
        if in_aggregate[i] && !in_matrix[i] {
            Phase::Inclusion
        } else {
            Phase::Matrix
        }
    };
    let node_blocks = group_by_phase(mesh.nodes.len(), entity_of_node);
    let element_blocks = group_by_phase(mesh.triangles.len(), |k| mesh.triangles[k].phase);

    write_header(w, "4.1")?;

    writeln!(w, "$Entities\n0 0 {} 0", PHASES.len())?;
    for (phase, used) in PHASES.iter().zip([&in_matrix, &in_aggregate]) {
        let points = mesh
            .nodes
            .iter()
            .zip(used)
            .filter(|(_, &u)| u)
            .map(|(p, _)| *p);
        let (lo, hi) = bounding_box(points);
        let tag = phase_tag(*phase);
        writeln!(
            w,
            "{tag} {:?} {:?} 0 {:?} {:?} 0 1 {tag} 0",
            lo[0], lo[1], hi[0], hi[1]
        )?;
    }
    writeln!(w, "$EndEntities")?;

    let n = mesh.nodes.len();
    writeln!(w, "$Nodes\n{} {n} {} {n}", node_blocks.len(), n.min(1))?;
    for (phase, block) in &node_blocks {
        writeln!(w, "2 {} 0 {}", phase_tag(*phase), block.len())?;
        for &i in block {
            writeln!(w, "{}", i + 1)?;
        }
        for &i in block {
            let [x, y] = mesh.nodes[i];
            writeln!(w, "{x:?} {y:?} 0")?;
        }
    }
    writeln!(w, "$EndNodes")?;

    let m = mesh.triangles.len();
    writeln!(
        w,
        "$Elements\n{} {m} {} {m}",
        element_blocks.len(),
        m.min(1)
    )?;
    for (phase, block) in &element_blocks {
        writeln!(w, "2 {} {TRIANGLE} {}", phase_tag(*phase), block.len())?;
        for &k in block {
            let [a, b, c] = mesh.triangles[k].nodes.map(|i| i + 1);
            writeln!(w, "{} {a} {b} {c}", k + 1)?;
        }
    }
    writeln!(w, "$EndElements")
}

/// The phases in the order of their tags.
const PHASES: [Phase; 2] = [Phase::Matrix, Phase::Inclusion];

/// The indices `0..len` grouped by phase, in [`PHASES`] order, empty groups left out.
fn group_by_phase(len: usize, phase_of: impl Fn(usize) -> Phase) -> Vec<(Phase, Vec<usize>)> {
    PHASES
        .iter()
        .map(|&phase| (phase, (0..len).filter(|&i| phase_of(i) == phase).collect()))
        .filter(|(_, indices): &(Phase, Vec<usize>)| !indices.is_empty())
        .collect()
}

/// Which nodes the triangles of `phase` use.
fn used_by(mesh: &PhaseMesh, phase: Phase) -> Vec<bool> {
    let mut used = vec![false; mesh.nodes.len()];
    for t in mesh.triangles.iter().filter(|t| t.phase == phase) {
        for &i in &t.nodes {
            if let Some(flag) = used.get_mut(i) {
                *flag = true;
            }
        }
    }
    used
}

/// `$MeshFormat` and `$PhysicalNames`, common to both writers.
fn write_header(w: &mut impl Write, version: &str) -> io::Result<()> {
    writeln!(w, "$MeshFormat\n{version} 0 8\n$EndMeshFormat")?;
    writeln!(w, "$PhysicalNames\n2")?;
    writeln!(w, "2 {MATRIX_TAG} \"{MATRIX_GROUP}\"")?;
    writeln!(w, "2 {AGGREGATE_TAG} \"{AGGREGATE_GROUP}\"")?;
    writeln!(w, "$EndPhysicalNames")
}

fn phase_tag(phase: Phase) -> i64 {
    match phase {
        Phase::Matrix => MATRIX_TAG,
        Phase::Inclusion => AGGREGATE_TAG,
    }
}

/// Bounding box of some points; all zeros when there are none.
fn bounding_box(points: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if lo[0] > hi[0] {
        ([0.0; 2], [0.0; 2])
    } else {
        (lo, hi)
    }
}
