//! The committed core of a state as host state variables (the UMAT's `STATEV`): what the
//! physics needs to continue, written as values that survive any copy of their values.
//!
//! **What the core holds** ([`Core`]): the macro strain, the interface history
//! (`delta_max` per point for the paper's law, eq. 25), the contact status of every
//! interface point, what IMPL-EX needs for its next extrapolation (`h_{n-1}`, `dt_n`), and
//! the host's time at the end of the increment that committed it.
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
//! entry  value (format 2)
//!     0  tag: STATEV_TAG * 2^16 + format version (CORE_FORMAT_VERSION)
//!     1  payload bytes L + 2^24 * (fingerprint mod 2^24)
//!     2  model sizes: unknowns * 2^24 + history values
//!     3  CRC-32C + 2^32 * (fingerprint div 2^24); the CRC of the little-endian u64s of
//!        entries 0-2, of the fingerprint's high part and of the payload bytes
//!   4..  the payload, 6 bytes per entry (little-endian, the last one zero-padded):
//!        bincode 1 of `Core`
//!  rest  zeros, up to the count the model needs (`values_needed`)
//! ```
//! The fingerprint ([`FINGERPRINT_BITS`] bits, `model::fingerprint`) names what the values
//! mean: the scene after `PROPS`, a Gmsh file's content, the integration. It sits in the
//! spare bits of the header. Format 1 (the first STATEV format, on main after 0.3.0 and
//! never released) is the same without the fingerprint (entry 1 = L, entry 3 = the CRC of
//! entries 0-2 and the payload) and with a core without the time (`CoreV1`): it is still
//! read, as a state that cannot be verified ([`Stored::verified`] false).
//!
//! All zeros is the virgin state (hosts initialize `STATEV` to zero). Any other content
//! that is not exactly what [`write`] writes for some core of this model is refused by
//! [`read`] with [`Error::BadState`] saying what is wrong; the checksum catches flipped
//! bits and overwritten entries, the length and trailing zeros catch truncation. A state
//! of another fingerprint is [`Error::StateOwner`].

use std::borrow::Cow;
use std::cell::RefCell;

use serde::{Deserialize, Serialize};

use super::instance_state::{held_contact_words, status_bit};
use super::persist::StateSizes;
use crate::error::{Error, Result};

/// "MESV" in ASCII, the tag's high 32 bits.
const STATEV_TAG: u64 = 0x4D45_5356;
/// Version of the core layout; bump when [`Core`] or the header changes.
pub const CORE_FORMAT_VERSION: u64 = 2;
/// The first format (main after 0.3.0, unreleased): no fingerprint, read as unverified.
const UNVERIFIED_FORMAT: u64 = 1;
/// Bits of a state's fingerprint: 24 in entry 1, 16 in entry 3.
pub const FINGERPRINT_BITS: u32 = 40;
/// Payload bytes are below 2^24 (entry 1's low bits).
const PAYLOAD_LIMIT: usize = 1 << 24;
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
    /// The host's total time at the end of the increment that committed this state
    /// (`TIME(2) + DTIME` of the UMAT call that wrote it), when the host gives a time: the
    /// next increment must start there (a state of an earlier increment is refused).
    pub time: Option<f64>,
}

/// A [`Core`] borrowing its buffers, encoded to the same bytes ([`encode_payload`]): what
/// [`write`] encodes, so that a state's core is written without copying its histories.
/// The contact status is borrowed where the state holds it in the core's layout, and
/// formed otherwise.
#[derive(Clone, Debug)]
pub struct CoreView<'a> {
    pub strain: [f64; 3],
    pub history: &'a [f64],
    pub closed: Cow<'a, [u64]>,
    pub previous: &'a [f64],
    pub step: f64,
    pub at_start: bool,
    pub time: Option<f64>,
}

impl CoreView<'_> {
    /// Whether point `point` is closed.
    pub fn is_closed(&self, point: usize) -> bool {
        status_bit(&self.closed, point)
    }

    /// Whether `core` is this core, field by field (as `Core`'s `==`; every field named, so
    /// that a field added to `Core` must be added here).
    pub fn is(&self, core: &Core) -> bool {
        let Core {
            strain,
            history,
            closed,
            previous,
            step,
            at_start,
            time,
        } = core;
        self.strain == *strain
            && self.history == history.as_slice()
            && *self.closed == **closed
            && self.previous == previous.as_slice()
            && self.step == *step
            && self.at_start == *at_start
            && self.time == *time
    }

    /// The owned core.
    pub fn to_core(&self) -> Core {
        Core {
            strain: self.strain,
            history: self.history.to_vec(),
            closed: self.closed.to_vec(),
            previous: self.previous.to_vec(),
            step: self.step,
            at_start: self.at_start,
            time: self.time,
        }
    }
}

