//! Random sequential placement ("take-and-place", largest first) and explicit lists.
//!
//! Algorithm, one round:
//! 1. Draw diameters uniformly in `[d_min, d_max]` until the next one would overshoot the
//!    target inclusion area; then close the gap exactly with one last inclusion whose size
//!    is whatever area remains, if that size lies in `[d_min, d_max]`; if the remainder is
//!    too small for `d_min`, the round redraws its sizes (bounded).
//! 2. Sort largest first and place each inclusion at uniformly random positions (and, for
//!    random orientation, angles) until it keeps `gap` to all placed ones and `margin` to
//!    the cell boundary, at most `max_attempts` trials.
//!
//! A round that jams starts again with fresh sizes from the same seeded stream; after
//! `max_rounds` rounds placement fails with an error that reports the best fraction
//! reached. Everything derives from one ChaCha8 stream seeded by `seed`, so the same scene
//! gives the same microstructure on every platform.

use std::f64::consts::PI;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::shape::Inclusion;
use super::spec::{Explicit, Orientation, RandomSpec, ShapeKind};
use crate::error::{Error, Result};

/// A placed microstructure.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Placement {
    pub inclusions: Vec<Inclusion>,
    /// Exact inclusion area over cell area.
    pub area_fraction: f64,
    /// Placement rounds used (1 when the first round succeeded).
    pub rounds: u32,
}

/// Inclusion with major axis `2a = d`: a circle of diameter `d`, or an ellipse with
/// `a / b = aspect`.
fn shaped(spec: &RandomSpec, d: f64, angle: f64) -> Inclusion {
    let a = 0.5 * d;
    let b = match spec.shape {
        ShapeKind::Circle => a,
        ShapeKind::Ellipse => a / spec.aspect_ratio,
    };
    Inclusion {
        center: [0.0, 0.0],
        semi_axes: [a, b],
        angle,
    }
}

/// Area of an inclusion of major diameter `d`.
fn area_of(spec: &RandomSpec, d: f64) -> f64 {
    shaped(spec, d, 0.0).area()
}

/// Major diameter that gives area `area`.
fn diameter_for(spec: &RandomSpec, area: f64) -> f64 {
    let aspect = match spec.shape {
        ShapeKind::Circle => 1.0,
        ShapeKind::Ellipse => spec.aspect_ratio,
    };
    2.0 * (area * aspect / PI).sqrt()
}

/// Draws the diameters of one round, largest first; `None` if no exact closure was found.
fn draw_sizes(spec: &RandomSpec, target_area: f64, rng: &mut ChaCha8Rng) -> Option<Vec<f64>> {
    let [dmin, dmax] = spec.diameter;
    const REDRAWS: usize = 64;
    for _ in 0..REDRAWS {
        let mut sizes = Vec::new();
        let mut area = 0.0;
        loop {
            let d = if dmax > dmin {
                rng.random_range(dmin..=dmax)
            } else {
                dmin
            };
            if area + area_of(spec, d) <= target_area {
                area += area_of(spec, d);
                sizes.push(d);
                continue;
            }
            let rest = target_area - area;
            let d_last = diameter_for(spec, rest);
            if rest <= 1e-12 * target_area {
                break;
            }
            if d_last >= dmin * (1.0 - 1e-12) && d_last <= dmax {
                sizes.push(d_last.max(dmin));
                break;
            }
            // Remainder smaller than d_min: redraw the whole sequence.
            sizes.clear();
            break;
        }
        if !sizes.is_empty() {
            sizes.sort_by(|a, b| b.total_cmp(a));
            return Some(sizes);
        }
    }
    None
}

