//! The C interface called from Rust: handles, statuses, trial semantics, state bytes,
//! batch and threads. The same extern functions a C host calls.

mod common;

use std::ffi::CString;
use std::ptr::{null, null_mut};

use rve::ffi::*;

const OK: u32 = RveStatus::Ok as u32;
const CONSISTENT: i32 = RveTangentRequest::Consistent as i32;

fn init_paper() -> RveHandle {
    let path = CString::new(common::repo("scenes/paper_rve.toml").to_str().unwrap()).unwrap();
    let mut h = 0;
    assert_eq!(unsafe { rve_init_file(path.as_ptr(), &mut h) }, OK);
    assert_ne!(h, 0);
    h
}

fn init_text(text: &str) -> (u32, RveHandle) {
    let text = CString::new(text).unwrap();
    let mut h = 0;
    let s = unsafe { rve_init_text(text.as_ptr(), null(), &mut h) };
    (s, h)
}

fn update(h: RveHandle, strain: [f64; 3]) -> (u32, [f64; 3], [f64; 9]) {
    let mut stress = [f64::NAN; 3];
    let mut tangent = [f64::NAN; 9];
    let s = unsafe {
        rve_update(
            h,
            strain.as_ptr(),
            stress.as_mut_ptr(),
            tangent.as_mut_ptr(),
            CONSISTENT,
        )
    };
    (s, stress, tangent)
}

#[test]
fn trial_commit_revert_and_bit_identical_repeats() {
    let h = init_paper();
    let e = [5e-5, 0.0, 0.0];
    let (s1, sig1, d1) = update(h, e);
    let (s2, sig2, d2) = update(h, e);
    assert_eq!((s1, s2), (OK, OK));
    assert_eq!(sig1.map(f64::to_bits), sig2.map(f64::to_bits));
    assert_eq!(d1.map(f64::to_bits), d2.map(f64::to_bits));
    assert!(sig1[0] > 0.0);
    assert_eq!(rve_commit(h), OK);
    assert_eq!(rve_commit(h), RveStatus::NoTrial as u32);
    assert_eq!(rve_revert(h), OK);
    assert_eq!(rve_reset(h), OK);
    assert_eq!(rve_commit(h), RveStatus::NoTrial as u32);
    // After reset the first update is the same as on a fresh instance.
    let (_, sig3, _) = update(h, e);
    assert_eq!(sig1.map(f64::to_bits), sig3.map(f64::to_bits));
    assert_eq!(rve_free(h), OK);
    assert_eq!(rve_free(h), RveStatus::BadHandle as u32);
    assert_eq!(rve_free(0), OK);
}

#[test]
fn matches_the_safe_api_and_info_and_requests() {
    let h = init_paper();
    let scene = common::scene("scenes/paper_rve.toml");
    let model = std::sync::Arc::new(rve::Model::from_scene(&scene).unwrap());
    let mut inst = rve::Instance::new(model.clone());
    let mut ws = model.workspace();
    let e = [4e-5, -1e-5, 1e-5];
    let r = inst
        .update(e, &mut ws, rve::TangentRequest::Consistent)
        .unwrap();
    let (mut stress, mut tangent) = ([0.0; 3], [0.0; 9]);
    let mut info = RveInfo {
        iterations: 0,
        substeps: 0,
        factorizations: 0,
        reliability: -1,
        suggested_step_ratio: 0.0,
        s_zz: f64::NAN,
    };
    let s = unsafe {
        rve_update_ex(
            h,
            e.as_ptr(),
            stress.as_mut_ptr(),
            tangent.as_mut_ptr(),
            CONSISTENT,
            &mut info,
        )
    };
    assert_eq!(s, OK);
    assert_eq!(stress.map(f64::to_bits), r.stress.map(f64::to_bits));
    assert_eq!(tangent.map(f64::to_bits), r.tangent.map(f64::to_bits));
    assert_eq!(info.iterations, r.report.iterations);
    assert_eq!(info.substeps, r.report.substeps);
    assert_eq!(info.suggested_step_ratio, 1.0);
    assert_eq!(info.reliability, RveReliability::Reliable as i32);
    assert_eq!(info.s_zz, r.s_zz);
    // Stress only: tangent may be NULL and the stress is the same.
    let mut s_only = [0.0; 3];
    let st = unsafe {
        rve_update(
            h,
            e.as_ptr(),
            s_only.as_mut_ptr(),
            null_mut(),
            RveTangentRequest::None as i32,
        )
    };
    assert_eq!(st, OK);
    assert_eq!(s_only.map(f64::to_bits), r.stress.map(f64::to_bits));
    // Elastic tangent.
    let st = unsafe {
        rve_update(
            h,
            e.as_ptr(),
            s_only.as_mut_ptr(),
            tangent.as_mut_ptr(),
            RveTangentRequest::Elastic as i32,
        )
    };
    assert_eq!(st, OK);
    assert_eq!(tangent, model.elastic_tangent());
    // Unknown request.
    let st = unsafe { rve_update(h, e.as_ptr(), s_only.as_mut_ptr(), tangent.as_mut_ptr(), 7) };
    assert_eq!(st, RveStatus::InvalidArgument as u32);
    rve_free(h);
}

