"""The plotter of every study figure: curves and points on linear or log axes, written as
plain SVG (no dependency; a figure is a text file that diffs).

    from kit.plot import COLOURS, svg_plot
    svg_plot("out.svg", "title", "x label", "y label",
             [("label", COLOURS[0], [(x, y, "point label"), ...], True)], logy=True)
"""

import math

def svg_plot(path, title, xlabel, ylabel, series, logx=False, logy=False, w=640, h=420,
             legend=160, hlines=(), marks=()):
    """series: list of (label, colour, [(x, y, point_label)], draw_line[, marker radius,
    default 3, 0 for none]); draw_line "dashed" draws it dashed. hlines: (y, label), dotted
    lines across the plot; marks: (x, y, label), open circles with a label. A linear axis
    whose values are all positive starts at 0 when the smallest is below 30 % of the
    largest; the lines x = 0 and y = 0 are drawn when inside the plot."""
    ml, mr, mt, mb = 70, legend, 40, 50
    pw, ph = w - ml - mr, h - mt - mb
    xs = [p[0] for s in series for p in s[2]] + [m[0] for m in marks]
    ys = [p[1] for s in series for p in s[2]] + [m[1] for m in marks] + [y for y, _ in hlines]
    fx = (lambda v: math.log10(v)) if logx else (lambda v: v)
    fy = (lambda v: math.log10(v)) if logy else (lambda v: v)

    def span(vals, f, log):
        lo, hi = min(f(v) for v in vals), max(f(v) for v in vals)
        if log:
            return math.floor(lo), math.ceil(hi) if math.ceil(hi) > math.floor(lo) else math.floor(lo) + 1
        pad = 0.05 * (hi - lo or 1.0)
        return (0.0 if lo >= 0 and lo < 0.3 * hi else lo - pad), hi + pad

    x0, x1 = span(xs, fx, logx)
    y0, y1 = span(ys, fy, logy)
    X = lambda v: ml + (fx(v) - x0) / (x1 - x0) * pw
    Y = lambda v: mt + ph - (fy(v) - y0) / (y1 - y0) * ph
    o = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" '
         'font-family="sans-serif" font-size="12">' % (w, h),
         '<rect width="100%" height="100%" fill="white"/>',
         '<text x="%d" y="22" font-size="14">%s</text>' % (ml, title),
         '<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="#333"/>' % (ml, mt, pw, ph)]

    def ticks(a, b, log):
        if log:
            return [10.0 ** k for k in range(int(a), int(b) + 1)]
        step = 10 ** math.floor(math.log10((b - a) / 5))
        for m in (1, 2, 5, 10):
            if (b - a) / (m * step) <= 6:
                step *= m
                break
        t = math.ceil(a / step) * step
        out = []
        while t <= b + 1e-12:
            out.append(t)
            t += step
        return out

    for t in ticks(x0, x1, logx):
        x = X(t)
        o.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#ddd"/>' % (x, mt, x, mt + ph))
        o.append('<text x="%.1f" y="%d" text-anchor="middle">%s</text>' % (x, mt + ph + 16, "%g" % t))
    for t in ticks(y0, y1, logy):
        y = Y(t)
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ddd"/>' % (ml, y, ml + pw, y))
        o.append('<text x="%d" y="%.1f" text-anchor="end">%s</text>' % (ml - 6, y + 4, "%g" % t))
    o.append('<text x="%d" y="%d" text-anchor="middle">%s</text>' % (ml + pw / 2, h - 10, xlabel))
    o.append('<text transform="translate(16,%d) rotate(-90)" text-anchor="middle">%s</text>'
             % (mt + ph / 2, ylabel))
    if not logy and y0 < 0 < y1:
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#999"/>' % (ml, Y(0), ml + pw, Y(0)))
    if not logx and x0 < 0 < x1:
        o.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#999"/>' % (X(0), mt, X(0), mt + ph))
    for y, label in hlines:
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="black" stroke-dasharray="2 3"/>'
                 '<text x="%d" y="%.1f">%s</text>' % (ml, Y(y), ml + pw, Y(y), ml + 4, Y(y) - 4, label))
    for k, (label, colour, pts, line, *radius) in enumerate(series):
        dash = ' stroke-dasharray="6 4"' if line == "dashed" else ""
        if line and len(pts) > 1:
            o.append('<polyline fill="none" stroke="%s" stroke-width="1.5"%s points="%s"/>'
                     % (colour, dash, " ".join("%.1f,%.1f" % (X(p[0]), Y(p[1])) for p in pts)))
        for p in pts:
            if (radius or [3])[0]:
                o.append('<circle cx="%.1f" cy="%.1f" r="%g" fill="%s"/>'
                         % (X(p[0]), Y(p[1]), (radius or [3])[0], colour))
            if p[2]:
                o.append('<text x="%.1f" y="%.1f" font-size="10">%s</text>'
                         % (X(p[0]) + 5, Y(p[1]) - 5, p[2]))
        ly = mt + 14 + 18 * k
        o.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"%s/>'
                 % (ml + pw + 10, ly - 4, ml + pw + 30, ly - 4, colour, dash))
        o.append('<text x="%d" y="%d">%s</text>' % (ml + pw + 34, ly, label))
    for x, y, label in marks:
        o.append('<circle cx="%.1f" cy="%.1f" r="4.5" fill="none" stroke="black"/>'
                 '<text x="%.1f" y="%.1f" font-size="11">%s</text>'
                 % (X(x), Y(y), X(x) + 7, Y(y) - 6, label))
    o.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(o) + "\n")


COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f"]
