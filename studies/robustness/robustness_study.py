"""Robustness and cost past the peak: `rve run` on a sample of strain paths through the
limit point, written to OUT.md (studies/robustness/run: target/studies/robustness/
robustness.md, copied to docs/robustness.md with --docs).

Usage: python3 studies/robustness/robustness_study.py RVE OUT.md [--keep DIR]

The sample (every run is a variant of a shipped scene, made in a temporary directory):
  - tension: `paper_rve.toml` and `paper_rve_ellipses.toml`, eps_xx and eps_yy each taken
    to 2.6e-4 in N equal increments, N = 16, 20, ..., 48, 56, 64 (11 values);
  - uniaxial stress: `paper_rve.toml` along eps = t [1, -0.1935, -3.6e-4] (the Poisson
    contraction of a uniaxial stress) to t = 2.6e-4, same N;
  - linear BC: `paper/rve_linear.toml` along eps_xx, same N;
  - fine mesh: `paper_rve_fine.toml` along eps_xx, N = 20 and 40;
  - cycle: `paper_rve_cycle.toml` (section 5.2.2) with the increments of both its
    segments multiplied by 1/2, 3/4, 1, 3/2, 2;
each with three contact laws: the paper's (`contact_shear = "penalty"`) with its contact
status held within a Newton iteration (`solver.contact_status = "active_set"`, the
default), the paper's read at every evaluation (`"per_iteration"`, the behaviour before
the active set), and `contact_shear = "cohesive"`.

What is counted, per run: whether it reaches the end of its path (a failed run keeps the
increments before the failure), the increments that took more than 4 Newton iterations,
the iterations and factorizations summed over the path, the increment with the most
iterations, the snap-back increments (those whose traced path shows limit points), and
the solver's own time (`seconds` column of response.csv). Times are single runs on
whatever machine this runs on: compare them only within one document.

Differences: on every path where the per-iteration run completes, the largest difference
of the active-set run's stress and consistent tangent, over the increments, relative to
the largest stress and tangent entry of the per-iteration run.

Standard library only.
"""

import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from kit import provenance, rve  # noqa: E402

