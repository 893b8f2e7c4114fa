//! Checkpoint/restart through the safe API only: `Instance::save_state`, `load_state` and
//! the typed errors of `mesorve_core::state::persist`, without the C interface.

mod common;

use std::sync::Arc;

use rve::scene::path_points;
use rve::{Error, Instance, Model, Response, TangentRequest};

fn bits(r: &Response) -> ([u64; 3], [u64; 9], u64) {
    (
        r.stress.map(f64::to_bits),
        r.tangent.map(f64::to_bits),
        r.s_zz.to_bits(),
    )
}

/// Along the paper path (20 increments, through the snap-back at increment 19), the state
/// saved after every increment `k`, loaded into a new instance of a model built again from
/// the scene (as a restarted process would), continues the path bit-identically: stress,
/// tangent, `s_zz` and the solver's counters of every later increment, and the saved
/// bytes of every later state. The loaded state equals the saved one.
#[test]
fn a_restarted_instance_continues_the_path_bit_identically() {
    let scene = common::scene("scenes/paper_rve.toml");
    let path = path_points(&scene.spec.path);
    assert_eq!(path.len(), 20);
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws = model.workspace();
    // The reference run: responses, states and saved bytes after every increment.
    let mut reference = Instance::new(model.clone());
    let mut states = vec![reference.committed().clone()];
    let mut saved = vec![reference.save_state().unwrap()];
    let mut responses = Vec::new();
    for eps in &path {
        let r = reference
            .update(*eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        reference.commit().unwrap();
        assert_eq!(
            reference.state_size().unwrap(),
            reference.save_state().unwrap().len()
        );
        states.push(reference.committed().clone());
        saved.push(reference.save_state().unwrap());
        responses.push(r);
    }
    assert!(
        responses.iter().any(|r| r.report.substeps > 1),
        "the path crosses the snap-back"
    );
    let restarted_model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws2 = restarted_model.workspace();
    for k in 0..path.len() {
        let mut restarted = Instance::new(restarted_model.clone());
        restarted.load_state(&saved[k]).unwrap();
        // Compared without `assert_eq!`, whose message would print two whole states.
        assert!(
            restarted.committed() == &states[k],
            "saved at {k}: the loaded state differs from the saved one"
        );
        for j in k..path.len() {
            let r = restarted
                .update(path[j], &mut ws2, TangentRequest::Consistent)
                .unwrap();
            restarted.commit().unwrap();
            assert_eq!(bits(&r), bits(&responses[j]), "saved at {k}, increment {j}");
            assert_eq!(r.report, responses[j].report, "saved at {k}, increment {j}");
            assert_eq!(restarted.save_state().unwrap(), saved[j + 1]);
        }
    }
}

/// A refused load changes nothing: not the committed state, not the pending trial. Each
/// refusal is its own typed error; a successful load discards the trial.
#[test]
fn a_refused_load_changes_nothing() {
    let scene = common::scene("scenes/paper_rve.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws = model.workspace();
    let mut inst = Instance::new(model.clone());
    inst.update([1e-4, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
        .unwrap();
    inst.commit().unwrap();
    let bytes = inst.save_state().unwrap();
    let committed = inst.committed().clone();
    inst.update([1.2e-4, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
        .unwrap();

    let mut truncated = bytes.clone();
    truncated.pop();
    // A later format with its own checksum; the same version change without one is
    // corruption.
    let mut future = bytes.clone();
    future[8..12].copy_from_slice(&(rve::STATE_FORMAT_VERSION + 1).to_le_bytes());
    let e = inst.load_state(&future).unwrap_err();
    assert!(matches!(e, Error::BadState { .. }), "{e}");
    let body = future.len() - 4;
    let checksum = crc32c::crc32c(&future[..body]);
    future[body..].copy_from_slice(&checksum.to_le_bytes());
    let other_scene = common::scene("scenes/gmsh_two_circles.toml");
    let other_model = Arc::new(Model::from_scene(&other_scene).unwrap());
    let foreign = Instance::new(other_model).save_state().unwrap();
    let e = inst.load_state(&truncated).unwrap_err();
    assert!(matches!(e, Error::BadState { .. }), "{e}");
    let e = inst.load_state(&future).unwrap_err();
    assert!(matches!(e, Error::StateVersion { found: 11, .. }), "{e}");
    assert_eq!(
        e.to_string(),
        "state format version 11; this library reads versions [1, 2, 3, 4, 5, 6, 7, 8, 9] \
         and 10"
    );
    let e = inst.load_state(&foreign).unwrap_err();
    assert!(matches!(e, Error::StateMismatch { .. }), "{e}");
    assert!(e.to_string().contains("(another scene)"), "{e}");
    // A contact status held at a point the model does not have (a spare bit of the
    // bitset's last word, past the interface points).
    let points = model.discretization().interface_points();
    let nh = u64::from_le_bytes(bytes[24..32].try_into().unwrap()) as usize;
    assert!(
        points % 64 != 0,
        "the bitset has spare bits past the points"
    );
    let words = nh.div_ceil(64);
    let mut beyond = bytes.clone();
    // The bitset's words end where the (empty, implicit) IMPL-EX history starts: two
    // empty vectors' lengths, the step and a flag, 25 bytes before the checksum.
    let bitset = beyond.len() - 4 - 25 - 8 * words;
    let byte = bitset + 8 * (points / 64) + (points % 64) / 8;
    beyond[byte] |= 1 << (points % 8);
    let body = beyond.len() - 4;
    let checksum = crc32c::crc32c(&beyond[..body]);
    beyond[body..].copy_from_slice(&checksum.to_le_bytes());
    let e = inst.load_state(&beyond).unwrap_err();
    assert!(matches!(e, Error::BadState { .. }), "{e}");
    assert!(e.to_string().contains("beyond the model's"), "{e}");

    assert!(
        inst.committed() == &committed,
        "a refused load changed the state"
    );
    assert!(inst.has_trial(), "the trial survives refused loads");
    inst.load_state(&bytes).unwrap();
    assert!(!inst.has_trial());
    assert!(matches!(inst.commit(), Err(Error::NoTrial)));
    assert!(inst.committed() == &committed, "the loaded state differs");
}

/// The format 1 checkpoint that mesorve 0.1.0 saved (see tests/ffi.rs) loads through the
/// safe API too, and is saved again in the current format.
#[test]
fn a_format_1_checkpoint_loads_through_the_safe_api() {
    let bytes = std::fs::read(common::repo("tests/data/state_format1_paper_rve.bin")).unwrap();
    let scene = common::scene("scenes/paper_rve.toml");
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut inst = Instance::new(model.clone());
    inst.load_state(&bytes).unwrap();
    assert_eq!(inst.committed().strain, [1.5e-4, 0.0, 0.0]);
    assert!(!inst.committed().sensitivity.valid);
    let again = inst.save_state().unwrap();
    assert_eq!(
        u32::from_le_bytes(again[8..12].try_into().unwrap()),
        mesorve_core::state::STATE_FORMAT_VERSION
    );
    let mut copy = Instance::new(model);
    copy.load_state(&again).unwrap();
    assert!(
        copy.committed() == inst.committed(),
        "the state saved again differs"
    );
}

/// On a hard path whose increments end with interface points held against their gap
/// (uniaxial stress, seed 1 of `common::hard_paths`), the state saved after such an
/// increment records those points, and a restarted instance continues the path
/// bit-identically from it. Loaded with no point held (as a format 7 state is), the next
/// increment starts from another contact status and its response differs.
#[test]
fn a_state_with_points_held_against_their_gap_restarts_bit_identically() {
    let case = common::hard_paths::case(1);
    assert_eq!(case.kind, "uniaxial stress");
    let scene = rve::scene::Scene::from_toml_str(&case.scene, common::repo("scenes")).unwrap();
    let model = Arc::new(Model::from_scene(&scene).unwrap());
    let mut ws = model.workspace();
    let mut reference = Instance::new(model.clone());
    let mut held_after = None;
    let mut responses = Vec::new();
    let mut saved = Vec::new();
    for (k, eps) in case.targets.iter().enumerate() {
        let r = reference
            .update(*eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        reference.commit().unwrap();
        saved.push(reference.save_state().unwrap());
        if held_after.is_none() && r.report.held_points > 0 && k + 1 < case.targets.len() {
            held_after = Some(k);
        }
        responses.push(r);
    }
    let k = held_after.expect("an increment ends with points held against their gap");
    let held = responses[k].report.held_points;
    let mut loaded = Instance::new(model.clone());
    loaded.load_state(&saved[k]).unwrap();
    let recorded: u32 = loaded
        .committed()
        .held_contact
        .iter()
        .map(|w| w.count_ones())
        .sum();
    assert_eq!(
        recorded as usize, held,
        "increment {k}: the state records its held points"
    );
    for (j, (eps, expected)) in case.targets.iter().zip(&responses).enumerate().skip(k + 1) {
        let r = loaded
            .update(*eps, &mut ws, TangentRequest::Consistent)
            .unwrap();
        loaded.commit().unwrap();
        assert_eq!(bits(&r), bits(expected), "saved at {k}, increment {j}");
    }

    // The same bytes as format 7 (without the held status: its u64 length and words).
    let bytes = &saved[k];
    let nh = u64::from_le_bytes(bytes[24..32].try_into().unwrap()) as usize;
    let held_bytes = 8 + 8 * nh.div_ceil(64);
    let mut format7 = bytes[..bytes.len() - 4 - held_bytes].to_vec();
    format7.drain(40..48); // format 10's fingerprint
    format7[8..12].copy_from_slice(&7u32.to_le_bytes());
    let payload = (format7.len() - 40) as u64;
    format7[32..40].copy_from_slice(&payload.to_le_bytes());
    let checksum = crc32c::crc32c(&format7);
    format7.extend_from_slice(&checksum.to_le_bytes());
    let mut forgetful = Instance::new(model.clone());
    forgetful.load_state(&format7).unwrap();
    assert!(forgetful.committed().held_contact.iter().all(|&w| w == 0));
    let r = forgetful
        .update(case.targets[k + 1], &mut ws, TangentRequest::Consistent)
        .unwrap();
    assert_ne!(bits(&r), bits(&responses[k + 1]), "the held status matters");
}

/// A checkpoint carries its model's fingerprint: loaded into a model of the same sizes but
/// another meaning (the paper's RVE with `contact_shear = "cohesive"`, or integrated by
/// IMPL-EX) it is refused with `StateOwner`, naming both fingerprints, and changes
/// nothing; a model built again from the same scene (a restarted process) takes it.
#[test]
fn a_checkpoint_of_another_fingerprint_is_refused() {
    let model = |text: &str| {
        Arc::new(Model::from_scene(&rve::Scene::from_toml_str(text, ".").unwrap()).unwrap())
    };
    let paper = common::paper_scene_with(&[]);
    let shear = common::paper_scene_with(&[(
        "beta = 0.707,",
        "beta = 0.707, contact_shear = \"cohesive\",",
    )]);
    let implex = common::paper_scene_with(&[("[solver]", "[solver]\nintegration = \"implex\"")]);
    let source = model(&paper);
    let mut ws = source.workspace();
    let mut inst = Instance::new(source.clone());
    inst.update([1.2e-4, 0.0, 0.0], &mut ws, TangentRequest::Consistent)
        .unwrap();
    inst.commit().unwrap();
    let bytes = inst.save_state().unwrap();
    for (what, text) in [("cohesive shear", &shear), ("IMPL-EX", &implex)] {
        let other = model(text);
        assert_eq!(
            other.unknowns(),
            source.unknowns(),
            "{what}: the same sizes"
        );
        let mut target = Instance::new(other.clone());
        let before = target.committed().clone();
        let e = target.load_state(&bytes).unwrap_err();
        assert!(matches!(e, Error::StateOwner { .. }), "{what}: {e}");
        let text = e.to_string();
        assert!(
            text.contains(&format!("{:010x}", source.fingerprint())),
            "{text}"
        );
        assert!(
            text.contains(&format!("{:010x}", other.fingerprint())),
            "{text}"
        );
        assert_eq!(
            target.committed(),
            &before,
            "{what}: a refused load changes nothing"
        );
    }
    let mut again = Instance::new(model(&paper));
    again.load_state(&bytes).unwrap();
    assert_eq!(again.committed(), inst.committed());
}