/// The core of format 1: [`Core`] without the host's time.
#[derive(Serialize, Deserialize)]
struct CoreV1 {
    strain: [f64; 3],
    history: Vec<f64>,
    closed: Vec<u64>,
    previous: Vec<f64>,
    step: f64,
    at_start: bool,
}

impl From<CoreV1> for Core {
    fn from(c: CoreV1) -> Self {
        Core {
            strain: c.strain,
            history: c.history,
            closed: c.closed,
            previous: c.previous,
            step: c.step,
            at_start: c.at_start,
            time: None,
        }
    }
}

impl Core {
    /// This core as a [`CoreView`] (for [`write`]).
    pub fn view(&self) -> CoreView<'_> {
        CoreView {
            strain: self.strain,
            history: &self.history,
            closed: Cow::Borrowed(&self.closed),
            previous: &self.previous,
            step: self.step,
            at_start: self.at_start,
            time: self.time,
        }
    }

    /// Heap and inline bytes of this core.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + (self.history.capacity() + self.previous.capacity()) * std::mem::size_of::<f64>()
            + self.closed.capacity() * std::mem::size_of::<u64>()
    }

    /// Whether point `point` is closed.
    pub fn is_closed(&self, point: usize) -> bool {
        status_bit(&self.closed, point)
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
            && self.time.is_none_or(f64::is_finite)
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
        time: Some(0.0),
        ..Core::default()
    };
    HEADER + payload_len(&largest).div_ceil(BYTES_PER_VALUE)
}

fn payload_len(core: &Core) -> usize {
    bincode::serialized_size(core).expect("a core always serializes") as usize
}

/// A core [`read`] found, and whether its fingerprint was checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Stored {
    pub core: Core,
    /// False for a format 1 state, which carries no fingerprint.
    pub verified: bool,
}

/// Writes `core` of a model of `sizes` and `fingerprint` into `out` (zeros after it).
/// Fails, writing nothing, when `out` is too short.
pub fn write(
    core: &CoreView<'_>,
    sizes: StateSizes,
    fingerprint: u64,
    out: &mut [f64],
) -> Result<()> {
    let mut payload = PAYLOAD.try_with(RefCell::take).unwrap_or_default();
    payload.clear();
    let written = write_payload(core, sizes, fingerprint, &mut payload, out);
    let _ = PAYLOAD.try_with(|b| b.replace(payload));
    written
}

/// Appends bincode 1's bytes of the [`Core`] `core` views to `payload` (its default
/// options: fixed-width little-endian integers, `u64` lengths before a sequence, a `u8`
/// before an `Option`'s value), written slice by slice without serde. [`read`] decodes
/// them with bincode; a test holds the two to the same bytes.
fn encode_payload(core: &CoreView<'_>, payload: &mut Vec<u8>) {
    /// A sequence: its length, then its values; the bytes are placed into room made first,
    /// which compiles to a plain copy loop (pushing value by value did not).
    fn words<const N: usize>(
        payload: &mut Vec<u8>,
        values: impl ExactSizeIterator<Item = [u8; N]>,
    ) {
        payload.extend((values.len() as u64).to_le_bytes());
        let start = payload.len();
        payload.resize(start + N * values.len(), 0);
        for (room, v) in payload[start..].chunks_exact_mut(N).zip(values) {
            room.copy_from_slice(&v);
        }
    }
    core.strain
        .iter()
        .for_each(|v| payload.extend(v.to_le_bytes()));
    words(payload, core.history.iter().map(|v| v.to_le_bytes()));
    words(payload, core.closed.iter().map(|v| v.to_le_bytes()));
    words(payload, core.previous.iter().map(|v| v.to_le_bytes()));
    payload.extend(core.step.to_le_bytes());
    payload.push(u8::from(core.at_start));
    match core.time {
        None => payload.push(0),
        Some(t) => {
            payload.push(1);
            payload.extend(t.to_le_bytes());
        }
    }
}

