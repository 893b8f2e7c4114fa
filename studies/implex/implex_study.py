#!/usr/bin/env python3
"""IMPL-EX against the implicit scheme: error against cost.

Runs `rve run` with `[solver] integration = "implex"` at N, 2N, 4N and 8N increments and
with the implicit scheme at N ... 16N on twelve paths: section 5.2.1
(scenes/paper_rve.toml), section 5.2.2 (scenes/paper_rve_cycle.toml) and ten seeded hard
cases (tests/common/hard_paths.rs, written as scenes by the Rust generator itself, built
once into target/studies/implex/). N is each path's own number of increments; every
segment of a path is cut m times finer. The reference is the implicit run at 16N, checked
against the implicit run at 8N. Writes implex_accuracy.md and implex_*.svg into --out
(default target/studies/implex; studies/implex/run --docs copies them into docs/).
Called by studies/implex/run; standard library only (plus cargo for the generator).

Every number on the page comes from the runs made here; times are the `seconds` column
of response.csv summed over the path (median over repeats, as in accuracy_study.py).
"""

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from kit import ms, provenance  # noqa: E402
from kit.plot import COLOURS, svg_plot  # noqa: E402
from kit.rve import Runner  # noqa: E402

LEVELS = (1, 2, 4, 8)  # IMPL-EX at m N increments
IMPLICIT_LEVELS = (1, 2, 4, 8, 16)  # the last one is the reference
HARD_SEEDS = tuple(range(10))
# IMPL-EX under solver.step_tolerance (docs/step_control.md), the path's own increments as
# the largest step: runs keyed ("control", round(1e4 * tolerance)).
CONTROL_TOLERANCES = (0.03, 0.01, 0.003)
# What the page's numbers depend on: a change there uncommitted is named on the page.
INPUTS = ("src", "build.rs", "Cargo.toml", "Cargo.lock", "scenes", "tests/common/hard_paths.rs",
          "studies/implex", "studies/accuracy", "scripts/kit")
GENERATOR = os.path.join(ROOT, "target", "studies", "implex", "hard-case-scenes")


# ---------------------------------------------------------------- paths

class StrainPath:
    """A scene file (`base`; `body`, its content) and its path's segments
    `(to, increments)`."""

    def __init__(self, name, family, base, segments, note=""):
        with open(base, "rb") as f:
            self.body = tomllib.load(f)
        self.name, self.family, self.base, self.segments = name, family, base, segments
        self.note = note
        self.n = sum(n for _, n in segments)

    def no_floor(self):
        """A `solver.smallest_step` (the scene needs one with a tolerance) 16 times below
        `rve run`'s own smallest step, 1/1024 of the path's shortest increment: the control
        cuts down to rve run's own minimum as it would without a floor."""
        prev, shortest = [0.0, 0.0, 0.0], float("inf")
        for to, n in self.segments:
            norm = sum((float(a) - b) ** 2 for a, b in zip(to, prev)) ** 0.5 / n
            if norm > 0.0:
                shortest = min(shortest, norm)
            prev = [float(v) for v in to]
        return float("%.6g" % (shortest / 1024 / 16))

    def edits(self, m, integration, step_tolerance=None):
        """The edits (`rve run --set`) of a run of the integration with every segment cut m
        times finer."""
        edits = {"solver.integration": integration}
        if step_tolerance is not None:
            edits["solver.step_tolerance"] = float("%g" % step_tolerance)
            edits["solver.smallest_step"] = self.no_floor()
        edits["path"] = [{"to": [float(v) for v in to], "increments": n * m}
                         for to, n in self.segments]
        return edits


def shipped(file, name, family):
    with open(file, "rb") as f:
        segs = [(p["to"], p["increments"]) for p in tomllib.load(f)["path"]]
    return StrainPath(name, family, file, segs, os.path.relpath(file, ROOT))


GENERATOR_MAIN = """#[path = "%s"]
mod hard_paths;
fn main() {
    for a in std::env::args().skip(1) {
        let c = hard_paths::case(a.parse().expect("seed"));
        let t: Vec<String> = c.targets.iter().map(|t| format!("[{:?},{:?},{:?}]", t[0], t[1], t[2])).collect();
        println!("{{\\"seed\\":{},\\"kind\\":{:?},\\"setup\\":{:?},\\"scene\\":{:?},\\"targets\\":[{}]}}",
                 c.seed, c.kind, c.setup, c.scene, t.join(","));
    }
}
"""


def generator_binary():
    """Builds (once) a program that prints the hard cases of tests/common/hard_paths.rs as
    JSON, with the project's own rand and rand_chacha versions (read from Cargo.lock)."""
    lock = tomllib.load(open(os.path.join(ROOT, "Cargo.lock"), "rb"))
    ver = {p["name"]: p["version"] for p in lock["package"]}
    os.makedirs(os.path.join(GENERATOR, "src"), exist_ok=True)
    files = {
        "Cargo.toml": "[package]\nname = \"hard-case-scenes\"\nversion = \"0.0.0\"\n"
                      "edition = \"2021\"\n[workspace]\n[dependencies]\n"
                      "rand = { version = \"=%s\", default-features = false, features = [\"std\"] }\n"
                      "rand_chacha = \"=%s\"\n" % (ver["rand"], ver["rand_chacha"]),
        "src/main.rs": GENERATOR_MAIN % os.path.join(ROOT, "tests", "common", "hard_paths.rs"),
    }
    for rel, body in files.items():
        p = os.path.join(GENERATOR, rel)
        if not os.path.exists(p) or open(p).read() != body:
            with open(p, "w") as f:
                f.write(body)
    cmd = ["cargo", "build", "--release", "--quiet", "--manifest-path",
           os.path.join(GENERATOR, "Cargo.toml")]
    if subprocess.run(cmd + ["--offline"], capture_output=True).returncode != 0:
        subprocess.run(cmd, check=True)  # the crates are not cached yet: fetch them
    return os.path.join(GENERATOR, "target", "release", "hard-case-scenes")


