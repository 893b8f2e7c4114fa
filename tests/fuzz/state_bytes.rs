//! State bytes for `rve_state_load`: states of the paper's RVE (virgin, and after one to
//! four committed increments, with the sensitivity and the path curvature filled) with one
//! to three corruptions: 1 to 8 flipped bits, truncation, appended bytes, an overwritten
//! run, random bytes, a payload length, a model size or a format version that lies; and
//! intact states of another scene.
//!
//! Properties: no panic; every corrupted buffer is refused (`BAD_STATE`, `STATE_VERSION`
//! or `STATE_MISMATCH`, a state of another scene `STATE_MISMATCH`), with a message; a
//! refused load leaves the instance's committed state as it was, byte for byte.

use std::time::Duration;

use arbitrary::{Arbitrary, Unstructured};
use rve::ffi::*;

use crate::call_sequences::{init, load, save, update, FFI};
use crate::driver::{self, Tally};

#[derive(Arbitrary, Debug)]
enum Corruption {
    FlipBits(Vec<u32>),
    Truncate(u32),
    Append(Vec<u8>),
    Overwrite(u32, Vec<u8>),
    Random(Vec<u8>),
    /// Sets a u64 header field (16: unknowns, 24: history points, 32: payload length).
    HeaderLie(u8, Lie),
    /// Sets the format version.
    Version(u32),
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Lie {
    PlusOne,
    MinusOne,
    Zero,
    Max,
    Double,
    Any(u64),
}

fn apply(bytes: &mut Vec<u8>, c: &Corruption) {
    let len = bytes.len().max(1);
    match c {
        Corruption::FlipBits(bits) => {
            for &b in bits.iter().take(8).chain(bits.is_empty().then_some(&0)) {
                let bit = b as usize % (8 * len);
                if let Some(byte) = bytes.get_mut(bit / 8) {
                    *byte ^= 1 << (bit % 8);
                }
            }
        }
        Corruption::Truncate(at) => bytes.truncate(*at as usize % len),
        Corruption::Append(extra) => {
            bytes.extend_from_slice(if extra.is_empty() { &[0] } else { extra })
        }
        Corruption::Overwrite(at, run) => {
            let at = *at as usize % len;
            for (i, v) in run.iter().enumerate() {
                if let Some(b) = bytes.get_mut(at + i) {
                    *b = *v;
                }
            }
        }
        Corruption::Random(random) => *bytes = random.clone(),
        Corruption::HeaderLie(field, lie) => {
            let at = [16, 24, 32][*field as usize % 3];
            if bytes.len() >= at + 8 {
                let old = u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
                let new = match lie {
                    Lie::PlusOne => old.wrapping_add(1),
                    Lie::MinusOne => old.wrapping_sub(1),
                    Lie::Zero => 0,
                    Lie::Max => u64::MAX,
                    Lie::Double => old.wrapping_mul(2),
                    Lie::Any(v) => *v,
                };
                bytes[at..at + 8].copy_from_slice(&new.to_le_bytes());
            }
        }
        Corruption::Version(v) => {
            if bytes.len() >= 12 {
                bytes[8..12].copy_from_slice(&v.to_le_bytes());
            }
        }
    }
}

/// States of a scene: virgin and after 1..=4 increments along a direction.
fn states(scene: usize, direction: [f64; 3]) -> Vec<Vec<u8>> {
    let h = init(scene);
    let mut out = vec![save(h).1];
    for k in 1..=4 {
        let e = direction.map(|d| d * f64::from(k));
        let (s, _, _) = update(h, e, RveTangentRequest::Consistent as i32);
        assert_eq!(s, RveStatus::Ok as u32, "{}", last_error_message());
        assert_eq!(rve_commit(h), RveStatus::Ok as u32);
        out.push(save(h).1);
    }
    assert_eq!(rve_free(h), RveStatus::Ok as u32);
    out
}

#[test]
fn corrupted_state_bytes_are_refused_and_change_nothing() {
    let _one_at_a_time = FFI.lock().unwrap_or_else(|e| e.into_inner());
    let ours = [
        states(0, [3e-5, -5e-6, 2e-6]),
        states(0, [-2e-5, 3e-5, -1e-5]),
    ]
    .concat();
    let theirs = states(1, [2e-5, -2e-5, 5e-5]);
    let target = init(0);
    driver::run(
        "state_bytes",
        5000,
        Duration::from_secs(30),
        |u: &mut Unstructured, tally: &mut Tally| {
            // The target starts from one of our states.
            let start = &ours[u.choose_index(ours.len()).unwrap_or(0)];
            assert_eq!(load(target, start), RveStatus::Ok as u32);
            let before = save(target).1;
            let foreign = u.ratio(1, 20).unwrap_or(false);
            let original = if foreign {
                &theirs[u.choose_index(theirs.len()).unwrap_or(0)]
            } else {
                &ours[u.choose_index(ours.len()).unwrap_or(0)]
            };
            let mut bytes = original.clone();
            let mut corruptions = Vec::new();
            if !foreign {
                for _ in 0..u.int_in_range(1..=3).unwrap_or(1) {
                    let c = Corruption::arbitrary(u).unwrap_or(Corruption::FlipBits(vec![0]));
                    apply(&mut bytes, &c);
                    corruptions.push(c);
                }
                if &bytes == original {
                    tally.count("unchanged by its corruptions (skipped)");
                    return Ok(());
                }
            }
            let status = load(target, &bytes);
            let name = ALL_STATUSES
                .iter()
                .find(|s| **s as u32 == status)
                .map_or(format!("unknown {status}"), |s| format!("{s:?}"));
            tally.count(format!(
                "{} {name}",
                if foreign {
                    "another scene:"
                } else {
                    "corrupted:"
                }
            ));
            let what = || {
                format!(
                    "{} bytes of {} ({corruptions:?})",
                    bytes.len(),
                    if foreign {
                        "another scene"
                    } else {
                        "our scene"
                    }
                )
            };
            let refused = [
                RveStatus::BadState,
                RveStatus::StateVersion,
                RveStatus::StateMismatch,
            ];
            let expected: &[RveStatus] = if foreign {
                &[RveStatus::StateMismatch]
            } else {
                &refused
            };
            if !expected.iter().any(|s| *s as u32 == status) {
                return Err(format!("{}: status {name}", what()));
            }
            if last_error_message().len() < 10 {
                return Err(format!("{}: refused without a message", what()));
            }
            if save(target).1 != before {
                return Err(format!("{}: the refused load changed the state", what()));
            }
            Ok(())
        },
    );
    assert_eq!(rve_free(target), RveStatus::Ok as u32);
}

/// Exhaustive: every single flipped bit and every truncation of a state of the paper's
/// RVE with every part filled (sensitivity, path curvature) is `BAD_STATE`.
#[test]
fn every_flipped_bit_and_every_truncation_is_bad_state() {
    let _one_at_a_time = FFI.lock().unwrap_or_else(|e| e.into_inner());
    let bytes = states(0, [3e-5, -5e-6, 2e-6]).pop().unwrap();
    let target = init(0);
    let before = save(target).1;
    let bad = RveStatus::BadState as u32;
    let mut corrupted = bytes.clone();
    for bit in 0..8 * bytes.len() {
        corrupted[bit / 8] ^= 1 << (bit % 8);
        let s = load(target, &corrupted);
        corrupted[bit / 8] ^= 1 << (bit % 8);
        assert_eq!(
            s,
            bad,
            "bit {bit} of {}: {}",
            8 * bytes.len(),
            last_error_message()
        );
    }
    for len in 0..bytes.len() {
        assert_eq!(
            load(target, &bytes[..len]),
            bad,
            "{len} of {} bytes",
            bytes.len()
        );
    }
    assert_eq!(save(target).1, before, "a refused load changed the state");
    assert_eq!(load(target, &bytes), RveStatus::Ok as u32);
    eprintln!(
        "state bytes: all {} single-bit flips and {} truncations of a {}-byte state refused",
        8 * bytes.len(),
        bytes.len(),
        bytes.len()
    );
    assert_eq!(rve_free(target), RveStatus::Ok as u32);
}
