//! Sharing's error against each point's own exact run (`[solver] share_tolerance`,
//! docs/sharing.md): batches of points along their own strain paths, run with and without
//! the key, compared point by point. Used by `tests/share_error.rs` (CI sizes) and
//! `benches/share_error.rs` (many random cases).

#![allow(dead_code)]

use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rve::model::batch::{update_batch, BatchOutputs, BatchStep, PointReport};
use rve::model::share;
use rve::{Instance, Model, Scene, TangentRequest};

/// The tolerances a scene accepts are `(0, MAX]`; these are checked.
pub const TOLERANCES: [f64; 5] = [0.005, 0.01, 0.02, 0.05, 0.1];

/// `scene` (a file of the repository) with `share_tolerance = tol` when given.
pub fn model(scene: &str, tol: Option<f64>) -> Arc<Model> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{scene}: {e}"));
    let extra = tol.map_or(String::new(), |t| format!("share_tolerance = {t}\n"));
    let text = text.replacen("[solver]\n", &format!("[solver]\n{extra}"), 1);
    let scene = Scene::from_toml_str(&text, env!("CARGO_MANIFEST_DIR")).unwrap();
    Arc::new(Model::from_scene(&scene).unwrap())
}

/// The stresses of every point at every increment (`[increment][point]`) and the
/// (solved, shared) counts, every increment one batch (`DTIME` 1) then a commit.
pub fn run(model: &Arc<Model>, paths: &[Vec<[f64; 3]>]) -> (Vec<Vec<[f64; 3]>>, (usize, usize)) {
    let n = paths.len();
    let increments = paths[0].len();
    let mut points: Vec<Instance> = (0..n).map(|_| Instance::new(model.clone())).collect();
    let (mut all, mut counts) = (Vec::new(), (0, 0));
    for i in 0..increments {
        let strains: Vec<[f64; 3]> = paths.iter().map(|p| p[i]).collect();
        let (mut stresses, mut tangents) = (vec![[0.0; 3]; n], vec![[0.0; 9]; n]);
        let mut reports = vec![PointReport::default(); n];
        let step = BatchStep {
            dtime: 1.0,
            request: TangentRequest::Consistent,
            threads: 1,
        };
        let out = BatchOutputs {
            stresses: &mut stresses,
            tangents: Some(&mut tangents),
            reports: &mut reports,
        };
        let failures = update_batch(&mut points, &strains, step, out).unwrap();
        assert!(failures.is_empty(), "increment {i}: {failures:?}");
        points.iter_mut().for_each(|p| p.commit().unwrap());
        let (s, f) = share::counts(&reports);
        counts = (counts.0 + s, counts.1 + f);
        all.push(stresses);
    }
    (all, counts)
}

/// The error measure of docs/sharing.md, point by point: the largest difference of a
/// point's stress from its exact run's (any component, any increment) over the largest
/// stress of its exact run; returns the worst point's value and index.
pub fn worst_point(exact: &[Vec<[f64; 3]>], shared: &[Vec<[f64; 3]>]) -> (f64, usize) {
    let n = exact[0].len();
    let inf = |v: &[f64; 3]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    (0..n)
        .map(|p| {
            let largest = exact.iter().map(|s| inf(&s[p])).fold(0.0f64, f64::max);
            let diff = exact
                .iter()
                .zip(shared)
                .map(|(a, b)| inf(&std::array::from_fn(|c| a[p][c] - b[p][c])))
                .fold(0.0f64, f64::max);
            (diff / largest, p)
        })
        .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a })
}

/// A path of `up` increments from 0 to `amplitude * direction`, then `down` back
/// towards `back * amplitude * direction`.
pub fn up_and_back(
    direction: [f64; 3],
    amplitude: f64,
    (up, down): (usize, usize),
    back: f64,
) -> Vec<[f64; 3]> {
    let mut path: Vec<f64> = (1..=up).map(|i| amplitude * i as f64 / up as f64).collect();
    path.extend((1..=down).map(|i| amplitude * (1.0 - (1.0 - back) * i as f64 / down as f64)));
    path.iter().map(|a| direction.map(|d| d * a)).collect()
}

/// One random case: a direction (tension-dominated, with some lateral strain and shear),
/// `n` points at scales within `spread` of 1 along it, some of them with a history of
/// their own first (a pre-load in another direction and back), an amplitude past the
/// peak, increment counts and an unloading depth; all from `seed`.
pub fn random_case(seed: u64, n: usize, spread: f64) -> (Vec<Vec<[f64; 3]>>, String) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let direction = [
        1.0,
        rng.random_range(-0.3..0.1),
        rng.random_range(-0.3..0.3),
    ];
    let amplitude = rng.random_range(1.8e-4..4.0e-4);
    let up = rng.random_range(10..240);
    let down = rng.random_range(5..120);
    let back = rng.random_range(-0.5..0.5);
    let base = up_and_back(direction, amplitude, (up, down), back);
    let pre_len = rng.random_range(0..40usize);
    let other = [
        rng.random_range(-0.5..1.0),
        rng.random_range(0.2..1.0),
        rng.random_range(-1.0..1.0),
    ];
    let paths = (0..n)
        .map(|_| {
            let scale = 1.0 + rng.random_range(-spread..spread);
            let pre = if pre_len > 1 && rng.random_bool(0.3) {
                let size = rng.random_range(0.3..1.2) * amplitude;
                up_and_back(other, size, (pre_len / 2, pre_len - pre_len / 2), 0.0)
            } else {
                vec![[0.0; 3]; pre_len]
            };
            pre.iter()
                .copied()
                .chain(base.iter().map(|e| e.map(|v| v * scale)))
                .collect()
        })
        .collect();
    let what = format!(
        "seed {seed}: direction {direction:?}, amplitude {amplitude:.3e}, {up} up, {down} back \
         to {back:.2}, pre-load of {pre_len} increments along {other:?}"
    );
    (paths, what)
}
