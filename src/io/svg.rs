//! SVG picture of a mesh in the manner of the paper's Figs. 9 and 14: matrix grey,
//! aggregates tan, triangle edges thin, ITZ elements drawn as thick red segments.

use std::io::{self, Write};

use crate::mesh::{Mesh, Phase};

/// Writes an SVG of `mesh`, `pixels` wide.
pub fn write_svg(mesh: &Mesh, pixels: f64, w: &mut impl Write) -> io::Result<()> {
    let scale = pixels / mesh.width;
    let (width_px, height_px) = (pixels, mesh.height * scale);
    let pad = 0.02 * pixels;
    // y up in the mesh, down in SVG.
    let xy = |p: [f64; 2]| (pad + p[0] * scale, pad + height_px - p[1] * scale);
    writeln!(
        w,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{:.0}" height="{:.0}" viewBox="0 0 {:.1} {:.1}">"#,
        width_px + 2.0 * pad,
        height_px + 2.0 * pad,
        width_px + 2.0 * pad,
        height_px + 2.0 * pad
    )?;
    writeln!(w, r#"<rect width="100%" height="100%" fill="white"/>"#)?;
    writeln!(
        w,
        r##"<g stroke="#333" stroke-width="{:.2}" stroke-linejoin="round">"##,
        0.0015 * pixels
    )?;
    for t in &mesh.triangles {
        let fill = match t.phase {
            Phase::Matrix => "#c8c8c8",
            Phase::Inclusion => "#d9a95b",
        };
        let pts: Vec<String> = t
            .nodes
            .iter()
            .map(|&i| {
                let (x, y) = xy(mesh.nodes[i]);
                format!("{x:.2},{y:.2}")
            })
            .collect();
        writeln!(w, r#"<polygon points="{}" fill="{fill}"/>"#, pts.join(" "))?;
    }
    writeln!(w, "</g>")?;
    writeln!(
        w,
        r##"<g stroke="#d01010" stroke-width="{:.2}" stroke-linecap="round">"##,
        0.006 * pixels
    )?;
    for e in &mesh.interfaces {
        let (x0, y0) = xy(mesh.nodes[e.nodes[0]]);
        let (x1, y1) = xy(mesh.nodes[e.nodes[1]]);
        writeln!(
            w,
            r#"<line x1="{x0:.2}" y1="{y0:.2}" x2="{x1:.2}" y2="{y1:.2}"/>"#
        )?;
    }
    writeln!(w, "</g>\n</svg>")?;
    Ok(())
}
