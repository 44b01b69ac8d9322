#!/usr/bin/env python3
"""Faces no light reaches (issue 12, point 3): in a baked asset, the faces whose three corners
all have transfer zero (every coefficient below 1e-6 in magnitude), their share of the area, and
the connected pieces (faces joined through shared positions) that hold them: whether they could
be collapsed on their own or share their pieces with lit faces. Reads prtsub's binary PLY assets
(float vertex properties x y z, nx ny nz, t0.., then a uchar/int face list and int source_face).
usage: python3 bench/dark_faces.py ASSET.ply"""
import sys

import numpy as np

with open(sys.argv[1], 'rb') as f:
    data = f.read()
end = data.index(b'end_header\n') + len(b'end_header\n')
counts, vertex_props, element = {}, [], None
for line in data[:end].decode().splitlines():
    w = line.split()
    if w[:1] == ['element']:
        element = w[1]
        counts[element] = int(w[2])
    elif w[:1] == ['property'] and element == 'vertex':
        if w[1] != 'float':
            sys.exit('%s: vertex property %s is not float' % (sys.argv[1], w[-1]))
        vertex_props.append(w[-1])
V, F = counts['vertex'], counts['face']
v = np.frombuffer(data, dtype='<f4', count=V * len(vertex_props), offset=end).reshape(V, len(vertex_props))
t = v[:, [i for i, p in enumerate(vertex_props) if p.startswith('t')]]
face = np.frombuffer(data, dtype=np.dtype([('n', 'u1'), ('i', '<i4', 3), ('s', '<i4')]), count=F,
                     offset=end + V * len(vertex_props) * 4)
tri = face['i']
p = v[:, :3].astype(np.float64)
area = 0.5 * np.linalg.norm(np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]), axis=1)
dark = np.abs(t).max(axis=1)[tri].max(axis=1) < 1e-6

# Pieces: union-find over positions (render vertices split at creases share a position).
_, position = np.unique(p, axis=0, return_inverse=True)
position = position.reshape(-1)
parent = np.arange(position.max() + 1)


def find(a):
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


for a, b, c in position[tri]:
    for x, y in ((a, b), (b, c)):
        rx, ry = find(x), find(y)
        if rx != ry:
            parent[rx] = ry
piece = np.array([find(position[f[0]]) for f in tri])
with_dark = set(piece[dark])
all_dark = [c for c in with_dark if dark[piece == c].all()]
print('%s: %d faces, %d dark (%.1f%% of the area); %d pieces, %d with dark faces, %d of them all dark (%d faces)'
      % (sys.argv[1], F, dark.sum(), 100 * area[dark].sum() / area.sum(), len(set(piece)), len(with_dark),
         len(all_dark), sum(int((piece == c).sum()) for c in all_dark)))
