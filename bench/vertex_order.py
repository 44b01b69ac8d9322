#!/usr/bin/env python3
"""How far a mesh's vertex order is from its face order (why the fit numbers its unknowns
breadth-first): the median index distance between a face's first two vertices, and between the
first vertices of consecutive faces. Binary little-endian PLY with float x y z and a uchar/int
face list only (the shared scans).
usage: python3 bench/vertex_order.py MESH.ply"""
import statistics
import struct
import sys

with open(sys.argv[1], 'rb') as f:
    counts = {}
    while True:
        line = f.readline().decode().split()
        if line[:1] == ['element']:
            counts[line[1]] = int(line[2])
        if line[:1] == ['end_header']:
            break
    f.read(12 * counts['vertex'])
    faces = [struct.unpack('<B3i', f.read(13))[1:] for _ in range(counts['face'])]
within = statistics.median(abs(a - b) for a, b, _ in faces)
consecutive = statistics.median(abs(faces[i + 1][0] - faces[i][0]) for i in range(len(faces) - 1))
print('%s: %d vertices, %d faces; median |v0 - v1| within a face %.0f; median jump between consecutive faces %.0f'
      % (sys.argv[1], counts['vertex'], counts['face'], within, consecutive))
