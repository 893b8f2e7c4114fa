//! SVG picture of a mesh in the manner of the paper's Figs. 9 and 14: matrix grey,
//! aggregates tan, triangle edges thin, ITZ elements drawn as thick red segments; the
//! deformed RVE of a state (Figs. 10, 12, 13) and the stress plot of a run.

use std::io::{self, Write};

use super::fields::RveFields;
use mesorve_core::mesh::{Mesh, Phase};

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

/// The amplification of the displacements in [`write_deformed_svg`]: the largest nodal
/// displacement drawn as about 8% of the cell width, rounded down to 1, 2 or 5 times a
/// power of ten (1 for a state at rest).
pub fn amplification(mesh: &Mesh, fields: &RveFields) -> f64 {
    let umax = fields
        .displacement
        .iter()
        .fold(0.0f64, |m, u| m.max(u[0].hypot(u[1])));
    if umax <= 0.0 || !umax.is_finite() {
        return 1.0;
    }
    let raw = 0.08 * mesh.width.max(mesh.height) / umax;
    let decade = 10f64.powf(raw.log10().floor());
    let mantissa = [5.0, 2.0, 1.0]
        .into_iter()
        .find(|m| m * decade <= raw)
        .unwrap_or(1.0);
    mantissa * decade
}

/// Colour of `delta_max/delta_c` on a white-yellow-red-black scale: 0 white, 1 (the
/// peak of the envelope) orange, 5 and more dark red.
fn opening_colour(ratio: f64) -> String {
    let r = if ratio.is_finite() {
        ratio.max(0.0)
    } else {
        0.0
    };
    let t = (r / 5.0).min(1.0).sqrt();
    let (red, green, blue) = (
        255.0 * (1.0 - 0.55 * (t - 0.6).max(0.0) / 0.4),
        255.0 * (1.0 - t),
        255.0 * (1.0 - (3.0 * t).min(1.0)),
    );
    format!("#{:02x}{:02x}{:02x}", red as u8, green as u8, blue as u8)
}

/// Writes an SVG of the deformed RVE in the manner of the paper's Figs. 10, 12 and 13:
/// the nodes moved by `A u` with the amplification `A` of [`amplification`] (stated in the
/// caption), triangles by phase, every ITZ element as the quad between its two deformed
/// faces (`class="itz"`) coloured by `delta_max/delta_c` (legend), and a black dot
/// (`class="closed"`) on each element with a point in contact. `caption` is printed on
/// top, followed by the amplification.
pub fn write_deformed_svg(
    mesh: &Mesh,
    fields: &RveFields,
    pixels: f64,
    caption: &str,
    w: &mut impl Write,
) -> io::Result<()> {
    let view = DeformedView::new(mesh, fields, pixels);
    view.write_header(caption, w)?;
    view.write_triangles(w)?;
    view.write_itz(w)?;
    view.write_contact(w)?;
    view.write_legend(w)?;
    writeln!(w, "</svg>")
}

/// The layout of [`write_deformed_svg`]'s picture, `pixels` wide.
struct DeformedView<'a> {
    mesh: &'a Mesh,
    fields: &'a RveFields,
    pixels: f64,
    /// The amplification of the displacements.
    amp: f64,
    /// Pixels per unit of length.
    scale: f64,
    /// The margin round the cell, and the room above it.
    pad: f64,
    top: f64,
    /// The picture's width and height.
    wpx: f64,
    hpx: f64,
    /// The font size of the caption.
    font: f64,
}

impl<'a> DeformedView<'a> {
    fn new(mesh: &'a Mesh, fields: &'a RveFields, pixels: f64) -> Self {
        let amp = amplification(mesh, fields);
        let scale = 0.8 * pixels / mesh.width;
        let pad = 0.1 * pixels;
        let top = 0.0;
        let (wpx, hpx) = (pixels, mesh.height * scale + 2.0 * pad + top);
        DeformedView {
            mesh,
            fields,
            pixels,
            amp,
            scale,
            pad,
            top,
            wpx,
            hpx,
            font: 0.022 * pixels,
        }
    }

