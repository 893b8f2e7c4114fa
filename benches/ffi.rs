//! C-ABI benchmark: `cargo bench --bench ffi` (env MESORVE_BENCH_INSTANCES sets the
//! instance count of the memory sections, default 100000). Markdown tables on stdout:
//!
//! 1. Call overhead: trial updates through the safe API and through `rve_update`, each
//!    from the same committed pre-peak state (`LOADING`, committed) to a NEW strain every
//!    call (`trial_strain(k)`, eps_xx = 5e-5 (1 + 1e-9 k)), alternating, in the same run:
//!    medians and their ratio. Every timed update is a solve: the safe API's answer is
//!    asserted `Answer::Solved`, and `rve_fast_updates` (which counts the fast path and
//!    repeated trials) must not move. The repeated trial (same strain bit for bit: the
//!    stored answer, no solve) is timed apart, labelled as such.
//! 2. Batch throughput (`rve_update_batch`) on 1 and 2 threads, alternating rounds, each
//!    round at a new strain from the same committed state; medians and the ratio.
//! 3. Memory of N paper-RVE instances, each part in a fresh process (this binary again,
//!    env MESORVE_BENCH_PART) so that its peak RSS is its own: (a) the loading steady
//!    state (every instance committed along `LOADING`, then a trial at 5e-5 kept), (b)
//!    the fast steady state (the committed state of the 5.2.2 cycle's increment 28,
//!    unloading, loaded into each instance, then a fast update committed and another
//!    kept). Peak RSS, bytes per instance, `rve_state_size`, and one instance's bytes
//!    per component (`State` fields, from the safe API driven the same way).

mod common;
use common::{load_average, peak_rss_mib};

use std::ffi::CString;
use std::process::Command;
use std::sync::Arc;
use std::time::Instant;

use mesorve_core::solver::Answer;
use rve::ffi::*;
use rve::{Instance, Model, Scene, State, TangentRequest};

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/paper_rve.toml");

/// The committed loading path (eps_xx): pre-peak (the paper RVE peaks near 2e-4).
const LOADING: [f64; 3] = [1.25e-5, 2.5e-5, 3.75e-5];

/// The strain of the timed trials, one step on from `LOADING`.
const E_TRIAL: f64 = 5e-5;

/// Instances of the warm-up in the memory parts (pools, per-thread workspaces).
const WARM_UP: usize = 64;

fn eps(x: f64) -> [f64; 3] {
    [x, 0.0, 0.0]
}