#[test]
fn every_misuse_gets_its_status_and_writes_nothing() {
    let h = init_paper();
    let mut stress = [7.0; 3];
    let mut tangent = [7.0; 9];
    let mut call = |h: RveHandle, e: [f64; 3]| unsafe {
        rve_update(
            h,
            e.as_ptr(),
            stress.as_mut_ptr(),
            tangent.as_mut_ptr(),
            CONSISTENT,
        )
    };
    assert_eq!(
        call(h, [f64::NAN, 0.0, 0.0]),
        RveStatus::NonFiniteStrain as u32
    );
    assert!(last_error_message().contains("not finite"));
    assert_eq!(
        call(h, [0.0, f64::INFINITY, 0.0]),
        RveStatus::NonFiniteStrain as u32
    );
    assert_eq!(call(h, [0.0, 0.0, 0.5]), RveStatus::AbsurdStrain as u32);
    assert_eq!(call(0, [0.0; 3]), RveStatus::BadHandle as u32);
    assert_eq!(call(12345, [0.0; 3]), RveStatus::BadHandle as u32);
    assert_eq!(call(h + (1 << 32), [0.0; 3]), RveStatus::BadHandle as u32);
    assert_eq!(call(-h, [0.0; 3]), RveStatus::BadHandle as u32);
    assert_eq!(stress, [7.0; 3]);
    assert_eq!(tangent, [7.0; 9]);
    assert_eq!(rve_commit(h), RveStatus::NoTrial as u32);
    let s = unsafe { rve_update(h, null(), stress.as_mut_ptr(), null_mut(), CONSISTENT) };
    assert_eq!(s, RveStatus::NullArgument as u32);
    let s = unsafe {
        rve_update(
            h,
            [0.0; 3].as_ptr(),
            stress.as_mut_ptr(),
            null_mut(),
            CONSISTENT,
        )
    };
    assert_eq!(s, RveStatus::NullArgument as u32);
    assert!(last_error_message().contains("tangent"));
    // Scene errors.
    assert_eq!(
        init_text("this is not toml [").0,
        RveStatus::BadScene as u32
    );
    let bad = common::paper_scene_with(&[("delta_c = 0.0002", "delta_c = -1.0")]);
    assert_eq!(init_text(&bad).0, RveStatus::BadScene as u32);
    let crowded = common::paper_scene_with(&[("area_fraction = 0.45", "area_fraction = 0.7")]);
    let crowded = crowded.replace("max_rounds", "x").replace(
        "margin = 0.3",
        "margin = 0.3\nmax_rounds = 1\nmax_attempts = 10",
    );
    assert_eq!(init_text(&crowded).0, RveStatus::MeshFailed as u32);
    let missing = CString::new("/nonexistent/scene.toml").unwrap();
    let mut out = 0;
    assert_eq!(
        unsafe { rve_init_file(missing.as_ptr(), &mut out) },
        RveStatus::BadScene as u32
    );
    assert_eq!(out, 0);
    assert_eq!(
        unsafe { rve_init_file(null(), &mut out) },
        RveStatus::NullArgument as u32
    );
    // Last error buffer: truncation and length query.
    let n = unsafe { rve_last_error(null_mut(), 0) };
    assert!(n > 10);
    let mut buf = [0x55u8; 8];
    assert_eq!(
        unsafe { rve_last_error(buf.as_mut_ptr().cast(), buf.len()) },
        n
    );
    assert_eq!(buf[7], 0);
    assert_eq!(rve_free(h), OK);
}

