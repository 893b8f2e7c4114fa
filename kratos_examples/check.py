#!/usr/bin/env python3
"""Checks the Kratos runs of scripts/test-kratos (steps.json of run.py) and prints the
figures docs/kratos.md quotes. Every check can fail; the exit status says whether all
passed.

  check.py homogeneous STEPS.json RESPONSE.csv
      every point of every step equal (to 1e-12 of the stress: Kratos's strains differ by
      round-off between points), and each step's stress within 1e-5 (relative to the
      peak stress) of `rve run` on Kratos's strains up to the peak (rve run's largest
      sigma_xx), 1e-3 after
  check.py same STEPS_A.json STEPS_B.json
      the two runs' stresses equal bit for bit (2 threads against 1)
  check.py uniaxial STEPS.json MAX_ITERATIONS
      Newton's iterations per step at most MAX_ITERATIONS, no step cut, every point
      equal to 1e-6, sigma_yy below 1e-6 of sigma_xx (uniaxial stress)
  check.py cut STEPS.json RESPONSE.csv
      at least one step cut (Kratos halved it after NaN in the stress), the run reached
      time 1, and its last stress within 1e-3 of `rve run` on Kratos's strains
  check.py path STEPS.json SCENE OUT_SCENE
      writes OUT_SCENE: SCENE with a [[path]] of one increment per Kratos step (its
      first point's strain [xx, yy, xy]), for `rve run`
"""
import csv
import json
import sys


def load(path):
    with open(path) as f:
        return json.load(f)


def rve_stresses(csv_path):
    with open(csv_path) as f:
        return [[float(r["sig_xx"]), float(r["sig_yy"]), float(r["sig_xy"])]
                for r in csv.DictReader(f)]


def plane(v):
    """Kratos's [xx, yy, zz, xy] as the RVE's [xx, yy, xy]."""
    return [v[0], v[1], v[3]]


def check(ok, what, failures):
    print(("ok     " if ok else "FAILED ") + what)
    if not ok:
        failures.append(what)


def spread(step):
    first = step["points"][0]["stress"]
    return max(abs(a - b) for p in step["points"] for a, b in zip(p["stress"], first))


def homogeneous(steps, response, failures):
    rve = rve_stresses(response)
    peak = 1 + max(range(len(rve)), key=lambda k: rve[k][0])
    check(len(rve) == len(steps), f"{len(steps)} Kratos steps, {len(rve)} rve run rows", failures)
    scale = max(abs(s[0]) for s in rve)
    worst = [0.0, 0.0]
    for k, (step, r) in enumerate(zip(steps, rve)):
        check(spread(step) <= 1e-12 * scale, f"step {k + 1}: every point equal "
              f"(spread {spread(step):.1e})", failures)
        d = max(abs(a - b) for a, b in zip(plane(step["points"][0]["stress"]), r)) / scale
        after = k + 1 > peak
        worst[after] = max(worst[after], d)
        limit = 1e-3 if after else 1e-5
        check(d <= limit, f"step {k + 1} ({'after' if after else 'up to'} the peak): "
              f"{d:.2e} of the peak stress from rve run (limit {limit:g})", failures)
    print(f"homogeneous: largest difference from rve run {worst[0]:.2e} up to the peak "
          f"(step {peak}), {worst[1]:.2e} after, relative to the peak stress {scale:.4f}")


def same(a, b, failures):
    sa = [[p["stress"] for p in s["points"]] for s in a]
    sb = [[p["stress"] for p in s["points"]] for s in b]
    check(sa == sb, f"2 threads = 1 thread, bit for bit ({len(sa)} steps)", failures)


def uniaxial(steps, most, failures):
    its = [s["iterations"] for s in steps]
    print(f"uniaxial: Newton iterations per step {its}")
    check(max(its) <= most, f"at most {most} Newton iterations per step", failures)
    check(all(s["cycles"] == 1 for s in steps), "no step cut", failures)
    for k, s in enumerate(steps):
        sxx = s["points"][0]["stress"][0]
        syy = max(abs(p["stress"][1]) for p in s["points"])
        check(spread(s) <= 1e-6 * abs(sxx) and syy <= 1e-6 * abs(sxx),
              f"step {k + 1}: homogeneous uniaxial stress (sigma_xx {sxx:.4f}, "
              f"spread {spread(s):.1e}, |sigma_yy| {syy:.1e})", failures)


def cut(steps, response, failures):
    cycles = [s["cycles"] for s in steps]
    print(f"cut: cycles per converged step {cycles}, times "
          f"{[round(s['time'], 5) for s in steps]}")
    check(max(cycles) > 1, "Kratos cut at least one step", failures)
    check(abs(steps[-1]["time"] - 1.0) < 1e-9, "the run reached the end", failures)
    rve = rve_stresses(response)
    scale = max(abs(s[0]) for s in rve)
    d = max(abs(a - b) for a, b in zip(plane(steps[-1]["points"][0]["stress"]), rve[-1]))
    check(d <= 1e-3 * scale, f"last stress {d / scale:.2e} of the peak from rve run", failures)


def path(steps, scene, out):
    with open(scene) as f:
        text = f.read()
    lines = [text.rstrip(), ""]
    for s in steps:
        e = plane(s["points"][0]["strain"])
        lines += ["[[path]]", f"to = [{e[0]!r}, {e[1]!r}, {e[2]!r}]", "increments = 1", ""]
    with open(out, "w") as f:
        f.write("\n".join(lines))


def main():
    mode, args, failures = sys.argv[1], sys.argv[2:], []
    if mode == "path":
        path(load(args[0]), args[1], args[2])
        return
    if mode == "homogeneous":
        homogeneous(load(args[0]), args[1], failures)
    elif mode == "same":
        same(load(args[0]), load(args[1]), failures)
    elif mode == "uniaxial":
        uniaxial(load(args[0]), int(args[1]), failures)
    elif mode == "cut":
        cut(load(args[0]), args[1], failures)
    if failures:
        sys.exit(f"{len(failures)} check(s) failed")


if __name__ == "__main__":
    main()
