"""The project's toolkit for studies and CI stages: standard library only.

- `kit.ccx`: the CalculiX runner (find or build ccx, stage the library as libRVE.so, run
  a deck with the environment the UMAT reads, time it, check "Job finished") and the
  readers of ccx's .dat, .sta and .cvg files;
- `kit.rve`: the `rve run` runner (scene edits as `--set KEY=VALUE`, response.csv read
  back, repeated runs with median timings) and the scene writer for hosts that read a
  scene file (C, ccx) and so cannot take `--set`;
- `kit.plot`: the plain-SVG plotter of every figure;
- `kit.provenance`: where and when a study ran, in the sentence every generated page uses.

From a program in the repository (a study in studies/NAME/ or a stage in scripts/):

    ROOT = Path(__file__).resolve().parents[2]      # parents[1] from scripts/
    sys.path.insert(0, str(ROOT / "scripts"))
    from kit import ccx, plot, rve

Each module also runs as a command (`python3 scripts/kit/ccx.py run ...`) for shell
stages; the modules import nothing from each other, so both ways work. scripts/README.md
lists the API.
"""

import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def pct(x, digits=2):
    """A fraction as a percentage with `digits` significant digits: 0.0064 -> "0.64 %"."""
    return f"{100 * x:.{digits}g} %"


def ms(x):
    """Seconds as milliseconds for a table cell: two significant digits below 0.1 ms, one
    decimal below 10 s, none above."""
    if 1e3 * x < 0.1:
        return "%.2g" % (1e3 * x)
    return "%.1f" % (1e3 * x) if x < 10 else "%.0f" % (1e3 * x)
