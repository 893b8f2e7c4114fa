#!/usr/bin/env python3
"""The step control (`solver.step_tolerance`, `solver.smallest_step`) in the hosts, against
uniform refinement: the tension's peak, the force at its end, its work and the mean
distance of its curve from a uniformly refined reference, with the cost of each run.
docs/step_control.md quotes its tables; studies/step-control/run keeps them in
target/studies/step-control/.

  step_control_study.py localize [--quick]
      c_examples/localize.c (scripts/build-c-examples first) on the plain IMPL-EX scene at
      1x, 8x, 16x and 32x (the reference) its steps, and on the step-control scene with
      several (tolerance, floor) pairs (scene files by kit.rve.write_scene). Cost: RVE
      factorizations (a count) and the time in rve_update. --quick: 1x, 8x and the shipped
      control scene against 16x.

  step_control_study.py calculix DECK [--reference N]
      CalculiX (the kit's runner: scripts/build-calculix, target/release/librve.so) on a
      shipped cycle deck (calculix_examples/specimen_weak.inp, specimen_notch.inp): the
      deck as it is, the
      deck with concrete_implex.toml plus step_tolerance = 0.01 and smallest_step = 1/16
      of the tension's increment, and the deck at 16x and N x (default 64, the reference)
      its increments. Cost: wall time, increments and cut-backs.

Each run's curve is compared with the reference's over the tension: the peak, the last
force, the trapezoidal work, and the mean over the reference's points of
|F_run(U) - F_ref(U)| (the run's curve interpolated linearly) over the reference's peak.
Runs one at a time; needs python3 only (standard library).
"""
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
from calculix_report import curve, phases  # noqa: E402
from kit import ccx as kit_ccx  # noqa: E402
from kit.rve import write_scene  # noqa: E402

LOCALIZE = ROOT / "target/c_examples/bin/localize"
PLAIN_SCENE = ROOT / "scenes/paper_rve_host_implex.toml"
CONTROL_SCENE = ROOT / "scenes/paper_rve_host_step_control.toml"
# (tolerance, floor as a fraction of the tension's step) of the localize study.
LOCALIZE_CONTROLS = [(0.01, 1 / 1024), (0.01, 1 / 16), (0.02, 1 / 16), (0.02, 1 / 12), (0.03, 1 / 8)]
LOCALIZE_STEP = 4e-4  # localize.c's tension |dU| per step (mm), its time increment


def interpolate(u_run, f_run, u):
    for i in range(1, len(u_run)):
        if u_run[i] >= u:
            w = (u - u_run[i - 1]) / (u_run[i] - u_run[i - 1]) if u_run[i] > u_run[i - 1] else 1.0
            return f_run[i - 1] + w * (f_run[i] - f_run[i - 1])
    return f_run[-1]


def work(u, f):
    return sum((u[i] - u[i - 1]) * (f[i] + f[i - 1]) / 2 for i in range(1, len(u)))


def errors(run, reference):
    """(peak, end, work, distance) of a tension curve (U, F lists from 0) against the
    reference's, in % of the reference's."""
    (u, f), (ur, fr) = run, reference
    peak = max(fr)
    distance = sum(abs(interpolate(u, f, x) - y) for x, y in zip(ur, fr)) / len(ur) / peak
    return (100 * (max(f) / peak - 1), 100 * (f[-1] / fr[-1] - 1),
            100 * (work(u, f) / work(ur, fr) - 1), 100 * distance)


def localize_tension(text):
    """The tension rows (U, F) of localize's output, from the origin."""
    u, f = [0.0], [0.0]
    for line in text.splitlines():
        w = line.split()
        if len(w) > 4 and w[0] == "tension" and w[1].isdigit() and "e" in w[2]:
            u.append(float(w[2]))
            f.append(float(w[3]))
    return u, f


def localize(scene, scale=1):
    """(tension curve, tension steps, factorizations, rve_update seconds) of one run."""
    out = subprocess.run([str(LOCALIZE), str(scene), str(scale)], capture_output=True,
                         text=True, check=True).stdout
    total = next(line.split() for line in out.splitlines() if line.startswith("all "))
    seconds = float(re.search(r"time in rve_update: ([0-9.]+) s", out).group(1))
    tension = localize_tension(out)
    return tension, len(tension[0]) - 1, int(total[5].split("/")[0]), seconds


def control_scene(directory, tolerance, floor):
    """The step-control scene with `solver.step_tolerance` and `solver.smallest_step` set
    (the floor as 6 significant digits), as a file: localize.c reads a scene file."""
    path = Path(directory) / f"control_{tolerance}_{floor:.3g}.toml"
    write_scene(CONTROL_SCENE, path, {"solver.step_tolerance": float(tolerance),
                                      "solver.smallest_step": float(f"{floor:.6g}")})
    return path


