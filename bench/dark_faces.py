#!/usr/bin/env python3
"""Faces no light reaches (issue 12, point 3): in a baked asset, the faces whose three corners
all have transfer zero (every coefficient, or AO, below 1e-6 in magnitude), their share of the
area, and the connected pieces (faces joined through shared positions) that hold them: whether
they could be collapsed on their own or share their pieces with lit faces.
usage: PYTHONPATH=build/python /usr/bin/python3 bench/dark_faces.py ASSET"""
import sys

import numpy as np
import prtsub

a = prtsub.load(sys.argv[1])
p = np.asarray(a.vertices, dtype=np.float64)
tri = np.asarray(a.faces)
t = np.asarray(a.transfer) if a.transfer is not None else np.asarray(a.ao).reshape(-1, 1)
area = 0.5 * np.linalg.norm(np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]), axis=1)
dark = np.abs(t).max(axis=1)[tri].max(axis=1) < 1e-6

# Pieces: union-find over positions (render vertices split at creases share a position).
_, position = np.unique(p, axis=0, return_inverse=True)
position = position.reshape(-1)
parent = np.arange(position.max() + 1)


def find(x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


for u, v, w in position[tri]:
    for x, y in ((u, v), (v, w)):
        rx, ry = find(x), find(y)
        if rx != ry:
            parent[rx] = ry
piece = np.array([find(position[f[0]]) for f in tri])
with_dark = set(piece[dark])
all_dark = [c for c in with_dark if dark[piece == c].all()]
print('%s: %d faces, %d dark (%.1f%% of the area); %d pieces, %d with dark faces, %d of them all dark (%d faces)'
      % (sys.argv[1], len(tri), dark.sum(), 100 * area[dark].sum() / area.sum(), len(set(piece)), len(with_dark),
         len(all_dark), sum(int((piece == c).sum()) for c in all_dark)))
