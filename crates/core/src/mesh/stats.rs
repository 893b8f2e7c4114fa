//! Mesh statistics, as printed by `rve mesh --json`.

use serde::Serialize;

use super::model::{Mesh, Phase};

/// Summary of a mesh. The first keys are a stable interface of `rve mesh --json`.
#[derive(Clone, Debug, Serialize)]
pub struct MeshStats {
    pub nodes: usize,
    pub triangles: usize,
    pub matrix_triangles: usize,
    pub inclusion_triangles: usize,
    pub interface_elements: usize,
    /// Meshed inclusion area over cell area.
    pub inclusion_area_fraction: f64,
    /// Smallest interior angle over all triangles, degrees.
    pub min_angle_deg: f64,
    pub periodic_sides_match: bool,
    /// Sum of triangle areas over the cell area (1 for a mesh that fills the cell).
    pub area_ratio: f64,
    pub cell: [f64; 2],
    /// Total ITZ length and the mean interface element length.
    pub interface_length: f64,
    pub mean_interface_element_length: f64,
}

/// Interior angles of the triangle with vertices `p`, degrees.
pub fn triangle_angles_deg(p: [[f64; 2]; 3]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for k in 0..3 {
        let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
        let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
        let cross = u[0] * v[1] - u[1] * v[0];
        let dot = u[0] * v[0] + u[1] * v[1];
        out[k] = cross.abs().atan2(dot).to_degrees();
    }
    out
}

impl MeshStats {
    pub fn of(mesh: &Mesh) -> Self {
        let mut matrix_triangles = 0;
        let (mut area, mut inclusion_area) = (0.0, 0.0);
        let mut min_angle = f64::INFINITY;
        for t in &mesh.triangles {
            let a = mesh.triangle_area(t);
            area += a;
            match t.phase {
                Phase::Matrix => matrix_triangles += 1,
                Phase::Inclusion => inclusion_area += a,
            }
            let angles = triangle_angles_deg(t.nodes.map(|i| mesh.nodes[i]));
            min_angle = angles.iter().fold(min_angle, |m, &x| m.min(x));
        }
        let interface_length: f64 = mesh.interfaces.iter().map(|e| e.length).sum();
        let n_itz = mesh.interfaces.len();
        MeshStats {
            nodes: mesh.nodes.len(),
            triangles: mesh.triangles.len(),
            matrix_triangles,
            inclusion_triangles: mesh.triangles.len() - matrix_triangles,
            interface_elements: n_itz,
            inclusion_area_fraction: inclusion_area / mesh.cell_area(),
            min_angle_deg: min_angle,
            periodic_sides_match: mesh.boundary.sides_match,
            area_ratio: area / mesh.cell_area(),
            cell: [mesh.width, mesh.height],
            interface_length,
            mean_interface_element_length: if n_itz > 0 {
                interface_length / n_itz as f64
            } else {
                0.0
            },
        }
    }
}