def segments_of(targets):
    """Equal-increment segments `(to, n)` of a list of path points starting from zero."""
    segs, prev, step = [], [0.0, 0.0, 0.0], None
    for t in targets:
        d = [a - b for a, b in zip(t, prev)]
        size = max(map(abs, d)) or 1.0
        if step is None or max(abs(a - b) for a, b in zip(d, step)) > 1e-6 * size:
            segs.append([t, 0])
            step = d
        segs[-1][0] = t
        segs[-1][1] += 1
        prev = t
    return [(to, n) for to, n in segs]


def hard_cases(seeds):
    out = subprocess.run([generator_binary()] + [str(s) for s in seeds], check=True,
                         capture_output=True, text=True).stdout
    paths = []
    for line in out.splitlines():
        c = json.loads(line)
        segs = segments_of(c["targets"])
        assert sum(n for _, n in segs) == len(c["targets"])
        base = os.path.join(os.path.dirname(GENERATOR), "hard_case_%d.toml" % c["seed"])
        with open(base, "w") as f:
            f.write(c["scene"])
        paths.append(StrainPath("hard case %d" % c["seed"], "hard cases", base, segs,
                                "%s; %s" % (c["kind"], c["setup"])))
    return paths


def all_paths():
    return [shipped(os.path.join(ROOT, "scenes", "paper_rve.toml"), "§5.2.1", "§5.2.1"),
            shipped(os.path.join(ROOT, "scenes", "paper_rve_cycle.toml"), "§5.2.2", "§5.2.2")
            ] + hard_cases(HARD_SEEDS)


# ---------------------------------------------------------------- running

def run_path(R, p):
    """Every run of path `p`: {("implicit" | "implex", m): Runner result}."""
    slug = re.sub(r"[^0-9a-z]+", "_", p.name.lower()).strip("_")
    runs = {}
    for integration, levels in (("implicit", IMPLICIT_LEVELS), ("implex", LEVELS)):
        for m in levels:
            name = "%s_%s_%d" % (slug, integration, m)
            runs[integration, m] = R.run(name, p.base, p.edits(m, integration))
    for tol in CONTROL_TOLERANCES:
        name = "%s_control_%g" % (slug, tol)
        runs["control", round(1e4 * tol)] = R.run(name, p.base, p.edits(1, "implex", tol))
    return runs


# ---------------------------------------------------------------- measures

EPS = ("eps_xx", "eps_yy", "gamma_xy")
SIG = ("sig_xx", "sig_yy", "sig_xy")
SNAP_JUMP = 0.05  # a reference increment whose stress jumps by 5 % of its largest stress
SNAP_WINDOW = 0.05  # "near a snap-back": within this share of the path's length
WIDE = 0.1  # the strain interval on which a run is off by more than this share of the stress


def norm(v):
    return math.sqrt(sum(x * x for x in v))


def diff(r, s, keys):
    return [r[k] - s[k] for k in keys]


def dissipated(rows):
    """W - sigma . eps / 2 at the path's end (trapezoidal external work): the energy the
    ITZ dissipated, exact since every branch of the law unloads through the origin."""
    work, pe, ps = 0.0, [0.0] * 3, [0.0] * 3
    for r in rows:
        e, s = [r[k] for k in EPS], [r[k] for k in SIG]
        work += sum(0.5 * (s[c] + ps[c]) * (e[c] - pe[c]) for c in range(3))
        pe, ps = e, s
    return work - 0.5 * sum(a * b for a, b in zip(ps, pe))


def arc(rows):
    """The path length up to each increment, and each increment's strain step."""
    s, out, steps, prev = 0.0, [], [], {k: 0.0 for k in EPS}
    for r in rows:
        d = norm(diff(r, prev, EPS))
        s += d
        out.append(s)
        steps.append(d)
        prev = r
    return out, steps


def snaps(ref):
    """Arc-length coordinates of the reference's snap-backs: increments with limit points
    or a stress jump over SNAP_JUMP of the largest stress."""
    scale = max(norm([r[k] for k in SIG]) for r in ref)
    s, _ = arc(ref)
    prev = {k: 0.0 for k in SIG}
    out = []
    for k, r in enumerate(ref):
        if r["limit_points"] > 0 or norm(diff(r, prev, SIG)) > SNAP_JUMP * scale:
            out.append(s[k])
        prev = r
    return out


def near_snaps(s, marks, width):
    """Whether each arc-length coordinate of `s` lies within `width` of a snap-back."""
    return [any(abs(x - m) <= width for m in marks) for x in s]


