//! Random sequences of C calls, through the exported `rve_*` functions: init, clone,
//! update, commit, revert, reset, state size, save, load and free in random order, on live,
//! freed (stale), zero and garbage handles, with NaN, infinite, absurd and denormal
//! strains, invalid tangent requests, undersized save buffers, and loads of states of
//! another instance, of another scene, truncated or with flipped bits.
//!
//! Properties:
//! - every status is the one the header documents for the situation (a stale handle is
//!   `BAD_HANDLE`, a commit without a successful update `NO_TRIAL`, ...), never `PANIC`
//!   or `INTERNAL`;
//! - the committed state of every instance equals, bit for bit (its saved bytes), that of
//!   a reference instance that replays only the successful commits, loads and resets: a
//!   failed update, a revert, a save or a rejected load changes nothing;
//! - no instance leaks (the registry is back to its size after each case).
//!
//! A second test saves an instance in the middle of a random path, loads the bytes into
//! a fresh instance and into the same instance after a reset, and checks that all three
//! continue bit-identically.

use std::ffi::CString;
use std::path::Path;
use std::sync::Mutex;
use std::time::Duration;

use arbitrary::{Arbitrary, Unstructured};
use rve::ffi::*;

use crate::driver::{self, Tally};

/// The C-call families share the process-wide registry; they run one at a time so that
/// the leak check can count its instances.
pub static FFI: Mutex<()> = Mutex::new(());

const OK: u32 = RveStatus::Ok as u32;
const SCENES: [&str; 2] = ["scenes/paper_rve_host.toml", "scenes/single_interface.toml"];

pub fn init(scene: usize) -> RveHandle {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENES[scene]);
    let path = CString::new(path.to_str().unwrap()).unwrap();
    let mut h = 0;
    assert_eq!(unsafe { rve_init_file(path.as_ptr(), &mut h) }, OK);
    h
}

pub fn save(h: RveHandle) -> (u32, Vec<u8>) {
    let mut size = 0;
    let s = unsafe { rve_state_size(h, &mut size) };
    if s != OK {
        return (s, Vec::new());
    }
    let mut bytes = vec![0u8; size];
    let mut written = 0;
    let s = unsafe { rve_state_save(h, bytes.as_mut_ptr(), size, &mut written) };
    bytes.truncate(written);
    (s, bytes)
}

pub fn update(h: RveHandle, strain: [f64; 3], request: i32) -> (u32, [f64; 3], [f64; 9]) {
    let (mut stress, mut tangent) = ([f64::NAN; 3], [f64::NAN; 9]);
    let s = unsafe {
        rve_update(
            h,
            strain.as_ptr(),
            stress.as_mut_ptr(),
            tangent.as_mut_ptr(),
            request,
        )
    };
    (s, stress, tangent)
}

pub fn load(h: RveHandle, bytes: &[u8]) -> u32 {
    unsafe { rve_state_load(h, bytes.as_ptr(), bytes.len()) }
}

#[derive(Debug, Clone, Copy)]
enum Sel {
    Live(u8),
    Stale(u8),
    Zero,
    Garbage(i64),
}

#[derive(Debug, Clone, Copy)]
enum Strain {
    /// The committed strain plus `d / 127 * 4e-5` per component.
    Step([i8; 3]),
    Nan(u8),
    Inf(u8),
    Absurd(u8),
    Huge,
    Zero,
    Denormal,
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Corruption {
    None,
    Truncate(u16),
    FlipBit(u16),
    Zeroed,
    Empty,
}

#[derive(Debug, Clone, Copy)]
enum Op {
    Init(bool),
    Clone(Sel),
    Update(Sel, Strain, u8),
    Commit(Sel),
    Revert(Sel),
    Reset(Sel),
    Size(Sel),
    Save(Sel, bool),
    Load(Sel, u8, Corruption),
    Free(Sel),
    Check,
}

/// Six in ten strains are steps from the committed strain.
impl<'a> Arbitrary<'a> for Strain {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(match u.int_in_range(0..=9)? {
            0..=5 => Strain::Step(u.arbitrary()?),
            6 => Strain::Nan(u.arbitrary()?),
            7 => Strain::Inf(u.arbitrary()?),
            8 => match u.int_in_range(0..=3)? {
                0 => Strain::Huge,
                1 => Strain::Zero,
                2 => Strain::Denormal,
                _ => Strain::Absurd(u.arbitrary()?),
            },
            _ => Strain::Absurd(u.arbitrary()?),
        })
    }
}

