#!/usr/bin/env python3
"""Markdown table from bench/fit_table.sh's reports: python3 bench/summarize_fits.py OUT_DIR"""
import json, pathlib, sys

rows = []
for p in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    r = json.loads(p.read_text())
    rows.append(r)
print("| scene | signal | triangles | samples | E_point | E_avg | E_lsq (α=0) | E(α=0.1) | rays s (vertices + samples) | solve s (α=0.1) | solve MiB | order holds |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
for r in sorted(rows, key=lambda r: (r["signal"], r["triangles"])):
    e = [r["e_point_percent"], r["e_avg_percent"], r["e_lsq_percent"], r["e_alpha_percent"]]
    holds = "yes" if e[2] <= e[3] <= e[1] <= e[0] else "no: " + ", ".join(
        n for n, ok in [("lsq>α", e[2] <= e[3]), ("α>avg", e[3] <= e[1]), ("avg>point", e[1] <= e[0])] if not ok)
    name = pathlib.Path(r["input"]).stem
    print(f"| {name} | {r['signal']} | {r['triangles']} | {r['samples']} | {e[0]:.3f} | {e[1]:.3f} | {e[2]:.3f} | {e[3]:.3f} | "
          f"{r['seconds_rays_vertices']:.2f} + {r['seconds_rays_samples']:.2f} | {r['seconds_solve_alpha']:.3f} | "
          f"{r['solve_memory_mib_alpha']:.1f} | {holds} |")

def count(pred):
    return sum(1 for r in rows if pred(r))

n = len(rows)
print()
print(f"E_lsq <= E_avg on {count(lambda r: r['e_lsq_percent'] <= r['e_avg_percent'])} of {n} rows; "
      f"E_lsq <= E_point on {count(lambda r: r['e_lsq_percent'] <= r['e_point_percent'])}; "
      f"E(alpha) < E_point on {count(lambda r: r['e_alpha_percent'] < r['e_point_percent'])}; "
      f"E(alpha) <= E_avg on {count(lambda r: r['e_alpha_percent'] <= r['e_avg_percent'])}; "
      f"the full order on {count(lambda r: r['e_lsq_percent'] <= r['e_alpha_percent'] <= r['e_avg_percent'] <= r['e_point_percent'])}.")
