#!/usr/bin/env python3
"""Prints an asset's face count, smallest corner angle and faces below 1 degree, from its
positions alone (an independent count of what bake prints). usage: mesh_angles.py ASSET"""
import sys

import numpy as np
import prtsub

a = prtsub.load(sys.argv[1])
p = np.asarray(a.vertices)[np.asarray(a.faces)]
angles = []
for i in range(3):
    u, v = p[:, (i + 1) % 3] - p[:, i], p[:, (i + 2) % 3] - p[:, i]
    c = (u * v).sum(1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-300)
    angles.append(np.degrees(np.arccos(np.clip(c, -1, 1))))
m = np.minimum(np.minimum(angles[0], angles[1]), angles[2])
print(f"  {sys.argv[1]}: {len(m)} faces, min angle {m.min():.3f} deg, below 1 deg: {(m < 1).sum()} ({(m < 1).mean() * 100:.1f}%)")
