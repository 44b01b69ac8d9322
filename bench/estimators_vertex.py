#!/usr/bin/env python3
"""The estimators' own error at the vertices, without interpolation (issue 15, point 1).

bench/estimators.sh judges whole assets on the surface, where a coarse mesh's interpolation error
can hide the estimator. This judges each asset's vertex values against one reference asset of the
same scene, baked with point values at many rays and another seed (so no estimator shares its
directions): RMS over render vertices of |t - t_ref| in percent of ||t_unshadowed||.

usage: PYTHONPATH=build/python /usr/bin/python3 bench/estimators_vertex.py OUT SCENE_STEM REFERENCE.ply
       (OUT holds bench/estimators.sh's assets, named STEM_ESTIMATOR_RAYS.ply)
"""
import glob
import os
import sys

import numpy as np
import prtsub

UNSHADOWED_NORM = np.sqrt(sum(a * a * (2 * l + 1) / (4 * np.pi) for l, a in enumerate([np.pi, 2 * np.pi / 3, np.pi / 4, 0.0])))


def main():
    out, stem, reference = sys.argv[1:4]
    ref = np.asarray(prtsub.load(reference).transfer)
    rows = []
    for path in glob.glob(os.path.join(out, f"{stem}_*.ply")):
        estimator, rays = os.path.basename(path)[len(stem) + 1:-4].rsplit("_", 1)
        t = np.asarray(prtsub.load(path).transfer)
        if t.shape != ref.shape:
            sys.exit(f"{path}: {t.shape} values against the reference's {ref.shape}")
        err = np.sqrt(np.mean(np.sum((t - ref) ** 2, axis=1))) / UNSHADOWED_NORM * 100
        rows.append((estimator, int(rays), err))
    for estimator, rays, err in sorted(rows):
        print(f"{stem:16s} {estimator:8s} {rays:6d} {err:9.3f}")


if __name__ == "__main__":
    main()
