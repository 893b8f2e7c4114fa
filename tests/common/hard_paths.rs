//! Seeded hard cases for the paper's RVE: a microstructure, a mesh, a boundary
//! condition, a contact penalty and a strain path a host could hand an RVE past the peak.
//! Shared by `tests/hard_cases.rs`, `tests/fracture.rs` and `examples/hard_cases.rs`, with
//! the host loop that follows a path as a UMAT host does (`host_follow`).
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rve::{Error, Instance, TangentRequest};

/// The path families; case `seed` draws family `seed % 8`, so any 8 consecutive seeds
/// cover them all.
pub const KINDS: [&str; 8] = [
    "uniaxial strain",
    "uniaxial stress",
    "shear reversal",
    "biaxial",
    "tension-compression",
    "unload-reload",
    "turn x then y",
    "across softening",
];

/// One drawn case.
pub struct HardCase {
    pub seed: u64,
    pub kind: &'static str,
    /// Shape, boundary condition, mesh size and penalty, for messages.
    pub setup: String,
    /// The scene (TOML) without a path.
    pub scene: String,
    /// The macro strain after each increment of the path (the first from zero).
    pub targets: Vec<[f64; 3]>,
}

/// `a [c^2, s^2, 2 c s]`: uniaxial strain `a` along the angle `theta`.
fn uniaxial(a: f64, theta: f64) -> [f64; 3] {
    let (s, c) = theta.sin_cos();
    [a * c * c, a * s * s, 2.0 * a * c * s]
}

/// Principal strains `(e1, e2)` with the first axis at `theta`, in Voigt form.
fn principal(e1: f64, e2: f64, theta: f64) -> [f64; 3] {
    let (s, c) = theta.sin_cos();
    [
        e1 * c * c + e2 * s * s,
        e1 * s * s + e2 * c * c,
        2.0 * (e1 - e2) * c * s,
    ]
}

/// Appends `n` equal increments from the last target (or zero) to `to`.
fn segment(targets: &mut Vec<[f64; 3]>, to: [f64; 3], n: u32) {
    let from = targets.last().copied().unwrap_or([0.0; 3]);
    for k in 1..=n {
        let f = k as f64 / n as f64;
        targets.push(std::array::from_fn(|c| from[c] + f * (to[c] - from[c])));
    }
}

