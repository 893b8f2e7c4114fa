//! Circles and ellipses, their polygons and their separation.

use std::f64::consts::PI;

use super::polygon::{distance_below, polygon_area};

/// An elliptic inclusion (a circle when `a == b`): centre, semi-axes along the rotated
/// axes, and the rotation angle in radians (counter-clockwise, x axis to the `a` axis).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Inclusion {
    pub center: [f64; 2],
    pub semi_axes: [f64; 2],
    pub angle: f64,
}

impl Inclusion {
    pub fn circle(center: [f64; 2], radius: f64) -> Self {
        Inclusion {
            center,
            semi_axes: [radius, radius],
            angle: 0.0,
        }
    }

    pub fn is_circle(&self) -> bool {
        self.semi_axes[0] == self.semi_axes[1]
    }

    pub fn area(&self) -> f64 {
        PI * self.semi_axes[0] * self.semi_axes[1]
    }

    /// Radius of the circumscribed circle.
    pub fn bounding_radius(&self) -> f64 {
        self.semi_axes[0].max(self.semi_axes[1])
    }

    /// Half extents of the axis-aligned bounding box.
    pub fn half_extents(&self) -> [f64; 2] {
        let [a, b] = self.semi_axes;
        let (s, c) = self.angle.sin_cos();
        [
            (a * a * c * c + b * b * s * s).sqrt(),
            (a * a * s * s + b * b * c * c).sqrt(),
        ]
    }

    /// Point of the boundary at parameter `t` (radians), scaled by `scale`.
    fn boundary_point(&self, t: f64, scale: f64) -> [f64; 2] {
        let [a, b] = self.semi_axes;
        let (s, c) = self.angle.sin_cos();
        let (x, y) = (scale * a * t.cos(), scale * b * t.sin());
        [
            self.center[0] + c * x - s * y,
            self.center[1] + s * x + c * y,
        ]
    }

