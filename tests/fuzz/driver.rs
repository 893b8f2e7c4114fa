//! The seeded, bounded driver every fuzz family runs on (stable Rust, no fuzzing engine).
//!
//! Case `i` of a family draws its input from `arbitrary::Unstructured` over bytes of a
//! ChaCha8 stream seeded with `seed + i`, so a failing case reproduces alone with
//! `MESORVE_FUZZ_SEED=<seed + i> MESORVE_FUZZ_CASES=1`. Every case runs under
//! `catch_unwind` (a panic is a finding), a watchdog (a case that runs longer than the
//! family's limit aborts the process, naming the case) and a capped global allocator (a
//! case that holds more than `MESORVE_FUZZ_MEMORY_MIB` of heap aborts the process,
//! naming the case), so no input can hang or exhaust the machine unnoticed.
//!
//! Environment: `MESORVE_FUZZ_CASES` (cases per family, default: each family's own),
//! `MESORVE_FUZZ_SEED` (default 1), `MESORVE_FUZZ_SECONDS` (stop a family early after
//! this long; default: no limit), `MESORVE_FUZZ_MEMORY_MIB` (default 3072),
//! `MESORVE_FUZZ_SHOW` (print each case's input).

use std::alloc::{GlobalAlloc, Layout, System};
use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use arbitrary::Unstructured;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Bytes of randomness each case may draw from.
const CASE_BYTES: usize = 8192;

/// The system allocator with a cap on the live heap of the whole test process.
struct CappedAlloc;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static CAP: AtomicUsize = AtomicUsize::new(usize::MAX);
/// The cases running now, for the messages of the watchdog and the allocator.
static RUNNING: Mutex<Vec<String>> = Mutex::new(Vec::new());
static OVER_CAP: AtomicBool = AtomicBool::new(false);

