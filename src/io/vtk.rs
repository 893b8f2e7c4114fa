//! ASCII VTK XML unstructured grid (`.vtu`), readable by ParaView.
//!
//! Cells: the bulk triangles (`VTK_TRIANGLE = 5`), then the interface elements as
//! zero-thickness quads (`VTK_QUAD = 9`, nodes `a0 a1 b1 b0`). Cell data: `phase`
//! (0 matrix, 1 inclusion, 2 interface) and `element_kind` (0 bulk, 1 interface).
//! Point data: `duplicate` = 1 on matrix-side ITZ duplicates.

use std::io::{self, Write};

use super::super::mesh::Mesh;

const VTK_TRIANGLE: u8 = 5;
const VTK_QUAD: u8 = 9;

/// Writes `mesh` as a `.vtu` document.
pub fn write_vtu(mesh: &Mesh, w: &mut impl Write) -> io::Result<()> {
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