/// Seven in ten calls go to a live instance.
impl<'a> Arbitrary<'a> for Sel {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(match u.int_in_range(0..=9)? {
            0..=6 => Sel::Live(u.arbitrary()?),
            7 => Sel::Stale(u.arbitrary()?),
            8 => Sel::Zero,
            _ => Sel::Garbage(u.arbitrary()?),
        })
    }
}

/// Updates and commits are the most frequent calls, so that paths build up.
impl<'a> Arbitrary<'a> for Op {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(match u.int_in_range(0..=99)? {
            0..=29 => Op::Update(u.arbitrary()?, u.arbitrary()?, u.arbitrary()?),
            30..=49 => Op::Commit(u.arbitrary()?),
            50..=54 => Op::Revert(u.arbitrary()?),
            55..=57 => Op::Reset(u.arbitrary()?),
            58..=65 => Op::Save(u.arbitrary()?, u.arbitrary()?),
            66..=73 => Op::Load(u.arbitrary()?, u.arbitrary()?, u.arbitrary()?),
            74..=77 => Op::Free(u.arbitrary()?),
            78..=81 => Op::Init(u.arbitrary()?),
            82..=85 => Op::Clone(u.arbitrary()?),
            86..=89 => Op::Size(u.arbitrary()?),
            _ => Op::Check,
        })
    }
}

struct Inst {
    h: RveHandle,
    /// Replays only what must change the committed state.
    reference: RveHandle,
    scene: usize,
    committed_strain: [f64; 3],
    /// The strain and tangent request of the last successful update, while it can be
    /// committed (the request decides whether the predictor's sensitivity is stored).
    trial: Option<([f64; 3], i32)>,
}

struct World {
    live: Vec<Inst>,
    stale: Vec<RveHandle>,
    /// Saved states with their scene and the strain they were committed at.
    blobs: Vec<(usize, Vec<u8>, [f64; 3])>,
    log: Vec<String>,
}

enum Target {
    Live(usize),
    Dead(RveHandle),
}

impl World {
    fn target(&self, sel: Sel) -> Target {
        match sel {
            Sel::Live(k) if !self.live.is_empty() => Target::Live(k as usize % self.live.len()),
            Sel::Stale(k) if !self.stale.is_empty() => {
                Target::Dead(self.stale[k as usize % self.stale.len()])
            }
            Sel::Garbage(g) if g != 0 => Target::Dead(g),
            _ => Target::Dead(0),
        }
    }

    fn new_instance(&mut self, h: RveHandle, scene: usize) {
        let mut reference = 0;
        assert_eq!(unsafe { rve_clone_model(h, &mut reference) }, OK);
        self.live.push(Inst {
            h,
            reference,
            scene,
            committed_strain: [0.0; 3],
            trial: None,
        });
    }

    /// The committed states of every instance and its reference, bit for bit.
    fn check(&self) -> Result<(), String> {
        for inst in &self.live {
            let (sa, a) = save(inst.h);
            let (sb, b) = save(inst.reference);
            if (sa, sb) != (OK, OK) || a != b {
                return Err(format!(
                    "instance {} (scene {}): committed state differs from the replay of its \
                     successful commits (save statuses {sa}, {sb}; {} and {} bytes, first \
                     difference at byte {:?})",
                    inst.h,
                    SCENES[inst.scene],
                    a.len(),
                    b.len(),
                    a.iter().zip(&b).position(|(x, y)| x != y)
                ));
            }
        }
        Ok(())
    }

    fn expect(&self, op: &Op, got: u32, allowed: &[RveStatus]) -> Result<(), String> {
        if allowed.iter().any(|&s| s as u32 == got) {
            Ok(())
        } else {
            Err(format!(
                "{op:?}: status {got} ({}), expected one of {allowed:?}; message: {}; \
                 calls so far: {}",
                status_name(got),
                last_error_message(),
                self.log.join(", ")
            ))
        }
    }

