//! Regularization by the host element's size (`docs/fracture.md`, "Regularization by the
//! host's element size"): `Model::regularized(h)` stretches the softening of the paste's
//! cracks by `L_cell / h`.
//!
//! - At `h = L_cell` the regularized cell answers bit for bit as the scene's own.
//! - In uniaxial tension (IMPL-EX, lateral stresses free, the same strain increment) the
//!   strength stays the cell's bit for bit, and the energy a host element of size `h`
//!   dissipates per unit crack length, `h * int sigma d eps`, changes by less than 10 %
//!   from `h` to `2 h` for `h` from `L_cell / 2` to `2 L_cell` (without the
//!   regularization it would double); what remains is the ITZ's share, which is not
//!   stretched: `G_paste + (h / L_cell) G_itz`, fitted at 5 and 10 mm and checked by its
//!   prediction at 20 and 2.5 mm. At 100 mm the cell still fails.
//! - The regularized model shares the scene's workspaces; a state of one element length
//!   is refused at another; a scene without `effects.regularization` refuses a length.
//! - Through the UMAT: `PROPS(7)` = `L_cell` answers as no length, and so does a `CELENT`
//!   of 0 (CalculiX's unset one); a `CELENT` as the same `PROPS(7)`, two lengths differ after the peak only, and a scene without the effect
//!   refuses a `PROPS(7)` with a message that names the key.
//! - Through C: `rve_clone_for_element` answers as the safe API's regularized model, bit
//!   for bit; one model per scene and length; a bad length or scene gets `BAD_SCENE`.

mod common;

use std::sync::Arc;

use std::ffi::CString;

use rve::ffi::{rve_clone_for_element, rve_commit, rve_init_text, rve_update, RveStatus};
use rve::host::{SearchPath, Umat, UmatOutputs};
use rve::model::cache;
use rve::model::mixed::update_mixed;
use rve::{Instance, Model, Scene, TangentRequest};

const SCENE: &str = "scenes/concrete_fracture.toml";
/// The cell's side (mm).
const CELL: f64 = 10.0;

fn scene_text(regularization: bool) -> String {
    let text = std::fs::read_to_string(common::repo(SCENE)).unwrap();
    if !regularization {
        return text;
    }
    text.replacen(
        "paste_cracking = true",
        "paste_cracking = true\nregularization = true",
        1,
    )
}

fn scene_model(regularization: bool) -> Arc<Model> {
    let scene = Scene::from_toml_str(&scene_text(regularization), common::repo("scenes")).unwrap();
    Arc::new(Model::from_scene(&scene).unwrap())
}

/// Uniaxial tension in x to `last` in `increments`: the (strain, stress) pairs.
fn uniaxial_tension(model: &Arc<Model>, last: f64, increments: usize) -> Vec<(f64, f64)> {
    let mut inst = Instance::new(model.clone());
    let mut ws = model.workspace();
    (1..=increments)
        .map(|k| {
            let eps = [last * k as f64 / increments as f64, 0.0, 0.0];
            let (r, e) = update_mixed(&mut inst, eps, [false, true, true], 1.0, &mut ws)
                .unwrap_or_else(|err| panic!("increment {k}: {err}"));
            inst.commit().unwrap();
            (e[0], r.stress[0])
        })
        .collect()
}

/// Peak stress (MPa), work of the stress per unit volume (MPa = N/mm^2), last stress.
fn peak_work_last(curve: &[(f64, f64)]) -> (f64, f64, f64) {
    let peak = curve.iter().map(|p| p.1).fold(f64::MIN, f64::max);
    let mut work = 0.0;
    let mut previous = (0.0, 0.0);
    for &(e, s) in curve {
        work += 0.5 * (s + previous.1) * (e - previous.0);
        previous = (e, s);
    }
    (peak, work, curve.last().unwrap().1)
}

#[test]
fn at_the_cells_own_size_nothing_moves() {
    let base = scene_model(true);
    let same = Arc::new(base.regularized(CELL).unwrap());
    let (a, b) = (
        uniaxial_tension(&base, 4e-3, 200),
        uniaxial_tension(&same, 4e-3, 200),
    );
    assert_eq!(a, b);
    assert_ne!(base.fingerprint(), same.fingerprint());
}

