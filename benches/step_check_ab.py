"""The implicit step check's cost against a build before it, alternated in one run.

Usage: python3 benches/step_check_ab.py BASE_RVE NEW_RVE [REPEATS]   (default 5)

BASE_RVE is `rve` built at 2c6f5e9 (before the step check: `git worktree add /tmp/base
2c6f5e9 && cd /tmp/base && cargo build --release --bin rve`), NEW_RVE this tree's
(`cargo build --release --bin rve`). Each repeat runs every path with BASE, then with NEW,
the order alternating from one repeat to the next, so that both see the same machine.
Per path and binary: the factorizations of the solve and of the check (response.csv's
`factorizations` and `check_factorizations`; counts, the same on every machine), the
increments flagged (`step_too_large`), and the median over the repeats of the solver's
own time (the sum of the `seconds` column) and of the mean update; then NEW / BASE.

The paths: the fine RVE's §5.2.1 path (scenes/paper_rve_fine.toml, 20 increments) and
three of studies/robustness/run's (the circles and the ellipses in tension along x at 16
increments, the §5.2.2 cycle at 60), the paper's contact law. Standard library only.
"""

import csv
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def line(to, n):
    return f"[[path]]\nto = [{to:e}, 0.0, 0.0]\nincrements = {n}\n"


CYCLE = "[[path]]\nto = [2.3e-4, 0.0, 0.0]\nincrements = 20\n\n[[path]]\nto = [-4.5e-4, 0.0, 0.0]\nincrements = 40\n"
PATHS = [
    ("fine RVE, 5.2.1 (20 increments)", "scenes/paper_rve_fine.toml", None),
    ("circles, tension x, 16 increments", "scenes/paper_rve.toml", line(2.6e-4, 16)),
    ("ellipses, tension x, 16 increments", "scenes/paper_rve_ellipses.toml", line(2.6e-4, 16)),
    ("cycle 5.2.2, 60 increments", "scenes/paper_rve_cycle.toml", CYCLE),
]


def scene(work, k, src, path):
    text = open(os.path.join(ROOT, src)).read()
    if path is not None:
        text = text[: text.index("[[path]]")] + path
    name = os.path.join(work, f"path{k}.toml")
    with open(name, "w") as f:
        f.write(text)
    return name


def run(rve, toml, out):
    subprocess.run([rve, "run", toml, "--out", out, "--quiet"], check=True, cwd=ROOT)
    rows = list(csv.DictReader(open(os.path.join(out, "response.csv"))))
    count = lambda key: sum(int(r.get(key, 0)) for r in rows)
    seconds = sum(float(r["seconds"]) for r in rows)
    return count("factorizations"), count("check_factorizations"), count("step_too_large"), seconds, len(rows)


def main():
    base, new = sys.argv[1], sys.argv[2]
    repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 5
    with tempfile.TemporaryDirectory() as work:
        tomls = [scene(work, k, src, p) for k, (_, src, p) in enumerate(PATHS)]
        got = {}
        for rep in range(repeats):
            order = [("base", base), ("new", new)]
            for tag, rve in order if rep % 2 == 0 else order[::-1]:
                for k, toml in enumerate(tomls):
                    r = run(rve, toml, os.path.join(work, f"{tag}{k}"))
                    got.setdefault((tag, k), []).append(r)
    print("| path | build | factorizations (solve + check) | flagged | solver time, median | mean update |")
    print("|---|---|---|---|---|---|")
    for k, (label, _, _) in enumerate(PATHS):
        med = {}
        for tag in ("base", "new"):
            runs = got[(tag, k)]
            f, c, flagged, _, n = runs[0]
            t = statistics.median(r[3] for r in runs)
            med[tag] = (f + c, t)
            print(f"| {label} | {tag} | {f} + {c} | {flagged} | {t:.3f} s | {1e3 * t / n:.1f} ms |")
        print(f"| {label} | new / base | {med['new'][0] / med['base'][0]:.2f} | | "
              f"{med['new'][1] / med['base'][1]:.2f} | |")


main()