thread_local! {
    /// This thread's buffer for a core's bincode bytes ([`write`] runs on every `STATEV`
    /// call of a host: no allocation once the buffer has grown to a core's length).
    static PAYLOAD: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// [`write`] with `payload` (empty) as the buffer for the core's bytes.
fn write_payload(
    core: &CoreView<'_>,
    sizes: StateSizes,
    fingerprint: u64,
    payload: &mut Vec<u8>,
    out: &mut [f64],
) -> Result<()> {
    encode_payload(core, payload);
    if payload.len() >= PAYLOAD_LIMIT || fingerprint >> FINGERPRINT_BITS != 0 {
        return Err(Error::StateEncoding {
            reason: format!(
                "a state core of {} bytes (at most {PAYLOAD_LIMIT}) or a fingerprint of more \
                 than {FINGERPRINT_BITS} bits",
                payload.len()
            ),
        });
    }
    let used = HEADER + payload.len().div_ceil(BYTES_PER_VALUE);
    if out.len() < used {
        return Err(Error::BadState {
            reason: format!(
                "STATEV has {} entries, this state needs {used} (set *DEPVAR to at least \
                 `rve info`'s umat_nstatv, + 5 for the UMAT's mirrors)",
                out.len()
            ),
        });
    }
    let header = Header {
        format: CORE_FORMAT_VERSION,
        payload_len: payload.len(),
        sizes: sizes_entry(sizes),
        fingerprint: Some(fingerprint),
        crc: 0,
    };
    let mut entries = header.entries();
    entries[3] += u64::from(header.checksum(payload));
    for (o, e) in out.iter_mut().zip(entries) {
        *o = e as f64;
    }
    // Six bytes an entry; the last entry zero-padded. Values are below 2^48, so the
    // signed conversion (one instruction) is exact.
    let full = payload.len() / BYTES_PER_VALUE;
    let (chunks, rest) = payload.split_at(full * BYTES_PER_VALUE);
    let body = &mut out[HEADER..];
    for (o, c) in body.iter_mut().zip(chunks.chunks_exact(BYTES_PER_VALUE)) {
        *o = i64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], 0, 0]) as f64;
    }
    if !rest.is_empty() {
        let mut last = [0u8; 8];
        last[..rest.len()].copy_from_slice(rest);
        body[full] = i64::from_le_bytes(last) as f64;
    }
    body[used - HEADER..].fill(0.0);
    Ok(())
}

/// The core `values` hold for a model of `sizes` with `points` interface points and
/// `fingerprint`: `None` for all zeros (virgin), else the core [`write`] wrote, or
/// [`Error::BadState`], [`Error::StateMismatch`] (other sizes) or [`Error::StateOwner`]
/// (another fingerprint).
pub fn read(
    values: &[f64],
    sizes: StateSizes,
    points: usize,
    fingerprint: u64,
) -> Result<Option<Stored>> {
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
    let header = Header::parse(&entries)?;
    let used = HEADER + header.payload_len.div_ceil(BYTES_PER_VALUE);
    if used > entries.len() {
        return Err(bad(format!(
            "STATEV has {} entries, its header says the state takes {used} (truncated, or \
             NSTATV smaller than when written)",
            entries.len()
        )));
    }
    let payload = unpack(&entries[HEADER..used], header.payload_len)?;
    if let Some(k) = (used..entries.len()).find(|&k| entries[k] != 0) {
        return Err(bad(format!(
            "STATEV({}) is not zero after the state's {used} entries",
            k + 1
        )));
    }
    if header.checksum(&payload) != header.crc {
        return Err(bad(
            "STATEV checksum mismatch: the state values were changed or truncated",
        ));
    }
    header.check_owner(sizes, fingerprint)?;
    let undecodable = |e: bincode::Error| bad(format!("STATEV payload does not decode ({e})"));
    let core: Core = if header.fingerprint.is_some() {
        bincode::deserialize(&payload).map_err(undecodable)?
    } else {
        bincode::deserialize::<CoreV1>(&payload)
            .map_err(undecodable)?
            .into()
    };
    if !core.fits(sizes, points) {
        return Err(bad(
            "STATEV state of another size than the model's, or not finite",
        ));
    }
    Ok(Some(Stored {
        core,
        verified: header.fingerprint.is_some(),
    }))
}

/// The four header entries, decoded.
struct Header {
    format: u64,
    payload_len: usize,
    /// Entry 2: unknowns * 2^24 + history values.
    sizes: u64,
    /// `None` in format 1.
    fingerprint: Option<u64>,
    crc: u32,
}

