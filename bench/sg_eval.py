#!/usr/bin/env python3
"""Spherical-Gaussian lobes judged by `prtsub eval`, as SH assets are (issue 15, point 3).

For each mesh: a point-valued order-4 bake at RAYS rays (the SH-4 row; with band 3 set to zero, what an order-3
asset gives, the SH-3 row), and lobes from prtsub.sg_transfer at the same rays, converted to order-4 SH by
Funk-Hecke (prtsub.sg_to_sh: exact for every order-4 light) and written into a copy of the SH-4 asset. Each
asset goes to `prtsub eval --rays 8192 --points 10000` against one fixed reference: surface RMS error under
every order-4 light, interpolation included.

usage: PYTHONPATH=build/python /usr/bin/python3 bench/sg_eval.py BUILD OUT RAYS MESH...
"""
import json
import os
import subprocess
import sys

import numpy as np
import prtsub


def evaluate(build, asset, source):
    report = asset + ".eval.json"
    subprocess.run([os.path.join(build, "prtsub"), "eval", asset, "--source", source, "--rays", "8192", "--points", "10000",
                    "--report", report], check=True, stdout=subprocess.DEVNULL)
    return json.load(open(report))["rms_percent"]


def main():
    build, out, rays, meshes = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]
    os.makedirs(out, exist_ok=True)
    print(f"{'mesh':16s} {'SH-3 (9)':>9s} {'SG-9 (9)':>9s} {'SG-12 (12)':>10s} {'SG-12 signed':>12s} {'SH-4 (16)':>9s}")
    for path in meshes:
        name = os.path.basename(path).rsplit(".", 1)[0]
        mesh = prtsub.load_mesh(path)
        row = {}
        for label, lobes, nn in (("SH-3", 0, False), ("SG-9", 9, True), ("SG-12", 12, True), ("SG-12 signed", 12, False),
                                 ("SH-4", 0, False)):
            a = prtsub.bake(mesh, order=4, rays=rays, fit="point", source=path)
            if label == "SH-3":  # band 3 dropped: what an order-3 asset gives under order-4 lights
                np.asarray(a.transfer)[:, 9:] = 0
            if lobes:
                np.asarray(a.transfer)[:] = prtsub.sg_to_sh(prtsub.sg_transfer(mesh, lobes, rays=rays, non_negative=nn), 4)
            asset = os.path.join(out, f"{name}_{label.replace(' ', '_').lower()}.ply")
            prtsub.save(a, asset)
            row[label] = evaluate(build, asset, path)
        print(f"{name:16s} {row['SH-3']:9.3f} {row['SG-9']:9.3f} {row['SG-12']:10.3f} {row['SG-12 signed']:12.3f} {row['SH-4']:9.3f}",
              flush=True)


if __name__ == "__main__":
    main()
