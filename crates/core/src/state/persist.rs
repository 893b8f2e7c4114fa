//! Checkpointing: a [`State`] as versioned bytes, and back. A fixed header, then the state
//! encoded by serde (bincode 1, little-endian, fixed-width integers), then a checksum.
//!
//! ```text
//! offset  size  field
//!      0     8  magic "MESORVE\0"
//!      8     4  format version (u32 LE), STATE_FORMAT_VERSION
//!     12     4  reserved, 0
//!     16     8  number of unknowns of the model (u64 LE)
//!     24     8  number of interface history points of the model (u64 LE)
//!     32     8  payload length in bytes (u64 LE), without the checksum
//!     40     8  the model's fingerprint (u64 LE, `Model::fingerprint`); formats >= 10
//!      H     .  payload: bincode of `State` (H = 48 from format 10, 40 before)
//!    H+len   4  CRC-32C (Castagnoli) of every byte before it (u32 LE); formats >= 6
//! ```
//! A reader refuses another magic or a buffer shorter than the header
//! ([`Error::BadState`]). Unless the version is one of the old formats 1-5, which carry
//! no checksum, it then checks the CRC-32C of the whole buffer before anything else, so
//! that any flipped bit (in the header too) and any truncation is [`Error::BadState`];
//! CRC-32C detects every error of up to 3 bits in buffers of this size, and all but one
//! in 2^32 of the others. A version bit flipped from 6 to an old format (4 or 2) is
//! refused by the payload length, which leaves the checksum out. Then it refuses an
//! unknown format version ([`Error::StateVersion`]: a later format adds a decoder here,
//! keeps the trailing checksum and keeps reading the old ones), and a model of other
//! sizes ([`Error::StateMismatch`]) or, from format 10, of another fingerprint
//! ([`Error::StateOwner`]: another scene, other `PROPS`, another mesh file or integration).
//! Formats before 10 carry no fingerprint: they load as before, unverified.
//!
//! | format | library | payload history |
//! |---|---|---|
//! | 1 | 0.1.0 | `[delta_max, t_max]` per point (read, `t_max` dropped) |
//! | 2 | main after 0.1.0 | `delta_max` per point (read, no sensitivity: the next increment starts from the elastic predictor) |
//! | 3 | main after 0.1.0 | format 2 plus the predictor's sensitivity `X`, 16-bit (read, sensitivity dropped: the next increment starts from the elastic predictor) |
//! | 4 | main after 0.1.0 | format 2 plus the predictor's sensitivity `X`, 8-bit by blocks, empty until filled (`Sensitivity`) (read, kept) |
//! | 5 | main after 0.1.0 | format 4 plus the path curvature, 8-bit by blocks, empty until filled (`PathCurvature`) (read, kept) |
//! | 6 | 0.2.0 | format 5 plus the trailing CRC-32C (read, kept; no fast-path data: the next update solves) |
//! | 7 | main after 0.2.0 | format 6 plus the fast path's `LinearBranch` (read, kept; no point held against its gap) |
//! | 8 | main after 0.2.0 | format 7 plus the points held at a contact status their gap contradicts, a bitset ([`State::held_contact`]) (read, kept; no IMPL-EX history) |
//! | 9 | 0.3.0 | format 8 plus IMPL-EX's previous history, step and contact status (`ImplexHistory`), empty with implicit integration (read, not verified against the model's fingerprint) |
//! | 10 | 0.4.0 | format 9 with the model's fingerprint in the header (written) |
//!
//! The functions take the sizes of the state's model ([`StateSizes`]) instead of the
//! model, so this module depends on the state alone; `model::Instance::save_state` and
//! `load_state` pass them, and the C functions `rve_state_*` are thin over those.

use serde::Deserialize;

use super::instance_state::{held_contact_words, PathCurvature, Sensitivity, State};
use super::linear_branch::LinearBranch;
use crate::error::{Error, Result};