RVE, MD = sys.argv[1:3]
KEEP = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == "--keep" else None
NS = [16, 20, 24, 28, 32, 36, 40, 44, 48, 56, 64]
FINE_NS = [20, 40]
CYCLE_FACTORS = [0.5, 0.75, 1.0, 1.5, 2.0]
# contact law -> scene keys it sets
LAWS = {
    "paper": {},
    "paper, per iteration": {"solver.contact_status": "per_iteration"},
    "cohesive": {"materials.itz.contact_shear": "cohesive"},
}
STRESS = ["sig_xx", "sig_yy", "sig_xy"]
TANGENT = [f"D{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]


def line_path(to, n):
    # The targets as written with 7 significant digits (the sample's definition).
    return rve.line_path([float(f"{v:e}") for v in to], n)


def cycle_path(factor):
    # paper_rve_cycle.toml: to 2.3e-4 in 20, then to -4.5e-4 in 40.
    a, b = round(20 * factor), round(40 * factor)
    return [{"to": [2.3e-4, 0.0, 0.0], "increments": a}, {"to": [-4.5e-4, 0.0, 0.0], "increments": b}]


def sample():
    """(group, label, source scene, law, path (`[[path]]` tables), increments) of every run."""
    t = 2.6e-4
    groups = [
        ("tension circles x", "scenes/paper_rve.toml", (t, 0.0, 0.0), NS),
        ("tension circles y", "scenes/paper_rve.toml", (0.0, t, 0.0), NS),
        ("tension ellipses x", "scenes/paper_rve_ellipses.toml", (t, 0.0, 0.0), NS),
        ("tension ellipses y", "scenes/paper_rve_ellipses.toml", (0.0, t, 0.0), NS),
        ("uniaxial stress circles", "scenes/paper_rve.toml", (t, -0.1935 * t, -3.6e-4 * t), NS),
        ("tension circles x, linear BC", "scenes/paper/rve_linear.toml", (t, 0.0, 0.0), NS),
        ("tension fine x", "scenes/paper_rve_fine.toml", (t, 0.0, 0.0), FINE_NS),
    ]
    runs = []
    for group, scene, to, ns in groups:
        for n in ns:
            for law in LAWS:
                runs.append((group, f"N = {n}", scene, law, line_path(to, n), n))
    for factor in CYCLE_FACTORS:
        for law in LAWS:
            n = round(20 * factor) + round(40 * factor)
            runs.append(("cycle", f"{n} increments", "scenes/paper_rve_cycle.toml", law, cycle_path(factor), n))
    return runs


class Result:
    def __init__(self, run, total):
        self.rows = rows = run.rows
        self.ok, self.status, self.wall, self.total = run.ok, run.status, run.wall, total
        self.done = len(rows)
        its = [int(r["iterations"]) for r in rows]
        self.iterations = sum(its)
        self.factorizations = sum(int(r["factorizations"]) for r in rows)
        self.seconds = sum(float(r["seconds"]) for r in rows)
        self.slow = sum(1 for i in its if i > 4)
        self.worst = max(its) if its else 0
        self.worst_seconds = max((float(r["seconds"]) for r in rows), default=0.0)
        # Factorizations of the increments that passed a snap-back.
        self.snap_factorizations = [int(r["factorizations"]) for r in rows if int(r["limit_points"]) > 0]
        # The first increment after the first drop of |stress| (the peak, or in the cycle
        # the start of unloading if that comes first).
        norms = [sum(float(r[c]) ** 2 for c in STRESS) ** 0.5 for r in rows]
        self.past_peak = next((k + 1 for k in range(len(norms) - 1) if norms[k + 1] < norms[k]), len(rows))
        # Increments ending with interface points held against their gap.
        self.held = sum(1 for r in rows if int(r["held_points"]) > 0)
        # Increments answered without a solve (the fast path, `fast` column).
        self.fast = sum(int(r.get("fast", "0")) for r in rows)


def run_all(work):
    results = []
    for k, (group, label, src, law, path, n) in enumerate(sample()):
        name = f"run{k:03d}"
        edits = dict(LAWS[law], path=path)
        res = Result(rve.run_rve(src, os.path.join(work, name), rve=RVE, edits=edits), n)
        results.append((group, label, law, res))
        verdict = "ok" if res.ok else f"fails at increment {res.done + 1}"
        print(f"{group:30} {label:16} {law:22} {res.wall:6.2f} s  {verdict}", flush=True)
    return results


def ms(x):
    return f"{1e3 * x:.1f}"


def largest_difference(a, b, columns, increments):
    """max |a - b| over `increments` (indices) and `columns`, over max |b| on the path."""
    scale = max(abs(float(r[c])) for r in b.rows for c in columns)
    diff = max((abs(float(a.rows[k][c]) - float(b.rows[k][c])) for k in increments for c in columns),
               default=0.0)
    return diff / scale if scale > 0 else diff


class Difference:
    """Active set against per iteration on one path: up to the peak (the last increment
    before the first drop of |stress| in either run) and after it."""

    def __init__(self, group, label, new, ref):
        self.group, self.label, self.fails = group, label, not new.ok
        if self.fails:
            return
        peak = min(new.past_peak, ref.past_peak)
        before, after = range(peak), range(peak, len(ref.rows))
        self.before = (largest_difference(new, ref, STRESS, before), largest_difference(new, ref, TANGENT, before))
        self.after = (largest_difference(new, ref, STRESS, after), largest_difference(new, ref, TANGENT, after))
        self.peak = peak if peak < len(ref.rows) else None
        self.held = new.held

    def worst(self):
        return max(self.before + self.after)


def differences(results):
    """A `Difference` per path where the per-iteration run completes."""
    by_key = {(g, label, law): r for g, label, law, r in results}
    return [Difference(g, label, by_key[(g, label, "paper")], ref)
            for (g, label, law), ref in by_key.items() if law == "paper, per iteration" and ref.ok]


def intro(w, record):
    """The title, the provenance and what the tables count."""
    w("# Robustness and cost past the peak\n")
    w(provenance.sentence(record) + "\n")
    w("Generated by `studies/robustness/run`; do not edit by hand. Every run is `rve run` on a")
    w("variant of a shipped scene (see the script's header for the sample). A run *fails* when")
    w("an increment exhausts every remedy (sub-steps, path following, secant iterations) and")
    w("`rve run` stops with the solver's error. *Slow* increments took more than 4 Newton")
    w("iterations; *snap-back* increments are those whose traced path shows limit points of the")
    w("strain. Times are the solver's own (`seconds` column), single runs. Contact laws: *paper*,")
    w("the paper's law (`contact_shear = \"penalty\"`) with its contact status held within a")
    w("Newton iteration (`solver.contact_status = \"active_set\"`, the default, see")
    w("`docs/contact-algorithm.md`); *paper, per iteration*, the same law with the status read")
    w("at every evaluation (the behaviour before the active set); *cohesive*,")
    w("`contact_shear = \"cohesive\"`. *Answered by the fast path*: increments whose every ITZ")
    w("point stayed on the linear branch of the last full solve (unloading, contact), answered")
    w("as `D_b eps` without Newton (`solver.fast_path`, `docs/fast_path.md`).\n")
    w("The other half of robustness, bad input and long runs (fuzzed scenes, Gmsh files, call")
    w("sequences and checkpoints, the checksummed state format, the threaded soak with its")
    w("memory and replay checks, sanitizers and valgrind), is measured in")
    w("`docs/reliability.md`. Cost candidates for the snap-back increments that were measured")
    w("and not kept are in `CHANGELOG.md` (0.3.0, \"Measured and not kept\").\n")


def group_names(results):
    groups = []
    for g, _, _, _ in results:
        if g not in groups:
            groups.append(g)
    return groups


def summary(w, results):
    """Per contact law and group: outcomes, iterations, factorizations and times."""
    w("## Summary\n")
    w("| group | contact law | runs | completed | failed | slow increments | iterations | factorizations | solver time (s) | mean ms per increment | slowest increment (ms) | snap-back increments | factorizations per snap-back increment: median / max | increments ending with held points | answered by the fast path |")
    w("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    groups = group_names(results)
    for law in LAWS:
        for g in groups + ["all"]:
            sel = [r for (gg, _, l, r) in results if l == law and (g == "all" or gg == g)]
            if not sel:
                continue
            snaps = [f for r in sel for f in r.snap_factorizations]
            incs = sum(r.done for r in sel)
            label = f"**{g}**" if g == "all" else g
            w(
                f"| {label} | {law} | {len(sel)} | {sum(r.ok for r in sel)} | {sum(not r.ok for r in sel)} | "
                f"{sum(r.slow for r in sel)} | {sum(r.iterations for r in sel)} | "
                f"{sum(r.factorizations for r in sel)} | {sum(r.seconds for r in sel):.2f} | "
                f"{ms(sum(r.seconds for r in sel) / max(incs, 1))} | "
                f"{ms(max(r.worst_seconds for r in sel))} | {len(snaps)} | "
                + (f"{statistics.median(snaps):.0f} / {max(snaps)} |" if snaps else "- |")
                + f" {sum(r.held for r in sel)} | {sum(r.fast for r in sel)} of {incs} |"
            )


def comparison(w, results):
    """The active-set runs against the per-iteration ones, per group and per path."""
    diffs, groups = differences(results), group_names(results)
    w("\n## Active set against per iteration, where the per-iteration run completes\n")
    w("Largest difference of the active-set run's stress and consistent tangent from the")
    w("per-iteration run's, relative to the largest |stress| and |tangent| entry of the")
    w("per-iteration run, up to the peak (the last increment before the first drop of |stress|")
    w("in either run; in the cycle the start of unloading if that comes first) and after it.")
    w("*Held*: increments of the active-set run that end with interface points held at a")
    w("contact status their gap contradicts (`held_points` column of `rve run`).\n")
    w("| group | paths | active set fails | stress up to the peak | tangent up to the peak | stress after the peak | tangent after the peak | paths with held increments |")
    w("|---|---|---|---|---|---|---|---|")
    for g in groups + ["all"]:
        sel = [d for d in diffs if g == "all" or d.group == g]
        if not sel:
            continue
        ok = [d for d in sel if not d.fails]
        label = f"**{g}**" if g == "all" else g
        w(
            f"| {label} | {len(sel)} | {len(sel) - len(ok)} | "
            f"{max((d.before[0] for d in ok), default=0.0):.1e} | {max((d.before[1] for d in ok), default=0.0):.1e} | "
            f"{max((d.after[0] for d in ok), default=0.0):.1e} | {max((d.after[1] for d in ok), default=0.0):.1e} | "
            f"{sum(1 for d in ok if d.held > 0)} |"
        )
    w("\nEvery path, largest difference first:\n")
    w("| group | path | peak at increment | stress up to the peak | tangent up to the peak | stress after | tangent after | held increments |")
    w("|---|---|---|---|---|---|---|---|")
    for d in sorted((d for d in diffs if not d.fails), key=lambda d: -d.worst()):
        w(f"| {d.group} | {d.label} | {d.peak or '-'} | {d.before[0]:.1e} | {d.before[1]:.1e} | "
          f"{d.after[0]:.1e} | {d.after[1]:.1e} | {d.held} |")


def every_run(w, results):
    """A row per run, then the failures' messages."""
    w("\n## Every run\n")
    w("| group | path | contact law | outcome | increments done | slow | most iterations | iterations | factorizations | solver time (ms) |")
    w("|---|---|---|---|---|---|---|---|---|---|")
    for g, label, law, r in results:
        outcome = "ok" if r.ok else f"**fails at {r.done + 1}**"
        w(
            f"| {g} | {label} | {law} | {outcome} | {r.done}/{r.total} | {r.slow} | {r.worst} | "
            f"{r.iterations} | {r.factorizations} | {ms(r.seconds)} |"
        )
    failures = [(g, label, law, r) for g, label, law, r in results if not r.ok]
    if failures:
        w("\n## Failure messages\n")
        for g, label, law, r in failures:
            w(f"- {g}, {label}, {law}: `{r.status.replace('rve: error: ', '')}`")


def write(results, record):
    out = []
    intro(out.append, record)
    for part in (summary, comparison, every_run):
        part(out.append, results)
    with open(MD, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    record = provenance.start()  # the commit the binary was just built from
    with tempfile.TemporaryDirectory() as work:
        results = run_all(work)
        write(results, provenance.finish(record, len(results)))
        if KEEP:
            subprocess.run(["cp", "-r", work + "/.", KEEP], check=True)
    print(f"wrote {MD}")


main()
