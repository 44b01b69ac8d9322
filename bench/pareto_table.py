#!/usr/bin/env python3
"""The Markdown table of bench/pareto.sh: per scene and signal, the default and each --error run
against the grid's front at the same bake time (--error runs with the same result at several
targets as one row, at the slowest of their times); writes each
report's plot to OUT/pareto_SCENE_SIGNAL.svg.
usage: pareto_table.py OUT SCENE... -- SIGNAL...   (pairs not run are left out)"""
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
        if not os.path.exists(os.path.join(d, "pareto.json")):
            continue  # a scene run for some signals only
        runs = json.load(open(os.path.join(d, "pareto.json")))["runs"]
        grid = [r for r in runs if r["series"] == "grid"]
        html = open(os.path.join(d, "report.html"), encoding="utf-8").read()
        m = re.search(r"<h2>Speed against error</h2>.*?(<svg.*?</svg>)", html, re.S)
        if m:
            with open(os.path.join(out, "pareto_%s_%s.svg" % (name, signal)), "w", encoding="utf-8") as f:
                f.write(m.group(1))
        default = next(r for r in runs if r["series"] == "default")
        # --error runs that traced the same rays to the same error are one result at several
        # targets (all below what the bake could reach): one row, its slowest time.
        rows = []
        for r in runs:
            if r["series"] == "grid":
                continue
            same = next((x for x in rows if x[0]["series"] == "--error" and r["series"] == "--error"
                         and x[0]["rays"] == r["rays"] and x[0]["rms_percent"] == r["rms_percent"]), None)
            if same:
                same.append(r)
            else:
                rows.append([r])
        for group in rows:
            r = max(group, key=lambda g: g["seconds"])
            front = r["front_rms_percent"]
            ratio = r["rms_percent"] / front if front else None
            if r["series"] == "--error" and r["rays"] == default["rays"]:
                refused.append("%s %s %s" % (name, signal, r["label"]))
            if ratio:
                ratios.append((ratio, name, signal, r["label"]))
            label = r["label"] if len(group) == 1 else "--error " + ", ".join(g["label"].split()[-1] for g in group)
            under = [g for g in grid if g["seconds"] <= r["seconds"]]
            best = min(under, key=lambda g: g["rms_percent"]) if under else None
            best_text = "%s: %.3f%% in %.3g s" % (best["label"], best["rms_percent"], best["seconds"]) if best else "none"
            print("| %s | %s | %s | %.3g | %.0f | %.3f | %s | %s | %s |" % (
                name, signal, label, r["seconds"], r["rays"] / r["vertices"], r["rms_percent"],
                "%.3f" % front if front else "faster than the grid", "%.3f" % ratio if ratio else "", best_text))
ratios.sort(reverse=True)
print()
print("Runs above the front by more than 10%%: %d of %d%s" % (
    sum(1 for w in ratios if w[0] > 1.10), len(ratios),
    "".join("; %s %s %s %.3f" % (w[1], w[2], w[3], w[0]) for w in ratios if w[0] > 1.10)) + ".")
print("--error runs that traced nothing more than the default: %d%s." % (len(refused), "".join("; " + x for x in refused)))

# The grid's front of each scene and signal, as settings.
print()
for scene in scenes:
    name = os.path.splitext(scene)[0]
    for signal in signals:
        path = os.path.join(out, "%s_%s" % (name, signal), "pareto.json")
        if not os.path.exists(path):
            continue
        grid = sorted((r for r in json.load(open(path))["runs"] if r["series"] == "grid"), key=lambda r: (r["seconds"], r["rms_percent"]))
        front, best = [], float("inf")
        for r in grid:
            if r["rms_percent"] < best:
                front.append(r["label"])
                best = r["rms_percent"]
        print("front, %s %s: %s" % (name, signal, ", ".join(front)))
