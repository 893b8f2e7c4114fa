//! Plain polygon helpers: closed polygons as vertex lists, counter-clockwise.

/// Shoelace area (positive for counter-clockwise).
pub fn polygon_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
}

/// Distance between point `p` and segment `ab`.
fn point_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (vx, vy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = vx * vx + vy * vy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * vx + (p[1] - a[1]) * vy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p[0] - a[0] - t * vx).powi(2) + (p[1] - a[1] - t * vy).powi(2)).sqrt()
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// True when the closed segments `ab` and `cd` cross or touch (collinear segments only
/// when their extents overlap).
pub fn segments_intersect(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if o1 == 0.0 && o2 == 0.0 {
        // Collinear: overlap of the coordinate ranges along both axes.
        let overlap =
            |k: usize| a[k].min(b[k]) <= c[k].max(d[k]) && c[k].min(d[k]) <= a[k].max(b[k]);
        return overlap(0) && overlap(1);
    }
    (o1 * o2 <= 0.0) && (o3 * o4 <= 0.0)
}

/// Smallest distance between the boundaries of two closed polygons (0 if they cross).
pub fn polygon_distance(pa: &[[f64; 2]], pb: &[[f64; 2]]) -> f64 {
    distance_below(pa, pb, 0.0)
}

/// Like [`polygon_distance`], but stops as soon as a distance below `stop` is seen; the
/// result is then some distance `< stop`, not the minimum. `polygon_distance(a, b) >= gap`
/// is equivalent to `distance_below(a, b, gap) >= gap`, and much faster when it is false.
pub fn distance_below(pa: &[[f64; 2]], pb: &[[f64; 2]], stop: f64) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..pa.len() {
        let (a0, a1) = (pa[i], pa[(i + 1) % pa.len()]);
        for j in 0..pb.len() {
            let (b0, b1) = (pb[j], pb[(j + 1) % pb.len()]);
            if segments_intersect(a0, a1, b0, b1) {
                return 0.0;
            }
            best = best
                .min(point_segment(a0, b0, b1))
                .min(point_segment(b0, a0, a1));
            if best < stop {
                return best;
            }
        }
    }
    best
}

/// Axis-aligned bounding box `[x_min, y_min, x_max, y_max]`.
pub fn bounding_box(p: &[[f64; 2]]) -> [f64; 4] {
    p.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, q| {
            [
                b[0].min(q[0]),
                b[1].min(q[1]),
                b[2].max(q[0]),
                b[3].max(q[1]),
            ]
        },
    )
}

/// Even-odd ray casting test (points on the boundary may go either way).
pub fn point_in_polygon(p: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_area_inside_and_distance() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(polygon_area(&sq), 1.0);
        assert!(point_in_polygon([0.5, 0.5], &sq));
        assert!(!point_in_polygon([1.5, 0.5], &sq));
        let moved: Vec<[f64; 2]> = sq.iter().map(|p| [p[0] + 1.25, p[1]]).collect();
        let d = polygon_distance(&sq, &moved);
        assert!((d - 0.25).abs() < 1e-14, "distance {d}");
        assert!(!segments_intersect(
            [0.0, 0.0],
            [1.0, 0.0],
            [1.25, 0.0],
            [2.0, 0.0]
        ));
        assert!(segments_intersect(
            [0.0, 0.0],
            [1.0, 0.0],
            [0.5, 0.0],
            [2.0, 0.0]
        ));
        assert!(segments_intersect(
            [0.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [1.0, 0.0]
        ));
        let crossing: Vec<[f64; 2]> = sq.iter().map(|p| [p[0] + 0.5, p[1] + 0.5]).collect();
        assert_eq!(polygon_distance(&sq, &crossing), 0.0);
        assert_eq!(bounding_box(&crossing), [0.5, 0.5, 1.5, 1.5]);
    }
}