/// The case of `seed`.
pub fn case(seed: u64) -> HardCase {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let kind = KINDS[(seed % 8) as usize];
    let ellipses = rng.random_bool(0.4);
    let linear = rng.random_bool(0.3);
    let geometry_seed: u32 = rng.random_range(1..1000);
    // The paper's meshes: 0.84 (circles) and 0.62 (ellipses), varied by -15..+15 %.
    let size = if ellipses { 0.62 } else { 0.84 } * rng.random_range(0.85..1.15);
    let lambda_p = 10f64.powf(rng.random_range(4.0..=9.0));
    let shape = if ellipses {
        "shape = \"ellipse\"\naspect_ratio = 1.5\norientation = \"random\""
    } else {
        "shape = \"circle\""
    };
    let interface_size = if ellipses { size } else { 0.57 * size };
    let scene = format!(
        "[cell]\nsize = [10.0, 10.0]\nanalysis = \"plane_stress\"\n\n\
         [geometry]\nkind = \"random\"\n{shape}\ndiameter = [2.5, 5.0]\narea_fraction = 0.45\n\
         seed = {geometry_seed}\ngap = 0.3\nmargin = 0.3\n\n\
         [mesh]\nsize = {size:.4}\ninterface_size = {interface_size:.4}\n\n\
         [materials]\nmatrix = {{ young = 25000.0, poisson = 0.2 }}\n\
         aggregate = {{ young = 30000.0, poisson = 0.2 }}\n\
         itz = {{ sigma_c = 4.0, delta_c = 0.0002, beta = 0.707, penalty = {{ lambda_p = {lambda_p:.4e} }} }}\n\n\
         [boundary]\nkind = \"{}\"\n\n[solver]\ntolerance = 1e-6\nmax_iterations = 40\n",
        if linear { "linear" } else { "periodic" }
    );
    let setup = format!(
        "{} seed {geometry_seed}, {} BC, mesh {size:.3}, lambda_p {lambda_p:.2e}",
        if ellipses { "ellipses" } else { "circles" },
        if linear { "linear" } else { "periodic" }
    );

    let theta = rng.random_range(0.0..std::f64::consts::PI);
    // Past the peak (2.2e-4 along x on the paper's RVE).
    let amplitude = rng.random_range(2.6e-4..4.0e-4);
    let n = |rng: &mut ChaCha8Rng| rng.random_range(6..=30u32);
    let mut t = Vec::new();
    match kind {
        "uniaxial strain" => segment(&mut t, uniaxial(amplitude, theta), n(&mut rng)),
        "uniaxial stress" => {
            let nu = rng.random_range(0.15..0.25);
            segment(
                &mut t,
                principal(amplitude, -nu * amplitude, theta),
                n(&mut rng),
            );
        }
        "shear reversal" => {
            let g = rng.random_range(4e-4..8e-4);
            let n1 = n(&mut rng);
            segment(&mut t, [0.0, 0.0, g], n1);
            segment(&mut t, [0.0, 0.0, -g], 2 * n1);
        }
        "biaxial" => {
            let ratio = rng.random_range(-1.0..1.0);
            segment(
                &mut t,
                principal(amplitude, ratio * amplitude, theta),
                n(&mut rng),
            );
        }
        "tension-compression" => {
            let c = rng.random_range(1.0..2.0);
            let n1 = n(&mut rng);
            segment(&mut t, uniaxial(amplitude, theta), n1);
            segment(&mut t, uniaxial(-c * amplitude, theta), 2 * n1);
        }
        "unload-reload" => {
            let back = rng.random_range(0.0..0.5);
            let (n1, n2, n3) = (n(&mut rng), n(&mut rng), n(&mut rng));
            segment(&mut t, uniaxial(amplitude, theta), n1);
            segment(&mut t, uniaxial(back * amplitude, theta), n2);
            segment(&mut t, uniaxial(1.4 * amplitude, theta), n3);
        }
        "turn x then y" => {
            let (a, b) = (
                rng.random_range(1.5e-4..2.5e-4),
                rng.random_range(1.5e-4..3.0e-4),
            );
            let (n1, n2) = (n(&mut rng), n(&mut rng));
            segment(&mut t, [a, 0.0, 0.0], n1);
            segment(&mut t, [a, b, 0.0], n2);
        }
        _ => {
            // One to three increments from 90 % of the peak across the softening branch.
            let far = rng.random_range(4.0e-4..6.0e-4);
            let across = rng.random_range(1..=3u32);
            segment(&mut t, uniaxial(2.0e-4, theta), rng.random_range(6..=12u32));
            segment(&mut t, uniaxial(far, theta), across);
        }
    }
    HardCase {
        seed,
        kind,
        setup,
        scene,
        targets: t,
    }
}

/// What the host loop did on one path.
#[derive(Default)]
pub struct HostRun {
    pub updates: u32,
    /// Updates that failed and were retried with a smaller step.
    pub retries: u32,
}

/// Follows `targets` like a host: each increment from the committed state; on a solver
/// failure, checks it is clean and retries the rest of the increment with the suggested
/// step ratio (growing the step again after a success). Err: a failure that is not clean,
/// or more than 200 retries on one increment.
pub fn host_follow(inst: &mut Instance, targets: &[[f64; 3]]) -> Result<HostRun, String> {
    let model = inst.model().clone();
    let mut ws = model.workspace();
    let mut run = HostRun::default();
    for (k, target) in targets.iter().enumerate() {
        let start = inst.committed().strain;
        let (mut done, mut step, mut retries) = (0.0f64, 1.0f64, 0);
        while done < 1.0 {
            let to = (done + step).min(1.0);
            let eps: [f64; 3] = std::array::from_fn(|c| start[c] + to * (target[c] - start[c]));
            let before = inst.committed().clone();
            run.updates += 1;
            match inst.update(eps, &mut ws, TangentRequest::Consistent) {
                Ok(r) => {
                    if !(r.stress.iter().chain(&r.tangent).all(|v| v.is_finite())) {
                        return Err(format!("increment {}: non-finite response", k + 1));
                    }
                    inst.commit().map_err(|e| e.to_string())?;
                    done = to;
                    step = (2.0 * step).min(1.0);
                }
                Err(Error::Solve {
                    suggested_step_ratio,
                    reason,
                    ..
                }) => {
                    if !(suggested_step_ratio > 0.0 && suggested_step_ratio < 1.0) {
                        return Err(format!("step ratio {suggested_step_ratio} ({reason})"));
                    }
                    if *inst.committed() != before {
                        return Err(format!("increment {}: failure changed the state", k + 1));
                    }
                    run.retries += 1;
                    retries += 1;
                    if retries > 200 {
                        return Err(format!("increment {}: 200 retries ({reason})", k + 1));
                    }
                    step *= suggested_step_ratio;
                }
                Err(e) => return Err(format!("increment {}: not a solver failure: {e}", k + 1)),
            }
        }
    }
    Ok(run)
}