    /// The picture coordinates of node `i` moved by `A u`, from the first corner.
    fn xy(&self, i: usize) -> (f64, f64) {
        let (mesh, amp, scale, pad) = (self.mesh, self.amp, self.scale, self.pad);
        let y0 = mesh.nodes[mesh.boundary.corners[0]];
        let p = mesh.nodes[i];
        let u = self.fields.displacement[i];
        let (x, y) = (p[0] - y0[0] + amp * u[0], p[1] - y0[1] + amp * u[1]);
        (
            pad + x * scale,
            self.top + pad + mesh.height * scale - y * scale,
        )
    }

    /// The `points` attribute of a polygon through `nodes`.
    fn pts(&self, nodes: &[usize]) -> String {
        nodes
            .iter()
            .map(|&i| {
                let (x, y) = self.xy(i);
                format!("{x:.2},{y:.2}")
            })
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The `<svg>` element, the white background and the caption.
    fn write_header(&self, caption: &str, w: &mut impl Write) -> io::Result<()> {
        let (wpx, hpx, pad, font) = (self.wpx, self.hpx, self.pad, self.font);
        writeln!(
            w,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{wpx:.0}" height="{hpx:.0}" viewBox="0 0 {wpx:.1} {hpx:.1}">"#
        )?;
        writeln!(w, r#"<rect width="100%" height="100%" fill="white"/>"#)?;
        writeln!(
            w,
            r#"<text x="{pad:.1}" y="{:.1}" font-family="sans-serif" font-size="{font:.1}">{} (displacements x {})</text>"#,
            0.05 * self.pixels,
            xml_escape(caption),
            self.amp
        )
    }

    /// The triangles, filled by phase.
    fn write_triangles(&self, w: &mut impl Write) -> io::Result<()> {
        writeln!(
            w,
            r##"<g stroke="#555" stroke-width="{:.2}" stroke-linejoin="round">"##,
            0.001 * self.pixels
        )?;
        for t in &self.mesh.triangles {
            let fill = match t.phase {
                Phase::Matrix => "#d4d4d4",
                Phase::Inclusion => "#e3c08a",
            };
            writeln!(
                w,
                r#"<polygon points="{}" fill="{fill}"/>"#,
                self.pts(&t.nodes)
            )?;
        }
        writeln!(w, "</g>")
    }

    /// Every ITZ element as the quad between its deformed faces, coloured by
    /// `delta_max/delta_c`.
    fn write_itz(&self, w: &mut impl Write) -> io::Result<()> {
        writeln!(
            w,
            r##"<g stroke-width="{:.2}" stroke-linejoin="round">"##,
            0.0008 * self.pixels
        )?;
        for (e, itz) in self.mesh.interfaces.iter().enumerate() {
            let ratio = self
                .fields
                .itz
                .get(e)
                .map_or(f64::NAN, |f| f.measures.max_opening_ratio);
            let colour = opening_colour(ratio);
            let [a0, a1, b0, b1] = itz.nodes;
            writeln!(
                w,
                r#"<polygon class="itz" points="{}" fill="{colour}" stroke="{colour}"><title>delta_max/delta_c = {ratio:.3}</title></polygon>"#,
                self.pts(&[a0, a1, b1, b0])
            )?;
        }
        writeln!(w, "</g>")
    }

    /// A black dot on each ITZ element with a point in contact.
    fn write_contact(&self, w: &mut impl Write) -> io::Result<()> {
        writeln!(w, r#"<g fill="black">"#)?;
        for (e, itz) in self.mesh.interfaces.iter().enumerate() {
            if self.fields.itz.get(e).is_some_and(|f| f.closed_points > 0) {
                let (xa, ya) = self.xy(itz.nodes[0]);
                let (xb, yb) = self.xy(itz.nodes[1]);
                writeln!(
                    w,
                    r#"<circle class="closed" cx="{:.2}" cy="{:.2}" r="{:.2}"/>"#,
                    0.5 * (xa + xb),
                    0.5 * (ya + yb),
                    0.004 * self.pixels
                )?;
            }
        }
        writeln!(w, "</g>")
    }

    /// Legend of delta_max/delta_c.
    fn write_legend(&self, w: &mut impl Write) -> io::Result<()> {
        let (pixels, pad, font) = (self.pixels, self.pad, self.font);
        let (lx, ly, lw, lh) = (pad, self.hpx - 0.55 * pad, 0.4 * pixels, 0.2 * pad);
        for k in 0..50 {
            let r = 5.0 * (k as f64 / 49.0).powi(2);
            writeln!(
                w,
                r#"<rect x="{:.2}" y="{ly:.2}" width="{:.2}" height="{lh:.2}" fill="{}"/>"#,
                lx + lw * k as f64 / 50.0,
                lw / 50.0 + 0.5,
                opening_colour(r)
            )?;
        }
        for tick in [0.0, 1.0, 2.0, 5.0] {
            writeln!(
                w,
                r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="{:.1}" text-anchor="middle">{tick}</text>"#,
                lx + lw * (tick / 5.0f64).sqrt(),
                ly + lh + 1.2 * font,
                0.8 * font
            )?;
        }
        writeln!(
            w,
            r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="{:.1}">ITZ delta_max/delta_c; dots: contact</text>"#,
            lx + lw + 0.02 * pixels,
            ly + lh,
            0.8 * font
        )
    }
}

/// One increment of a run for [`write_response_svg`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResponsePoint {
    /// The path parameter (the increment number).
    pub t: f64,
    /// `[s_xx, s_yy, s_xy]`.
    pub stress: [f64; 3],
    /// Interface points loading and in contact at the end of the increment.
    pub loading_points: usize,
    pub contact_points: usize,
}

/// Writes the stress-path plot of a run: `s_xx`, `s_yy`, `s_xy` against the path
/// parameter. A filled marker is an increment with interface points on the loading
/// branch, a hollow one an increment without (unloading/reloading); a grey bar under the
/// axis marks increments with points in contact.
pub fn write_response_svg(points: &[ResponsePoint], w: &mut impl Write) -> io::Result<()> {
    let plot = ResponsePlot::new(points);
    plot.write_axes(w)?;
    for p in points.iter().filter(|p| p.contact_points > 0) {
        writeln!(
            w,
            r##"<rect class="contact" x="{:.2}" y="{:.2}" width="3" height="8" fill="#888"/>"##,
            plot.x(p.t) - 1.5,
            plot.top + plot.ph + 24.0
        )?;
    }
    let names = ["s_xx", "s_yy", "s_xy"];
    let colours = ["#1f4fb4", "#c0392b", "#2e8b3a"];
    for (k, (name, colour)) in names.iter().zip(colours).enumerate() {
        plot.write_curve(points, k, name, colour, w)?;
    }
    let (left, pw) = (plot.left, plot.pw);
    let ly = plot.top + 80.0;
    writeln!(
        w,
        r#"<text x="{0:.1}" y="{ly:.1}" font-size="11">filled: ITZ loading</text><text x="{0:.1}" y="{1:.1}" font-size="11">hollow: unloading</text><text x="{0:.1}" y="{2:.1}" font-size="11">grey bars: contact</text>"#,
        left + pw + 12.0,
        ly + 16.0,
        ly + 32.0
    )?;
    writeln!(w, "</svg>")
}

/// The layout of [`write_response_svg`]'s plot: the picture, the plot area in it and the
/// ranges of the path parameter and of the stress.
struct ResponsePlot {
    wpx: f64,
    hpx: f64,
    left: f64,
    top: f64,
    /// Width and height of the plot area.
    pw: f64,
    ph: f64,
    /// The largest path parameter (at least 1).
    tmax: f64,
    /// The stress range, with a margin of 5 % each way.
    lo: f64,
    hi: f64,
}

impl ResponsePlot {
    fn new(points: &[ResponsePoint]) -> Self {
        let (wpx, hpx) = (720.0, 440.0);
        let (left, right, top, bottom) = (80.0, 140.0, 30.0, 60.0);
        let (pw, ph) = (wpx - left - right, hpx - top - bottom);
        let tmax = points.iter().fold(1.0f64, |m, p| m.max(p.t));
        let (mut lo, mut hi) = (0.0f64, 0.0f64);
        for p in points {
            for s in p.stress {
                lo = lo.min(s);
                hi = hi.max(s);
            }
        }
        if hi - lo <= 0.0 {
            hi = lo + 1.0;
        }
        let margin = 0.05 * (hi - lo);
        let (lo, hi) = (lo - margin, hi + margin);
        ResponsePlot {
            wpx,
            hpx,
            left,
            top,
            pw,
            ph,
            tmax,
            lo,
            hi,
        }
    }

    /// The picture abscissa of the path parameter `t`.
    fn x(&self, t: f64) -> f64 {
        self.left + self.pw * t / self.tmax
    }

    /// The picture ordinate of the stress `s`.
    fn y(&self, s: f64) -> f64 {
        self.top + self.ph * (self.hi - s) / (self.hi - self.lo)
    }

    /// The `<svg>` element, the frame, the zero line, the ticks and the axis labels.
    fn write_axes(&self, w: &mut impl Write) -> io::Result<()> {
        let (wpx, hpx, left, top, pw, ph) =
            (self.wpx, self.hpx, self.left, self.top, self.pw, self.ph);
        let (lo, hi, tmax) = (self.lo, self.hi, self.tmax);
        writeln!(
            w,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{wpx}" height="{hpx}" viewBox="0 0 {wpx} {hpx}" font-family="sans-serif" font-size="13">"#
        )?;
        writeln!(w, r#"<rect width="100%" height="100%" fill="white"/>"#)?;
        writeln!(
            w,
            r##"<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="#000"/>"##
        )?;
        writeln!(
            w,
            r##"<line x1="{left}" y1="{0:.2}" x2="{1}" y2="{0:.2}" stroke="#999" stroke-dasharray="4 3"/>"##,
            self.y(0.0),
            left + pw
        )?;
        for k in 0..=4 {
            let s = lo + (hi - lo) * k as f64 / 4.0;
            writeln!(
                w,
                r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{s:.3}</text>"#,
                left - 6.0,
                self.y(s) + 4.0
            )?;
            let t = tmax * k as f64 / 4.0;
            writeln!(
                w,
                r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{t:.0}</text>"#,
                self.x(t),
                top + ph + 18.0
            )?;
        }
        writeln!(
            w,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">increment (path parameter)</text>"#,
            left + 0.5 * pw,
            hpx - 12.0
        )?;
        writeln!(
            w,
            r#"<text x="16" y="{:.1}" transform="rotate(-90 16 {:.1})" text-anchor="middle">stress</text>"#,
            top + 0.5 * ph,
            top + 0.5 * ph
        )
    }

    /// Stress component `k` (`name`, in `colour`): its line, its markers (filled where
    /// interface points load) and its legend entry.
    fn write_curve(
        &self,
        points: &[ResponsePoint],
        k: usize,
        name: &str,
        colour: &str,
        w: &mut impl Write,
    ) -> io::Result<()> {
        let line: Vec<String> = points
            .iter()
            .map(|p| format!("{:.2},{:.2}", self.x(p.t), self.y(p.stress[k])))
            .collect();
        writeln!(
            w,
            r#"<polyline class="curve" points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
            line.join(" ")
        )?;
        for p in points {
            let fill = if p.loading_points > 0 {
                colour
            } else {
                "white"
            };
            writeln!(
                w,
                r#"<circle cx="{:.2}" cy="{:.2}" r="2.5" fill="{fill}" stroke="{colour}"/>"#,
                self.x(p.t),
                self.y(p.stress[k])
            )?;
        }
        let (left, pw) = (self.left, self.pw);
        let ly = self.top + 20.0 * k as f64 + 10.0;
        writeln!(
            w,
            r#"<line x1="{0:.1}" y1="{ly:.1}" x2="{1:.1}" y2="{ly:.1}" stroke="{colour}" stroke-width="2"/><text x="{2:.1}" y="{3:.1}">{name}</text>"#,
            left + pw + 12.0,
            left + pw + 36.0,
            left + pw + 42.0,
            ly + 4.0
        )
    }
}

/// Escapes the XML special characters of a text node.
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