/// The `k`-th timed trial strain: distinct for every `k`, so no update repeats the
/// pending trial bit for bit; the work is that of the step `LOADING` -> `E_TRIAL`.
fn trial_strain(k: usize) -> [f64; 3] {
    eps(E_TRIAL * (1.0 + 1e-9 * (k + 1) as f64))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn instances() -> usize {
    std::env::var("MESORVE_BENCH_INSTANCES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100_000)
}

fn init() -> RveHandle {
    let path = CString::new(SCENE).unwrap();
    let mut h = 0;
    assert_eq!(unsafe { rve_init_file(path.as_ptr(), &mut h) }, 0);
    h
}

/// `rve_update` with the consistent tangent; returns the stress.
fn update(h: RveHandle, e: [f64; 3]) -> [f64; 3] {
    let (mut sig, mut d) = ([0.0; 3], [0.0; 9]);
    let s = unsafe { rve_update(h, e.as_ptr(), sig.as_mut_ptr(), d.as_mut_ptr(), 0) };
    assert_eq!(s, 0, "rve_update: {}", last_error_message());
    sig
}

fn fast_count(h: RveHandle) -> u64 {
    let mut n = 0;
    assert_eq!(unsafe { rve_fast_updates(h, &mut n) }, 0);
    n
}

fn fast_total(handles: &[RveHandle]) -> u64 {
    handles.iter().map(|&h| fast_count(h)).sum()
}

fn commit_all(handles: &[RveHandle]) {
    for &h in handles {
        assert_eq!(rve_commit(h), 0);
    }
}

fn state_size(h: RveHandle) -> usize {
    let mut n = 0;
    assert_eq!(unsafe { rve_state_size(h, &mut n) }, 0);
    n
}

/// The buffers of `rve_update_batch`, allocated once.
struct Batch {
    strains: Vec<f64>,
    stresses: Vec<f64>,
    tangents: Vec<f64>,
    statuses: Vec<u32>,
}

impl Batch {
    /// Buffers for `n` items, written through (not zero pages the kernel maps later), so
    /// that a resident set measured after this counts them.
    fn new(n: usize) -> Self {
        Batch {
            strains: vec![f64::NAN; 3 * n],
            stresses: vec![f64::NAN; 3 * n],
            tangents: vec![f64::NAN; 9 * n],
            statuses: vec![u32::MAX; n],
        }
    }

    /// Every handle trial-updated at `e` (consistent tangent) on `threads`; seconds of
    /// the call alone. Every item must succeed.
    fn run(&mut self, handles: &[RveHandle], e: [f64; 3], threads: usize) -> f64 {
        let n = handles.len();
        for s in self.strains[..3 * n].chunks_mut(3) {
            s.copy_from_slice(&e);
        }
        let t = Instant::now();
        let s = unsafe {
            rve_update_batch(
                handles.as_ptr(),
                n,
                self.strains.as_ptr(),
                self.stresses.as_mut_ptr(),
                self.tangents.as_mut_ptr(),
                self.statuses.as_mut_ptr(),
                0,
                threads,
            )
        };
        let seconds = t.elapsed().as_secs_f64();
        assert_eq!(s, 0, "rve_update_batch: {}", last_error_message());
        assert!(self.statuses[..n].iter().all(|&s| s == 0));
        seconds
    }

    /// Commits every handle along `LOADING`.
    fn load(&mut self, handles: &[RveHandle], threads: usize) -> Vec<f64> {
        let mut seconds = Vec::new();
        for x in LOADING {
            seconds.push(self.run(handles, eps(x), threads));
            commit_all(handles);
        }
        seconds
    }
}

fn main() {
    match std::env::var("MESORVE_BENCH_PART").as_deref() {
        Ok("loading") => memory_loading(instances()),
        Ok("fast") => memory_fast(instances()),
        Ok(other) => panic!("MESORVE_BENCH_PART={other}: loading or fast"),
        Err(_) => {
            sizes();
            let load = load_average();
            overhead(200);
            batch_throughput(instances().min(2000), 7);
            println!("| machine during sections 1-2 | value |");
            println!("|---|---|");
            let after = load_average();
            println!("| load average (1 min), before / after | {load} / {after} |");
            println!();
            for part in ["loading", "fast"] {
                let exe = std::env::current_exe().unwrap();
                let status = Command::new(exe)
                    .env("MESORVE_BENCH_PART", part)
                    .status()
                    .unwrap();
                assert!(status.success(), "memory part {part}: {status}");
            }
        }
    }
}

/// The model's sizes, what the per-component figures follow from.
fn sizes() {
    let model = Model::from_scene(&Scene::from_file(SCENE).unwrap()).unwrap();
    let d = model.discretization();
    println!("| scenes/paper_rve.toml | value |");
    println!("|---|---|");
    println!("| unknowns (f64) | {} |", d.n());
    println!(
        "| interface elements x points | {} x {} = {} |",
        d.interfaces.len(),
        d.points_per_interface(),
        d.interface_points()
    );
    println!("| history values | {} |", d.history_len());
    println!(
        "| size_of::<Instance>() | {} |",
        std::mem::size_of::<Instance>()
    );
    println!("| size_of::<State>() | {} |", std::mem::size_of::<State>());
    println!();
}

/// Section 1: the same pre-peak trial through the safe API and the C ABI.
fn overhead(reps: usize) {
    let model = Arc::new(Model::from_scene(&Scene::from_file(SCENE).unwrap()).unwrap());
    let (mut inst, mut ws) = (Instance::new(model.clone()), model.workspace());
    let h = init();
    let consistent = TangentRequest::Consistent;
    for x in LOADING {
        inst.update(eps(x), &mut ws, consistent).unwrap();
        inst.commit().unwrap();
        update(h, eps(x));
        assert_eq!(rve_commit(h), 0);
    }
    let (fast_safe, fast_c) = (inst.fast_updates(), fast_count(h));
    let (mut safe, mut ffi) = (Vec::new(), Vec::new());
    for k in 0..reps {
        let e = trial_strain(k);
        let mut time_safe = || {
            let t = Instant::now();
            let r = inst.update(e, &mut ws, consistent).unwrap();
            safe.push(t.elapsed().as_secs_f64());
            assert_eq!(
                r.report.answer,
                Answer::Solved,
                "safe update {k} not solved"
            );
            r.stress
        };
        // Alternate which goes first.
        let first = (k % 2 == 0).then(&mut time_safe);
        let t = Instant::now();
        let sig = update(h, e);
        ffi.push(t.elapsed().as_secs_f64());
        let r = first.unwrap_or_else(time_safe);
        assert_eq!(
            r.map(f64::to_bits),
            sig.map(f64::to_bits),
            "safe and C differ"
        );
    }
    assert_eq!(inst.fast_updates(), fast_safe);
    assert_eq!(fast_count(h), fast_c, "a timed rve_update was not solved");
    let (ms, mf) = (median(safe), median(ffi));
    println!(
        "| trial update {LOADING:?} -> eps_xx {E_TRIAL:e} (1 + 1e-9 k), a solve each | median |"
    );
    println!("|---|---|");
    println!(
        "| safe API, Instance::update ({reps} calls) | {:.1} us |",
        1e6 * ms
    );
    println!(
        "| C ABI, rve_update ({reps} calls, alternating) | {:.1} us |",
        1e6 * mf
    );
    println!("| C ABI / safe (same run) | {:.3} |", mf / ms);
    println!("| C ABI - safe | {:.2} us |", 1e6 * (mf - ms));
    not_solves(&mut inst, &mut ws, trial_strain(reps - 1), reps);
    rve_free(h);
}

/// The rows of section 1 that time no solve: a repeated trial (what the trial figures
/// measured before every timed update had a strain of its own) and the bare boundary.
fn not_solves(inst: &mut Instance, ws: &mut rve::Workspace, e: [f64; 3], reps: usize) {
    assert!(inst.has_trial(), "the repeat needs the pending trial at e");
    let repeated: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            let r = inst.update(e, ws, TangentRequest::Consistent).unwrap();
            let s = t.elapsed().as_secs_f64();
            assert_eq!(r.report.answer, Answer::Repeated);
            s
        })
        .collect();
    println!(
        "| not a solve: the pending trial repeated (Answer::Repeated) | {:.2} us |",
        1e6 * median(repeated)
    );
    let t = Instant::now();
    for _ in 0..100_000 {
        std::hint::black_box(rve_commit(std::hint::black_box(1)));
    }
    println!(
        "| not a solve: boundary round trip (rve_commit on a bad handle, mean of 10^5) | {:.0} ns |",
        1e9 * t.elapsed().as_secs_f64() / 1e5
    );
    println!();
}