def errors(rows, ref, stride):
    """Errors of a run against the reference, at the run's own points (the reference's
    every stride-th): stress L1 along the path, sum |dsig| |deps| / (L max|sig_ref|),
    stress max, max |dsig| / max|sig_ref| (|.| the Euclidean norm of the three
    components), the dissipated energy's relative error, the share of the L1 error within
    SNAP_WINDOW of the path's length of a snap-back of the reference, and the
    strain interval on which the run is off by more than WIDE of max|sig_ref|."""
    scale = max(norm([r[k] for k in SIG]) for r in ref)
    s, steps = arc(rows)
    matched = [ref[(k + 1) * stride - 1] for k in range(len(rows))]
    for r, e in zip(rows, matched):
        assert norm(diff(r, e, EPS)) <= 1e-9 * s[-1], "the runs' strain points differ"
    ds = [norm(diff(r, e, SIG)) for r, e in zip(rows, matched)]
    l1 = sum(d * h for d, h in zip(ds, steps))
    marks = snaps(ref)
    near = near_snaps(s, marks, SNAP_WINDOW * s[-1])
    d_ref = dissipated(ref)
    wide = [k for k, d in enumerate(ds) if d > WIDE * scale]
    kmax = max(range(len(ds)), key=lambda k: ds[k])
    return {"l1": l1 / (s[-1] * scale), "max": max(ds) / scale,
            "energy": abs(dissipated(rows) - d_ref) / d_ref,
            "energy_signed": (dissipated(rows) - d_ref) / d_ref,
            "near_snap": sum(d * h for d, h, y in zip(ds, steps, near) if y) / l1 if l1 > 0 else 0.0,
            "wide": sum(steps[k] for k in wide), "wide_steps": len(wide),
            "max_after_snap": bool(marks) and s[kmax] >= marks[0] - 1e-9 * s[-1],
            "end": ds[-1] / scale, "step": max(steps)}


def snap_zone(ref):
    """The share of the path within SNAP_WINDOW of its length of the reference's snaps."""
    s, steps = arc(ref)
    near = near_snaps(s, snaps(ref), SNAP_WINDOW * s[-1])
    return sum(h for h, y in zip(steps, near) if y) / s[-1]


