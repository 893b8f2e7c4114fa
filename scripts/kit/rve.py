#!/usr/bin/env python3
"""The `rve run` runner of every study, and the scene writer for hosts.

- scenes: `set_args` (a study's edits as `rve`'s own `--set KEY=VALUE`: the one scene
  editor, the command line's; `toml_value` writes a value), `line_path`; `write_scene`
  (a scene file with the same edits, for a host that reads a file: a C program, ccx);
- running: `run_rve` (one `rve run` with its response rows, status and wall time),
  `read_response`, `Runner` (variants run a few times each, with median timings, and
  `rve mesh --json` statistics).

Command line, for shell studies (studies/paper-examples/run):

    rve.py run NAME SCENE WORK [KEY=VALUE ...]   rve run into WORK/NAME with each
                                                 `--set KEY=VALUE`; writes
                                                 WORK/NAME/status ("ok" or the error)
    rve.py write-scene BASE OUT [KEY=VALUE ...]  BASE with the edits (VALUE in TOML) as OUT
"""

import csv
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RVE = os.path.join(ROOT, "target", "release", "rve")


# ------------------------------------------------------------------------------- scenes
# One scene editor: `rve`'s own `--set KEY=VALUE` (docs/cli.md), which every study passes
# its edits through, so a scene is edited as the command line edits it and no study writes
# TOML of its own.
def toml_value(v):
    """A Python value as a TOML value: `0.5`, `true`, `"lu"`, `[1, 2]`, `{ to = [...] }`.
    Floats are written with `repr`, which reads back to the same double. `None` is the
    empty value, with which `--set KEY=` removes the key."""
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"no TOML value for {v!r}")


def toml_key(k):
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else toml_value(k)


def set_args(edits):
    """`rve`'s `--set KEY=VALUE` arguments for the dotted keys of `edits`
    ("geometry.seed": 11, "materials.itz.penalty.lambda_p": 1e7, "path.0.increments": 40
    for the first `[[path]]`, "path": [{...}] for a new path, None to remove a key). Missing
    tables are created;
    the scene's validation refuses a misspelt key."""
    return [a for key, value in (edits or {}).items() for a in ("--set", f"{key}={toml_value(value)}")]


def line_path(to, increments):
    """A `[[path]]` list of one straight segment."""
    return [{"to": list(to), "increments": increments}]


def edit(doc, edits):
    """`doc` (a parsed scene) with the dotted `edits` applied as `--set` applies them: a
    missing table is created, a number indexes an array (`path.0.increments`)."""
    for key, value in (edits or {}).items():
        *parents, last = key.split(".")
        node = doc
        for part in parents:
            node = node[int(part)] if isinstance(node, list) else node.setdefault(part, {})
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return doc


def is_table_array(v):
    return isinstance(v, list) and v and all(isinstance(x, dict) for x in v)


def toml_body(prefix, table, out):
    """Appends the TOML lines of `table` (whose header the caller wrote; `prefix` its
    dotted name, None at the top): its values, then its tables and arrays of tables."""
    values = [(k, v) for k, v in table.items() if not isinstance(v, dict) and not is_table_array(v)]
    nested = [(k, v) for k, v in table.items() if isinstance(v, dict) or is_table_array(v)]
    out += [f"{toml_key(k)} = {toml_value(v)}" for k, v in values]
    for k, v in nested:
        name = toml_key(k) if prefix is None else f"{prefix}.{toml_key(k)}"
        if isinstance(v, dict):
            if not v or any(not isinstance(x, dict) and not is_table_array(x) for x in v.values()):
                out.append(f"\n[{name}]")
            toml_body(name, v, out)
        else:
            for item in v:
                out.append(f"\n[[{name}]]")
                toml_body(name, item, out)


def write_scene(base, out, edits=None):
    """Writes the scene file `base` with `edits` (`set_args`' dotted keys) to `out`, for a
    host that reads a scene file and so cannot take `--set` (a C program, ccx through
    MESORVE_SCENE_PATH). The file is parsed and written back (comments are not kept), so
    the edit is the key's, never a text substitution. Returns `out`."""
    with open(base, "rb") as f:
        doc = edit(tomllib.load(f), edits)
    lines = [f"# {os.path.basename(base)} with " + ", ".join(f"{k} = {toml_value(v)}"
                                                              for k, v in (edits or {}).items())]
    toml_body(None, doc, lines)
    with open(out, "w") as f:
        f.write("\n".join(lines).strip() + "\n")
    return out


# ------------------------------------------------------------------------------ running
class Run:
    """One `rve run`: `rows` (response.csv as floats; the increments before a failure),
    `ok`, `status` ("ok" or the last line of the error), `wall` (seconds), `returncode`
    and `stderr`."""

    def __init__(self, rows, ok, status, wall, returncode=0, stderr=""):
        self.rows, self.ok, self.status, self.wall = rows, ok, status, wall
        self.returncode, self.stderr = returncode, stderr