#[test]
fn the_energy_per_crack_length_does_not_follow_the_element_size() {
    let base = scene_model(true);
    // (element length, last strain, increments): the strain to full separation grows
    // as the element shrinks (about 2e-2 at the cell's own size).
    let runs = [
        (5.0, 4e-2, 4000),
        (10.0, 2e-2, 2000),
        (20.0, 1e-2, 1000),
        (2.5, 8e-2, 8000),
        (100.0, 4e-3, 400),
    ];
    let mut energies = Vec::new();
    let mut peaks = Vec::new();
    for (h, last, increments) in runs {
        let model = Arc::new(base.regularized(h).unwrap());
        let (peak, work, end) = peak_work_last(&uniaxial_tension(&model, last, increments));
        let energy = 1e3 * work * h; // N/m per unit crack length
        println!(
            "h {h:>4} mm: peak {peak:.3} MPa, h * W = {energy:.1} N/m, \
             at {last:.0e}: {end:.4} MPa ({:.2} % of the peak)",
            100.0 * end / peak
        );
        assert!(end.abs() <= 0.05 * peak, "h {h}: still {end} MPa at {last}");
        energies.push(energy);
        peaks.push(peak);
    }
    for pair in energies[..3].windows(2) {
        assert!(
            (pair[1] / pair[0] - 1.0).abs() < 0.10,
            "h and 2h dissipate {pair:?} N/m"
        );
    }
    // What remains is the ITZ's share, which is not stretched: h * W = G_paste +
    // (h / L_cell) G_itz. Fitted on h = 5 and 10 mm, it predicts h = 20 mm.
    let g_itz = 2.0 * (energies[1] - energies[0]);
    let g_paste = energies[1] - g_itz;
    let predict = |h: f64| g_paste + h / CELL * g_itz;
    println!(
        "G_paste {g_paste:.1} N/m (stretched), G_itz {g_itz:.1} N/m (not): predicted at \
         h = 20, 2.5, 100 mm {:.1}, {:.1}, {:.1} N/m",
        predict(20.0),
        predict(2.5),
        predict(100.0)
    );
    assert!(
        g_itz > 0.0 && g_itz < 0.15 * g_paste,
        "G_itz {g_itz}, G_paste {g_paste}"
    );
    assert!((energies[2] / predict(20.0) - 1.0).abs() < 0.02);
    assert!((energies[3] / predict(2.5) - 1.0).abs() < 0.02);
    // Ten times the cell: it still fails (above), and the ITZ's unstretched share is
    // most of what it dissipates beyond the paste's.
    assert!(energies[4] > predict(20.0));
    // Without the regularization the element would dissipate h W with the cell's own W:
    // from h = 5 to 20 mm, four times as much.
    let unregularized: Vec<f64> = runs.iter().map(|r| r.0 * energies[1] / CELL).collect();
    assert!(unregularized[2] / unregularized[0] > 3.9);
}

#[test]
fn a_regularized_model_shares_workspaces_and_keeps_its_states_apart() {
    let base = scene_model(true);
    let fine = Arc::new(base.regularized(5.0).unwrap());
    let coarse = Arc::new(base.regularized(20.0).unwrap());
    assert_ne!(fine.fingerprint(), coarse.fingerprint());
    // The scene's workspace serves the regularized models.
    let mut ws = base.workspace();
    let mut inst = Instance::new(fine.clone());
    let (_, _) = update_mixed(
        &mut inst,
        [5e-4, 0.0, 0.0],
        [false, true, true],
        1.0,
        &mut ws,
    )
    .expect("an update in the scene's workspace");
    inst.commit().unwrap();
    let saved = inst.save_state().unwrap();
    let mut other = Instance::new(coarse.clone());
    let refused = other.load_state(&saved).unwrap_err();
    assert!(refused.to_string().contains("fingerprint"), "{refused}");
    let mut again = Instance::new(fine);
    again
        .load_state(&saved)
        .expect("the same element length loads its state");
}