def localize_study(quick):
    scales = [1, 8] if quick else [1, 8, 16]
    runs = [(f"IMPL-EX, {s}x the steps", PLAIN_SCENE, s) for s in scales]
    with tempfile.TemporaryDirectory() as tmp:
        controls = [(0.01, 1 / 16)] if quick else LOCALIZE_CONTROLS
        for tol, fraction in controls:
            scene = control_scene(tmp, tol, LOCALIZE_STEP * fraction)
            runs.append((f"step_tolerance {tol}, floor 1/{round(1 / fraction)}", scene, 1))
        reference_scale = 16 if quick else 32
        reference = localize(PLAIN_SCENE, reference_scale)
        results = [(label, localize(scene, s)) for label, scene, s in runs]
    plain = results[0][1]
    print(f"localize.c, tension against IMPL-EX at {reference_scale}x its steps "
          f"(peak {max(reference[0][1]):.2f} N, {reference[2]} factorizations)\n")
    print("| run | tension steps | factorizations | of the plain run's | time in rve_update (s) "
          "| of the plain run's | peak % | end % | work % | distance % |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, (tension, steps, factorizations, seconds) in results:
        e = errors(tension, reference[0])
        print(f"| {label} | {steps} | {factorizations} | {factorizations / plain[2]:.1f} | "
              f"{seconds:.2f} | {seconds / plain[3]:.1f} | "
              + " | ".join(f"{x:+.2f}" for x in e[:3]) + f" | {e[3]:.2f} |")


def scaled_deck(text, scale):
    """The deck with every *STATIC line's increments `scale` times finer and fixed."""
    def fine(m):
        initial = float(m.group(1)) / scale
        return f"*STATIC\n{initial:.8g}, {m.group(2)}, {initial / 100:.3g}, {initial:.8g}"
    text = re.sub(r"(?m)^\*STATIC\n([0-9.e-]+), ([0-9.]+), [0-9.e-]+, [0-9.e-]+$", fine, text)
    return re.sub(r"(?m)^\*STEP, INC=\d+", "*STEP, INC=100000", text)


def ccx_run(directory, job, deck, scene_edits, ccx):
    """(tension curve, increments, cut-backs, wall seconds, finished) of one ccx run, in its
    own folder with concrete_implex.toml (with `scene_edits`) and the library staged."""
    d = Path(directory) / job
    d.mkdir()
    (d / f"{job}.inp").write_text(deck)
    scene = ROOT / "calculix_examples/concrete_implex.toml"
    if scene_edits:
        write_scene(scene, d / "concrete_implex.toml", scene_edits)
    else:
        shutil.copy(scene, d / "concrete_implex.toml")
    kit_ccx.stage(str(d))
    run = kit_ccx.run(job, str(d), ccx, scenes=str(d), threads=1,
                      env={"CCX_NPROC_RESULTS": "2"}, check=False)
    tension = phases(curve(str(d / job)))[0]
    u, f = [0.0] + [p[1] for p in tension], [0.0] + [p[2] for p in tension]
    increments = len(curve(str(d / job)))
    cuts = run.log().count("increment size decrease requested by a material user routine")
    return (u, f), increments, cuts, run.wall, run.finished


def calculix_study(deck_path, reference_scale):
    ccx = kit_ccx.binary()
    deck = Path(deck_path).read_text()
    first = float(re.search(r"(?m)^\*STATIC\n([0-9.e-]+),", deck).group(1))
    controlled = {"solver.step_tolerance": 0.01, "solver.smallest_step": float(f"{first / 16:.6g}")}
    with tempfile.TemporaryDirectory() as tmp:
        runs = [("the deck's increments", "plain", deck, None),
                ("step_tolerance 0.01, floor 1/16", "control", deck, controlled),
                ("16x the increments", "fine16", scaled_deck(deck, 16), None)]
        results = [(label, ccx_run(tmp, job, d, s, ccx)) for label, job, d, s in runs]
        reference = ccx_run(tmp, "reference", scaled_deck(deck, reference_scale), None, ccx)
    plain_seconds = results[0][1][3]
    print(f"{Path(deck_path).name}, tension against {reference_scale}x its increments "
          f"(peak {max(reference[0][1]):.2f} N, {reference[3]:.0f} s)\n")
    print("| run | finished | increments | cut-backs | wall (s) | of the plain run's "
          "| peak % | end % | work % | distance % |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, (tension, increments, cuts, seconds, finished) in results:
        e = errors(tension, reference[0])
        print(f"| {label} | {'yes' if finished else 'no'} | {increments} | {cuts} | {seconds:.1f} "
              f"| {seconds / plain_seconds:.1f} | "
              + " | ".join(f"{x:+.2f}" for x in e[:3]) + f" | {e[3]:.2f} |")


def main(argv):
    if len(argv) >= 1 and argv[0] == "localize":
        localize_study("--quick" in argv)
    elif len(argv) >= 2 and argv[0] == "calculix":
        scale = int(argv[argv.index("--reference") + 1]) if "--reference" in argv else 64
        calculix_study(argv[1], scale)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