unsafe impl GlobalAlloc for CappedAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let size = layout.size();
        let live = LIVE.fetch_add(size, Ordering::Relaxed) + size;
        if live > CAP.load(Ordering::Relaxed) {
            // Refuse (Rust aborts on a failed infallible allocation); report the first
            // time, without allocating.
            LIVE.fetch_sub(size, Ordering::Relaxed);
            if !OVER_CAP.swap(true, Ordering::Relaxed) {
                eprintln!(
                    "fuzz: an allocation of {size} bytes would bring the live heap to {live} \
                     bytes, over the cap of {} bytes (MESORVE_FUZZ_MEMORY_MIB); running:",
                    CAP.load(Ordering::Relaxed)
                );
                if let Ok(running) = RUNNING.try_lock() {
                    for case in running.iter() {
                        eprintln!("  {case}");
                    }
                }
            }
            return std::ptr::null_mut();
        }
        PEAK.fetch_max(live, Ordering::Relaxed);
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            LIVE.fetch_sub(size, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CappedAlloc = CappedAlloc;

fn env<T: std::str::FromStr>(name: &str) -> Option<T> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

/// Peak live heap of the process so far, MiB.
pub fn peak_heap_mib() -> f64 {
    PEAK.load(Ordering::Relaxed) as f64 / (1024.0 * 1024.0)
}

/// Prints a case's input when `MESORVE_FUZZ_SHOW` is set (to reproduce a finding).
pub fn show(what: &str, input: &str) {
    if std::env::var_os("MESORVE_FUZZ_SHOW").is_some() {
        eprintln!("---- {what}\n{input}\n----");
    }
}

/// What the cases of a family did: outcome labels with their counts.
#[derive(Default)]
pub struct Tally {
    counts: BTreeMap<String, usize>,
}

impl Tally {
    pub fn count(&mut self, label: impl Into<String>) {
        self.add(label, 1);
    }

    pub fn add(&mut self, label: impl Into<String>, n: usize) {
        *self.counts.entry(label.into()).or_default() += n;
    }
}

/// Runs `cases` cases of a family; `case` returns `Err` when a property fails. Each case
/// must end within `case_limit`. Panics (failing the test) after the run when any case
/// panicked or broke a property, listing them with their seeds.
pub fn run(
    family: &str,
    default_cases: usize,
    case_limit: Duration,
    mut case: impl FnMut(&mut Unstructured, &mut Tally) -> Result<(), String>,
) {
    let cases = env("MESORVE_FUZZ_CASES").unwrap_or(default_cases);
    let seed: u64 = env("MESORVE_FUZZ_SEED").unwrap_or(1);
    let budget = env::<f64>("MESORVE_FUZZ_SECONDS").map(Duration::from_secs_f64);
    let cap_mib: usize = env("MESORVE_FUZZ_MEMORY_MIB").unwrap_or(3072);
    CAP.store(cap_mib << 20, Ordering::Relaxed);

    // The watchdog: the running case of this family and when it started.
    let current: Arc<Mutex<Option<(u64, Instant)>>> = Arc::new(Mutex::new(None));
    let done = Arc::new(AtomicBool::new(false));
    let watchdog = {
        let (current, done, family) = (current.clone(), done.clone(), family.to_string());
        std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(50));
                let running = *current.lock().unwrap_or_else(|e| e.into_inner());
                if let Some((case_seed, start)) = running {
                    if start.elapsed() > case_limit {
                        eprintln!(
                            "fuzz {family}: case seed {case_seed} ran longer than {case_limit:?} \
                             (hang); reproduce with MESORVE_FUZZ_SEED={case_seed} \
                             MESORVE_FUZZ_CASES=1"
                        );
                        std::process::abort();
                    }
                }
            }
        })
    };

    let start = Instant::now();
    let mut tally = Tally::default();
    let mut failures = Vec::new();
    let mut slowest = (Duration::ZERO, seed);
    let mut ran = 0;
    let mut bytes = vec![0u8; CASE_BYTES];
    for i in 0..cases as u64 {
        if budget.is_some_and(|b| start.elapsed() > b) {
            break;
        }
        let case_seed = seed.wrapping_add(i);
        ChaCha8Rng::seed_from_u64(case_seed).fill_bytes(&mut bytes);
        let label = format!("{family} seed {case_seed}");
        RUNNING.lock().unwrap().push(label.clone());
        let t0 = Instant::now();
        *current.lock().unwrap() = Some((case_seed, t0));
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            let mut u = Unstructured::new(&bytes);
            case(&mut u, &mut tally)
        }));
        *current.lock().unwrap() = None;
        RUNNING.lock().unwrap().retain(|l| l != &label);
        let elapsed = t0.elapsed();
        if elapsed > slowest.0 {
            slowest = (elapsed, case_seed);
        }
        ran += 1;
        match outcome {
            Ok(Ok(())) => {}
            Ok(Err(why)) => failures.push(format!("seed {case_seed}: {why}")),
            Err(panic) => {
                let msg = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                failures.push(format!("seed {case_seed}: PANIC {msg}"));
            }
        }
    }
    done.store(true, Ordering::Relaxed);
    let _ = watchdog.join();

    let outcomes: Vec<String> = tally
        .counts
        .iter()
        .map(|(k, v)| format!("{k}: {v}"))
        .collect();
    eprintln!(
        "fuzz {family}: {ran} cases (seeds {seed}..{}), {} failures, {:.1} s, slowest case \
         {:.0} ms (seed {}), process heap peak {:.0} MiB\n  outcomes: {}",
        seed.wrapping_add(ran),
        failures.len(),
        start.elapsed().as_secs_f64(),
        slowest.0.as_secs_f64() * 1e3,
        slowest.1,
        peak_heap_mib(),
        outcomes.join(", ")
    );
    assert!(ran > 0, "fuzz {family}: no case ran");
    assert!(
        failures.is_empty(),
        "fuzz {family}: {} of {ran} cases failed:\n{}",
        failures.len(),
        failures
            .iter()
            .take(30)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
}
