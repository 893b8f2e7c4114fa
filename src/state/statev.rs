//! The committed core of a state as host state variables (the UMAT's `STATEV`): what the
//! physics needs to continue, written as values that survive any copy of their values.
//!
//! **What the core holds** ([`Core`]): the macro strain, the interface history
//! (`delta_max` per point for the paper's law, eq. 25), the contact status of every
//! interface point, and what IMPL-EX needs for its next extrapolation (`h_{n-1}`, `dt_n`).
//! Nothing else: the fluctuation, the predictor's sensitivity, the path curvature and the
//! fast path's data are caches the library rebuilds or keeps per process
//! (`Model::expand_core`), so that the state a host stores stays a few hundred values.
//!
//! **Values, not bit patterns.** Hosts copy `STATEV` through floating-point registers and
//! some write it as text, so a value must mean the same after any copy that keeps its
//! value: every entry is an integer in `[0, 2^48)`, exact as an `f64` (53-bit
//! significand) and printed exactly by any `%.17g`-style writer. Raw bytes reinterpreted
//! as doubles would form NaNs and denormals that registers and printers do not keep.
//!
//! ```text
//! entry  value
//!     0  tag: STATEV_TAG * 2^16 + format version (CORE_FORMAT_VERSION)
//!     1  payload bytes L
//!     2  model sizes: unknowns * 2^24 + history values
//!     3  CRC-32C of the little-endian u64s of entries 0-2 and of the payload bytes
//!   4..  the payload, 6 bytes per entry (little-endian, the last one zero-padded):
//!        bincode 1 of `Core`
//!  rest  zeros, up to the count the model needs (`values_needed`)
//! ```
//! All zeros is the virgin state (hosts initialize `STATEV` to zero). Any other content
//! that is not exactly what [`write`] writes for some core of this model is refused by
//! [`read`] with [`Error::BadState`] saying what is wrong; the checksum catches flipped
//! bits and overwritten entries, the length and trailing zeros catch truncation.

use serde::{Deserialize, Serialize};

use super::instance_state::held_contact_words;
use super::persist::StateSizes;
use crate::error::{Error, Result};

/// "MESV" in ASCII, the tag's high 32 bits.
const STATEV_TAG: u64 = 0x4D45_5356;
/// Version of the core layout; bump when [`Core`] changes.
pub const CORE_FORMAT_VERSION: u64 = 1;
/// Entries before the payload.
const HEADER: usize = 4;
/// Payload bytes per entry.
const BYTES_PER_VALUE: usize = 6;
/// Entries are integers below this (48 bits).
const VALUE_LIMIT: f64 = (1u64 << 48) as f64;

/// What a state must carry from one host increment to the next (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Core {
    /// Macro strain `[eps_xx, eps_yy, gamma_xy]` the state is in equilibrium with.
    pub strain: [f64; 3],
    /// The interface history, as `State::history`.
    pub history: Vec<f64>,
    /// The contact status of every interface point (closed), one bit per point, point `i`
    /// in bit `i % 64` of word `i / 64`.
    pub closed: Vec<u64>,
    /// IMPL-EX's `h_{n-1}`; empty with implicit integration and before the first step.
    pub previous: Vec<f64>,
    /// IMPL-EX's `dt_n`; 0 when not given.
    pub step: f64,
    /// IMPL-EX: the step that led here froze the history it started from.
    pub at_start: bool,
}

impl Core {
    /// Whether point `point` is closed.
    pub fn is_closed(&self, point: usize) -> bool {
        self.closed
            .get(point / 64)
            .is_some_and(|w| w >> (point % 64) & 1 == 1)
    }

    /// Whether the buffers fit a model of `sizes` with `points` interface points and hold
    /// finite values (a law's admissibility is checked by the caller).
    pub fn fits(&self, sizes: StateSizes, points: usize) -> bool {
        let spare_bits = (points..64 * self.closed.len()).any(|i| self.is_closed(i));
        self.history.len() == sizes.history
            && self.closed.len() == held_contact_words(points)
            && !spare_bits
            && (self.previous.is_empty() || self.previous.len() == sizes.history)
            && self.step.is_finite()
            && self.step >= 0.0
            && self
                .strain
                .iter()
                .chain(&self.history)
                .chain(&self.previous)
                .all(|v| v.is_finite())
    }
}

