#!/usr/bin/env python3
"""Prints the Markdown tables of BENCHMARKS.md (issue 4) from the outputs of bench/refine.sh.
usage: summarize.py OUT_DIR [--scaling-only | --estimates-only | --batch-only]   (--scaling-only: bench/refine_scaling.sh's tables)"""
import json
import math
import os
import sys

out = sys.argv[1]
scaling_only = "--scaling-only" in sys.argv[2:]
estimates_only = "--estimates-only" in sys.argv[2:]
batch_only = "--batch-only" in sys.argv[2:]


def load(path):
    with open(path) as f:
        return json.load(f)


def print_scaling():
    for name, rays in (("scaling", 64), ("scaling256", 256)):
        print("\n### Refinement time at four budgets (teapot, 15,704 triangles in, %d rays per vertex)\n" % rays)
        print("| budget | splits | refine s | tracing new vertices s | overhead s | overhead % | overhead / (T log2 T) ns | overhead / (splits log2 T) ns |")
        print("|---:|---:|---:|---:|---:|---:|---:|---:|")
        for T in (25000, 50000, 100000, 200000):
            r = load(os.path.join(out, "%s_%d.json" % (name, T)))
            total, traced = r["seconds_refine"], r["seconds_refine_rays"]
            over = total - traced
            n = r["splits"]
            print("| %d | %d | %.3f | %.3f | %.3f | %.1f | %.1f | %.1f |" % (T, n, total, traced, over, 100 * over / total,
                  1e9 * over / (T * math.log2(T)), 1e9 * over / (n * math.log2(T))))


def print_batch():
    print("\n### Batch size (64x the input, 64 rays per vertex)\n")
    print("| scene | batch | refine s | tracing s | batches | RMS % |")
    print("|---|---:|---:|---:|---:|---:|")
    for n in ("house_on_site", "spot_on_ground"):
        for b in (16, 64, 256, 1024, 4096):
            r = load(os.path.join(out, "batch_%s_%d.json" % (n, b)))
            e = load(os.path.join(out, "batch_eval_%s_%d.json" % (n, b)))
            print("| %s | %d | %.3f | %.3f | %d | %.3f |" % (n, b, r["seconds_refine"], r["seconds_refine_rays"], r["batches"], e["rms_percent"]))


def rows(d):
    return load(os.path.join(d, "results.json"))["runs"]


if scaling_only:
    print_scaling()
    sys.exit(0)
if batch_only:
    print_batch()
    sys.exit(0)


print("### Estimates: RMS error (%) by scene and budget\n")
est_dir = os.path.join(out, "estimates")
estimates = ["relative", "shadow", "curvature", "length", "probe", "root"]
default = "root"
print("| scene | input | budget | uniform | " + " | ".join(estimates) + " | best |")
print("|---|---:|---:|---:|" + "---:|" * len(estimates) + "---|")
wins = {e: 0 for e in estimates}
ratios = {e: [] for e in estimates}
worse_than_uniform = []
for scene in sorted(d for d in os.listdir(est_dir) if os.path.isdir(os.path.join(est_dir, d))):
    rs = rows(os.path.join(est_dir, scene))
    base = [r for r in rs if r["method"] == "none"][0]
    uni = {r["triangles"]: r["rms_percent"] for r in rs if r["method"] == "uniform"}
    counts = sorted({r["triangles"] for r in rs if r["method"] == "adaptive"})
    for c in counts:
        by = {r["estimate"]: r["rms_percent"] for r in rs
              if r["method"] == "adaptive" and r["triangles"] == c and r.get("fit", "point") == "point"}
        best = min(by, key=by.get)
        wins[best] += 1
        for e in estimates:
            ratios[e].append(by[e] / by[best])
        u = uni.get(c)
        if u is not None and by[default] > u:
            worse_than_uniform.append((scene, c, by[default], u))
        cells = " | ".join(("**%.3f**" if e == best else "%.3f") % by[e] for e in estimates)
        print("| %s | %d | %d | %s | %s | %s |" % (scene, base["triangles"], c, "%.3f" % u if u is not None else "", cells, best))
print()
print("Wins: " + ", ".join("%s %d" % (e, wins[e]) for e in estimates) + ".  ")
print("Geometric mean of error relative to the best estimate: " +
      ", ".join("%s %.3f" % (e, math.exp(sum(math.log(x) for x in ratios[e]) / len(ratios[e]))) for e in estimates) + ".")
if worse_than_uniform:
    print("\nAdaptive (%s) worse than uniform: " % default + "" + "; ".join("%s at %d: %.3f vs %.3f" % w for w in worse_than_uniform))

if estimates_only:
    sys.exit(0)

print("\n### Targets: uniform level 3 against adaptive at the same count\n")
print("| scene | triangles | uniform RMS % | adaptive (length) RMS % | ratio | adaptive (root, the default) RMS % | ratio | best estimate | its ratio | noise floor % |")
print("|---|---:|---:|---:|---:|---:|---:|---|---:|---:|")
tdir = os.path.join(out, "targets")
for scene in sorted(os.listdir(tdir)):
    j = load(os.path.join(tdir, scene, "results.json"))
    rs = j["runs"]
    u3 = max((r for r in rs if r["method"] == "uniform"), key=lambda r: r["triangles"])
    ad = {r["estimate"]: r["rms_percent"] for r in rs if r["method"] == "adaptive" and r["triangles"] == u3["triangles"]}
    best = min(ad, key=ad.get)
    print("| %s | %d | %.3f | %.3f | %.2f | %.3f | %.2f | %s | %.2f | %.3f |" % (scene, u3["triangles"], u3["rms_percent"], ad["length"],
          ad["length"] / u3["rms_percent"], ad["root"], ad["root"] / u3["rms_percent"], best, ad[best] / u3["rms_percent"], j["noise_floor_percent"]))

print_scaling()

print_batch()