#[test]
fn a_scene_without_regularization_refuses_a_length() {
    let err = scene_model(false).regularized(5.0).unwrap_err().to_string();
    assert!(err.contains("effects.regularization"), "{err}");
    let err = scene_model(true).regularized(-1.0).unwrap_err().to_string();
    assert!(err.contains("positive"), "{err}");
    let path = common::repo(SCENE);
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replacen("paste_cracking = true", "regularization = true", 1)
        .replacen("paste_crack = {", "# paste_crack = {", 1);
    let err = Scene::from_toml_str(&text, common::repo("scenes"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("needs effects.paste_cracking"), "{err}");
}

/// The stresses of a UMAT point (table mode) along uniaxial strain in x to 1e-3, 40
/// increments, with `props` and `celent`; the first failure's message instead.
fn umat_path(
    umat: &Umat,
    noel: i32,
    props: &[f64],
    celent: Option<f64>,
) -> Result<Vec<f64>, String> {
    let mut start = [0.0; 3];
    let mut out = Vec::new();
    for k in 0..40 {
        let strain = [1e-3 * (k + 1) as f64 / 40.0, 0.0, 0.0];
        let dstran: Vec<f64> = strain.iter().zip(&start).map(|(e, s)| e - s).collect();
        let mut call = common::cycle_call("FRACTURE", props, &start, &dstran, noel, k);
        call.celent = celent;
        let (mut stress, mut ddsdde, mut statev, mut pnewdt) = ([0.0; 3], [0.0; 9], [0.0; 3], 1.0);
        let outputs = &mut UmatOutputs {
            stress: &mut stress,
            ddsdde: &mut ddsdde,
            statev: &mut statev,
            pnewdt: &mut pnewdt,
        };
        umat.call(&call, outputs).map_err(|e| e.to_string())?;
        out.push(stress[0]);
        start = strain;
    }
    Ok(out)
}

#[test]
fn the_umat_takes_the_length_from_props_7_or_celent() {
    let dir = std::env::temp_dir().join(format!("mesorve-regularization-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("fracture.toml"), scene_text(true)).unwrap();
    std::fs::write(dir.join("itz_only.toml"), common::paper_scene_with(&[])).unwrap();
    let umat = Umat::new(SearchPath::new([dir.clone()]));
    let with = |h: f64| [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, h];
    let none = umat_path(&umat, 1, &[], None).unwrap();
    let own = umat_path(&umat, 2, &with(CELL), None).unwrap();
    let fine = umat_path(&umat, 3, &with(5.0), None).unwrap();
    let by_celent = umat_path(&umat, 4, &[], Some(5.0)).unwrap();
    let coarse = umat_path(&umat, 5, &with(20.0), None).unwrap();
    assert_eq!(own, none, "PROPS(7) = L_cell");
    // CalculiX 2.20 passes a CELENT it never sets: 0 is no length.
    let unset = umat_path(&umat, 7, &[], Some(0.0)).unwrap();
    assert_eq!(unset, none, "CELENT = 0");
    assert_eq!(by_celent, fine, "CELENT as PROPS(7)");
    let peak = none.iter().copied().fold(f64::MIN, f64::max);
    let at_peak = none.iter().position(|&s| s == peak).unwrap();
    // Before the cell's peak a few paste points already pass their strength, so the
    // stretched softening moves the stress there, by less than 1e-6 of the peak.
    for (a, b) in fine[..=at_peak].iter().zip(&coarse[..=at_peak]) {
        assert!((a - b).abs() <= 1e-6 * peak, "before the peak: {a} and {b}");
    }
    let (f, c) = (fine.last().unwrap(), coarse.last().unwrap());
    println!("at 1e-3: {f:.4} MPa at h = 5 mm, {c:.4} at 20 mm (peak {peak:.3})");
    assert!(f > c, "the finer element keeps more stress after the peak");
    let mut call = common::cycle_call("ITZ_ONLY", &[], &[0.0; 3], &[1e-5, 0.0, 0.0], 6, 0);
    let props = with(5.0);
    call.props = &props;
    let (mut stress, mut ddsdde, mut statev, mut pnewdt) = ([0.0; 3], [0.0; 9], [0.0; 3], 1.0);
    let refused = umat
        .call(
            &call,
            &mut UmatOutputs {
                stress: &mut stress,
                ddsdde: &mut ddsdde,
                statev: &mut statev,
                pnewdt: &mut pnewdt,
            },
        )
        .unwrap_err()
        .to_string();
    assert!(refused.contains("effects.regularization"), "{refused}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_c_interface_clones_an_instance_for_an_element() {
    let ok = RveStatus::Ok as u32;
    let text = CString::new(scene_text(true)).unwrap();
    let mut base = 0;
    assert_eq!(
        unsafe { rve_init_text(text.as_ptr(), std::ptr::null(), &mut base) },
        ok
    );
    let mut fine = 0;
    assert_eq!(unsafe { rve_clone_for_element(base, 5.0, &mut fine) }, ok);
    let model = Arc::new(
        Model::from_scene(&Scene::from_toml_str(&scene_text(true), ".").unwrap()).unwrap(),
    );
    let mut reference = Instance::new(Arc::new(model.regularized(5.0).unwrap()));
    let mut ws = model.workspace();
    for k in 1..=30 {
        let strain = [4e-5 * f64::from(k), 0.0, 0.0];
        let (mut stress, mut tangent) = ([0.0; 3], [0.0; 9]);
        let status = unsafe {
            rve_update(
                fine,
                strain.as_ptr(),
                stress.as_mut_ptr(),
                tangent.as_mut_ptr(),
                0,
            )
        };
        assert_eq!(status, ok, "increment {k}");
        assert_eq!(rve_commit(fine), ok);
        let r = reference
            .update(strain, &mut ws, TangentRequest::Consistent)
            .unwrap();
        reference.commit().unwrap();
        assert_eq!((stress, tangent), (r.stress, r.tangent), "increment {k}");
    }
    let (a, b) = (
        cache::regularized(&model, 5.0).unwrap(),
        cache::regularized(&model, 5.0).unwrap(),
    );
    assert!(Arc::ptr_eq(&a, &b), "one model per scene and length");
    let mut out = 0;
    for bad in [0.0, -1.0, f64::NAN] {
        assert_eq!(
            unsafe { rve_clone_for_element(base, bad, &mut out) },
            RveStatus::BadScene as u32
        );
    }
    let paper = CString::new(common::paper_scene_with(&[])).unwrap();
    let mut itz_only = 0;
    assert_eq!(
        unsafe { rve_init_text(paper.as_ptr(), std::ptr::null(), &mut itz_only) },
        ok
    );
    assert_eq!(
        unsafe { rve_clone_for_element(itz_only, 5.0, &mut out) },
        RveStatus::BadScene as u32
    );
    assert_eq!(
        unsafe { rve_clone_for_element(12345, 5.0, &mut out) },
        RveStatus::BadHandle as u32
    );
    assert_eq!(out, 0, "nothing written on failure");
}