#[test]
fn solver_failure_keeps_the_committed_state_and_suggests_a_smaller_step() {
    let text = common::paper_scene_with(&[(
        "max_iterations = 40",
        "max_iterations = 1\npath_following = false\nmax_secant_iterations = 0\nmax_substep_depth = 0",
    )]);
    let (s, h) = init_text(&text);
    assert_eq!(s, OK, "{}", last_error_message());
    let mut saved_before = vec![0u8; 1 << 20];
    let mut n_before = 0;
    unsafe {
        rve_state_save(
            h,
            saved_before.as_mut_ptr(),
            saved_before.len(),
            &mut n_before,
        )
    };
    let e = [3e-4, 0.0, 0.0];
    let mut stress = [7.0; 3];
    let mut tangent = [7.0; 9];
    let mut info = RveInfo {
        iterations: 9,
        substeps: 9,
        factorizations: 9,
        reliability: 9,
        suggested_step_ratio: 9.0,
        s_zz: 9.0,
    };
    let s = unsafe {
        rve_update_ex(
            h,
            e.as_ptr(),
            stress.as_mut_ptr(),
            tangent.as_mut_ptr(),
            CONSISTENT,
            &mut info,
        )
    };
    assert_eq!(
        s,
        RveStatus::SolverFailed as u32,
        "{}",
        last_error_message()
    );
    assert_eq!(stress, [7.0; 3]);
    assert_eq!(info.reliability, RveReliability::Failed as i32);
    assert!(info.suggested_step_ratio > 0.0 && info.suggested_step_ratio < 1.0);
    assert_eq!(rve_commit(h), RveStatus::NoTrial as u32);
    let mut saved_after = vec![0u8; 1 << 20];
    let mut n_after = 0;
    unsafe { rve_state_save(h, saved_after.as_mut_ptr(), saved_after.len(), &mut n_after) };
    assert_eq!(saved_before[..n_before], saved_after[..n_after]);
    rve_free(h);
}

/// Bytes of a filled format 4 sensitivity for `n` unknowns (bincode: the valid flag, the
/// block scales (f32) and the 3n i8 values, each vector after its u64 length).
fn sensitivity_bytes(n: usize) -> usize {
    1 + 8 + 4 * (3 * n).div_ceil(mesorve_core::state::SENSITIVITY_BLOCK) + 8 + 3 * n
}

/// Bytes of format 5's path curvature for `n` unknowns: the valid flag, the step (3 f64),
/// then, each after its u64 length, the block scales and the n i8 values (both empty
/// until an increment filled them).
fn curvature_bytes(n: usize, filled: bool) -> usize {
    let (scales, values) = if filled {
        (n.div_ceil(mesorve_core::state::SENSITIVITY_BLOCK), n)
    } else {
        (0, 0)
    };
    1 + 24 + 8 + 4 * scales + 8 + values
}

/// Bytes of the trailing CRC-32C of state format 6.
const CHECKSUM: usize = 4;

/// Bytes of format 7's fast-path data when not valid: the valid flag, `D_b` (9 f64), the
/// `s_zz` row (3 f64), the empty jump operators and contact status (their u64 lengths),
/// the anchor strain (3 f64).
const NO_FAST_PATH_DATA: usize = 1 + 72 + 24 + 8 + 8 + 24;

