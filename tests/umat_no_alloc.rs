//! A `STATEV`-mode UMAT call allocates nothing, once warm: one point of
//! `scenes/paper_rve_host_implex.toml` follows the paper's cycle as CalculiX calls it (two
//! calls per increment from the start-of-increment values, at 99 % of the step and at its
//! end, the last call's values kept; then the end call again, a repeat), and as Kratos
//! calls it (no `PNEWDT`, every point 0). After a few increments of warm-up (the
//! workspace, the thread's buffers and the point grow to their sizes), every call is
//! counted with the counting allocator of `tests/no_alloc.rs`: the host's point is found,
//! its material known, its `STATEV` checked, the IMPL-EX update made (the second call and
//! the repeat without a factorization) and the trial encoded without a heap allocation.
//! The same cycle with a short `NSTATV` (table mode) allocates nothing either.

mod common;
#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::count_allocations;
use rve::host::{HostSignal, SearchPath, Umat, UmatOutputs};

const CMNAME: &str = "PAPER_RVE_HOST_IMPLEX";
/// Increments before the counting starts.
const WARM_UP: usize = 4;

/// One call of a host that hears by `signal` at increment `k` from `statev` (the values
/// kept at its start) to `strain`; the values written stay in `written`. Returns the
/// allocations the call made.
fn counted_call(
    (umat, signal): (&Umat, HostSignal),
    k: usize,
    (start, strain): ([f64; 3], [f64; 3]),
    statev: &[f64],
    written: &mut [f64],
) -> usize {
    let dstran: [f64; 3] = std::array::from_fn(|c| strain[c] - start[c]);
    let (mut stress, mut ddsdde, mut pnewdt) = ([0.0; 3], [0.0; 9], 1e36);
    written.copy_from_slice(statev);
    let mut c = common::cycle_call(CMNAME, &[], &start, &dstran, 1, k);
    if signal == HostSignal::NanStress {
        (c.noel, c.npt, pnewdt) = (0, 0, 0.0);
    }
    let mut out = UmatOutputs {
        stress: &mut stress,
        ddsdde: &mut ddsdde,
        statev: written,
        pnewdt: &mut pnewdt,
    };
    let mut answered = false;
    let n = count_allocations(|| answered = umat.call_as(&c, &mut out, signal).is_ok());
    assert!(answered, "increment {}: the call failed", k + 1);
    n
}

/// Follows the cycle with calls of a host that hears by `signal`, with `STATEV` room for
/// the state (else 5 entries: table mode); the allocations of each increment's calls
/// after the warm-up: (increment, first, second, repeat).
fn cycle(signal: HostSignal, statev_mode: bool) -> Vec<(usize, usize, usize, usize)> {
    let path = rve::scene::path_points(&common::scene("scenes/paper_rve_cycle.toml").spec.path);
    let model =
        rve::model::cache::model_for_file(&common::repo("scenes/paper_rve_host_implex.toml"))
            .unwrap();
    let umat = Umat::new(SearchPath::new([common::repo("scenes")]));
    let n = if statev_mode { model.statev_len() } else { 0 };
    let mut statev = vec![0.0; n + 5];
    let mut written = statev.clone();
    let mut allocations = Vec::new();
    for (k, &end) in path.iter().enumerate() {
        let start = if k == 0 { [0.0; 3] } else { path[k - 1] };
        let near = std::array::from_fn(|c| start[c] + 0.99 * (end[c] - start[c]));
        let host = (&umat, signal);
        let first = counted_call(host, k, (start, near), &statev, &mut written);
        let second = counted_call(host, k, (start, end), &statev, &mut written);
        let repeat = counted_call(host, k, (start, end), &statev, &mut written);
        statev.copy_from_slice(&written);
        if k >= WARM_UP {
            allocations.push((k + 1, first, second, repeat));
        }
    }
    let stats = umat.stats();
    assert_eq!(stats.repeats, path.len() as u64, "{stats:?}");
    allocations
}

#[test]
fn a_warm_umat_call_does_not_allocate_in_either_mode_or_host_style() {
    let hosts = [
        (HostSignal::Pnewdt, true),
        (HostSignal::NanStress, true),
        (HostSignal::Pnewdt, false),
    ];
    for (signal, statev_mode) in hosts {
        let allocations = cycle(signal, statev_mode);
        let host = format!("{signal:?}, STATEV mode {statev_mode}");
        println!("{host}: (increment, first call, second call, repeat): {allocations:?}");
        assert!(allocations.len() >= 50, "{host}: {allocations:?}");
        for &(k, first, second, repeat) in &allocations {
            assert_eq!(
                (first, second, repeat),
                (0, 0, 0),
                "{host}, increment {k}: allocations of the first call, the second and the \
                 repeat"
            );
        }
    }
}
