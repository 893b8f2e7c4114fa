//! Versioned state bytes: a fixed header, then the committed [`State`] encoded by serde
//! (bincode 1, little-endian, fixed-width integers).
//!
//! ```text
//! offset  size  field
//!      0     8  magic "MESORVE\0"
//!      8     4  format version (u32 LE), STATE_FORMAT_VERSION
//!     12     4  reserved, 0
//!     16     8  number of unknowns of the model (u64 LE)
//!     24     8  number of interface history points of the model (u64 LE)
//!     32     8  payload length in bytes (u64 LE)
//!     40     .  payload: bincode of `State`
//! ```
//! A reader refuses another magic or a truncated buffer (`BadState`), an unknown format
//! version (`StateVersion`: a later format adds a decoder here and keeps reading the old
//! ones), and a model of other sizes (`StateMismatch`).
//!
//! | format | library | payload history |
//! |---|---|---|
//! | 1 | 0.1.0 | `[delta_max, t_max]` per point (read, `t_max` dropped) |
//! | 2 | main after 0.1.0 | `delta_max` per point (read, no sensitivity: the next increment starts from the elastic predictor) |
//! | 3 | main after 0.1.0 | format 2 plus the predictor's sensitivity `X`, 16-bit (read, sensitivity dropped: the next increment starts from the elastic predictor) |
//! | 4 | main after 0.1.0 | format 2 plus the predictor's sensitivity `X`, 8-bit by blocks, empty until filled ([`crate::state::Sensitivity`]) (read, kept) |
//! | 5 | main after 0.1.0 | format 4 plus the path curvature, 8-bit by blocks, empty until filled ([`crate::state::PathCurvature`]) (written) |

use super::boundary::{Failure, FfiResult};
use super::status::RveStatus;
use crate::model::Model;
use crate::state::{State, StateFormat1, StateFormat2, StateFormat3, StateFormat4};

const MAGIC: &[u8; 8] = b"MESORVE\0";
/// Version of the state byte format; bump when the layout or `State` changes.
pub const STATE_FORMAT_VERSION: u32 = 5;
/// Older formats this library still reads.
const READABLE_OLD_FORMATS: [u32; 4] = [1, 2, 3, 4];
const HEADER: usize = 40;

fn sizes(model: &Model) -> (u64, u64) {
    (model.disc.n() as u64, model.disc.history_len() as u64)
}

/// Bytes of `state` saved for `model`.
pub(crate) fn encoded_len(state: &State) -> FfiResult<usize> {
    let payload = bincode::serialized_size(state)
        .map_err(|e| Failure::new(RveStatus::Internal, format!("state encoding: {e}")))?;
    Ok(HEADER + payload as usize)
}

/// Encodes `state` of `model`.
pub(crate) fn encode(model: &Model, state: &State) -> FfiResult<Vec<u8>> {
    let payload = bincode::serialize(state)
        .map_err(|e| Failure::new(RveStatus::Internal, format!("state encoding: {e}")))?;
    let (n, nh) = sizes(model);
    let mut out = Vec::with_capacity(HEADER + payload.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&STATE_FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&n.to_le_bytes());
    out.extend_from_slice(&nh.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&payload);
    Ok(out)
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
}

/// Decodes bytes saved by [`encode`] for a model of the same sizes.
pub(crate) fn decode(model: &Model, bytes: &[u8]) -> FfiResult<State> {
    let bad = |why: &str| Failure::new(RveStatus::BadState, format!("state bytes: {why}"));
    if bytes.len() < HEADER {
        return Err(bad(&format!(
            "{} bytes, shorter than the {HEADER}-byte header",
            bytes.len()
        )));
    }
    if &bytes[..8] != MAGIC {
        return Err(bad("no mesorve magic (not a saved state)"));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != STATE_FORMAT_VERSION && !READABLE_OLD_FORMATS.contains(&version) {
        return Err(Failure::new(
            RveStatus::StateVersion,
            format!(
                "state format version {version}; this library reads versions \
                 {READABLE_OLD_FORMATS:?} and {STATE_FORMAT_VERSION}"
            ),
        ));
    }
    let (n, nh) = (u64_at(bytes, 16), u64_at(bytes, 24));
    let (mn, mnh) = sizes(model);
    if (n, nh) != (mn, mnh) {
        return Err(Failure::new(
            RveStatus::StateMismatch,
            format!(
                "state of a model with {n} unknowns and {nh} history points; this \
                 instance's model has {mn} and {mnh} (another scene)"
            ),
        ));
    }
    let len = u64_at(bytes, 32);
    if len != (bytes.len() - HEADER) as u64 {
        return Err(bad(&format!(
            "payload of {} bytes, header says {len}",
            bytes.len() - HEADER
        )));
    }
    let payload = &bytes[HEADER..];
    let state: State = if version == 1 {
        bincode::deserialize::<StateFormat1>(payload)
            .map_err(|e| bad(&e.to_string()))?
            .into()
    } else if version == 2 {
        bincode::deserialize::<StateFormat2>(payload)
            .map_err(|e| bad(&e.to_string()))?
            .into()
    } else if version == 3 {
        bincode::deserialize::<StateFormat3>(payload)
            .map_err(|e| bad(&e.to_string()))?
            .into()
    } else if version == 4 {
        bincode::deserialize::<StateFormat4>(payload)
            .map_err(|e| bad(&e.to_string()))?
            .into()
    } else {
        bincode::deserialize(payload).map_err(|e| bad(&e.to_string()))?
    };
    // A valid sensitivity or curvature must have its buffers; empty ones are fine.
    let filled_if_valid = |valid: bool, values: &[i8]| !valid || !values.is_empty();
    if state.unknowns.len() as u64 != n
        || state.history.len() as u64 != nh
        || !state.sensitivity.data.is_consistent(3 * n as usize)
        || !filled_if_valid(state.sensitivity.valid, &state.sensitivity.data.values)
        || !state.curvature.data.is_consistent(n as usize)
        || !filled_if_valid(state.curvature.valid, &state.curvature.data.values)
    {
        return Err(bad("payload sizes disagree with the header"));
    }
    if state
        .strain
        .iter()
        .chain(&state.unknowns)
        .chain(&state.curvature.step)
        .any(|v| !v.is_finite())
    {
        return Err(bad("non-finite values"));
    }
    let admissible = match &model.disc.law {
        Some(law) => law.history_is_valid(&state.history),
        None => state.history.iter().all(|v| v.is_finite()),
    };
    if !admissible {
        return Err(bad(
            "an interface history value that is negative or not finite",
        ));
    }
    Ok(state)
}
