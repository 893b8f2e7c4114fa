//! The scene's macro strain path: the strain bound every path point and every update
//! respect, and the strain at each increment of the `[[path]]` segments. Shared by
//! `rve run`, the C functions `rve_path_len`/`rve_path_point` and the tests, so they
//! all follow the same points.

use super::schema::PathSegment;

/// Largest strain component accepted: 10 %, a hundred times the strains at which concrete
/// fails; beyond it a small-strain RVE makes no sense and the input is taken as absurd.
pub const MAX_STRAIN: f64 = 0.1;

/// Which components each increment of the path holds at zero stress (its segment's).
pub fn path_zero_stress(path: &[PathSegment]) -> Vec<[bool; 3]> {
    path.iter()
        .flat_map(|seg| std::iter::repeat_n(seg.zero_stress.0, seg.increments as usize))
        .collect()
}

/// The strain at every increment of the path, in order. Segment `k` goes from the end of
/// segment `k - 1` (zero strain for the first) to `to` in `increments` equal steps; its
/// last point is `to` exactly, so the next segment starts from the value written in the
/// scene, not from an interpolation.
pub fn path_points(path: &[PathSegment]) -> Vec<[f64; 3]> {
    let mut points = Vec::new();
    let mut from = [0.0; 3];
    for seg in path {
        for k in 1..=seg.increments {
            let t = k as f64 / seg.increments as f64;
            points.push(if k == seg.increments {
                seg.to
            } else {
                [
                    from[0] + t * (seg.to[0] - from[0]),
                    from[1] + t * (seg.to[1] - from[1]),
                    from[2] + t * (seg.to[2] - from[2]),
                ]
            });
        }
        from = seg.to;
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equal steps within a segment, the segment ends exact, the next segment from there.
    #[test]
    fn segments_in_equal_steps_ending_exactly() {
        let path = [
            PathSegment {
                to: [3e-4, 0.0, -3e-4],
                increments: 3,
                zero_stress: Default::default(),
            },
            PathSegment {
                to: [1e-4, 0.0, 0.0],
                increments: 2,
                zero_stress: Default::default(),
            },
        ];
        let p = path_points(&path);
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-18);
        assert_eq!(p.len(), 5);
        assert!(close(p[0], [1e-4, 0.0, -1e-4]));
        assert!(close(p[1], [2e-4, 0.0, -2e-4]));
        assert_eq!(p[2], [3e-4, 0.0, -3e-4]);
        assert!(close(p[3], [2e-4, 0.0, -1.5e-4]));
        assert_eq!(p[4], [1e-4, 0.0, 0.0]);
        assert!(path_points(&[]).is_empty());
    }
}
