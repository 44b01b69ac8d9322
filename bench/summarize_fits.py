#!/usr/bin/env python3
"""Markdown table from bench/fit_table.sh's reports: python3 bench/summarize_fits.py OUT_DIR"""
import json, pathlib, sys

COARSE = {"conference", "house_on_site", "cornell_box", "sibenik"}
rows = []
for p in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    r = json.loads(p.read_text())
    r["name"] = pathlib.Path(r["input"]).stem
    rows.append(r)
print("| scene | signal | triangles | samples | E_point | E_avg | E_lsq (α=0) | E(α=0.1) | E_default | kept | "
      "rays s (vertices + samples) | solve s (default) | solve MiB | default ≤ point | coarse: default ≤ E(0.1) |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|")
for r in sorted(rows, key=lambda r: (r["signal"], r["triangles"])):
    e = [r["e_point_percent"], r["e_avg_percent"], r["e_lsq_percent"], r["e_alpha_percent"], r["e_default_percent"]]
    coarse = ("yes" if e[4] <= e[3] else "no") if r["name"] in COARSE else ""
    print(f"| {r['name']} | {r['signal']} | {r['triangles']} | {r['samples']} | {e[0]:.3f} | {e[1]:.3f} | {e[2]:.3f} | "
          f"{e[3]:.3f} | **{e[4]:.3f}** | {100 * r['kept_correction']:.0f}% | "
          f"{r['seconds_rays_vertices']:.2f} + {r['seconds_rays_samples']:.2f} | {r['seconds_solve_default']:.3f} | "
          f"{r['solve_memory_mib_default']:.1f} | {'yes' if e[4] <= e[0] else 'no'} | {coarse} |")

def count(pred, among=None):
    return sum(1 for r in rows if (among is None or r["name"] in among) and pred(r))

n = len(rows)
nc = count(lambda r: True, COARSE)
print()
print(f"E_default <= E_point on {count(lambda r: r['e_default_percent'] <= r['e_point_percent'])} of {n} rows; "
      f"E_default <= E(0.1) on {count(lambda r: r['e_default_percent'] <= r['e_alpha_percent'])} of {n}, "
      f"on {count(lambda r: r['e_default_percent'] <= r['e_alpha_percent'], COARSE)} of the {nc} coarse rows; "
      f"E_default <= min(E_point, E(0.1)) on {count(lambda r: r['e_default_percent'] <= min(r['e_point_percent'], r['e_alpha_percent']))}.")