/// `STATEV` entries a model of `sizes` with `points` interface points needs for its
/// largest core (with IMPL-EX's `h_{n-1}` when `implex`).
pub fn values_needed(sizes: StateSizes, points: usize, implex: bool) -> usize {
    let largest = Core {
        history: vec![0.0; sizes.history],
        closed: vec![0; held_contact_words(points)],
        previous: vec![0.0; if implex { sizes.history } else { 0 }],
        ..Core::default()
    };
    HEADER + payload_len(&largest).div_ceil(BYTES_PER_VALUE)
}

fn payload_len(core: &Core) -> usize {
    bincode::serialized_size(core).expect("a core always serializes") as usize
}

/// Writes `core` of a model of `sizes` into `out` (zeros after it). Fails, writing
/// nothing, when `out` is too short.
pub fn write(core: &Core, sizes: StateSizes, out: &mut [f64]) -> Result<()> {
    let payload = bincode::serialize(core).map_err(|e| Error::StateEncoding {
        reason: e.to_string(),
    })?;
    let used = HEADER + payload.len().div_ceil(BYTES_PER_VALUE);
    if out.len() < used {
        return Err(Error::BadState {
            reason: format!(
                "STATEV has {} entries, this state needs {used} (set *DEPVAR to `rve info`'s \
                 umat_nstatv)",
                out.len()
            ),
        });
    }
    let header = header(payload.len(), sizes);
    out.fill(0.0);
    for (o, h) in out.iter_mut().zip(header) {
        *o = h as f64;
    }
    out[3] = f64::from(checksum(&header[..3], &payload));
    for (o, chunk) in out[HEADER..]
        .iter_mut()
        .zip(payload.chunks(BYTES_PER_VALUE))
    {
        let mut bytes = [0u8; 8];
        bytes[..chunk.len()].copy_from_slice(chunk);
        *o = u64::from_le_bytes(bytes) as f64;
    }
    Ok(())
}

/// The core `values` hold for a model of `sizes` with `points` interface points: `None`
/// for all zeros (virgin), else the core [`write`] wrote, or [`Error::BadState`].
pub fn read(values: &[f64], sizes: StateSizes, points: usize) -> Result<Option<Core>> {
    if values.iter().all(|&v| v == 0.0) {
        return Ok(None);
    }
    if let Some(k) = values
        .iter()
        .position(|&v| !((0.0..VALUE_LIMIT).contains(&v) && v.fract() == 0.0))
    {
        return Err(bad(format!(
            "STATEV({}) = {:e} is not a mesorve state value (an integer in [0, 2^48)): \
             not written by this library, or changed",
            k + 1,
            values[k]
        )));
    }
    if values.len() < HEADER {
        return Err(bad(format!("only {} STATEV entries", values.len())));
    }
    let entries: Vec<u64> = values.iter().map(|&v| v as u64).collect();
    check_header(&entries, sizes)?;
    let len = entries[1] as usize;
    let used = HEADER + len.div_ceil(BYTES_PER_VALUE);
    if used > entries.len() {
        return Err(bad(format!(
            "STATEV has {} entries, its header says the state takes {used} (truncated, or \
             NSTATV smaller than when written)",
            entries.len()
        )));
    }
    let payload = unpack(&entries[HEADER..used], len)?;
    if let Some(k) = (used..entries.len()).find(|&k| entries[k] != 0) {
        return Err(bad(format!(
            "STATEV({}) is not zero after the state's {used} entries",
            k + 1
        )));
    }
    if checksum(&entries[..3], &payload) as u64 != entries[3] {
        return Err(bad(
            "STATEV checksum mismatch: the state values were changed or truncated",
        ));
    }
    let core: Core = bincode::deserialize(&payload)
        .map_err(|e| bad(format!("STATEV payload does not decode ({e})")))?;
    if !core.fits(sizes, points) {
        return Err(bad(
            "STATEV state of another size than the model's, or not finite",
        ));
    }
    Ok(Some(core))
}

/// Checks the tag, the format and the model sizes of the header entries.
fn check_header(entries: &[u64], sizes: StateSizes) -> Result<()> {
    if entries[0] >> 16 != STATEV_TAG {
        return Err(bad("STATEV(1) is not a mesorve state tag"));
    }
    let format = entries[0] & 0xFFFF;
    if format != CORE_FORMAT_VERSION {
        return Err(bad(format!(
            "STATEV state format {format}, this library reads {CORE_FORMAT_VERSION}"
        )));
    }
    let expected = header(0, sizes)[2];
    if entries[2] != expected {
        return Err(Error::StateMismatch {
            saved_unknowns: entries[2] >> 24,
            saved_history: entries[2] & 0xFF_FFFF,
            unknowns: sizes.unknowns as u64,
            history: sizes.history as u64,
        });
    }
    Ok(())
}