/// Places random inclusions in the `width x height` cell as `spec` asks.
pub fn place_random(spec: &RandomSpec, width: f64, height: f64) -> Result<Placement> {
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let cell_area = width * height;
    let target_area = spec.area_fraction * cell_area;
    let mut best_fraction = 0.0f64;
    for round in 1..=spec.max_rounds {
        let Some(sizes) = draw_sizes(spec, target_area, &mut rng) else {
            return Err(Error::Placement(format!(
                "cannot split area fraction {} into inclusions with diameters in [{}, {}]; widen geometry.diameter",
                spec.area_fraction, spec.diameter[0], spec.diameter[1]
            )));
        };
        let mut placed: Vec<Inclusion> = Vec::with_capacity(sizes.len());
        let mut placed_area = 0.0;
        for &d in &sizes {
            let mut ok = None;
            for _ in 0..spec.max_attempts {
                let angle = match (spec.shape, spec.orientation) {
                    (ShapeKind::Circle, _) => 0.0,
                    (ShapeKind::Ellipse, Orientation::Fixed(deg)) => deg.to_radians(),
                    (ShapeKind::Ellipse, Orientation::Named(_)) => rng.random_range(0.0..PI),
                };
                let mut inc = shaped(spec, d, angle);
                let [hx, hy] = inc.half_extents();
                let (lo_x, hi_x) = (hx + spec.margin, width - hx - spec.margin);
                let (lo_y, hi_y) = (hy + spec.margin, height - hy - spec.margin);
                if lo_x > hi_x || lo_y > hi_y {
                    break;
                }
                inc.center = [rng.random_range(lo_x..=hi_x), rng.random_range(lo_y..=hi_y)];
                if placed.iter().all(|p| p.separated_from(&inc, spec.gap)) {
                    ok = Some(inc);
                    break;
                }
            }
            match ok {
                Some(inc) => {
                    placed_area += inc.area();
                    placed.push(inc);
                }
                None => break,
            }
        }
        if placed.len() == sizes.len() {
            return Ok(Placement {
                area_fraction: placed_area / cell_area,
                inclusions: placed,
                rounds: round,
            });
        }
        best_fraction = best_fraction.max(placed_area / cell_area);
    }
    Err(Error::Placement(format!(
        "could not place area fraction {} in {} rounds of at most {} attempts per inclusion \
         (best round reached {:.4}); lower geometry.area_fraction, geometry.gap or \
         geometry.margin, or use smaller inclusions",
        spec.area_fraction, spec.max_rounds, spec.max_attempts, best_fraction
    )))
}

/// Checks an explicit list (inside the cell, no overlaps) and converts it.
pub fn build_inclusions(spec: &Explicit, width: f64, height: f64) -> Result<Vec<Inclusion>> {
    let mut out: Vec<Inclusion> = Vec::with_capacity(spec.inclusions.len());
    for (k, e) in spec.inclusions.iter().enumerate() {
        let inc = match (e.radius, e.semi_axes) {
            (Some(r), _) => Inclusion::circle(e.center, r),
            (None, Some(ab)) => Inclusion {
                center: e.center,
                semi_axes: ab,
                angle: e.angle.to_radians(),
            },
            (None, None) => unreachable_shape(k)?,
        };
        let [hx, hy] = inc.half_extents();
        let [cx, cy] = inc.center;
        if cx - hx <= 0.0 || cx + hx >= width || cy - hy <= 0.0 || cy + hy >= height {
            return Err(Error::scene(
                format!("geometry.inclusions[{k}]"),
                "crosses or touches the cell boundary (inclusions must lie strictly inside)",
            ));
        }
        if let Some(j) = out.iter().position(|o| !o.separated_from(&inc, 0.0)) {
            return Err(Error::scene(
                format!("geometry.inclusions[{k}]"),
                format!("overlaps geometry.inclusions[{j}]"),
            ));
        }
        out.push(inc);
    }
    Ok(out)
}

fn unreachable_shape(k: usize) -> Result<Inclusion> {
    Err(Error::scene(
        format!("geometry.inclusions[{k}]"),
        "give `radius` or `semi_axes`",
    ))
}
