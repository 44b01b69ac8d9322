#!/usr/bin/env python3
"""How much of what linear interpolation misses is the unshadowed transfer's curvature alone.

At a point inside a face the truth uses the normalised interpolation of the corner normals, as
eval's reference does, and t_u(n) is curved in n; the asset interpolates t_u at the corners. With
<t_u(a), t_u(b)> = sum_l A_l^2 (2l+1)/(4 pi) P_l(a.b), the squared error needs no SH basis. Prints
the surface RMS of that error in percent of ||t_unshadowed|| (order 4), per mesh.

usage: PYTHONPATH=build/python /usr/bin/python3 bench/unshadowed_curvature.py MESH...
"""
import sys

import numpy as np
import prtsub

A = [np.pi, 2 * np.pi / 3, np.pi / 4, 0.0]  # the clamped cosine's bands 0-3


def kernel(c):
    p = [np.ones_like(c), c, 0.5 * (3 * c * c - 1), 0.5 * (5 * c ** 3 - 3 * c)]
    return sum(A[l] ** 2 * (2 * l + 1) / (4 * np.pi) * p[l] for l in range(4))


def curvature_error(path):
    m = prtsub.load_mesh(path)
    pos = np.asarray(m.positions)[np.asarray(m.vertex_position)]
    nrm = np.asarray(m.normals)
    f = np.asarray(m.faces).astype(np.int64)
    area = np.linalg.norm(np.cross(pos[f[:, 1]] - pos[f[:, 0]], pos[f[:, 2]] - pos[f[:, 0]]), axis=1) / 2
    n = [nrm[f[:, k]] for k in range(3)]
    k01, k02, k12 = kernel((n[0] * n[1]).sum(1)), kernel((n[0] * n[2]).sum(1)), kernel((n[1] * n[2]).sum(1))
    k1 = kernel(np.ones(1))[0]
    grid = 6
    bary = [(1 - (i + 1 / 3) / grid - (j + 1 / 3) / grid, (i + 1 / 3) / grid, (j + 1 / 3) / grid)
            for i in range(grid) for j in range(grid - i) if (i + 1 / 3) / grid + (j + 1 / 3) / grid < 1]
    total = 0.0
    for b in bary:
        p = b[0] * n[0] + b[1] * n[1] + b[2] * n[2]
        p /= np.linalg.norm(p, axis=1, keepdims=True)
        e2 = (k1 - 2 * sum(b[k] * kernel((p * n[k]).sum(1)) for k in range(3))
              + (b[0] ** 2 + b[1] ** 2 + b[2] ** 2) * k1 + 2 * (b[0] * b[1] * k01 + b[0] * b[2] * k02 + b[1] * b[2] * k12))
        total += (area * np.maximum(e2, 0)).sum() / len(bary)
    return 100 * np.sqrt(total / area.sum() / k1)


if __name__ == "__main__":
    for path in sys.argv[1:]:
        print("%s: the unshadowed transfer's curvature inside the faces, interpolated: RMS %.3f%% of ||t_unshadowed||"
              % (path.split("/")[-1], curvature_error(path)))