/// Bytes of format 8's held contact status for `nh` history values: the u64 length, then
/// one u64 per 64 values.
fn held_contact_bytes(nh: usize) -> usize {
    8 + 8 * nh.div_ceil(64)
}

/// State bytes of format >= 6 with their trailing checksum recomputed (a deliberate edit).
fn with_checksum(mut bytes: Vec<u8>) -> Vec<u8> {
    let body = bytes.len() - CHECKSUM;
    let sum = crc32c::crc32c(&bytes[..body]);
    bytes[body..].copy_from_slice(&sum.to_le_bytes());
    bytes
}

#[test]
fn state_bytes_round_trip_and_refuse_foreign_states() {
    let h = init_paper();
    // Two increments: the second starts from the tangent predictor and fills the path
    // curvature, so every part of the state is in the bytes.
    for eps in [1.4e-4, 1.5e-4] {
        let (s, _, _) = update(h, [eps, 0.0, 0.0]);
        assert_eq!(s, OK);
        assert_eq!(rve_commit(h), OK);
    }
    let mut size = 0;
    assert_eq!(unsafe { rve_state_size(h, &mut size) }, OK);
    let mut small = vec![0u8; 10];
    let mut written = 0;
    assert_eq!(
        unsafe { rve_state_save(h, small.as_mut_ptr(), small.len(), &mut written) },
        RveStatus::BufferTooSmall as u32
    );
    assert_eq!(written, size);
    let mut bytes = vec![0u8; size];
    assert_eq!(
        unsafe { rve_state_save(h, bytes.as_mut_ptr(), size, &mut written) },
        OK
    );
    let next = [1.6e-4, 0.0, 0.0];
    let (_, sig_a, d_a) = update(h, next);
    // A new instance loaded with the bytes continues bit-identically.
    let h2 = init_paper();
    assert_eq!(unsafe { rve_state_load(h2, bytes.as_ptr(), size) }, OK);
    let (_, sig_b, d_b) = update(h2, next);
    assert_eq!(sig_a.map(f64::to_bits), sig_b.map(f64::to_bits));
    assert_eq!(d_a.map(f64::to_bits), d_b.map(f64::to_bits));
    // Garbage, truncation, another version, another scene.
    let load = |b: &[u8]| unsafe { rve_state_load(h2, b.as_ptr(), b.len()) };
    assert_eq!(load(&[1, 2, 3]), RveStatus::BadState as u32);
    assert_eq!(load(&[0u8; 100]), RveStatus::BadState as u32);
    assert_eq!(load(&bytes[..size - 1]), RveStatus::BadState as u32);
    // A format this library does not know, with a valid checksum (a later version), is
    // STATE_VERSION; the same version change without a new checksum is corruption.
    for unknown_version in [0u8, rve::STATE_FORMAT_VERSION as u8 + 1] {
        let mut other_version = bytes.clone();
        other_version[8] = unknown_version;
        assert_eq!(load(&other_version), RveStatus::BadState as u32);
        assert_eq!(
            load(&with_checksum(other_version)),
            RveStatus::StateVersion as u32
        );
    }
    // A negative delta_max is refused, and the instance keeps its state.
    // The payload ends with the history, the sensitivity and the path curvature, both
    // filled by the committed updates with tangent, the fast-path data (none: the points
    // load), then the checksum.
    let mut negative = bytes.clone();
    let n = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
    let nh = u64::from_le_bytes(bytes[24..32].try_into().unwrap()) as usize;
    // Format 9 ends the payload with the IMPL-EX history: 25 bytes when empty (implicit).
    let curvature_at = negative.len()
        - CHECKSUM
        - 25
        - held_contact_bytes(nh)
        - NO_FAST_PATH_DATA
        - curvature_bytes(n, true);
    assert_eq!(
        bytes[curvature_at], 1,
        "the path curvature is filled and valid"
    );
    let last = curvature_at - sensitivity_bytes(n) - 8;
    negative[last..last + 8].copy_from_slice(&(-1.0f64).to_le_bytes());
    assert_eq!(load(&negative), RveStatus::BadState as u32);
    let negative = with_checksum(negative);
    assert_eq!(load(&negative), RveStatus::BadState as u32);
    assert!(
        last_error_message().contains("delta_max"),
        "{}",
        last_error_message()
    );
    let (_, sig_c, _) = update(h2, next);
    assert_eq!(sig_a.map(f64::to_bits), sig_c.map(f64::to_bits));
    let gmsh = CString::new(
        common::repo("scenes/gmsh_two_circles.toml")
            .to_str()
            .unwrap(),
    )
    .unwrap();
    let mut other = 0;
    assert_eq!(unsafe { rve_init_file(gmsh.as_ptr(), &mut other) }, OK);
    assert_eq!(
        unsafe { rve_state_load(other, bytes.as_ptr(), size) },
        RveStatus::StateMismatch as u32
    );
    assert_eq!(
        unsafe { rve_state_load(h2, null(), 5) },
        RveStatus::NullArgument as u32
    );
    for x in [h, h2, other] {
        assert_eq!(rve_free(x), OK);
    }
}

