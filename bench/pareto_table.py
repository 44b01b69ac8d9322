#!/usr/bin/env python3
"""The Markdown table of bench/pareto.sh: per scene and signal, the default and each --error run
that traced more than the default, against the grid's front at the same bake time; writes each
report's plot to OUT/pareto_SCENE_SIGNAL.svg.
usage: pareto_table.py OUT SCENE... -- SIGNAL..."""
import json
import os
import re
import sys

out = sys.argv[1]
args = sys.argv[2:]
scenes, signals = args[:args.index("--")], args[args.index("--") + 1:]

print("| scene | signal | run | bake s | rays per vertex | E % | front's E % at that time | run / front | best grid run in that time |")
print("|---|---|---|---:|---:|---:|---:|---:|---|")
ratios, refused = [], []
for scene in scenes:
    name = os.path.splitext(scene)[0]
    for signal in signals:
        d = os.path.join(out, "%s_%s" % (name, signal))
        runs = json.load(open(os.path.join(d, "pareto.json")))["runs"]
        grid = [r for r in runs if r["series"] == "grid"]
        html = open(os.path.join(d, "report.html"), encoding="utf-8").read()
        m = re.search(r"<h2>Speed against error</h2>.*?(<svg.*?</svg>)", html, re.S)
        if m:
            with open(os.path.join(out, "pareto_%s_%s.svg" % (name, signal)), "w", encoding="utf-8") as f:
                f.write(m.group(1))
        default = next(r for r in runs if r["series"] == "default")
        for r in runs:
            if r["series"] == "grid":
                continue
            front = r["front_rms_percent"]
            ratio = r["rms_percent"] / front if front else None
            if r["series"] == "--error" and r["rays"] == default["rays"]:
                refused.append("%s %s %s" % (name, signal, r["label"]))
                continue
            if ratio:
                ratios.append((ratio, name, signal, r["label"]))
            under = [g for g in grid if g["seconds"] <= r["seconds"]]
            best = min(under, key=lambda g: g["rms_percent"]) if under else None
            best_text = "%s: %.3f%% in %.3g s" % (best["label"], best["rms_percent"], best["seconds"]) if best else "none"
            print("| %s | %s | %s | %.3g | %.0f | %.3f | %s | %s | %s |" % (
                name, signal, r["label"], r["seconds"], r["rays"] / r["vertices"], r["rms_percent"],
                "%.3f" % front if front else "faster than the grid", "%.3f" % ratio if ratio else "", best_text))
ratios.sort(reverse=True)
print()
print("Runs above the front by more than 10%%: %d of %d%s" % (
    sum(1 for w in ratios if w[0] > 1.10), len(ratios),
    "".join("; %s %s %s %.3f" % (w[1], w[2], w[3], w[0]) for w in ratios if w[0] > 1.10)) + ".")
print("--error runs that traced nothing more than the default (their target is below what vertex rays can reach): %d (%s)." % (
    len(refused), ", ".join(refused)))