def measure(runs):
    """Adds the errors against the implicit 16N run to every complete run of a path."""
    ref = runs["implicit", IMPLICIT_LEVELS[-1]]
    for (integration, m), v in runs.items():
        if v is ref or v["failed"] or ref["failed"]:
            continue
        if integration == "control":
            v["err"] = interpolated_errors(v["rows"], ref["rows"])
            continue
        v["err"] = errors(v["rows"], ref["rows"], IMPLICIT_LEVELS[-1] // m)
    return ref


def interpolated_errors(rows, ref):
    """`errors`' stress L1, stress max and energy of a run whose strain points are not
    the reference's (the step control's): the reference's stress interpolated linearly in
    arc length at each of the run's points (both follow the same piecewise-linear path)."""
    scale = max(norm([r[k] for k in SIG]) for r in ref)
    s, steps = arc(rows)
    s_ref, _ = arc(ref)
    ds, j = [], 0
    for x, r in zip(s, rows):
        while j < len(ref) - 1 and s_ref[j] < x:
            j += 1
        a, b = (ref[j - 1], ref[j]) if j > 0 else ({k: 0.0 for k in SIG}, ref[0])
        s0 = s_ref[j - 1] if j > 0 else 0.0
        w = (x - s0) / (s_ref[j] - s0) if s_ref[j] > s0 else 1.0
        w = min(max(w, 0.0), 1.0)
        ds.append(norm([r[k] - (a[k] + w * (b[k] - a[k])) for k in SIG]))
    d_ref = dissipated(ref)
    return {"l1": sum(d * h for d, h in zip(ds, steps)) / (s[-1] * scale),
            "max": max(ds) / scale, "energy": abs(dissipated(rows) - d_ref) / d_ref,
            "energy_signed": (dissipated(rows) - d_ref) / d_ref}


def order(a, b, key):
    """Observed order between successive refinements (steps halved)."""
    if "err" not in a or "err" not in b or a["err"][key] <= 0 or b["err"][key] <= 0:
        return None
    return math.log2(a["err"][key] / b["err"][key])


# ---------------------------------------------------------------- tables

def lv(m):
    return "N" if m == 1 else "%dN" % m


def pc(x, order=None):
    """A relative error in %, with the observed order after it."""
    if x is None:
        return "—"
    s = "%.2g" % (100 * x) if 100 * x < 10 else "%.0f" % (100 * x)
    return s if order is None else "%s (%.2f)" % (s, order)


def err(v, key):
    return v["err"][key] if "err" in v else None


def facts(v):
    return int(sum(r["factorizations"] for r in v["rows"]))


def path_table(p, runs, md):
    """Every run of one path, with the observed orders between successive levels."""
    md.append("| scheme | increments | step ‖Δε‖ | time ms | factorizations | "
              "stress L1 % (order) | stress max % (order) | energy % (order) | "
              "L1 near snaps % |")
    md.append("|---|---|---|---|---|---|---|---|---|")
    for integration, levels in (("implex", LEVELS), ("implicit", IMPLICIT_LEVELS)):
        for i, m in enumerate(levels):
            v = runs[integration, m]
            prev = runs[integration, levels[i - 1]] if i else None
            o = {k: order(prev, v, k) if prev else None for k in ("l1", "max", "energy")}
            ref = m == IMPLICIT_LEVELS[-1] and integration == "implicit"
            md.append("| %s | %d (%s)%s | %.2g | %s | %d | %s | %s | %s | %s |" % (
                integration, m * p.n, lv(m), " ref." if ref else "",
                path_length(p) / (m * p.n), ms(v["total"]), facts(v),
                "0 (ref.)" if ref else pc(err(v, "l1"), o["l1"]),
                "0 (ref.)" if ref else pc(err(v, "max"), o["max"]),
                "0 (ref.)" if ref else pc(err(v, "energy"), o["energy"]),
                "—" if ref else pc(err(v, "near_snap"))))
    for v in runs.values():
        if v["failed"]:
            md.append("\n- `%s`: %s." % (v["name"], v["failed"]))


def path_length(p):
    s, prev = 0.0, [0.0, 0.0, 0.0]
    for to, _ in p.segments:
        s += norm([a - b for a, b in zip(to, prev)])
        prev = to
    return s


def reference_table(results, md):
    """The implicit reference against the implicit run at half its increments, beside
    IMPL-EX's error at 8N."""
    md.append("| path | N | implicit 8N vs 16N: stress L1 % | max % | energy % | "
              "IMPL-EX 8N: stress L1 % | max % | energy % |")
    md.append("|---|---|---|---|---|---|---|---|")
    for p, runs in results:
        a, b = runs["implicit", IMPLICIT_LEVELS[-2]], runs["implex", LEVELS[-1]]
        md.append("| %s | %d | %s | %s | %s | %s | %s | %s |" % (
            p.name, p.n, pc(err(a, "l1")), pc(err(a, "max")), pc(err(a, "energy")),
            pc(err(b, "l1")), pc(err(b, "max")), pc(err(b, "energy"))))


def hard_table(results, md):
    """One row per hard case: IMPL-EX's errors and times at N ... 8N, implicit's at N."""
    head = "/".join(lv(m) for m in LEVELS)
    md.append("| path | kind; setup | N | implicit N ms | IMPL-EX ms %s | stress L1 %% %s | "
              "stress max %% %s | energy %% %s |" % (head, head, head, head))
    md.append("|---|---|---|---|---|---|---|---|")
    for p, runs in results:
        vs = [runs["implex", m] for m in LEVELS]
        md.append("| %s | %s | %d | %s | %s | %s | %s | %s |" % (
            p.name, p.note, p.n, ms(runs["implicit", 1]["total"]),
            " / ".join(ms(v["total"]) for v in vs),
            " / ".join(pc(err(v, "l1")) for v in vs),
            " / ".join(pc(err(v, "max")) for v in vs),
            " / ".join(pc(err(v, "energy")) for v in vs)))


def median(xs):
    xs = sorted(x for x in xs if x is not None)
    if not xs:
        return None
    k = len(xs) // 2
    return xs[k] if len(xs) % 2 else 0.5 * (xs[k - 1] + xs[k])


def family_rows(results):
    """Per scheme and level over a family of paths: total time, median and largest
    errors, median observed order against the level before."""
    rows = []
    for integration, levels in (("implex", LEVELS), ("implicit", IMPLICIT_LEVELS[:-1])):
        for i, m in enumerate(levels):
            vs = [runs[integration, m] for _, runs in results]
            row = {"integration": integration, "m": m, "time": sum(v["total"] for v in vs)}
            for key in ("l1", "max", "energy"):
                row[key] = (median(err(v, key) for v in vs), max(err(v, key) or 0 for v in vs))
                row[key + "_order"] = median(
                    order(runs[integration, levels[i - 1]], runs[integration, m], key)
                    for _, runs in results) if i else None
            rows.append(row)
    return rows


def family_table(rows, md):
    md.append("| scheme | increments | time ms, all paths | stress L1 %: median (order), "
              "largest | stress max %: median (order), largest | energy %: median (order), "
              "largest |")
    md.append("|---|---|---|---|---|---|")
    for r in rows:
        md.append("| %s | %s | %s | %s | %s | %s |" % (
            r["integration"], lv(r["m"]), ms(r["time"]),
            *("%s, %s" % (pc(r[k][0], r[k + "_order"]), pc(r[k][1]))
              for k in ("l1", "max", "energy"))))


# ---------------------------------------------------------------- plots

def error_plot(file, title, rows, worst):
    """Error against time, log-log: stress L1 and energy, both schemes (median over the
    family's paths; with `worst`, IMPL-EX's largest too)."""
    series, k = [], 0
    for integration in ("implex", "implicit"):
        for key, what in (("l1", "stress L1"), ("energy", "energy")):
            for idx, stat in ((0, "median"), (1, "largest"))[: 2 if worst and integration == "implex" else 1]:
                pts = [(r["time"], 100 * r[key][idx], lv(r["m"])) for r in rows
                       if r["integration"] == integration and r[key][idx] and r["time"] > 0]
                label = "%s %s%s" % (integration, what, ", " + stat if worst else "")
                series.append((label, COLOURS[k % len(COLOURS)], pts, True))
                k += 1
    svg_plot(file, title, "time of the path(s), s (seconds column summed)",
             "error, %", [s for s in series if s[2]], logx=True, logy=True, w=820,
             legend=260)


def curves_plot(file, p, runs):
    """sig_xx against eps_xx where eps_xx >= 0: IMPL-EX at N ... 8N, the implicit scheme
    at N and 16N."""
    pick = [("implicit", IMPLICIT_LEVELS[-1]), ("implicit", 1)] + [("implex", m) for m in LEVELS]
    series = []
    for k, (integration, m) in enumerate(pick):
        rows = runs[integration, m]["rows"]
        colour = ["#000000", "#999999"][k] if k < 2 else COLOURS[k - 2]
        series.append(("%s %s" % (integration, lv(m)), colour,
                       [(1e4 * r["eps_xx"], r["sig_xx"], "") for r in rows
                        if r["eps_xx"] >= 0], True, 0))
    svg_plot(file, "%s: sig_xx against eps_xx (eps_xx ≥ 0), IMPL-EX and implicit" % p.name,
             "eps_xx x 1e4", "sig_xx, N/mm²", series)


# ---------------------------------------------------------------- page

def header(stats):
    return [
        "# IMPL-EX against the implicit scheme: error and cost\n",
        "Generated by `studies/implex/run` (`studies/implex/implex_study.py`); do not edit by "
        "hand, every number and sentence below comes from the runs of that script. "
        + provenance.sentence(stats["provenance"]),
        "",
        "`[solver] integration = \"implex\"` extrapolates each ITZ point's history "
        "`delta_max` from the last two converged increments (scaled by the ratio of the "
        "increments' strain norms) and keeps the last converged contact status, so the RVE "
        "is linear within an increment: one factorization, no Newton loop, no snap-back "
        "to trace. Its error is meant to be of first order in the step. Here it runs at "
        "N, 2N, 4N and 8N increments (every segment of a path cut 1, 2, 4, 8 times finer; N is the "
        "path's own count) against the implicit scheme (`\"implicit\"`, the default) at "
        "16N, the reference, which is checked against the implicit run at 8N. The implicit "
        "scheme also runs at N, 2N, 4N and 8N: the cost side.",
        "",
        "**Errors**, at the run's own strain points (every one is a point of the reference "
        "path): with |.| the Euclidean norm of `[sig_xx, sig_yy, sig_xy]` and S the largest "
        "|sigma| of the reference along the path, L the path's length in strain, "
        "*stress L1* = sum over increments of |sigma − sigma_ref| ‖Δε‖ / (L S) (the mean "
        "error along the path), *stress max* = max |sigma − sigma_ref| / S, *energy* = the "
        "relative error of the dissipated energy at the path's end, W − sigma·eps/2 with W "
        "the external work by the trapezoidal rule over the run's own increments (exact "
        "for this law, whose branches all unload through the origin). *Order*: log2 of "
        "the ratio of the errors of two successive levels (1 for a first-order scheme). "
        "*L1 near snaps*: the share of the stress L1 error within %g %% of the path's "
        "length of a snap-back of the reference (an increment with limit points, or whose "
        "stress jumps by more than %g %% of S). *Time*: the `seconds` column of "
        "`response.csv` summed over the path (the updates only, no meshing), median over "
        "up to %d runs (fewer once a variant's runs took %g s); the machine may be shared, "
        "so times within ~20 %% of each other are not different." % (
            100 * SNAP_WINDOW, 100 * SNAP_JUMP, stats["repeats"], stats["budget"]),
        ""]


def write_page(results, stats, out):
    md = header(stats)
    fams = [("§5.2.1", "521"), ("§5.2.2", "522"), ("hard cases", "hard")]
    rows = {f: family_rows([(p, r) for p, r in results if p.family == f]) for f, _ in fams}
    md += findings(results, rows)
    for f, slug in fams:
        error_plot(os.path.join(out, "implex_error_vs_time_%s.svg" % slug),
                   "%s: error against time, IMPL-EX and implicit" % f, rows[f],
                   f == "hard cases")
    for p, runs in results[:2]:
        slug = "521" if p.family == "§5.2.1" else "522"
        curves_plot(os.path.join(out, "implex_curves_%s.svg" % slug), p, runs)
        md += ["## %s (`%s`, N = %d)\n" % (p.name, p.note, p.n),
               "![error against time](implex_error_vs_time_%s.svg)\n" % slug,
               "![curves](implex_curves_%s.svg)\n" % slug]
        path_table(p, runs, md)
        md.append("")
    hard = [(p, r) for p, r in results if p.family == "hard cases"]
    md += ["## Ten hard cases\n", hard_intro(hard),
           "", "![error against time](implex_error_vs_time_hard.svg)\n"]
    family_table(rows["hard cases"], md)
    md.append("")
    hard_table(hard, md)
    md += ["", "## Is the reference converged?\n", reference_intro(), ""]
    reference_table(results, md)
    with open(os.path.join(out, "implex_accuracy.md"), "w") as f:
        f.write(re.sub(r"\n{3,}", "\n\n", "\n".join(md)).rstrip() + "\n")


def hard_intro(hard):
    return ("The first %d seeded hard cases of `tests/common/hard_paths.rs` (seeds %d-%d: "
            "every path family of the generator, random microstructures, meshes, boundary "
            "conditions and contact penalties), written as scenes by the generator itself "
            "(built from that file with the project's `rand` versions into "
            "`target/studies/implex/`); each path's equal-increment segments become its "
            "`[[path]]` tables. Over the family: times summed over the paths, errors as "
            "median and largest over the paths, orders as the median over the paths." % (
                len(hard), HARD_SEEDS[0], HARD_SEEDS[-1]))


def reference_intro():
    return ("The implicit run at 8N against the reference (16N), beside IMPL-EX's error at "
            "8N against the same reference: where the first is well below the second, the "
            "reference resolves what IMPL-EX's error is measured against.")


def span(xs, f=pc):
    """"a–b" over a sequence of values (one value: "a")."""
    xs = [x for x in xs if x is not None]
    lo, hi = f(min(xs)), f(max(xs))
    return lo if lo == hi else "%s–%s" % (lo, hi)


def listing(xs):
    return ", ".join(xs[:-1]) + " and " + xs[-1] if len(xs) > 1 else "".join(xs)


def implex_errs(runs, key):
    return [err(runs["implex", m], key) for m in LEVELS]


def snap_finding(p, runs):
    """Where IMPL-EX's error sits on one of the paper's paths."""
    ref = runs["implicit", IMPLICIT_LEVELS[-1]]["rows"]
    marks = snaps(ref)
    if not marks:
        return "On %s the reference has no snap-back." % p.name
    vs = [runs["implex", m]["err"] for m in LEVELS]
    wide = [e["wide"] for e in vs]
    s = ("On %s the reference snaps back %s (at %s of the path's length). IMPL-EX at N, 2N, "
         "4N and 8N differs from it by more than %g %% of S on a strain interval of %s (%s "
         "of its own increments), with its largest error %s; %s of its stress L1 error "
         "lies within %g %% of the path's length of a snap-back (%s of the path). " % (
             p.name, "once" if len(marks) == 1 else "%d times" % len(marks),
             listing(["%.0f %%" % (100 * x / arc(ref)[0][-1]) for x in marks]), 100 * WIDE,
             ", ".join("%.2g" % w for w in wide), ", ".join(str(e["wide_steps"]) for e in vs),
             "at or after the first snap" if all(e["max_after_snap"] for e in vs)
             else "before the first snap at some level",
             span(implex_errs(runs, "near_snap")) + " %", 100 * SNAP_WINDOW,
             pc(snap_zone(ref)) + " %"))
    s += "Its largest error stays at %s %% of S (orders %s)" % (
        span(implex_errs(runs, "max")), ", ".join(
            fmt_order(order(runs["implex", a], runs["implex", b], "max"))
            for a, b in zip(LEVELS, LEVELS[1:])))
    if wide[-1] < 0.75 * wide[0]:
        s += (": the implicit scheme's snap is a jump in strain that IMPL-EX makes later, so a "
              "finer step narrows the interval where the two differ, not the difference. ")
    else:
        s += ", and the interval where the two differ does not narrow with the step. "
    if max(implex_errs(runs, "end")) > WIDE:
        s += ("The path ends %.0f %% of its length after the first snap, and there IMPL-EX is "
              "still %s %% of S off (N ... 8N): it has not softened as far by the end, so its "
              "dissipated energy is %s %% %s." % (
                  100 * (1 - marks[0] / arc(ref)[0][-1]), span(implex_errs(runs, "end")),
                  span(implex_errs(runs, "energy")),
                  "short" if all(e < 0 for e in implex_errs(runs, "energy_signed"))
                  else "off"))
    return s.strip()


def fmt_order(o):
    return "—" if o is None else ("%.2f" % o).replace("-0.00", "0.00")


def order_finding(rows):
    """The observed orders per family, from the family rows."""
    parts = []
    for fam, rs in rows.items():
        x = [r for r in rs if r["integration"] == "implex" and r["m"] > 1]
        parts.append("%s: stress L1 %s, energy %s, stress max %s" % (
            fam, *(span([r[k + "_order"] for r in x], fmt_order)
                   for k in ("l1", "energy", "max"))))
    return ("**Order.** Observed orders of IMPL-EX between successive refinements (N→2N, "
            "2N→4N, 4N→8N; over the hard cases the median over the paths): %s." % "; ".join(parts))


def hard_snap_finding(hard):
    """Where IMPL-EX's error sits on the hard cases, at 8N."""
    vs = [(p, runs, runs["implex", LEVELS[-1]]) for p, runs in hard]
    with_snap = [(p, runs, v) for p, runs, v in vs
                 if snaps(runs["implicit", IMPLICIT_LEVELS[-1]]["rows"])]
    if not with_snap:
        return "None of the hard cases' references snaps back."
    return ("On %d of the %d hard cases the reference snaps back; there IMPL-EX's largest "
            "error at 8N lies at or after the first snap on %d, and a median %s %% of its "
            "stress L1 error lies within %g %% of the path's length of a snap-back (a median "
            "%s %% of the path)." % (
                len(with_snap), len(hard), sum(v["err"]["max_after_snap"] for *_, v in with_snap),
                pc(median(v["err"]["near_snap"] for *_, v in with_snap)), 100 * SNAP_WINDOW,
                pc(median(snap_zone(runs["implicit", IMPLICIT_LEVELS[-1]]["rows"])
                          for p, runs, _ in with_snap))))


def fast_share(results, integration, m):
    rows = [r for _, runs in results for r in runs[integration, m]["rows"]]
    return sum(r.get("fast", 0.0) for r in rows) / max(1, len(rows))


def cost_finding(results, rows):
    """Time and factorizations of both schemes, and IMPL-EX at the implicit scheme's time."""
    f_x = sum(facts(runs["implex", 1]) for _, runs in results)
    f_i = sum(facts(runs["implicit", 1]) for _, runs in results)
    n_x = sum(len(runs["implex", 1]["rows"]) for _, runs in results)
    parts = []
    for fam, rs in rows.items():
        imp = next(r for r in rs if r["integration"] == "implicit" and r["m"] == 1)
        xs = [r for r in rs if r["integration"] == "implex"]
        near = min(xs, key=lambda r: abs(math.log(r["time"] / imp["time"])))
        parts.append(
            "%s: the implicit scheme at N takes %s ms (stress L1 %s %%, energy %s %%), IMPL-EX "
            "%s ms at N and %s ms at 8N; nearest in time, IMPL-EX at %s (%s ms) is at %s %% and "
            "%s %%" % (fam, ms(imp["time"]), pc(imp["l1"][0]), pc(imp["energy"][0]),
                       ms(xs[0]["time"]), ms(xs[-1]["time"]), lv(near["m"]), ms(near["time"]),
                       pc(near["l1"][0]), pc(near["energy"][0])))
    return ("**Cost.** An IMPL-EX increment is at most one factorization and no Newton loop "
            "(one whose history and contact status the last increment froze carries that "
            "increment's factorization over): %d factorizations for the %d increments at N "
            "on the %d paths, against the implicit scheme's %d (`response.csv` does not count "
            "the step check's, whose half steps are in the implicit scheme's times); the "
            "median increment took %s ms against %s ms (median over the paths at N). Times "
            "(errors over the hard cases are medians): %s. The implicit runs at N answered "
            "%.0f %% of their increments through the fast path (`solver.fast_path`: unloading "
            "and closed cracks without a solve), IMPL-EX %.0f %%." % (
                f_x, n_x, len(results), f_i,
                ms(median(runs["implex", 1]["per_inc"] for _, runs in results)),
                ms(median(runs["implicit", 1]["per_inc"] for _, runs in results)),
                "; ".join(parts), 100 * fast_share(results, "implicit", 1),
                100 * fast_share(results, "implex", 1)))


def reference_finding(results):
    """Whether the implicit reference resolves IMPL-EX's error, path by path."""
    bad = []
    for p, runs in results:
        a, b = runs["implicit", IMPLICIT_LEVELS[-2]], runs["implex", LEVELS[-1]]
        off = [(k, name) for k, name in (("l1", "stress L1"), ("max", "stress max"),
                                         ("energy", "energy"))
               if err(a, k) is None or err(b, k) is None or err(a, k) > err(b, k) / 3]
        if off:
            bad.append((p, a, b, off))
    s = ("**Reference.** The implicit run at 8N is within a third of IMPL-EX's 8N error of "
         "the reference (16N) in all three norms on %d of the %d paths." % (
             len(results) - len(bad), len(results)))
    if bad:
        s += " Not on %s." % "; ".join(
            "%s (%s)" % (p.name, ", ".join("%s %s %% against IMPL-EX's %s %%" % (
                name, pc(err(a, k)), pc(err(b, k))) for k, name in off)) for p, a, b, off in bad)
    split = [p.name for p, a, *_ in bad if err(a, "max") and err(a, "max") > WIDE
             and a["err"]["near_snap"] > 0.9]
    if split:
        s += (" On %s the implicit runs at 8N and 16N differ by more than %g %% of S, and "
              "over 90 %% of their L1 difference lies near a snap-back: they land on "
              "different equilibria there (which one depends on the increment, "
              "`docs/accuracy.md` (d)), and IMPL-EX's stress error there is measured against "
              "one of them." % (listing(split), 100 * WIDE))
    return s


THRESHOLDS = (("l1", "stress L1", (0.05, 0.02, 0.01)), ("energy", "energy", (0.2, 0.1, 0.05)),
              ("max", "stress max", (0.2, 0.1)))


def strain_scale(p):
    """delta_c / cell size: the strain that opens an ITZ by delta_c across the cell."""
    scene = p.body
    return scene["materials"]["itz"]["delta_c"] / max(scene["cell"]["size"])


def largest_step(runs_of_family, key, tol):
    """The largest step (as a share of delta_c / cell size) such that every IMPL-EX run of
    the family with that step or a smaller one has its error within tol, and the level of
    the coarsest such run; None if even the finest runs miss."""
    pts = sorted(((v["err"]["step"] / strain_scale(p), err(v, key), m)
                  for p, runs in runs_of_family for m in LEVELS
                  for v in [runs["implex", m]] if "err" in v), key=lambda x: x[0])
    best = None
    for step, e, m in pts:
        if e > tol:
            break
        best = (step, m)
    return best


def step_table(results, md):
    fams = []
    for p, _ in results:
        if p.family not in fams:
            fams.append(p.family)
    md.append("| IMPL-EX error within | %s |" % " | ".join(fams))
    md.append("|---|" + "---|" * len(fams))
    for key, name, tols in THRESHOLDS:
        for tol in tols:
            cells = []
            for fam in fams:
                b = largest_step([(p, r) for p, r in results if p.family == fam], key, tol)
                cells.append("not at 8N" if b is None else "%.2g (%s)" % (b[0], lv(b[1])))
            md.append("| %s %g %% | %s |" % (name, 100 * tol, " | ".join(cells)))


def step_summary(results):
    """The table's bounds in words: the tightest bound every family meets, per norm."""
    fams = sorted({p.family for p, _ in results})
    out = []
    for key, name, tols in THRESHOLDS:
        met = [(tol, [largest_step([(p, r) for p, r in results if p.family == f], key, tol)
                      for f in fams]) for tol in tols]
        met = [(tol, bs) for tol, bs in met if all(bs)]
        if met:
            tol, bs = met[-1]
            out.append("a %s error within %g %% needs steps of at most %.2g delta_c / cell "
                       "size on every family" % (name, 100 * tol, min(b[0] for b in bs)))
        else:
            out.append("no step measured brings the %s error within %g %% on every family"
                       % (name, 100 * max(tols)))
    return ("In words: with IMPL-EX, %s. The implicit scheme at N is more accurate than "
            "IMPL-EX at 8N in stress L1 on %d of the %d paths." % (
                "; ".join(out), sum(err(r["implicit", 1], "l1") is not None
                                    and err(r["implicit", 1], "l1") < err(r["implex", 8], "l1")
                                    for _, r in results), len(results)))


def control_table(results, md):
    """Per family and tolerance: the largest errors over the family's paths and the
    cost; then the loosest tolerance that keeps every path of a family within a bound."""
    fams = []
    for p, _ in results:
        if p.family not in fams:
            fams.append(p.family)
    md.append("| family | step_tolerance | increments (of N) | stress L1 %, largest | "
              "stress max %, largest | energy %, largest (signed) |")
    md.append("|---|---|---|---|---|---|")
    for fam in fams:
        rs = [(p, r) for p, r in results if p.family == fam]
        for tol in CONTROL_TOLERANCES:
            vs = [r["control", round(1e4 * tol)] for _, r in rs]
            if any("err" not in v for v in vs):
                md.append("| %s | %g | failed | | | |" % (fam, tol))
                continue
            incs = [len(v["rows"]) / p.n for (p, _), v in zip(rs, vs)]
            worst = max(vs, key=lambda v: v["err"]["energy"])
            md.append("| %s | %g | %s | %s | %s | %s (%+.1f) |" % (
                fam, tol, "%.1fN" % incs[0] if len(incs) == 1 else
                "%.1fN ... %.1fN" % (min(incs), max(incs)),
                pc(max(v["err"]["l1"] for v in vs)), pc(max(v["err"]["max"] for v in vs)),
                pc(worst["err"]["energy"]), 100 * worst["err"]["energy_signed"]))
    md.append("")
    md.append("| loosest step_tolerance within | %s |" % " | ".join(fams))
    md.append("|---|" + "---|" * len(fams))
    for key, name in (("l1", "stress L1"), ("max", "stress max"), ("energy", "energy")):
        for bound in (0.01, 0.02, 0.05):
            cells = []
            for fam in fams:
                ok = [tol for tol in CONTROL_TOLERANCES
                      if all("err" in r["control", round(1e4 * tol)] and
                             r["control", round(1e4 * tol)]["err"][key] <= bound
                             for p, r in results if p.family == fam)]
                cells.append("%g" % max(ok) if ok else "not at %g" % min(CONTROL_TOLERANCES))
            md.append("| %s %g %% | %s |" % (name, 100 * bound, " | ".join(cells)))


def findings(results, rows):
    hard = [(p, r) for p, r in results if p.family == "hard cases"]
    md = ["## Findings\n",
          "S is the largest stress of the reference along the path.\n",
          "**Where the error sits.** " + " ".join(snap_finding(p, runs) for p, runs in results
                                                  if p.family != "hard cases")
          + " " + hard_snap_finding(hard), "",
          order_finding(rows), "", cost_finding(results, rows), "",
          reference_finding(results), "",
          "**What step a user needs.** The largest strain step (the largest ‖Δε‖ of a run, in "
          "units of delta_c / cell size, the strain that opens an ITZ by delta_c across the "
          "cell) at which every IMPL-EX run of the family with that step or a smaller one "
          "kept its error within the bound, and the coarsest such level; *not at 8N*: some "
          "run at 8N or finer misses it.\n"]
    step_table(results, md)
    md += ["", step_summary(results), "",
           "**With the step control** (`solver.step_tolerance`, docs/step_control.md): IMPL-EX "
           "from the path's own N increments as the largest step, `rve run` redoing a step "
           "whose suggested ratio is below 1 and growing it again (down to 1/1024 of the "
           "path's increment); errors against the same reference, interpolated at the run's "
           "own points. The largest errors over each family's paths, and the loosest "
           "tolerance measured that keeps every path of the family within a bound:\n"]
    control_table(results, md)
    return md + [""]


# ---------------------------------------------------------------- main

def save(file, results, stats):
    data = [{"path": vars(p), "runs": {"%s:%d" % k: v for k, v in runs.items()}}
            for p, runs in results]
    with open(file, "w") as f:
        json.dump({"results": data, "stats": stats}, f)


def load(file):
    with open(file) as f:
        data = json.load(f)
    results = []
    for d in data["results"]:
        q = d["path"]
        p = StrainPath(q["name"], q["family"], q["text"], q["segments"], q["note"])
        runs = {(k.split(":")[0], int(k.split(":")[1])): v for k, v in d["runs"].items()}
        results.append((p, runs))
    return results, data["stats"]


def run_all(a):
    t0 = time.perf_counter()
    record = provenance.start(INPUTS)  # the commit the binary was just built from
    tmp = tempfile.mkdtemp(prefix="rve-implex-")
    R = Runner(a.rve, tmp, a.repeats, a.budget)
    results = []
    try:
        for p in all_paths():
            runs = run_path(R, p)
            results.append((p, runs))
            print("implex study: %s done (%d runs, %.0f s)" % (
                p.name, R.count, time.perf_counter() - t0), file=sys.stderr)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    stats = {"count": R.count, "elapsed": time.perf_counter() - t0,
             "provenance": provenance.finish(record, R.count),
             "repeats": a.repeats, "budget": a.budget}
    return results, stats


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rve", default=os.path.join(ROOT, "target", "release", "rve"))
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "studies", "implex"))
    ap.add_argument("--repeats", type=int, default=3, help="runs per variant (median time)")
    ap.add_argument("--budget", type=float, default=3.0,
                    help="no further repeats of a variant once its runs took this many seconds")
    ap.add_argument("--save", help="also write the runs' rows to this JSON file")
    ap.add_argument("--load", help="write the page from the runs saved by --save, no runs")
    a = ap.parse_args()
    results, stats = load(a.load) if a.load else run_all(a)
    if a.save:
        save(a.save, results, stats)
    for _, runs in results:
        measure(runs)
    os.makedirs(a.out, exist_ok=True)
    write_page(results, stats, a.out)
    print("wrote %s (%.0f s)" % (os.path.join(a.out, "implex_accuracy.md"), stats["elapsed"]),
          file=sys.stderr)


if __name__ == "__main__":
    main()