#[test]
fn path_points_match_the_cli() {
    let h = init_paper();
    let scene = common::scene("scenes/paper_rve.toml");
    let points = rve::scene::path_points(&scene.spec.path);
    let mut n = 0;
    assert_eq!(unsafe { rve_path_len(h, &mut n) }, OK);
    assert_eq!(n, points.len());
    for (i, p) in points.iter().enumerate() {
        let mut e = [0.0; 3];
        assert_eq!(unsafe { rve_path_point(h, i, e.as_mut_ptr()) }, OK);
        assert_eq!(&e, p);
    }
    let mut e = [0.0; 3];
    assert_eq!(
        unsafe { rve_path_point(h, n, e.as_mut_ptr()) },
        RveStatus::InvalidArgument as u32
    );
    rve_free(h);
}

#[test]
fn batch_and_threads_are_bit_identical_to_serial() {
    let m = 6;
    let handles: Vec<RveHandle> = (0..m).map(|_| init_paper()).collect();
    let strains: Vec<f64> = (0..m)
        .flat_map(|k| [1e-5 * (k as f64 + 1.0), -2e-6 * k as f64, 1e-6 * k as f64])
        .collect();
    let serial: Vec<_> = (0..m)
        .map(|k| {
            update(
                handles[k],
                [strains[3 * k], strains[3 * k + 1], strains[3 * k + 2]],
            )
        })
        .collect();
    for nthreads in [1usize, 2, 0] {
        let mut stresses = vec![0.0; 3 * m];
        let mut tangents = vec![0.0; 9 * m];
        let mut statuses = vec![77u32; m];
        let s = unsafe {
            rve_update_batch(
                handles.as_ptr(),
                m,
                strains.as_ptr(),
                stresses.as_mut_ptr(),
                tangents.as_mut_ptr(),
                statuses.as_mut_ptr(),
                CONSISTENT,
                nthreads,
            )
        };
        assert_eq!(s, OK);
        for k in 0..m {
            assert_eq!(statuses[k], OK);
            assert_eq!(stresses[3 * k..3 * k + 3], serial[k].1);
            assert_eq!(tangents[9 * k..9 * k + 9], serial[k].2);
        }
    }
    // A bad item fails alone.
    let mut bad_handles = handles.clone();
    bad_handles[1] = 42;
    let mut stresses = vec![0.0; 3 * m];
    let mut statuses = vec![77u32; m];
    let s = unsafe {
        rve_update_batch(
            bad_handles.as_ptr(),
            m,
            strains.as_ptr(),
            stresses.as_mut_ptr(),
            null_mut(),
            statuses.as_mut_ptr(),
            RveTangentRequest::None as i32,
            2,
        )
    };
    assert_eq!(s, RveStatus::BatchFailed as u32);
    assert_eq!(statuses[1], RveStatus::BadHandle as u32);
    assert!(last_error_message().starts_with("item 1:"));
    assert_eq!(statuses[0], OK);
    // Host threads on distinct instances.
    let results: Vec<_> = std::thread::scope(|s| {
        let hs: Vec<_> = (0..m)
            .map(|k| {
                let h = handles[k];
                let e = [strains[3 * k], strains[3 * k + 1], strains[3 * k + 2]];
                s.spawn(move || update(h, e))
            })
            .collect();
        hs.into_iter().map(|t| t.join().unwrap()).collect()
    });
    for k in 0..m {
        assert_eq!(results[k].1, serial[k].1);
        assert_eq!(results[k].2, serial[k].2);
    }
    for h in handles {
        assert_eq!(rve_free(h), OK);
    }
}