def read_response(out_dir):
    """response.csv of an `rve run --out out_dir` as a list of dicts of floats."""
    path = os.path.join(out_dir, "response.csv")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def run_rve(scene, out_dir, rve=RVE, extra=(), edits=None, cwd=None):
    """Runs `rve run SCENE --out OUT_DIR --quiet` with `edits` set (`set_args`) and reads
    its response."""
    t0 = time.perf_counter()
    p = subprocess.run([rve, "run", scene, "--out", out_dir, "--quiet", *set_args(edits), *extra],
                       capture_output=True, text=True, cwd=cwd)
    wall = time.perf_counter() - t0
    lines = [line for line in p.stderr.splitlines() if line.strip()]
    status = "ok" if p.returncode == 0 else (lines[-1] if lines else f"exit {p.returncode}")
    return Run(read_response(out_dir), p.returncode == 0, status, wall, p.returncode, p.stderr)


# ------------------------------------------------------------------- repeated runs
class Runner:
    """Runs variants of scenes REPEATS times each into `tmp` (deleted run by run), within a
    time `budget` per variant; counts the runs, their wall time and the increments the
    fast path answered."""

    def __init__(self, rve, tmp, repeats, budget):
        self.rve, self.tmp, self.repeats, self.budget = rve, tmp, repeats, budget
        self.count = 0
        self.wall = 0.0
        # Increments of the first run of every variant, and those the fast path answered.
        self.increments = 0
        self.fast = 0

    def mesh_stats(self, scene, edits=None):
        out = subprocess.run([self.rve, "mesh", scene, *set_args(edits), "--json"],
                             capture_output=True, text=True, check=True).stdout
        return json.loads(out)

    def run(self, name, base, edits):
        """Run a variant REPEATS times; return a dict with the rows and median timings.

        A run that fails (the solver gives up at some increment) is not repeated; its
        response.csv holds the increments before the failure, which are kept (`failed`
        holds the error message)."""
        totals, medians, rows, failed = [], [], None, None
        spent = 0.0
        for r in range(self.repeats):
            if r > 0 and spent > self.budget:
                break  # expensive variant: fewer repeats keep the study within minutes
            out = os.path.join(self.tmp, "%s.%d" % (name, r))
            run = run_rve(base, out, rve=self.rve, edits=edits)
            self.wall += run.wall
            spent += run.wall
            self.count += 1
            rr = run.rows
            shutil.rmtree(out, ignore_errors=True)
            if not run.ok:
                msg = run.status
                m = re.search(r"relative residual ([0-9.eE+-]+)", msg)
                failed = "solver gave up after increment %d (eps_xx = %.4g)%s" % (
                    len(rr), rr[-1]["eps_xx"] if rr else 0.0,
                    ", residual %s" % m.group(1) if m else ": " + msg)
                print("note: %s: %s" % (name, msg), file=sys.stderr)
            secs = [row["seconds"] for row in rr] or [0.0]
            totals.append(sum(secs))
            medians.append(statistics.median(secs))
            if rows is None:
                rows = rr
                self.increments += len(rr)
                self.fast += int(sum(row.get("fast", 0.0) for row in rr))
            elif any(a["sig_xx"] != b["sig_xx"] or a["iterations"] != b["iterations"]
                     for a, b in zip(rows, rr)):
                print("warning: %s is not reproducible across repeats" % name, file=sys.stderr)
            if failed:
                break
        return {
            "name": name, "scene": base, "edits": edits, "rows": rows, "failed": failed,
            "runs": len(totals), "total": statistics.median(totals), "total_min": min(totals),
            "total_max": max(totals), "per_inc": statistics.median(medians),
            "iterations": int(sum(r["iterations"] for r in rows)),
            "max_iterations": int(max([r["iterations"] for r in rows] or [0])),
            "max_substeps": int(max([r["substeps"] for r in rows] or [0])),
        }


# ---------------------------------------------------------------------- command line
def parse_value(text):
    """A TOML value given on the command line ("0.4", "\"lu\"", "[{to = [...]}]")."""
    return tomllib.loads(f"v = {text}")["v"]


def main(argv):
    if len(argv) >= 4 and argv[0] == "run":
        name, scene, work = argv[1:4]
        out = os.path.join(work, name)
        os.makedirs(out, exist_ok=True)
        extra = [a for item in argv[4:] for a in ("--set", item)]
        run = run_rve(scene, out, extra=extra)
        with open(os.path.join(out, "status"), "w") as f:
            f.write(run.status + "\n")
        print(f"{name:<28} {run.wall:6.2f} s  {run.status}", flush=True)
    elif len(argv) >= 3 and argv[0] == "write-scene":
        edits = {k: parse_value(v) for k, v in (item.split("=", 1) for item in argv[3:])}
        print(write_scene(argv[1], argv[2], edits))
    else:
        raise SystemExit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