/// Section 2: `rve_update_batch` of `m` instances on 1 and 2 threads, `rounds` rounds.
fn batch_throughput(m: usize, rounds: usize) {
    let handles: Vec<RveHandle> = (0..m).map(|_| init()).collect();
    let mut b = Batch::new(m);
    b.load(&handles, 2);
    let fast = fast_total(&handles);
    let (mut one, mut two, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    for r in 0..rounds {
        // Alternate the order; every call at a strain no earlier call used.
        let order = if r % 2 == 0 { [1, 2] } else { [2, 1] };
        let mut per_second = [0.0; 3];
        for (j, threads) in order.into_iter().enumerate() {
            let seconds = b.run(&handles, trial_strain(2 * r + j), threads);
            per_second[threads] = m as f64 / seconds;
        }
        one.push(per_second[1]);
        two.push(per_second[2]);
        ratio.push(per_second[2] / per_second[1]);
    }
    assert_eq!(
        fast_total(&handles),
        fast,
        "a timed batch item was not solved"
    );
    let (m1, m2) = (median(one), median(two));
    println!("| rve_update_batch, {m} pre-peak trials per call, a solve each ({rounds} rounds) | median |");
    println!("|---|---|");
    println!(
        "| 1 thread | {m1:.0} updates/s ({:.0} us per update) |",
        1e6 / m1
    );
    println!(
        "| 2 threads | {m2:.0} updates/s ({:.0} us per update) |",
        1e6 / m2
    );
    println!(
        "| 2 threads / 1 thread, ratio of the medians | {:.2} |",
        m2 / m1
    );
    println!(
        "| 2 threads / 1 thread, median of the per-round ratios | {:.2} |",
        median(ratio)
    );
    println!();
    for h in handles {
        rve_free(h);
    }
}

/// One instance's bytes by component of its committed state (capacities, as
/// `State::bytes` counts them); `owned` is `Instance::state_bytes` (committed + trial).
fn breakdown(label: &str, s: &State, owned: usize) {
    let q = |v: &mesorve_core::state::Quantized| (v.values.capacity(), 4 * v.scales.capacity());
    let (sens, sens_scales) = q(&s.sensitivity.data);
    let (curv, curv_scales) = q(&s.curvature.data);
    let rows = [
        ("unknowns (f64)", 8 * s.unknowns.capacity()),
        ("interface history (f64)", 8 * s.history.capacity()),
        ("sensitivity values (i8, 3 per unknown)", sens),
        ("sensitivity scales (f32, 1 per 32 values)", sens_scales),
        ("path curvature values (i8)", curv),
        ("path curvature scales (f32)", curv_scales),
        (
            "fast path jumps (f32, 6 per point)",
            4 * s.linear.jumps.capacity(),
        ),
        (
            "fast path contact status (bool per point)",
            s.linear.closed.capacity(),
        ),
        (
            "held contact bits (u64 words)",
            8 * s.held_contact.capacity(),
        ),
        (
            "IMPL-EX history (f64 + u64 words)",
            8 * (s.implex.previous.capacity() + s.implex.closed.capacity()),
        ),
        ("State inline (size_of)", std::mem::size_of::<State>()),
    ];
    let listed: usize = rows.iter().map(|r| r.1).sum();
    println!("| {label}: committed state, component | bytes |");
    println!("|---|---|");
    for (name, bytes) in rows {
        println!("| {name} | {bytes} |");
    }
    if s.bytes() != listed {
        println!("| not listed above | {} |", s.bytes() - listed);
    }
    println!("| committed state (State::bytes) | {} |", s.bytes());
    println!("| trial state | {} |", owned - s.bytes());
    println!("| committed + trial (Instance::state_bytes) | {owned} |");
    println!();
}

/// Peak RSS rows of a memory part.
fn memory_rows(label: &str, n: usize, rss0: f64, rss: f64, state: usize) {
    println!("| {n} instances, {label} | value |");
    println!("|---|---|");
    println!("| peak RSS before the instances / with them | {rss0:.0} / {rss:.0} MiB |");
    println!(
        "| peak RSS of the instances | {:.0} MiB, {:.0} bytes per instance |",
        rss - rss0,
        (rss - rss0) * 1048576.0 / n as f64
    );
    println!(
        "| committed state bytes saved (rve_state_size, format {STATE_FORMAT_VERSION}) | {state} |"
    );
}

/// Part 3a: `n` instances committed along `LOADING`, then a trial at `E_TRIAL` kept.
fn memory_loading(n: usize) {
    let mut b = Batch::new(n.max(WARM_UP));
    let warm: Vec<RveHandle> = (0..WARM_UP).map(|_| init()).collect();
    b.load(&warm, 2);
    b.run(&warm, eps(E_TRIAL), 2);
    let mut handles = vec![-1; n];
    let rss0 = peak_rss_mib();
    let t = Instant::now();
    handles.iter_mut().for_each(|h| *h = init());
    let t_init = t.elapsed().as_secs_f64();
    let mut seconds = b.load(&handles, 2);
    seconds.push(b.run(&handles, eps(E_TRIAL), 2));
    assert_eq!(fast_total(&handles), 0, "an update was not solved");
    let rss = peak_rss_mib();
    memory_rows(
        "loading steady state (3 increments committed, trial kept)",
        n,
        rss0,
        rss,
        state_size(handles[0]),
    );
    println!(
        "| init of the instances (models built by this process: {}) | {t_init:.2} s |",
        rve_model_builds()
    );
    let rates: Vec<String> = seconds
        .iter()
        .map(|s| format!("{:.0}", n as f64 / s))
        .collect();
    println!(
        "| the 4 increments, rve_update_batch on 2 threads | {} updates/s |",
        rates.join(" / ")
    );
    println!();
    let model = Arc::new(Model::from_scene(&Scene::from_file(SCENE).unwrap()).unwrap());
    let (mut inst, mut ws) = (Instance::new(model.clone()), model.workspace());
    for x in LOADING.into_iter().chain([E_TRIAL]) {
        let r = inst
            .update(eps(x), &mut ws, TangentRequest::Consistent)
            .unwrap();
        assert_eq!(r.report.answer, Answer::Solved);
        if x != E_TRIAL {
            inst.commit().unwrap();
        }
    }
    breakdown("loading steady state", inst.committed(), inst.state_bytes());
}

/// The 5.2.2 cycle's strain at increment `k` (1-based): 20 increments to 2.3e-4, then
/// steps of -1.7e-5 (`scenes/paper_rve_cycle.toml`, on the same RVE).
fn cycle_strain(k: usize) -> [f64; 3] {
    if k <= 20 {
        eps(2.3e-4 * k as f64 / 20.0)
    } else {
        eps(2.3e-4 - 1.7e-5 * (k - 20) as f64)
    }
}

/// The committed state of the cycle's increment 28 (unloading, answered by the fast
/// path), as state bytes, from a handle that followed the cycle.
fn fast_state_bytes() -> Vec<u8> {
    let h = init();
    for k in 1..=28 {
        update(h, cycle_strain(k));
        assert_eq!(rve_commit(h), 0);
    }
    assert!(
        fast_count(h) >= 5,
        "the unloading was not answered by the fast path"
    );
    let mut bytes = vec![0u8; state_size(h)];
    let mut written = 0;
    let s = unsafe { rve_state_save(h, bytes.as_mut_ptr(), bytes.len(), &mut written) };
    assert_eq!((s, written), (0, bytes.len()));
    rve_free(h);
    bytes
}

/// Part 3b: `n` instances in the fast steady state: the state of the cycle's increment 28
/// loaded, a fast update to increment 29 committed, one to increment 30 kept.
fn memory_fast(n: usize) {
    let bytes = fast_state_bytes();
    let mut handles = vec![-1; n];
    let rss0 = peak_rss_mib();
    for h in handles.iter_mut() {
        *h = init();
        assert_eq!(
            unsafe { rve_state_load(*h, bytes.as_ptr(), bytes.len()) },
            0
        );
        update(*h, cycle_strain(29));
        assert_eq!(rve_commit(*h), 0);
        update(*h, cycle_strain(30));
    }
    assert_eq!(fast_total(&handles), 2 * n as u64, "an update was solved");
    let rss = peak_rss_mib();
    memory_rows(
        "fast steady state (unloading: fast update committed, another kept)",
        n,
        rss0,
        rss,
        state_size(handles[0]),
    );
    println!();
    let model = Arc::new(Model::from_scene(&Scene::from_file(SCENE).unwrap()).unwrap());
    let (mut inst, mut ws) = (Instance::new(model.clone()), model.workspace());
    inst.load_state(&bytes).unwrap();
    for k in [29, 30] {
        let r = inst
            .update(cycle_strain(k), &mut ws, TangentRequest::Consistent)
            .unwrap();
        assert_eq!(r.report.answer, Answer::FastPath);
        if k == 29 {
            inst.commit().unwrap();
        }
    }
    breakdown("fast steady state", inst.committed(), inst.state_bytes());
}