/// The payload bytes of `len` bytes packed in `entries`, which must be exactly enough.
fn unpack(entries: &[u64], len: usize) -> Result<Vec<u8>> {
    let room = entries.len() * BYTES_PER_VALUE;
    if room < len || room >= len + BYTES_PER_VALUE || entries.iter().any(|&e| e >> 48 != 0) {
        return Err(bad(format!(
            "STATEV holds {} payload entries, its header says {len} bytes (truncated, or \
             NSTATV smaller than when written)",
            entries.len()
        )));
    }
    let mut payload: Vec<u8> = entries
        .iter()
        .flat_map(|e| e.to_le_bytes().into_iter().take(BYTES_PER_VALUE))
        .collect();
    if payload[len..].iter().any(|&b| b != 0) {
        return Err(bad("STATEV padding after the payload is not zero"));
    }
    payload.truncate(len);
    Ok(payload)
}

fn header(payload_len: usize, sizes: StateSizes) -> [u64; 4] {
    [
        (STATEV_TAG << 16) | CORE_FORMAT_VERSION,
        payload_len as u64,
        ((sizes.unknowns as u64) << 24) | sizes.history as u64,
        0,
    ]
}

fn checksum(header: &[u64], payload: &[u8]) -> u32 {
    let mut bytes: Vec<u8> = header.iter().flat_map(|h| h.to_le_bytes()).collect();
    bytes.extend_from_slice(payload);
    crc32c::crc32c(&bytes)
}

fn bad(reason: impl Into<String>) -> Error {
    Error::BadState {
        reason: reason.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SIZES: StateSizes = StateSizes {
        unknowns: 722,
        history: 192,
    };

    fn core() -> Core {
        let mut closed = vec![0u64; 3];
        closed[1] = 0b1011;
        Core {
            strain: [1e-4, -3e-5, 2.5e-6],
            history: (0..192).map(|i| 1e-6 * f64::from(i) / 3.0).collect(),
            closed,
            previous: (0..192).map(|i| 1e-7 * f64::from(i)).collect(),
            step: 0.125,
            at_start: true,
        }
    }

    #[test]
    fn round_trip_through_text() {
        let n = values_needed(SIZES, 192, true);
        let mut values = vec![0.0; n + 3];
        write(&core(), SIZES, &mut values).unwrap();
        // As a text restart file would hold them.
        let text: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
        let back: Vec<f64> = text.iter().map(|t| t.parse().unwrap()).collect();
        assert_eq!(read(&back, SIZES, 192).unwrap(), Some(core()));
        assert_eq!(read(&vec![0.0; n], SIZES, 192).unwrap(), None);
    }

    #[test]
    fn every_single_change_is_refused() {
        let n = values_needed(SIZES, 192, true);
        let mut values = vec![0.0; n];
        write(&core(), SIZES, &mut values).unwrap();
        for k in 0..n {
            for change in [1.0, 2f64.powi(40), 0.5, -1.0] {
                let mut corrupted = values.clone();
                corrupted[k] += change;
                assert!(
                    read(&corrupted, SIZES, 192).is_err(),
                    "entry {k} + {change}"
                );
            }
            let mut zeroed = values.clone();
            if zeroed[k] != 0.0 {
                zeroed[k] = 0.0;
                assert!(read(&zeroed, SIZES, 192).is_err(), "entry {k} zeroed");
            }
        }
        for short in [n - 1, n / 2, 3] {
            assert!(
                read(&values[..short], SIZES, 192).is_err(),
                "{short} entries"
            );
        }
        let other = StateSizes {
            unknowns: 700,
            ..SIZES
        };
        assert!(matches!(
            read(&values, other, 192),
            Err(Error::StateMismatch { .. })
        ));
    }

    #[test]
    fn too_short_a_statev_is_refused_on_write() {
        let n = values_needed(SIZES, 192, false);
        let mut implicit = Core {
            previous: Vec::new(),
            ..core()
        };
        let mut values = vec![0.0; n];
        write(&implicit, SIZES, &mut values).unwrap();
        implicit.previous = vec![0.0; 192];
        assert!(write(&implicit, SIZES, &mut values).is_err());
    }
}