    /// Approximate perimeter (Ramanujan's second formula, exact for circles).
    pub fn perimeter(&self) -> f64 {
        let [a, b] = self.semi_axes;
        let h = ((a - b) / (a + b)).powi(2);
        PI * (a + b) * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()))
    }

    /// Counter-clockwise polygon with edges of length about `h` (at least 8 vertices),
    /// spaced evenly in arc length and scaled so that its area equals the exact area of
    /// the inclusion. Meshes then carry the requested area fraction exactly, not the
    /// polygonal deficit `~ pi^2/(3 n^2)` of an inscribed polygon.
    pub fn polygon(&self, h: f64) -> Vec<[f64; 2]> {
        let n = ((self.perimeter() / h).round() as usize).max(8);
        // Arc-length parametrisation by a fine table of the parameter t.
        const FINE: usize = 2048;
        let mut cumulative = Vec::with_capacity(FINE + 1);
        cumulative.push(0.0);
        let mut prev = self.boundary_point(0.0, 1.0);
        for k in 1..=FINE {
            let p = self.boundary_point(2.0 * PI * k as f64 / FINE as f64, 1.0);
            let last = cumulative[k - 1];
            cumulative.push(last + ((p[0] - prev[0]).powi(2) + (p[1] - prev[1]).powi(2)).sqrt());
            prev = p;
        }
        let total = cumulative[FINE];
        let params: Vec<f64> = (0..n)
            .map(|i| {
                let target = total * i as f64 / n as f64;
                let k = cumulative.partition_point(|&c| c < target).clamp(1, FINE);
                let (c0, c1) = (cumulative[k - 1], cumulative[k]);
                let frac = if c1 > c0 {
                    (target - c0) / (c1 - c0)
                } else {
                    0.0
                };
                2.0 * PI * ((k - 1) as f64 + frac) / FINE as f64
            })
            .collect();
        let unit: Vec<[f64; 2]> = params
            .iter()
            .map(|&t| self.boundary_point(t, 1.0))
            .collect();
        let scale = (self.area() / polygon_area(&unit)).sqrt();
        params
            .iter()
            .map(|&t| self.boundary_point(t, scale))
            .collect()
    }

    /// True when `p` lies inside the ellipse.
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let (dx, dy) = (p[0] - self.center[0], p[1] - self.center[1]);
        let (s, c) = self.angle.sin_cos();
        let (x, y) = (c * dx + s * dy, -s * dx + c * dy);
        (x / self.semi_axes[0]).powi(2) + (y / self.semi_axes[1]).powi(2) < 1.0
    }

    /// True when the two inclusions are at least `gap` apart (boundary to boundary).
    ///
    /// Circles: exact. Ellipses: quick accept/reject with the circumscribed and inscribed
    /// circles, then the distance between boundary polygons (96 vertices, scaled to
    /// circumscribe the exact curve) plus a containment test; conservative by at most
    /// `a (1/cos(pi/96) - 1) < 6e-4 a`.
    pub fn separated_from(&self, other: &Inclusion, gap: f64) -> bool {
        let d = ((self.center[0] - other.center[0]).powi(2)
            + (self.center[1] - other.center[1]).powi(2))
        .sqrt();
        if d >= self.bounding_radius() + other.bounding_radius() + gap {
            return true;
        }
        if self.is_circle() && other.is_circle() {
            return d >= self.semi_axes[0] + other.semi_axes[0] + gap;
        }
        let inscribed = |e: &Inclusion| e.semi_axes[0].min(e.semi_axes[1]);
        if d < inscribed(self) + inscribed(other) + gap {
            return false;
        }
        if self.contains(other.center) || other.contains(self.center) {
            return false;
        }
        const N: usize = 96;
        let circ = 1.0 / (PI / N as f64).cos();
        let pa: Vec<[f64; 2]> = (0..N)
            .map(|k| self.boundary_point(2.0 * PI * k as f64 / N as f64, circ))
            .collect();
        let pb: Vec<[f64; 2]> = (0..N)
            .map(|k| other.boundary_point(2.0 * PI * k as f64 / N as f64, circ))
            .collect();
        distance_below(&pa, &pb, gap) >= gap
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygon_is_ccw_area_preserving() {
        for inc in [
            Inclusion::circle([5.0, 5.0], 1.3),
            Inclusion {
                center: [4.0, 6.0],
                semi_axes: [2.0, 1.0],
                angle: 0.4,
            },
        ] {
            let p = inc.polygon(0.5);
            assert!(p.len() >= 8);
            let a = polygon_area(&p);
            assert!(
                (a - inc.area()).abs() < 1e-9 * inc.area(),
                "{a} vs {}",
                inc.area()
            );
            // Edges are close to h in length.
            for i in 0..p.len() {
                let q = p[(i + 1) % p.len()];
                let l = ((q[0] - p[i][0]).powi(2) + (q[1] - p[i][1]).powi(2)).sqrt();
                assert!(l > 0.3 && l < 0.7, "edge {l}");
            }
        }
    }

    #[test]
    fn separation_matches_circle_formula_for_equal_ellipses() {
        let a = Inclusion {
            center: [0.0, 0.0],
            semi_axes: [2.0, 1.0],
            angle: 0.0,
        };
        // Along x, boundaries 0.3 apart.
        let b = Inclusion {
            center: [4.3, 0.0],
            ..a
        };
        assert!(a.separated_from(&b, 0.29));
        assert!(!a.separated_from(&b, 0.31));
        // Along y the ellipses are thin: 2.3 apart in centres means 0.3 gap.
        let c = Inclusion {
            center: [0.0, 2.3],
            ..a
        };
        assert!(a.separated_from(&c, 0.29));
        assert!(!a.separated_from(&c, 0.31));
        // Rotating by 90 degrees swaps the result.
        let r = Inclusion {
            angle: std::f64::consts::FRAC_PI_2,
            center: [0.0, 4.3],
            ..a
        };
        let r0 = Inclusion {
            angle: std::f64::consts::FRAC_PI_2,
            ..a
        };
        assert!(r0.separated_from(&r, 0.29) && !r0.separated_from(&r, 0.31));
    }

    #[test]
    fn half_extents_of_rotated_ellipse() {
        let e = Inclusion {
            center: [0.0, 0.0],
            semi_axes: [2.0, 1.0],
            angle: std::f64::consts::FRAC_PI_2,
        };
        let [hx, hy] = e.half_extents();
        assert!((hx - 1.0).abs() < 1e-12 && (hy - 2.0).abs() < 1e-12);
    }
}
