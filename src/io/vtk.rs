//! ASCII VTK XML unstructured grid (`.vtu`), readable by ParaView.
//!
//! Cells: the bulk triangles (`VTK_TRIANGLE = 5`), then the interface elements as
//! zero-thickness quads (`VTK_QUAD = 9`, nodes `a0 a1 b1 b0`). Cell data: `phase`
//! (0 matrix, 1 inclusion, 2 interface) and `element_kind` (0 bulk, 1 interface).
//! Point data: `duplicate` = 1 on matrix-side ITZ duplicates.
//!
//! [`write_vtu_fields`] writes the same grid with the fields of a state ([`RveFields`])
//! as well, and [`write_pvd`] the ParaView index of a time series of such files. Floats
//! are written in Rust's shortest round-trip form, so a reader gets the exact values.

use std::io::{self, Write};

use super::fields::RveFields;
use mesorve_core::mesh::Mesh;

const VTK_TRIANGLE: u8 = 5;
const VTK_QUAD: u8 = 9;

/// Writes `mesh` as a `.vtu` document.
pub fn write_vtu(mesh: &Mesh, w: &mut impl Write) -> io::Result<()> {
    write_grid(mesh, w)?;
    writeln!(w, r#"<CellData Scalars="phase">"#)?;
    writeln!(w, r#"<DataArray type="UInt8" Name="phase" format="ascii">"#)?;
    for t in &mesh.triangles {
        writeln!(w, "{}", t.phase.id())?;
    }
    for _ in &mesh.interfaces {
        writeln!(w, "2")?;
    }
    writeln!(w, "</DataArray>")?;
    writeln!(
        w,
        r#"<DataArray type="UInt8" Name="element_kind" format="ascii">"#
    )?;
    for _ in &mesh.triangles {
        writeln!(w, "0")?;
    }
    for _ in &mesh.interfaces {
        writeln!(w, "1")?;
    }
    writeln!(w, "</DataArray>\n</CellData>")?;

    let mut duplicate = vec![0u8; mesh.nodes.len()];
    for e in &mesh.interfaces {
        duplicate[e.nodes[2]] = 1;
        duplicate[e.nodes[3]] = 1;
    }
    writeln!(w, "<PointData>")?;
    writeln!(
        w,
        r#"<DataArray type="UInt8" Name="duplicate" format="ascii">"#
    )?;
    for d in duplicate {
        writeln!(w, "{d}")?;
    }
    writeln!(w, "</DataArray>\n</PointData>")?;
    writeln!(w, "</Piece>\n</UnstructuredGrid>\n</VTKFile>")?;
    Ok(())
}

/// The header, points and cells of the grid of `mesh` (the piece stays open).
fn write_grid(mesh: &Mesh, w: &mut impl Write) -> io::Result<()> {
    let n_cells = mesh.triangles.len() + mesh.interfaces.len();
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        w,
        r#"<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">"#
    )?;
    writeln!(w, "<UnstructuredGrid>")?;
    writeln!(
        w,
        r#"<Piece NumberOfPoints="{}" NumberOfCells="{n_cells}">"#,
        mesh.nodes.len()
    )?;
    writeln!(w, "<Points>")?;
    writeln!(
        w,
        r#"<DataArray type="Float64" NumberOfComponents="3" format="ascii">"#
    )?;
    for p in &mesh.nodes {
        writeln!(w, "{:e} {:e} 0", p[0], p[1])?;
    }
    writeln!(w, "</DataArray>\n</Points>")?;

    writeln!(w, "<Cells>")?;
    writeln!(
        w,
        r#"<DataArray type="Int64" Name="connectivity" format="ascii">"#
    )?;
    for t in &mesh.triangles {
        writeln!(w, "{} {} {}", t.nodes[0], t.nodes[1], t.nodes[2])?;
    }
    for e in &mesh.interfaces {
        let [a0, a1, b0, b1] = e.nodes;
        writeln!(w, "{a0} {a1} {b1} {b0}")?;
    }
    writeln!(w, "</DataArray>")?;
    writeln!(
        w,
        r#"<DataArray type="Int64" Name="offsets" format="ascii">"#
    )?;
    let mut offset = 0;
    for _ in &mesh.triangles {
        offset += 3;
        writeln!(w, "{offset}")?;
    }
    for _ in &mesh.interfaces {
        offset += 4;
        writeln!(w, "{offset}")?;
    }
    writeln!(w, "</DataArray>")?;
    writeln!(w, r#"<DataArray type="UInt8" Name="types" format="ascii">"#)?;
    for _ in &mesh.triangles {
        writeln!(w, "{VTK_TRIANGLE}")?;
    }
    for _ in &mesh.interfaces {
        writeln!(w, "{VTK_QUAD}")?;
    }
    writeln!(w, "</DataArray>\n</Cells>")?;
    Ok(())
}

/// Writes `mesh` with the fields of one state as a `.vtu` document.
///
/// Point data: `displacement` (3 components, z = 0, for ParaView's "Warp By Vector").
/// Cell data, on every cell (NaN, or -1 for `branch`, where a value does not apply):
/// `phase`, `element_kind`, `strain` and `stress` (`[xx, yy, xy]`, engineering shear
/// strain) on triangles; `shear_opening`, `normal_opening`, `slip` (frictional; NaN
/// without friction), `opening_ratio`
/// (`delta/delta_c`), `max_opening_ratio` (`delta_max/delta_c`), `damage`, `branch`
/// (0 loading, 1 unloading, 2 contact) and `closed_points` (points in contact) on
/// interface elements (see [`RveFields`]).
pub fn write_vtu_fields(mesh: &Mesh, fields: &RveFields, w: &mut impl Write) -> io::Result<()> {
    let n_tri = mesh.triangles.len();
    let n_itz = mesh.interfaces.len();
    let itz = |f: &dyn Fn(&super::fields::ItzFields) -> f64| -> Vec<f64> {
        (0..n_itz)
            .map(|e| fields.itz.get(e).map_or(f64::NAN, f))
            .collect()
    };
    write_grid(mesh, w)?;
    writeln!(w, r#"<CellData Scalars="phase">"#)?;
    let phase: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|t| f64::from(t.phase.id()))
        .chain(std::iter::repeat_n(2.0, n_itz))
        .collect();
    data_array(w, "UInt8", "phase", 1, &phase)?;
    let kind: Vec<f64> = (0..n_tri + n_itz)
        .map(|c| if c < n_tri { 0.0 } else { 1.0 })
        .collect();
    data_array(w, "UInt8", "element_kind", 1, &kind)?;
    for (name, values) in [("strain", &fields.strain), ("stress", &fields.stress)] {
        let flat: Vec<f64> = values
            .iter()
            .flatten()
            .copied()
            .chain(std::iter::repeat_n(f64::NAN, 3 * n_itz))
            .collect();
        data_array(w, "Float64", name, 3, &flat)?;
    }
    let nan_tri = || std::iter::repeat_n(f64::NAN, n_tri);
    let scalars: [(&str, Vec<f64>); 6] = [
        ("shear_opening", itz(&|e| e.shear_opening)),
        ("normal_opening", itz(&|e| e.normal_opening)),
        ("slip", itz(&|e| e.slip)),
        ("opening_ratio", itz(&|e| e.measures.opening_ratio)),
        ("max_opening_ratio", itz(&|e| e.measures.max_opening_ratio)),
        ("damage", itz(&|e| e.measures.damage)),
    ];
    for (name, values) in scalars {
        let all: Vec<f64> = nan_tri().chain(values).collect();
        data_array(w, "Float64", name, 1, &all)?;
    }
    let branch: Vec<f64> = std::iter::repeat_n(-1.0, n_tri)
        .chain((0..n_itz).map(|e| fields.itz.get(e).map_or(-1.0, |f| f64::from(f.branch))))
        .collect();
    data_array(w, "Int8", "branch", 1, &branch)?;
    let closed: Vec<f64> = std::iter::repeat_n(-1.0, n_tri)
        .chain((0..n_itz).map(|e| fields.itz.get(e).map_or(-1.0, |f| f.closed_points as f64)))
        .collect();
    data_array(w, "Int8", "closed_points", 1, &closed)?;
    writeln!(w, "</CellData>")?;
    writeln!(w, r#"<PointData Vectors="displacement">"#)?;
    let disp: Vec<f64> = fields
        .displacement
        .iter()
        .flat_map(|u| [u[0], u[1], 0.0])
        .collect();
    data_array(w, "Float64", "displacement", 3, &disp)?;
    writeln!(w, "</PointData>")?;
    writeln!(w, "</Piece>\n</UnstructuredGrid>\n</VTKFile>")?;
    Ok(())
}

/// One ASCII `DataArray` of `components` values per tuple; integer types are written
/// without a fraction.
fn data_array(
    w: &mut impl Write,
    ty: &str,
    name: &str,
    components: usize,
    values: &[f64],
) -> io::Result<()> {
    writeln!(
        w,
        r#"<DataArray type="{ty}" Name="{name}" NumberOfComponents="{components}" format="ascii">"#
    )?;
    let integer = !ty.starts_with("Float");
    for tuple in values.chunks(components) {
        for (i, v) in tuple.iter().enumerate() {
            let sep = if i + 1 == tuple.len() { "\n" } else { " " };
            if integer {
                write!(w, "{}{sep}", *v as i64)?;
            } else {
                write!(w, "{v:e}{sep}")?;
            }
        }
    }
    writeln!(w, "</DataArray>")
}

/// Writes the ParaView index (`.pvd`) of a time series: `(time, file)` pairs, the files
/// relative to the index.
pub fn write_pvd(entries: &[(f64, String)], w: &mut impl Write) -> io::Result<()> {
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        w,
        r#"<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">"#
    )?;
    writeln!(w, "<Collection>")?;
    for (time, file) in entries {
        writeln!(
            w,
            r#"<DataSet timestep="{time:e}" group="" part="0" file="{file}"/>"#
        )?;
    }
    writeln!(w, "</Collection>\n</VTKFile>")
}