impl Header {
    /// Decodes and checks the tag and the format.
    fn parse(entries: &[u64]) -> Result<Self> {
        if entries[0] >> 16 != STATEV_TAG {
            return Err(bad("STATEV(1) is not a mesorve state tag"));
        }
        let format = entries[0] & 0xFFFF;
        let crc = (entries[3] & 0xFFFF_FFFF) as u32;
        let (payload_len, fingerprint) = match format {
            CORE_FORMAT_VERSION => (
                (entries[1] % PAYLOAD_LIMIT as u64) as usize,
                Some((entries[1] >> 24) | (entries[3] >> 32) << 24),
            ),
            UNVERIFIED_FORMAT if entries[3] >> 32 == 0 => (entries[1] as usize, None),
            _ => {
                return Err(bad(format!(
                    "STATEV state format {format}, this library reads {UNVERIFIED_FORMAT} \
                     and {CORE_FORMAT_VERSION}"
                )))
            }
        };
        Ok(Header {
            format,
            payload_len,
            sizes: entries[2],
            fingerprint,
            crc,
        })
    }

    /// The entries, with 0 for the CRC.
    fn entries(&self) -> [u64; 4] {
        let fp = self.fingerprint.unwrap_or(0);
        [
            (STATEV_TAG << 16) | self.format,
            self.payload_len as u64 | (fp % (1 << 24)) << 24,
            self.sizes,
            (fp >> 24) << 32,
        ]
    }

    /// The CRC-32C of entries 0-2, of the fingerprint's high part (format 2) and of the
    /// payload.
    fn checksum(&self, payload: &[u8]) -> u32 {
        let entries = self.entries();
        let mut bytes = [0u8; 32];
        for (b, e) in bytes
            .chunks_exact_mut(8)
            .zip(entries[..3].iter().chain([&(entries[3] >> 32)]))
        {
            b.copy_from_slice(&e.to_le_bytes());
        }
        let head = if self.fingerprint.is_some() { 32 } else { 24 };
        crc32c::crc32c_append(crc32c::crc32c(&bytes[..head]), payload)
    }

    /// Refuses a state of a model of other sizes or of another fingerprint.
    fn check_owner(&self, sizes: StateSizes, fingerprint: u64) -> Result<()> {
        if self.sizes != sizes_entry(sizes) {
            return Err(Error::StateMismatch {
                saved_unknowns: self.sizes >> 24,
                saved_history: self.sizes & 0xFF_FFFF,
                unknowns: sizes.unknowns as u64,
                history: sizes.history as u64,
            });
        }
        match self.fingerprint {
            Some(stored) if stored != fingerprint => Err(Error::StateOwner {
                stored,
                expected: fingerprint,
            }),
            _ => Ok(()),
        }
    }
}