#[test]
fn one_instance_from_two_threads_is_busy_or_fine_never_corrupt() {
    let h = init_paper();
    let e = [8e-5, 0.0, 0.0];
    let (_, reference, _) = update(h, e);
    let (busy, ok) = std::thread::scope(|s| {
        let workers: Vec<_> = (0..2)
            .map(|_| {
                s.spawn(move || {
                    let (mut busy, mut ok) = (0, 0);
                    for _ in 0..20 {
                        let (st, sig, _) = update(h, e);
                        if st == OK {
                            assert_eq!(sig, reference);
                            ok += 1;
                        } else {
                            assert_eq!(st, RveStatus::InstanceBusy as u32);
                            busy += 1;
                        }
                    }
                    (busy, ok)
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|w| w.join().unwrap())
            .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    });
    assert_eq!(busy + ok, 40);
    assert!(ok > 0);
    assert_eq!(rve_free(h), OK);
}

/// `tests/data/state_format1_paper_rve.bin` was saved by mesorve 0.1.0 (state format 1,
/// history as `[delta_max, t_max]` pairs) from `scenes/paper_rve.toml` after one committed
/// update to `[1.5e-4, 0, 0]` (made by `scripts/make_state_format1.sh`, kept for this
/// test). This library reads it, and the restarted instance continues like one that
/// computed the same state itself, to the Newton tolerance (see below). Format 2 (no
/// sensitivity), format 3 (a 16-bit sensitivity, dropped on loading), format 4 (no path
/// curvature) and format 5 (no checksum) states load too.
#[test]
fn a_format_1_checkpoint_of_version_0_1_0_still_loads() {
    let bytes = std::fs::read(common::repo("tests/data/state_format1_paper_rve.bin")).unwrap();
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 1);
    let old = init_paper();
    assert_eq!(
        unsafe { rve_state_load(old, bytes.as_ptr(), bytes.len()) },
        OK
    );
    let fresh = init_paper();
    assert_eq!(update(fresh, [1.5e-4, 0.0, 0.0]).0, OK);
    assert_eq!(rve_commit(fresh), OK);
    let next = [1.6e-4, 0.0, 0.0];
    let (s_old, sig_old, d_old) = update(old, next);
    let (s_new, sig_new, d_new) = update(fresh, next);
    assert_eq!((s_old, s_new), (OK, OK));
    // Format 1 carries no sensitivity, so the loaded instance's next increment starts
    // from the elastic predictor instead of the tangent one and converges to another
    // point within the Newton tolerance (1e-6 relative residual): stress and tangent agree
    // to that tolerance, not to round-off (measured: 1.4e-8 and 3.0e-8).
    let rel = common::max_rel_diff;
    assert!(
        rel(&sig_old, &sig_new) <= 1e-6,
        "{sig_old:?} vs {sig_new:?}"
    );
    assert!(rel(&d_old, &d_new) <= 1e-6, "{d_old:?} vs {d_new:?}");
    // Saved again, it is the current format (8) with the sensitivity (the increment from
    // the elastic predictor left the path curvature empty), and loads back.
    let mut size = 0;
    assert_eq!(rve_commit(old), OK);
    assert_eq!(unsafe { rve_state_size(old, &mut size) }, OK);
    let mut saved = vec![0u8; size];
    let mut written = 0;
    assert_eq!(
        unsafe { rve_state_save(old, saved.as_mut_ptr(), size, &mut written) },
        OK
    );
    assert_eq!(
        u32::from_le_bytes(saved[8..12].try_into().unwrap()),
        rve::STATE_FORMAT_VERSION
    );
    assert_eq!(
        unsafe { rve_state_load(fresh, saved.as_ptr(), written) },
        OK
    );
    // The same bytes without the fingerprint (format 10's header bytes 40..48): the
    // layout of format 9 and of the older formats derived from it below.
    let saved: Vec<u8> = [&saved[..40], &saved[48..written]].concat();
    let written = saved.len();
    // Format 5: format 8 without the held contact status, the fast-path data and the
    // checksum; format 4: without the path curvature either.
    let n = u64::from_le_bytes(saved[16..24].try_into().unwrap()) as usize;
    let nh = u64::from_le_bytes(saved[24..32].try_into().unwrap()) as usize;
    let with_version = |mut bytes: Vec<u8>, version: u32| {
        bytes[8..12].copy_from_slice(&version.to_le_bytes());
        let payload = (bytes.len() - 40) as u64;
        bytes[32..40].copy_from_slice(&payload.to_le_bytes());
        bytes
    };
    let format6_len = written - CHECKSUM - held_contact_bytes(nh) - NO_FAST_PATH_DATA;
    let format5 = with_version(saved[..format6_len].to_vec(), 5);
    let format4_len = format6_len - curvature_bytes(n, false);
    let format4 = with_version(saved[..format4_len].to_vec(), 4);
    // Format 2: without the sensitivity either.
    let format2 = with_version(saved[..format4_len - sensitivity_bytes(n)].to_vec(), 2);
    // Format 3: format 2 plus a 16-bit sensitivity (here a valid one of zeros).
    let mut format3 = format2.clone();
    format3.push(1);
    format3.extend_from_slice(&[0u8; 24]);
    format3.extend_from_slice(&(3 * n as u64).to_le_bytes());
    format3.extend(std::iter::repeat_n(0u8, 6 * n));
    let format3 = with_version(format3, 3);
    let (_, sig_old, d_old) = update(old, [1.7e-4, 0.0, 0.0]);
    // Format 4 keeps the sensitivity: the state is the one `old` has, bit for bit.
    assert_eq!(
        unsafe { rve_state_load(fresh, format4.as_ptr(), format4.len()) },
        OK
    );
    let (s, sig, d) = update(fresh, [1.7e-4, 0.0, 0.0]);
    assert_eq!(s, OK);
    assert_eq!(sig.map(f64::to_bits), sig_old.map(f64::to_bits));
    assert_eq!(d.map(f64::to_bits), d_old.map(f64::to_bits));
    // Format 5 is format 6 less the checksum: the same state, bit for bit.
    assert_eq!(
        unsafe { rve_state_load(fresh, format5.as_ptr(), format5.len()) },
        OK
    );
    let (s, sig, d) = update(fresh, [1.7e-4, 0.0, 0.0]);
    assert_eq!(s, OK);
    assert_eq!(sig.map(f64::to_bits), sig_old.map(f64::to_bits));
    assert_eq!(d.map(f64::to_bits), d_old.map(f64::to_bits));
    for bytes in [format2, format3] {
        assert_eq!(
            unsafe { rve_state_load(fresh, bytes.as_ptr(), bytes.len()) },
            OK
        );
        let (s, sig, _) = update(fresh, [1.7e-4, 0.0, 0.0]);
        assert_eq!(s, OK);
        assert!(rel(&sig, &sig_old) <= 1e-6, "{sig:?} vs {sig_old:?}");
    }
    for h in [old, fresh] {
        assert_eq!(rve_free(h), OK);
    }
}