    fn run(&mut self, op: Op, tally: &mut Tally) -> Result<(), String> {
        use RveStatus::*;
        self.log.push(format!("{op:?}"));
        match op {
            Op::Init(second) => {
                let scene = usize::from(second);
                let h = init(scene);
                self.new_instance(h, scene);
            }
            Op::Clone(sel) => match self.target(sel) {
                Target::Live(i) => {
                    let mut h = 0;
                    let s = unsafe { rve_clone_model(self.live[i].h, &mut h) };
                    self.expect(&op, s, &[Ok])?;
                    let scene = self.live[i].scene;
                    self.new_instance(h, scene);
                }
                Target::Dead(h) => {
                    let mut out = 0;
                    let s = unsafe { rve_clone_model(h, &mut out) };
                    self.expect(&op, s, &[BadHandle])?;
                }
            },
            Op::Update(sel, strain, request) => {
                let request = match request % 16 {
                    0..=9 => RveTangentRequest::Consistent as i32,
                    10 | 11 => RveTangentRequest::None as i32,
                    12 | 13 => RveTangentRequest::Elastic as i32,
                    14 => -1,
                    _ => 3,
                };
                let base = match self.target(sel) {
                    Target::Live(i) => self.live[i].committed_strain,
                    Target::Dead(_) => [0.0; 3],
                };
                let pick = |k: u8, v: f64| {
                    let mut e = base;
                    e[k as usize % 3] = v;
                    e
                };
                let e = match strain {
                    Strain::Step(d) => {
                        std::array::from_fn(|k| base[k] + f64::from(d[k]) / 127.0 * 4e-5)
                    }
                    Strain::Nan(k) => pick(k, f64::NAN),
                    Strain::Inf(k) => pick(
                        k,
                        if k % 2 == 0 {
                            f64::INFINITY
                        } else {
                            -f64::INFINITY
                        },
                    ),
                    Strain::Absurd(k) => pick(k, 0.2),
                    Strain::Huge => [1e308, -1e308, 1e308],
                    Strain::Zero => [0.0; 3],
                    Strain::Denormal => [5e-324, -5e-324, 5e-324],
                };
                let (s, stress, tangent) = update(self.handle(sel), e, request);
                let bad_request = request == -1 || request == 3;
                match self.target(sel) {
                    // The request is checked before the handle.
                    Target::Dead(_) if bad_request => self.expect(&op, s, &[InvalidArgument])?,
                    Target::Dead(_) => self.expect(&op, s, &[BadHandle])?,
                    Target::Live(i) => {
                        let allowed: &[RveStatus] = if bad_request {
                            &[InvalidArgument]
                        } else if e.iter().any(|v| !v.is_finite()) {
                            &[NonFiniteStrain]
                        } else if e.iter().any(|v| v.abs() > rve::MAX_STRAIN) {
                            &[AbsurdStrain]
                        } else {
                            &[Ok, SolverFailed]
                        };
                        self.expect(&op, s, allowed)?;
                        if s == OK && !stress.iter().all(|v| v.is_finite()) {
                            return Err(format!("{op:?}: OK with stress {stress:?}"));
                        }
                        if s == OK
                            && request != RveTangentRequest::None as i32
                            && !tangent.iter().all(|v| v.is_finite())
                        {
                            return Err(format!("{op:?}: OK with tangent {tangent:?}"));
                        }
                        if s != OK && stress.iter().any(|v| !v.is_nan()) {
                            return Err(format!("{op:?}: status {s} but stress written"));
                        }
                        tally.count(format!("update {}", status_name(s)));
                        self.live[i].trial = (s == OK).then_some((e, request));
                    }
                }
            }
            Op::Commit(sel) => {
                let s = rve_commit(self.handle(sel));
                match self.target(sel) {
                    Target::Dead(_) => self.expect(&op, s, &[BadHandle])?,
                    Target::Live(i) => {
                        let inst = &mut self.live[i];
                        match inst.trial.take() {
                            None => self.expect(&op, s, &[NoTrial])?,
                            Some((e, request)) => {
                                self.expect(&op, s, &[Ok])?;
                                let inst = &mut self.live[i];
                                let (rs, _, _) = update(inst.reference, e, request);
                                let rc = rve_commit(inst.reference);
                                if (rs, rc) != (OK, OK) {
                                    return Err(format!(
                                        "{op:?}: the reference's replay of the committed \
                                         update failed ({rs}, {rc}): {}",
                                        last_error_message()
                                    ));
                                }
                                inst.committed_strain = e;
                                tally.count("commit OK");
                            }
                        }
                    }
                }
            }
            Op::Revert(sel) | Op::Reset(sel) => {
                let reset = matches!(op, Op::Reset(_));
                let h = self.handle(sel);
                let s = if reset { rve_reset(h) } else { rve_revert(h) };
                match self.target(sel) {
                    Target::Dead(_) => self.expect(&op, s, &[BadHandle])?,
                    Target::Live(i) => {
                        self.expect(&op, s, &[Ok])?;
                        let inst = &mut self.live[i];
                        inst.trial = None;
                        if reset {
                            assert_eq!(rve_reset(inst.reference), OK);
                            inst.committed_strain = [0.0; 3];
                        }
                    }
                }
            }
            Op::Size(sel) => {
                let mut size = 0;
                let s = unsafe { rve_state_size(self.handle(sel), &mut size) };
                let expected = if matches!(self.target(sel), Target::Live(_)) {
                    Ok
                } else {
                    BadHandle
                };
                self.expect(&op, s, &[expected])?;
            }
            Op::Save(sel, undersized) => match self.target(sel) {
                Target::Dead(h) => {
                    let mut buf = [0u8; 16];
                    let mut written = 0;
                    let s = unsafe { rve_state_save(h, buf.as_mut_ptr(), buf.len(), &mut written) };
                    self.expect(&op, s, &[BadHandle])?;
                }
                Target::Live(i) => {
                    let inst = &self.live[i];
                    if undersized {
                        let mut buf = vec![0xAAu8; 64];
                        let mut written = 0;
                        let s =
                            unsafe { rve_state_save(inst.h, buf.as_mut_ptr(), 63, &mut written) };
                        self.expect(&op, s, &[BufferTooSmall])?;
                        if buf.iter().any(|&b| b != 0xAA) || written <= 63 {
                            return Err(format!(
                                "{op:?}: undersized save wrote {written} / the buffer"
                            ));
                        }
                    } else {
                        let (s, bytes) = save(inst.h);
                        self.expect(&op, s, &[Ok])?;
                        let (scene, strain) = (inst.scene, inst.committed_strain);
                        self.blobs.push((scene, bytes, strain));
                    }
                }
            },
            Op::Load(sel, blob, corruption) => {
                if self.blobs.is_empty() {
                    return Result::Ok(());
                }
                let (scene, bytes, strain) = self.blobs[blob as usize % self.blobs.len()].clone();
                let mut bytes = bytes;
                let intact = match corruption {
                    Corruption::None => true,
                    Corruption::Truncate(k) => {
                        bytes.truncate(k as usize % bytes.len());
                        false
                    }
                    Corruption::FlipBit(k) => {
                        let bit = k as usize % (8 * bytes.len());
                        bytes[bit / 8] ^= 1 << (bit % 8);
                        false
                    }
                    Corruption::Zeroed => {
                        bytes.iter_mut().for_each(|b| *b = 0);
                        false
                    }
                    Corruption::Empty => {
                        bytes.clear();
                        false
                    }
                };
                let h = self.handle(sel);
                let s = load(h, &bytes);
                match self.target(sel) {
                    Target::Dead(_) => self.expect(&op, s, &[BadHandle])?,
                    Target::Live(i) => {
                        let same_scene = self.live[i].scene == scene;
                        let allowed: &[RveStatus] = match (intact, same_scene) {
                            (true, true) => &[Ok],
                            (true, false) => &[StateMismatch],
                            // Refused, or a flipped bit that the format cannot see.
                            (false, _) => &[BadState, StateVersion, StateMismatch, Ok],
                        };
                        self.expect(&op, s, allowed)?;
                        tally.count(format!(
                            "load {} {}",
                            if intact { "intact" } else { "corrupted" },
                            status_name(s)
                        ));
                        if s == OK {
                            let inst = &mut self.live[i];
                            let rs = load(inst.reference, &bytes);
                            if rs != OK {
                                return Err(format!(
                                    "{op:?}: the reference refused the bytes: {rs}"
                                ));
                            }
                            inst.trial = None;
                            inst.committed_strain = strain;
                        }
                    }
                }
            }
            Op::Free(sel) => {
                let h = self.handle(sel);
                let s = rve_free(h);
                match self.target(sel) {
                    Target::Dead(0) => self.expect(&op, s, &[Ok])?,
                    Target::Dead(_) => self.expect(&op, s, &[BadHandle])?,
                    Target::Live(i) => {
                        self.expect(&op, s, &[Ok])?;
                        let inst = self.live.remove(i);
                        assert_eq!(rve_free(inst.reference), OK);
                        self.stale.push(inst.h);
                    }
                }
            }
            Op::Check => self.check()?,
        }
        Result::Ok(())
    }