fn sizes_entry(sizes: StateSizes) -> u64 {
    ((sizes.unknowns as u64) << 24) | sizes.history as u64
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
    /// A fingerprint with bits set in both of its parts.
    const FP: u64 = 0xA5_1234_5678;

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
            time: Some(1.25),
        }
    }

    #[test]
    fn round_trip_through_text() {
        let n = values_needed(SIZES, 192, true);
        let mut values = vec![0.0; n + 3];
        write(&core().view(), SIZES, FP, &mut values).unwrap();
        // As a text restart file would hold them.
        let text: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
        let back: Vec<f64> = text.iter().map(|t| t.parse().unwrap()).collect();
        assert_eq!(
            read(&back, SIZES, 192, FP).unwrap(),
            Some(Stored {
                core: core(),
                verified: true
            })
        );
        assert_eq!(read(&vec![0.0; n], SIZES, 192, FP).unwrap(), None);
    }

    /// The entries as the module docs lay them out, from the core's bincode bytes, to
    /// hold [`write`]'s packing to format 2 whatever the payload's length mod 6.
    fn documented_entries(core: &Core, fingerprint: u64, len: usize) -> Vec<u64> {
        let payload = bincode::serialize(core).unwrap();
        let mut crc_input = Vec::new();
        let head = [
            STATEV_TAG << 16 | CORE_FORMAT_VERSION,
            payload.len() as u64 + ((fingerprint % (1 << 24)) << 24),
            (SIZES.unknowns as u64) << 24 | SIZES.history as u64,
        ];
        head.iter().for_each(|h| crc_input.extend(h.to_le_bytes()));
        crc_input.extend((fingerprint >> 24).to_le_bytes());
        crc_input.extend(&payload);
        let mut entries = head.to_vec();
        entries.push(u64::from(crc32c::crc32c(&crc_input)) + ((fingerprint >> 24) << 32));
        for chunk in payload.chunks(6) {
            let mut bytes = [0u8; 8];
            bytes[..chunk.len()].copy_from_slice(chunk);
            entries.push(u64::from_le_bytes(bytes));
        }
        entries.resize(len, 0);
        entries
    }

    #[test]
    fn entries_are_the_documented_layout() {
        // Payloads of every length mod 6, each into a buffer of leftover garbage.
        for extra in 0..6 {
            let mut c = core();
            c.history.truncate(192 - extra);
            c.time = (extra % 2 == 0).then_some(2.0);
            if extra == 3 {
                c.previous.clear(); // implicit integration
            }
            let n = values_needed(SIZES, 192, true) + 2;
            let mut values = vec![7.0; n];
            write(&c.view(), SIZES, FP, &mut values).unwrap();
            let got: Vec<u64> = values.iter().map(|&v| v as u64).collect();
            let mut view_bytes = Vec::new();
            encode_payload(&c.view(), &mut view_bytes);
            assert_eq!(
                view_bytes,
                bincode::serialize(&c).unwrap(),
                "a view's bytes"
            );
            assert_eq!(
                got,
                documented_entries(&c, FP, n),
                "payload {extra} values short"
            );
        }
    }

    #[test]
    fn every_single_change_is_refused() {
        let n = values_needed(SIZES, 192, true);
        let mut values = vec![0.0; n];
        write(&core().view(), SIZES, FP, &mut values).unwrap();
        for k in 0..n {
            for change in [1.0, 2f64.powi(40), 0.5, -1.0] {
                let mut corrupted = values.clone();
                corrupted[k] += change;
                assert!(
                    read(&corrupted, SIZES, 192, FP).is_err(),
                    "entry {k} + {change}"
                );
            }
            let mut zeroed = values.clone();
            if zeroed[k] != 0.0 {
                zeroed[k] = 0.0;
                assert!(read(&zeroed, SIZES, 192, FP).is_err(), "entry {k} zeroed");
            }
        }
        for short in [n - 1, n / 2, 3] {
            assert!(
                read(&values[..short], SIZES, 192, FP).is_err(),
                "{short} entries"
            );
        }
        let other = StateSizes {
            unknowns: 700,
            ..SIZES
        };
        assert!(matches!(
            read(&values, other, 192, FP),
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
        write(&implicit.view(), SIZES, FP, &mut values).unwrap();
        implicit.previous = vec![0.0; 192];
        assert!(write(&implicit.view(), SIZES, FP, &mut values).is_err());
    }

    #[test]
    fn another_fingerprint_is_refused_and_names_both() {
        let mut values = vec![0.0; values_needed(SIZES, 192, true)];
        write(&core().view(), SIZES, FP, &mut values).unwrap();
        for other in [FP ^ 1, FP ^ (1 << 30), 1] {
            match read(&values, SIZES, 192, other) {
                Err(Error::StateOwner { stored, expected }) => {
                    assert_eq!((stored, expected), (FP, other));
                }
                r => panic!("fingerprint {other:#x}: {r:?}"),
            }
        }
    }

    /// Values as format 1 had them (the same layout without the fingerprint, the core
    /// without the time).
    fn format1(core: &Core) -> Vec<f64> {
        let payload = bincode::serialize(&CoreV1 {
            strain: core.strain,
            history: core.history.clone(),
            closed: core.closed.clone(),
            previous: core.previous.clone(),
            step: core.step,
            at_start: core.at_start,
        })
        .unwrap();
        let header = Header {
            format: UNVERIFIED_FORMAT,
            payload_len: payload.len(),
            sizes: sizes_entry(SIZES),
            fingerprint: None,
            crc: 0,
        };
        let mut entries = header.entries().to_vec();
        entries[3] = u64::from(header.checksum(&payload));
        entries.extend(payload.chunks(BYTES_PER_VALUE).map(|c| {
            let mut bytes = [0u8; 8];
            bytes[..c.len()].copy_from_slice(c);
            u64::from_le_bytes(bytes)
        }));
        entries.resize(values_needed(SIZES, 192, true), 0);
        entries.into_iter().map(|e| e as f64).collect()
    }

    #[test]
    fn format_1_is_read_unverified() {
        let old = format1(&core());
        let stored = read(&old, SIZES, 192, FP).unwrap().unwrap();
        let untimed = Core {
            time: None,
            ..core()
        };
        assert_eq!(
            stored,
            Stored {
                core: untimed,
                verified: false
            }
        );
        let mut changed = old.clone();
        changed[10] += 1.0;
        assert!(read(&changed, SIZES, 192, FP).is_err());
    }
}