const MAGIC: &[u8; 8] = b"MESORVE\0";
/// Version of the state byte format written; bump when the layout or `State` changes.
pub const STATE_FORMAT_VERSION: u32 = 10;
/// Older formats this library still reads without a checksum.
pub const READABLE_OLD_FORMATS: [u32; 5] = [1, 2, 3, 4, 5];
/// Older formats this library still reads, with the trailing checksum.
pub const READABLE_CHECKED_FORMATS: [u32; 4] = [6, 7, 8, 9];
/// Every older format this library reads.
const READABLE_FORMATS: [u32; 9] = [1, 2, 3, 4, 5, 6, 7, 8, 9];
/// Header bytes of the formats before 10.
const HEADER: usize = 40;
/// Header bytes from format 10: the fingerprint follows.
const FINGERPRINTED_HEADER: usize = 48;
/// The first format with the fingerprint.
const FIRST_FINGERPRINTED: u32 = 10;
/// Bytes of the trailing CRC-32C.
const CHECKSUM: usize = 4;

/// The sizes of the model a state belongs to, recorded in the header: a state loads only
/// into a model of the same sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateSizes {
    /// Unknowns of the model (`State::unknowns`).
    pub unknowns: usize,
    /// Interface history points of the model (`State::history`).
    pub history: usize,
}

/// Bytes [`encode`] writes for `state`.
pub fn encoded_len(state: &State) -> Result<usize> {
    let payload = bincode::serialized_size(state).map_err(encoding)?;
    Ok(FINGERPRINTED_HEADER + payload as usize + CHECKSUM)
}

/// Encodes `state`, a state of a model of `sizes` and `fingerprint`, in the current
/// format.
pub fn encode(state: &State, sizes: StateSizes, fingerprint: u64) -> Result<Vec<u8>> {
    let payload = bincode::serialize(state).map_err(encoding)?;
    let mut out = Vec::with_capacity(FINGERPRINTED_HEADER + payload.len() + CHECKSUM);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&STATE_FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&(sizes.unknowns as u64).to_le_bytes());
    out.extend_from_slice(&(sizes.history as u64).to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&fingerprint.to_le_bytes());
    out.extend_from_slice(&payload);
    let checksum = crc32c::crc32c(&out);
    out.extend_from_slice(&checksum.to_le_bytes());
    Ok(out)
}