    fn handle(&self, sel: Sel) -> RveHandle {
        match self.target(sel) {
            Target::Live(i) => self.live[i].h,
            Target::Dead(h) => h,
        }
    }
}

fn status_name(code: u32) -> String {
    ALL_STATUSES
        .iter()
        .find(|s| **s as u32 == code)
        .map_or(format!("unknown {code}"), |s| format!("{s:?}"))
}

#[test]
fn call_sequences_keep_the_committed_state() {
    let _one_at_a_time = FFI.lock().unwrap_or_else(|e| e.into_inner());
    // Keeps both models alive, so that an init in a case reuses the cached model.
    let keep = [init(0), init(1)];
    let baseline = live_instances();
    driver::run(
        "call_sequences",
        400,
        Duration::from_secs(120),
        |u: &mut Unstructured, tally: &mut Tally| {
            let mut world = World {
                live: Vec::new(),
                stale: Vec::new(),
                blobs: Vec::new(),
                log: Vec::new(),
            };
            let h = init(0);
            world.new_instance(h, 0);
            let len = u.int_in_range(5..=40).unwrap_or(5);
            let mut result = Ok(());
            for _ in 0..len {
                let op = Op::arbitrary(u).unwrap_or(Op::Check);
                result = world.run(op, tally);
                if result.is_err() {
                    break;
                }
            }
            let result = result.and_then(|()| world.check());
            tally.add("calls", world.log.len());
            for inst in world.live.drain(..) {
                assert_eq!(rve_free(inst.h), OK);
                assert_eq!(rve_free(inst.reference), OK);
            }
            result?;
            let live = live_instances();
            if live != baseline {
                return Err(format!(
                    "{live} live instances after the case, {baseline} before"
                ));
            }
            Ok(())
        },
    );
    for h in keep {
        assert_eq!(rve_free(h), OK);
    }
}

