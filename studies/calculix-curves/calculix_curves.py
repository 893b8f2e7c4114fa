#!/usr/bin/env python3
"""Draws docs/calculix_curves.svg: the CalculiX specimens' force against the end
displacement, from the "force-displacement (every increment)" tables of docs/calculix.md
(written by `MESORVE_CCX_FULL=1 MESORVE_CCX_STUDY=1 scripts/test-calculix`). Standard library
only; run it after regenerating docs/calculix.md.

Usage: scripts/calculix-curves [CALCULIX_MD [OUT_SVG]]
"""
import math
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RUNS = [  # (table name in calculix.md, legend)
    ("consistent", "strip, implicit (specimen.inp)"),
    ("band", "band, ductile ITZ (specimen_band.inp)"),
    ("weakened", "weakened strip, IMPL-EX (specimen_weak.inp)"),
    ("notch", "notched strip, IMPL-EX (specimen_notch.inp)"),
]
COLORS = ["#1f77b4", "#2ca02c", "#d62728", "#9467bd"]


def tables(path):
    """{run: [(U, F)]} of the force-displacement tables."""
    out, current = {}, None
    with open(path) as f:
        for line in f:
            m = re.match(r"(\w+): force-displacement \(every increment\)", line)
            if m:
                current = out.setdefault(m.group(1), [])
                continue
            if current is not None:
                cells = [c.strip() for c in line.strip().strip("|").split("|")]
                if len(cells) == 3 and re.match(r"^-?[0-9.]+(e[-+]?\d+)?$", cells[0]):
                    current.append((float(cells[1]), float(cells[2])))
                elif line.startswith("#") or (line.strip() and not line.startswith("|")):
                    current = None
    return out


def ticks(lo, hi, n=6):
    raw = (hi - lo) / n
    mag = 10 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 2.5, 5, 10) if raw <= m * mag)
    return [round(k * step, 12) for k in range(math.floor(lo / step), math.ceil(hi / step) + 1)]


def svg(series):
    W, H, L, R, T, B = 760, 440, 70, 290, 34, 48
    xs = [x for _, pts in series for x, _ in pts] + [0]
    ys = [y for _, pts in series for _, y in pts] + [0]
    xt, yt = ticks(min(xs), max(xs)), ticks(min(ys), max(ys))

    def px(x):
        return L + (x - xt[0]) / (xt[-1] - xt[0]) * (W - L - R)

    def py(y):
        return H - B - (y - yt[0]) / (yt[-1] - yt[0]) * (H - T - B)

    g = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" '
         'font-family="sans-serif" font-size="12">', f'<rect width="{W}" height="{H}" fill="white"/>',
         f'<text x="{L}" y="20" font-size="14">CalculiX specimens: tension, unloading, compression</text>']
    for t in xt:
        g.append(f'<line x1="{px(t):.1f}" y1="{T}" x2="{px(t):.1f}" y2="{H - B}" stroke="#e4e4e4"/>'
                 f'<text x="{px(t):.1f}" y="{H - B + 16}" text-anchor="middle">{t * 1e3:g}</text>')
    for t in yt:
        g.append(f'<line x1="{L}" y1="{py(t):.1f}" x2="{W - R}" y2="{py(t):.1f}" stroke="#e4e4e4"/>'
                 f'<text x="{L - 6}" y="{py(t) + 4:.1f}" text-anchor="end">{t:g}</text>')
    g.append(f'<rect x="{L}" y="{T}" width="{W - L - R}" height="{H - T - B}" fill="none" stroke="black"/>')
    g.append(f'<line x1="{px(0):.1f}" y1="{T}" x2="{px(0):.1f}" y2="{H - B}" stroke="#999"/>')
    g.append(f'<line x1="{L}" y1="{py(0):.1f}" x2="{W - R}" y2="{py(0):.1f}" stroke="#999"/>')
    g.append(f'<text x="{(L + W - R) / 2}" y="{H - 10}" text-anchor="middle">end displacement U (µm)</text>')
    g.append(f'<text x="16" y="{(T + H - B) / 2}" text-anchor="middle" '
             f'transform="rotate(-90 16 {(T + H - B) / 2})">force F (N)</text>')
    for k, (label, pts) in enumerate(series):
        c = COLORS[k % len(COLORS)]
        line = " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in [(0.0, 0.0)] + pts)
        g.append(f'<polyline points="{line}" fill="none" stroke="{c}" stroke-width="1.6"/>')
        ly = T + 14 + 18 * k
        g.append(f'<line x1="{W - R + 10}" y1="{ly - 4}" x2="{W - R + 34}" y2="{ly - 4}" stroke="{c}" '
                 f'stroke-width="2"/><text x="{W - R + 40}" y="{ly}">{label}</text>')
    g.append("</svg>")
    return "\n".join(g) + "\n"


def main():
    md = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs/calculix.md")
    out = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "docs/calculix_curves.svg")
    found = tables(md)
    series = []
    for name, label in RUNS:
        if not found.get(name):
            sys.exit(f"calculix-curves: no force-displacement table `{name}` in {md}")
        series.append((label, found[name]))
    with open(out, "w") as f:
        f.write(svg(series))
    print(f"{out}: " + ", ".join(f"{n} {len(found[n])} points" for n, _ in RUNS))


if __name__ == "__main__":
    main()
