"""Bench of the Python package (docs/python.md): prints two tables.

1. Python overhead: n = 10^4 points of the paper's RVE, loaded in tension and unloaded to
   half (two full solves each, committed), then updated again and again on their linear branches (unloading: the fast
   path, no solve) and with the same strain twice (a repeated trial), through
   `Points.update` and through the C ABI (`rve_update_batch_timed` of
   target/release/librve.so called once per batch with ctypes, the instances loaded with the
   same state bytes), on one thread: microseconds per point, median of the rounds. Both
   give the same arrays, and every point of the last update took the fast path.
2. Threads: full solves (each round resets the points and loads them past the ITZ's
   first opening) on 1 and on 2 threads: the median of the per-round ratios of the times.

Usage: python python/examples/bench.py [--n 10000] [--rounds 7] [--lib target/release/librve.so]
"""

import argparse
import ctypes
import pathlib
import statistics
import time

import numpy as np

import mesorve

ROOT = pathlib.Path(__file__).resolve().parents[2]


class PointReport(ctypes.Structure):
    _fields_ = [(name, ctypes.c_uint32) for name in
                ("status", "iterations", "substeps", "factorizations")] + [
        ("reliability", ctypes.c_int32), ("shared_from", ctypes.c_uint32),
        ("suggested_step_ratio", ctypes.c_double), ("error_estimate", ctypes.c_double),
        ("s_zz", ctypes.c_double)]


class CBatch:
    """n instances behind the C ABI, loaded with the states of `points`."""

    def __init__(self, lib, points):
        self.lib = ctypes.CDLL(lib)
        self.n = len(points)
        self.h = np.zeros(self.n, dtype=np.int64)
        one = ctypes.c_int64()
        for k in range(self.n):
            assert self.lib.rve_init(None, ctypes.byref(one)) == 0
            self.h[k] = one.value
            state = points.state(k)
            assert self.lib.rve_state_load(one, state, ctypes.c_size_t(len(state))) == 0
        self.sig = np.zeros((self.n, 3))
        self.D = np.zeros((self.n, 3, 3))
        self.reports = (PointReport * self.n)()
        f = self.lib.rve_update_batch_timed
        f.restype = ctypes.c_uint32
        f.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_double,
                      ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int32, ctypes.c_void_p,
                      ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t]

    def update(self, eps, threads=1):
        eps = np.ascontiguousarray(eps)
        st = self.lib.rve_update_batch_timed(
            self.h.ctypes.data, self.n, eps.ctypes.data, 0.0, self.sig.ctypes.data,
            self.D.ctypes.data, 0, ctypes.addressof(self.reports), None, 0, threads)
        assert st == 0, st
        return self.sig, self.D


def timed(f, rounds):
    out = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        f()
        out.append(time.perf_counter() - t0)
    return out


def overhead(args):
    model = mesorve.Model()
    n = args.n
    points = model.points(n, threads=0)
    rng = np.random.default_rng(1)
    eps = np.outer(rng.uniform(0.5, 1.0, n), [1.2e-4, 0.0, 0.0])
    t0 = time.perf_counter()
    for scale in (1.0, 0.5):  # loaded, then unloaded: every ITZ point on a linear branch
        points.update(scale * eps)
        points.commit()
    print(f"setup: {2 * n} full solves in {time.perf_counter() - t0:.1f} s (all threads)")
    points.threads = 1
    c = CBatch(args.lib, points)
    fast = [0.4 * eps, 0.3 * eps]
    rows = []
    for what, call in (("Points.update", points.update), ("C ABI (ctypes)", c.update)):
        k = [0]

        def fast_update():
            call(fast[k[0] % 2])
            k[0] += 1

        t_fast = timed(fast_update, args.rounds)
        call(fast[0])
        t_rep = timed(lambda: call(fast[0]), args.rounds)
        rows.append((what, 1e6 * statistics.median(t_fast) / n, 1e6 * statistics.median(t_rep) / n))
    sig_py, D_py = points.update(0.2 * eps)
    sig_c, D_c = c.update(0.2 * eps)
    assert np.array_equal(sig_py, sig_c) and np.array_equal(D_py, D_c)
    assert np.all(points.report()["fast"])
    print(f"\nPython overhead: n = {n}, 1 thread, microseconds per point (median of {args.rounds} rounds)")
    print(f"| through | fast path | repeated trial |\n|---|---|---|")
    for what, f, r in rows:
        print(f"| {what} | {f:.3f} | {r:.3f} |")
    print(f"| difference | {rows[0][1] - rows[1][1]:+.3f} | {rows[0][2] - rows[1][2]:+.3f} |")


def threads(args):
    model = mesorve.Model()
    n = args.solves
    eps = np.outer(np.linspace(0.8, 1.2, n), [1.5e-4, -3e-5, 2e-5])
    sets = {t: model.points(n, threads=t) for t in (1, 2)}
    times = {1: [], 2: []}
    for _ in range(args.rounds):
        for t, p in sets.items():
            p.reset()
            t0 = time.perf_counter()
            p.update(eps)
            times[t].append(time.perf_counter() - t0)
    ratios = [a / b for a, b in zip(times[1], times[2])]
    print(f"\nThreads: {n} full solves per round, {args.rounds} rounds")
    print("| threads | median seconds per round | ms per point |\n|---|---|---|")
    for t in (1, 2):
        m = statistics.median(times[t])
        print(f"| {t} | {m:.3f} | {1e3 * m / n:.2f} |")
    print(f"| speed-up 2 vs 1 (median of per-round ratios) | {statistics.median(ratios):.2f} | |")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=10_000)
    p.add_argument("--solves", type=int, default=64)
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--lib", default=str(ROOT / "target" / "release" / "librve.so"))
    args = p.parse_args()
    overhead(args)
    threads(args)


if __name__ == "__main__":
    main()
