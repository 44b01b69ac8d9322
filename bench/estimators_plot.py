#!/usr/bin/env python3
"""Log-log panels of error against rays per vertex, one per scene, one line per estimator, as SVG.

Reads the rows of bench/estimators_vertex.py (scene estimator rays error) or of bench/estimators.sh
(scene estimator rays eval_% ...; the header line is skipped) from standard input.

usage: /usr/bin/python3 bench/estimators_plot.py TITLE < rows > figure.svg
"""
import math
import sys

COLOURS = {"cv": "#1f77b4", "mc": "#d62728", "pls": "#2ca02c", "pls-cv": "#9467bd"}
W, H, PAD_L, PAD_B, PAD_T, PAD_R = 250, 230, 46, 34, 26, 8


def main():
    title = sys.argv[1]
    data = {}
    for line in sys.stdin:
        f = line.split()
        if len(f) < 4 or f[0] == "scene":
            continue
        data.setdefault(f[0].rsplit(".", 1)[0], {}).setdefault(f[1], []).append((int(f[2]), float(f[3])))
    scenes = list(data)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W * len(scenes) + 20}" height="{H + 40}" font-family="sans-serif" font-size="11">',
           f'<text x="6" y="14" font-size="13">{title}</text>']
    for i, scene in enumerate(scenes):
        x0 = i * W
        pts = [p for series in data[scene].values() for p in series]
        xlo, xhi = math.log10(min(p[0] for p in pts)), math.log10(max(p[0] for p in pts))
        ylo, yhi = math.floor(math.log10(min(p[1] for p in pts))), math.ceil(math.log10(max(p[1] for p in pts)))
        fx = lambda r: x0 + PAD_L + (math.log10(r) - xlo) / (xhi - xlo) * (W - PAD_L - PAD_R)
        fy = lambda e: PAD_T + 14 + (yhi - math.log10(e)) / (yhi - ylo) * (H - PAD_T - PAD_B)
        out.append(f'<text x="{x0 + PAD_L}" y="{PAD_T + 8}">{scene}</text>')
        out.append(f'<rect x="{x0 + PAD_L}" y="{PAD_T + 14}" width="{W - PAD_L - PAD_R}" height="{H - PAD_T - PAD_B}" fill="none" stroke="#888"/>')
        for d in range(ylo, yhi + 1):
            for m in (1, 2, 5):
                v = m * 10.0 ** d
                if ylo <= math.log10(v) <= yhi:
                    y = fy(v)
                    out.append(f'<line x1="{x0 + PAD_L}" x2="{x0 + W - PAD_R}" y1="{y:.1f}" y2="{y:.1f}" stroke="#ddd"/>')
                    out.append(f'<text x="{x0 + PAD_L - 4}" y="{y + 4:.1f}" text-anchor="end">{v:g}</text>')
        last = -1e9
        for r in sorted({p[0] for p in pts}, reverse=True):  # the largest always labelled; none crowded
            x = fx(r)
            if abs(last - x) >= 28:
                out.append(f'<text x="{x:.1f}" y="{H + 8}" text-anchor="middle">{r}</text>')
                last = x
        out.append(f'<text x="{x0 + W / 2}" y="{H + 24}" text-anchor="middle">rays per vertex</text>')
        for name, series in data[scene].items():
            series.sort()
            path = " ".join(f"{fx(r):.1f},{fy(e):.1f}" for r, e in series)
            c = COLOURS.get(name, "#000")
            out.append(f'<polyline points="{path}" fill="none" stroke="{c}" stroke-width="1.6"/>')
            out += [f'<circle cx="{fx(r):.1f}" cy="{fy(e):.1f}" r="2.5" fill="{c}"/>' for r, e in series]
    for j, (name, c) in enumerate(COLOURS.items()):
        out.append(f'<text x="{W * len(scenes) - 300 + 70 * j}" y="14" fill="{c}">&#9632; {name}</text>')
    out.append("</svg>")
    print("\n".join(out))


if __name__ == "__main__":
    main()