#[test]
fn a_save_and_load_mid_path_continues_bit_identically() {
    let _one_at_a_time = FFI.lock().unwrap_or_else(|e| e.into_inner());
    let keep = init(0);
    driver::run(
        "save_load_mid_path",
        30,
        Duration::from_secs(120),
        |u: &mut Unstructured, tally: &mut Tally| {
            let steps = u.int_in_range(4..=14).unwrap_or(4);
            let cut = u.int_in_range(1..=steps - 1).unwrap_or(1);
            let direction: [i8; 3] = u.arbitrary().unwrap_or([100, 0, 0]);
            let step: [f64; 3] = direction.map(|d| f64::from(d) / 127.0 * 2.5e-5);
            let a = init(0);
            let (mut b, mut c) = (0, 0);
            for k in 1..=steps {
                let e = step.map(|v| v * f64::from(k));
                if k == cut + 1 {
                    // b: a fresh instance; c: the same instance after a reset.
                    let (s, bytes) = save(a);
                    assert_eq!(s, OK);
                    b = init(0);
                    assert_eq!(load(b, &bytes), OK);
                    c = a;
                    assert_eq!(rve_reset(c), OK);
                    assert_eq!(load(c, &bytes), OK);
                    tally.count("round trips");
                }
                if k <= cut {
                    let (s, _, _) = update(a, e, RveTangentRequest::Consistent as i32);
                    if s != OK {
                        tally.count("path stopped by the solver before the cut");
                        assert_eq!(rve_free(a), OK);
                        return Ok(());
                    }
                    assert_eq!(rve_commit(a), OK);
                    continue;
                }
                // After the cut, `a` (= `c`, reloaded) runs against the fresh `b`; a
                // third copy replays the whole path without a round trip.
                let ra = update(c, e, RveTangentRequest::Consistent as i32);
                let rb = update(b, e, RveTangentRequest::Consistent as i32);
                let same = ra.0 == rb.0
                    && ra.1.map(f64::to_bits) == rb.1.map(f64::to_bits)
                    && ra.2.map(f64::to_bits) == rb.2.map(f64::to_bits);
                if !same {
                    return Err(format!(
                        "step {k} of {steps} (cut after {cut}, step {step:?}): reloaded \
                         instances differ: {ra:?} vs {rb:?}"
                    ));
                }
                if ra.0 != OK {
                    tally.count("path stopped by the solver after the cut");
                    break;
                }
                assert_eq!((rve_commit(c), rve_commit(b)), (OK, OK));
            }
            // The uninterrupted path gives the same committed state.
            let d = init(0);
            for k in 1..=steps {
                let e = step.map(|v| v * f64::from(k));
                if update(d, e, RveTangentRequest::Consistent as i32).0 != OK {
                    break;
                }
                assert_eq!(rve_commit(d), OK);
            }
            let (sc, sb, sd) = (save(c).1, save(b).1, save(d).1);
            for h in [c, b, d] {
                assert_eq!(rve_free(h), OK);
            }
            if sc == sb && sb == sd {
                Ok(())
            } else {
                Err(format!(
                    "final committed states differ (cut after {cut} of {steps})"
                ))
            }
        },
    );
    assert_eq!(rve_free(keep), OK);
}