/// Decodes bytes written by [`encode`] (this format or an older readable one) for a
/// model of `sizes` and `fingerprint`, and checks that the state is usable: sizes, the
/// fingerprint (formats from 10), finite values, a non-negative history.
pub fn decode(bytes: &[u8], sizes: StateSizes, fingerprint: u64) -> Result<State> {
    if bytes.len() < HEADER {
        return Err(bad(format!(
            "{} bytes, shorter than the {HEADER}-byte header",
            bytes.len()
        )));
    }
    if &bytes[..8] != MAGIC {
        return Err(bad("no mesorve magic (not a saved state)"));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    let bytes = if READABLE_OLD_FORMATS.contains(&version) {
        bytes
    } else {
        checked(bytes, version)?
    };
    if version != STATE_FORMAT_VERSION
        && !READABLE_OLD_FORMATS.contains(&version)
        && !READABLE_CHECKED_FORMATS.contains(&version)
    {
        return Err(Error::StateVersion {
            found: version,
            older: &READABLE_FORMATS,
            current: STATE_FORMAT_VERSION,
        });
    }
    let (n, nh) = (u64_at(bytes, 16), u64_at(bytes, 24));
    let (mn, mnh) = (sizes.unknowns as u64, sizes.history as u64);
    if (n, nh) != (mn, mnh) {
        return Err(Error::StateMismatch {
            saved_unknowns: n,
            saved_history: nh,
            unknowns: mn,
            history: mnh,
        });
    }
    let header = if version >= FIRST_FINGERPRINTED {
        FINGERPRINTED_HEADER
    } else {
        HEADER
    };
    let len = u64_at(bytes, 32);
    if bytes.len() < header || len != (bytes.len() - header) as u64 {
        return Err(bad(format!(
            "payload of {} bytes, header says {len}",
            bytes.len().saturating_sub(header)
        )));
    }
    if version >= FIRST_FINGERPRINTED && u64_at(bytes, HEADER) != fingerprint {
        return Err(Error::StateOwner {
            stored: u64_at(bytes, HEADER),
            expected: fingerprint,
        });
    }
    let state = payload(version, &bytes[header..])?;
    // A valid sensitivity or curvature must have its buffers; empty ones are fine.
    let filled_if_valid = |valid: bool, values: &[i8]| !valid || !values.is_empty();
    if state.unknowns.len() as u64 != n
        || state.history.len() as u64 != nh
        || !state.sensitivity.data.is_consistent(3 * n as usize)
        || !filled_if_valid(state.sensitivity.valid, &state.sensitivity.data.values)
        || !state.curvature.data.is_consistent(n as usize)
        || !filled_if_valid(state.curvature.valid, &state.curvature.data.values)
        || !state.linear.is_consistent(state.linear.closed.len())
        || state.held_contact.len() != held_contact_words(nh as usize)
    {
        return Err(bad("payload sizes disagree with the header"));
    }
    if state
        .strain
        .iter()
        .chain(&state.unknowns)
        .chain(&state.curvature.step)
        .chain(&state.history)
        .any(|v| !v.is_finite())
    {
        return Err(bad("non-finite values"));
    }
    Ok(state)
}

/// The bytes before the trailing checksum, if it matches them.
fn checked(bytes: &[u8], version: u32) -> Result<&[u8]> {
    if bytes.len() < HEADER + CHECKSUM {
        return Err(bad(format!(
            "{} bytes, too short for a format {version} state and its checksum",
            bytes.len()
        )));
    }
    let (body, stored) = bytes.split_at(bytes.len() - CHECKSUM);
    let stored = u32::from_le_bytes(stored.try_into().expect("4 bytes"));
    let computed = crc32c::crc32c(body);
    if stored != computed {
        return Err(bad(format!(
            "checksum mismatch (stored {stored:#010x}, computed {computed:#010x}): the \
             bytes were corrupted or truncated"
        )));
    }
    Ok(body)
}

fn bad(reason: impl Into<String>) -> Error {
    Error::BadState {
        reason: reason.into(),
    }
}

fn encoding(e: bincode::Error) -> Error {
    Error::StateEncoding {
        reason: e.to_string(),
    }
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
}

/// The payload of format `version` (readable, checked by the caller) as a [`State`].
fn payload(version: u32, payload: &[u8]) -> Result<State> {
    fn read<'a, T: Deserialize<'a>>(payload: &'a [u8]) -> Result<T> {
        bincode::deserialize(payload).map_err(|e| bad(e.to_string()))
    }
    Ok(match version {
        1 => read::<Format1>(payload)?.into(),
        2 => read::<Format2>(payload)?.into(),
        3 => read::<Format3>(payload)?.into(),
        4 => read::<Format4>(payload)?.into(),
        // Formats 5 and 6 have the same payload.
        5 | 6 => read::<Format6>(payload)?.into(),
        7 => read::<Format7>(payload)?.into(),
        8 => read::<Format8>(payload)?.into(),
        _ => read::<State>(payload)?,
    })
}

/// A state of the fields every format stores, without path curvature (formats 1-4 have
/// none: the first increment after loading predicts to first order) and, when
/// `sensitivity` is `None`, without sensitivity (the first increment after loading starts
/// from the elastic predictor). `delta_max` is the history as formats 2-5 store it.
fn old_state(
    strain: [f64; 3],
    unknowns: Vec<f64>,
    delta_max: Vec<f64>,
    sensitivity: Option<Sensitivity>,
) -> State {
    let mut state = State::virgin(0, 0);
    state.strain = strain;
    state.unknowns = unknowns;
    state.history = delta_max;
    if let Some(sensitivity) = sensitivity {
        state.sensitivity = sensitivity;
    }
    state.held_contact = vec![0; held_contact_words(state.history.len())];
    state
}

/// Format 1: history as `[delta_max, t_max]` pairs; the `t_max` column is dropped (it is
/// `t(delta_max)` by construction).
#[derive(Deserialize)]
struct Format1 {
    strain: [f64; 3],
    unknowns: Vec<f64>,
    history: Vec<[f64; 2]>,
}

impl From<Format1> for State {
    fn from(old: Format1) -> Self {
        let delta_max = old.history.iter().map(|&[delta_max, _t_max]| delta_max);
        old_state(old.strain, old.unknowns, delta_max.collect(), None)
    }
}

/// Format 2: history as `delta_max` per point, no sensitivity.
#[derive(Deserialize)]
struct Format2 {
    strain: [f64; 3],
    unknowns: Vec<f64>,
    history: Vec<f64>,
}

impl From<Format2> for State {
    fn from(old: Format2) -> Self {
        old_state(old.strain, old.unknowns, old.history, None)
    }
}

/// Format 3: format 2 plus a 16-bit sensitivity `X` (not its deviation), read and dropped.
#[derive(Deserialize)]
struct Format3 {
    strain: [f64; 3],
    unknowns: Vec<f64>,
    history: Vec<f64>,
    #[allow(dead_code)] // read to check the payload, then dropped
    sensitivity: SensitivityFormat3,
}

/// The 16-bit sensitivity of format 3.
#[derive(Deserialize)]
#[allow(dead_code)] // read to check the payload, then dropped
struct SensitivityFormat3 {
    valid: bool,
    scale: [f64; 3],
    values: Vec<i16>,
}

impl From<Format3> for State {
    fn from(old: Format3) -> Self {
        old_state(old.strain, old.unknowns, old.history, None)
    }
}

/// Format 4: format 2 plus the 8-bit [`Sensitivity`] (kept), without path curvature.
#[derive(Deserialize)]
struct Format4 {
    strain: [f64; 3],
    unknowns: Vec<f64>,
    history: Vec<f64>,
    sensitivity: Sensitivity,
}

impl From<Format4> for State {
    fn from(old: Format4) -> Self {
        old_state(old.strain, old.unknowns, old.history, Some(old.sensitivity))
    }
}

/// Formats 5 and 6: format 4 plus the [`PathCurvature`], without fast-path data.
#[derive(Deserialize)]
struct Format6 {
    strain: [f64; 3],
    unknowns: Vec<f64>,
    history: Vec<f64>,
    sensitivity: Sensitivity,
    curvature: PathCurvature,
}

impl From<Format6> for State {
    fn from(old: Format6) -> Self {
        let mut state = old_state(old.strain, old.unknowns, old.history, Some(old.sensitivity));
        state.curvature = old.curvature;
        state
    }
}

/// Format 7: format 6 plus the fast path's [`LinearBranch`], without the held contact
/// status (read as none held: the next update reads every point's status from its gap).
/// Bincode writes a nested struct as its fields in order: the bytes are format 6's, then
/// the branch.
#[derive(Deserialize)]
struct Format7 {
    format6: Format6,
    linear: LinearBranch,
}

impl From<Format7> for State {
    fn from(old: Format7) -> Self {
        let mut state = State::from(old.format6);
        state.linear = old.linear;
        state
    }
}

/// Format 8: format 7 plus the held contact status, without IMPL-EX history (read as
/// empty: a state written by implicit integration).
#[derive(Deserialize)]
struct Format8 {
    format7: Format7,
    held_contact: Vec<u64>,
}

impl From<Format8> for State {
    fn from(old: Format8) -> Self {
        let mut state = State::from(old.format7);
        state.held_contact = old.held_contact;
        state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SIZES: StateSizes = StateSizes {
        unknowns: 7,
        history: 5,
    };
    const FP: u64 = 0x12_3456_789A;

    fn state() -> State {
        let mut s = State::virgin(SIZES.unknowns, SIZES.history);
        s.strain = [1e-4, -2e-5, 3e-5];
        s.unknowns
            .iter_mut()
            .enumerate()
            .for_each(|(i, u)| *u = i as f64 * 1e-3);
        s.history[2] = 4e-4;
        s.sensitivity.store_negated(&[0.5; 21]);
        s.curvature.store(&[1e-6; 7], [1e-5, 0.0, 0.0]);
        s
    }

    /// What `encode` writes decodes to the same state, and `encoded_len` is its length.
    #[test]
    fn round_trip() {
        let s = state();
        let bytes = encode(&s, SIZES, FP).unwrap();
        assert_eq!(bytes.len(), encoded_len(&s).unwrap());
        assert_eq!(decode(&bytes, SIZES, FP).unwrap(), s);
    }

    /// Format 6 (0.2.0: format 7 without the fast-path data) loads, with no fast-path
    /// data, and the same checksum rules.
    #[test]
    fn format_6_loads_without_fast_path_data() {
        #[derive(serde::Serialize)]
        struct Format6Out<'a> {
            strain: [f64; 3],
            unknowns: &'a [f64],
            history: &'a [f64],
            sensitivity: &'a Sensitivity,
            curvature: &'a PathCurvature,
        }
        let s = state();
        let payload = bincode::serialize(&Format6Out {
            strain: s.strain,
            unknowns: &s.unknowns,
            history: &s.history,
            sensitivity: &s.sensitivity,
            curvature: &s.curvature,
        })
        .unwrap();
        let mut bytes = encode(&s, SIZES, FP).unwrap();
        bytes.truncate(HEADER);
        bytes[8..12].copy_from_slice(&6u32.to_le_bytes());
        bytes[32..40].copy_from_slice(&(payload.len() as u64).to_le_bytes());
        bytes.extend_from_slice(&payload);
        let sum = crc32c::crc32c(&bytes);
        bytes.extend_from_slice(&sum.to_le_bytes());
        let loaded = decode(&bytes, SIZES, FP).unwrap();
        assert_eq!(loaded, s, "the same state, no fast-path data");
        assert!(!loaded.linear.valid);
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        assert!(matches!(
            decode(&bytes, SIZES, FP),
            Err(Error::BadState { .. })
        ));
    }

    /// Formats 2-5 (main between 0.1.0 and 0.2.0; no file of them is kept): payloads laid
    /// out as the `State` of the commits that wrote them (110eed1, af8ec98, cf941b2,
    /// 8560fe2: strain, unknowns, `delta_max`, then the sensitivity, then the curvature),
    /// behind a header without checksum, load with what each kept; a payload cut inside
    /// its last field is refused.
    #[test]
    fn formats_2_to_5_load_with_what_each_kept() {
        #[derive(serde::Serialize)]
        struct Sensitivity16 {
            valid: bool,
            scale: [f64; 3],
            values: Vec<i16>,
        }
        let s = state();
        assert!(
            s.sensitivity.valid && s.curvature.valid,
            "a kept field is told apart"
        );
        let fields = bincode::serialize(&(s.strain, &s.unknowns, &s.history)).unwrap();
        let sensitivity16 = Sensitivity16 {
            valid: true,
            scale: [0.5; 3],
            values: vec![7; 21],
        };
        let payloads: [(u32, Vec<u8>); 4] = [
            (2, fields.clone()),
            (
                3,
                [fields.clone(), bincode::serialize(&sensitivity16).unwrap()].concat(),
            ),
            (
                4,
                [fields.clone(), bincode::serialize(&s.sensitivity).unwrap()].concat(),
            ),
            (
                5,
                [
                    fields,
                    bincode::serialize(&s.sensitivity).unwrap(),
                    bincode::serialize(&s.curvature).unwrap(),
                ]
                .concat(),
            ),
        ];
        let with_header = |version: u32, payload: &[u8]| {
            let mut bytes = encode(&s, SIZES, FP).unwrap();
            bytes.truncate(HEADER);
            bytes[8..12].copy_from_slice(&version.to_le_bytes());
            bytes[32..40].copy_from_slice(&(payload.len() as u64).to_le_bytes());
            bytes.extend_from_slice(payload);
            bytes
        };
        for (version, payload) in payloads {
            let loaded = decode(&with_header(version, &payload), SIZES, FP)
                .unwrap_or_else(|e| panic!("format {version}: {e}"));
            assert_eq!(loaded.strain, s.strain, "format {version}");
            assert_eq!(loaded.unknowns, s.unknowns, "format {version}");
            assert_eq!(loaded.history, s.history, "format {version}");
            assert_eq!(loaded.held_contact, vec![0; s.held_contact.len()]);
            assert!(!loaded.linear.valid && loaded.implex.previous.is_empty());
            if version >= 4 {
                assert_eq!(loaded.sensitivity, s.sensitivity, "format {version}");
            } else {
                assert!(!loaded.sensitivity.valid, "format {version}: dropped");
            }
            if version == 5 {
                assert_eq!(loaded.curvature, s.curvature);
            } else {
                assert!(!loaded.curvature.valid, "format {version}: none kept");
            }
            let cut = with_header(version, &payload[..payload.len() - 1]);
            assert!(
                matches!(decode(&cut, SIZES, FP), Err(Error::BadState { .. })),
                "format {version}: a cut payload"
            );
        }
    }

    /// Format 7 (format 8 without the held contact status) loads with no point held, and
    /// a state with held points round-trips in format 8.
    #[test]
    fn format_7_loads_with_no_point_held() {
        let mut s = state();
        s.held_contact[0] = 0b101;
        let bytes = encode(&s, SIZES, FP).unwrap();
        let decoded = decode(&bytes, SIZES, FP).unwrap();
        assert_eq!(decoded, s);
        assert!(decoded.is_held(0) && !decoded.is_held(1) && decoded.is_held(2));
        // Format 7: the same payload less the bitset (its u64 length and one word) and
        // the empty IMPL-EX history.
        let held = 8 + 8 * s.held_contact.len();
        let old = older_format(&bytes, 7, held + EMPTY_IMPLEX);
        let loaded = decode(&old, SIZES, FP).unwrap();
        assert!(loaded.held_contact.iter().all(|&w| w == 0));
        s.held_contact.fill(0);
        assert_eq!(loaded, s, "the same state, no point held");
    }

    /// Format 9 (0.3.0: no fingerprint) loads unverified; format 10 of another
    /// fingerprint is refused, naming both.
    #[test]
    fn fingerprint_is_checked_from_format_10() {
        let s = state();
        let bytes = encode(&s, SIZES, FP).unwrap();
        match decode(&bytes, SIZES, FP + 1) {
            Err(e @ Error::StateOwner { .. }) => {
                let text = e.to_string();
                assert!(text.contains(&format!("{FP:010x}")), "{text}");
                assert!(text.contains(&format!("{:010x}", FP + 1)), "{text}");
            }
            r => panic!("{r:?}"),
        }
        let format9 = older_format(&bytes, 9, 0);
        assert_eq!(decode(&format9, SIZES, FP + 1).unwrap(), s);
    }

    /// Bytes of an empty [`ImplexHistory`](crate::state::ImplexHistory): two empty
    /// vectors' lengths, the step and the flag.
    const EMPTY_IMPLEX: usize = 25;

    /// `bytes` (current format) rewritten as format `version` by dropping the payload's
    /// last `strip` bytes, with a new header and checksum.
    fn older_format(bytes: &[u8], version: u32, strip: usize) -> Vec<u8> {
        let mut old = bytes[..bytes.len() - CHECKSUM - strip].to_vec();
        old.drain(HEADER..FINGERPRINTED_HEADER);
        old[8..12].copy_from_slice(&version.to_le_bytes());
        let payload = (old.len() - HEADER) as u64;
        old[32..40].copy_from_slice(&payload.to_le_bytes());
        let sum = crc32c::crc32c(&old);
        old.extend_from_slice(&sum.to_le_bytes());
        old
    }

    /// A state with IMPL-EX history round-trips; format 8 (none) loads with it empty and
    /// every other field kept.
    #[test]
    fn format_8_loads_without_implex_history() {
        let mut s = state();
        s.held_contact[0] = 0b10;
        let plain = encode(&s, SIZES, FP).unwrap();
        let loaded = decode(&older_format(&plain, 8, EMPTY_IMPLEX), SIZES, FP).unwrap();
        assert_eq!(loaded, s);
        s.implex.previous = vec![1e-5; SIZES.history];
        s.implex.step = 0.25;
        s.implex.closed = vec![0b1001];
        let bytes = encode(&s, SIZES, FP).unwrap();
        let decoded = decode(&bytes, SIZES, FP).unwrap();
        assert_eq!(decoded, s);
        assert!(decoded.implex.is_closed(0) && !decoded.implex.is_closed(1));
        assert!(decoded.implex.is_consistent(SIZES.history, SIZES.history));
    }

    /// Fast-path data round-trips, and data of inconsistent sizes is refused.
    #[test]
    fn fast_path_data_round_trips() {
        let mut s = state();
        s.linear.valid = true;
        s.linear.tangent = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
        s.linear.szz = [0.1, 0.2, 0.3];
        s.linear.jumps = (0..12).map(|i| i as f32 * 0.5).collect();
        s.linear.closed = vec![true, false];
        s.linear.unknowns_strain = [1e-4, 0.0, 0.0];
        let bytes = encode(&s, SIZES, FP).unwrap();
        assert_eq!(decode(&bytes, SIZES, FP).unwrap(), s);
        s.linear.jumps.pop();
        let bytes = encode(&s, SIZES, FP).unwrap();
        assert!(matches!(
            decode(&bytes, SIZES, FP),
            Err(Error::BadState { .. })
        ));
        s.linear.jumps.push(f32::NAN);
        let bytes = encode(&s, SIZES, FP).unwrap();
        assert!(matches!(
            decode(&bytes, SIZES, FP),
            Err(Error::BadState { .. })
        ));
    }

    /// Each refusal is its own typed error, naming what it found.
    #[test]
    fn refusals_are_typed() {
        let bytes = encode(&state(), SIZES, FP).unwrap();
        assert!(matches!(
            decode(&bytes[..39], SIZES, FP),
            Err(Error::BadState { .. })
        ));
        assert!(matches!(
            decode(&bytes[..bytes.len() - 1], SIZES, FP),
            Err(Error::BadState { .. })
        ));
        let mut other = bytes.clone();
        other[0] = b'X';
        assert!(matches!(
            decode(&other, SIZES, FP),
            Err(Error::BadState { .. })
        ));
        // A later format with its checksum is StateVersion; a changed version without
        // a new checksum is corruption.
        let later = STATE_FORMAT_VERSION + 1;
        let mut other = bytes.clone();
        other[8..12].copy_from_slice(&later.to_le_bytes());
        assert!(matches!(
            decode(&other, SIZES, FP),
            Err(Error::BadState { .. })
        ));
        let body = other.len() - CHECKSUM;
        let sum = crc32c::crc32c(&other[..body]);
        other[body..].copy_from_slice(&sum.to_le_bytes());
        assert!(matches!(
            decode(&other, SIZES, FP),
            Err(Error::StateVersion {
                found,
                current: STATE_FORMAT_VERSION,
                ..
            }) if found == later
        ));
        // Any single flipped bit is BadState, in the header as in the payload.
        for bit in 0..8 * bytes.len() {
            let mut flipped = bytes.clone();
            flipped[bit / 8] ^= 1 << (bit % 8);
            assert!(
                matches!(decode(&flipped, SIZES, FP), Err(Error::BadState { .. })),
                "bit {bit}"
            );
        }
        let bigger = StateSizes {
            unknowns: 8,
            ..SIZES
        };
        let err = decode(&bytes, bigger, FP).unwrap_err();
        assert!(matches!(
            err,
            Error::StateMismatch {
                saved_unknowns: 7,
                saved_history: 5,
                unknowns: 8,
                history: 5
            }
        ));
        assert_eq!(
            err.to_string(),
            "state of a model with 7 unknowns and 5 history points; this instance's model \
             has 8 and 5 (another scene)"
        );
        // A header of matching sizes over a payload of other sizes.
        let small = State::virgin(3, 5);
        let lying = encode(&small, SIZES, FP).unwrap();
        let err = decode(&lying, SIZES, FP).unwrap_err();
        assert_eq!(
            err.to_string(),
            "state bytes: payload sizes disagree with the header"
        );
        let mut infinite = state();
        infinite.history[0] = f64::INFINITY;
        let err = decode(&encode(&infinite, SIZES, FP).unwrap(), SIZES, FP).unwrap_err();
        assert!(matches!(err, Error::BadState { .. }), "{err}");
    }
}
