//! The failing cell's cost against the paper's ITZ-only cell: `cargo bench --bench
//! fracture` prints one table (`docs/fracture.md`).
//!
//! Rows: `scenes/concrete_fracture.toml` (cracks through the paste) and the paper's cell
//! with the ITZ alone (`scenes/paper_rve.toml`, implicit; `paper_rve_host_implex.toml`,
//! IMPL-EX), each with both schemes, on the section 5.2.1 path (tension to 2.2e-4 in 20
//! increments, strain-controlled), and IMPL-EX in uniaxial tension to 2e-2 (the lateral
//! stresses held at zero, 1000 increments; the ITZ-only cell is the fracture scene's
//! without its paste cracks). Per row: the path's total time and the median update
//! (medians over `RUNS` fresh instances), the unknowns, the instance's bytes and
//! `umat_nstatv`.
//!
//! Timing tests do not belong in the test suite (noisy machines); this is the place.

use std::sync::Arc;
use std::time::Instant;

use rve::model::mixed::update_mixed;
use rve::{Instance, Model, Scene, TangentRequest};

const RUNS: usize = 3;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn model(file: &str, replacements: &[(&str, &str)]) -> Arc<Model> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut text = std::fs::read_to_string(dir.join(file)).expect("scene");
    for (from, to) in replacements {
        assert!(text.contains(from), "{file} has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    Arc::new(Model::from_scene(&Scene::from_toml_str(&text, dir).expect("scene")).expect("model"))
}

/// (total ms, median update ms, instance bytes) over `RUNS` runs of `increments` steps
/// to `last`, with `free` stress components held at zero.
fn follow(
    model: &Arc<Model>,
    last: [f64; 3],
    increments: usize,
    free: [bool; 3],
) -> (f64, f64, usize) {
    let (mut totals, mut updates, mut bytes) = (Vec::new(), Vec::new(), 0);
    for _ in 0..RUNS {
        let mut instance = Instance::new(model.clone());
        let mut ws = model.workspace();
        let start = Instant::now();
        for k in 1..=increments {
            let eps = last.map(|e| e * k as f64 / increments as f64);
            let t0 = Instant::now();
            if free == [false; 3] {
                instance
                    .update_timed(eps, 1.0, &mut ws, TangentRequest::Consistent)
                    .expect("update");
            } else {
                update_mixed(&mut instance, eps, free, 1.0, &mut ws).expect("mixed update");
            }
            updates.push(t0.elapsed().as_secs_f64() * 1e3);
            instance.commit().expect("commit");
        }
        totals.push(start.elapsed().as_secs_f64() * 1e3);
        bytes = instance.state_bytes();
    }
    (median(&mut totals), median(&mut updates), bytes)
}

fn main() {
    let implicit = ("integration = \"implex\"", "integration = \"implicit\"");
    let itz_only = [
        ("paste_cracking = true", "paste_cracking = false"),
        ("paste_crack = {", "# paste_crack = {"),
    ];
    let section_521 = ([2.2e-4, 0.0, 0.0], 20, [false; 3]);
    let uniaxial = ([2e-2, 0.0, 0.0], 1000, [false, true, true]);
    let rows: [(&str, &str, Arc<Model>, _); 6] = [
        (
            "ITZ only (paper_rve)",
            "implicit",
            model("paper_rve.toml", &[]),
            section_521,
        ),
        (
            "ITZ only (paper_rve_host_implex)",
            "IMPL-EX",
            model("paper_rve_host_implex.toml", &[]),
            section_521,
        ),
        (
            "paste cracks (concrete_fracture)",
            "implicit",
            model("concrete_fracture.toml", &[implicit]),
            section_521,
        ),
        (
            "paste cracks (concrete_fracture)",
            "IMPL-EX",
            model("concrete_fracture.toml", &[]),
            section_521,
        ),
        (
            "ITZ only (concrete_fracture without paste cracks)",
            "IMPL-EX",
            model("concrete_fracture.toml", &itz_only),
            uniaxial,
        ),
        (
            "paste cracks (concrete_fracture)",
            "IMPL-EX",
            model("concrete_fracture.toml", &[]),
            uniaxial,
        ),
    ];
    println!("| cell | scheme | path | total (ms) | median update (ms) | unknowns | instance bytes | umat_nstatv |");
    println!("|---|---|---|---|---|---|---|---|");
    for (cell, scheme, model, (last, increments, free)) in rows {
        let path = if free == [false; 3] {
            "5.2.1"
        } else {
            "uniaxial tension to 2e-2"
        };
        let (total, update, bytes) = follow(&model, last, increments, free);
        println!(
            "| {cell} | {scheme} | {path} | {total:.1} | {update:.3} | {} | {bytes} | {} |",
            model.unknowns(),
            model.statev_len()
        );
    }
}
