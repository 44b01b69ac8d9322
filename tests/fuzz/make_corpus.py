#!/usr/bin/env python3
"""Seed corpus for the readers' fuzz targets: a unit square in every format each reader takes
(OBJ with normals and UVs, PLY ascii / binary little- and big-endian, OFF, STL ascii and
binary), a one-triangle asset (ascii and binary), the glTF assets in seeds/gltf, which
`prtsub bake` wrote for a unit square (GLB and JSON, compressed, quantized, Z-up, AO), and the
parts in seeds/part, which `prtsub bake --shard` wrote for it (one shard, two; point values, pilot).
usage: make_corpus.py OUT_DIR"""
import os, shutil, struct, sys

out = sys.argv[1]
square = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
faces = [(0, 1, 2), (0, 2, 3)]

def write(reader, name, data):
    os.makedirs(os.path.join(out, reader), exist_ok=True)
    with open(os.path.join(out, reader, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())

obj = "".join("v %g %g %g\n" % p for p in square) + "vn 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
obj += "".join("f %d/%d/1 %d/%d/1 %d/%d/1\n" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1) for a, b, c in faces)
write("obj", "square.obj", obj)
write("obj", "quad.obj", "".join("v %g %g %g\n" % p for p in square) + "f 1 2 3 4\n")

def ply(fmt, extra_vertex_props="", values=None):
    head = "ply\nformat %s 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n" % fmt
    head += "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    if fmt == "ascii":
        return head + "".join("%g %g %g\n" % p for p in square) + "".join("3 %d %d %d\n" % f for f in faces)
    e = "<" if fmt == "binary_little_endian" else ">"
    body = b"".join(struct.pack(e + "3f", *p) for p in square) + b"".join(struct.pack(e + "B3i", 3, *f) for f in faces)
    return head.encode() + body

for fmt in ("ascii", "binary_little_endian", "binary_big_endian"):
    write("ply", "square_%s.ply" % fmt, ply(fmt))
write("off", "square.off", "OFF\n4 2 0\n" + "".join("%g %g %g\n" % p for p in square) + "".join("3 %d %d %d\n" % f for f in faces))
stl = "solid square\n" + "".join(
    "facet normal 0 0 1\nouter loop\n" + "".join("vertex %g %g %g\n" % square[i] for i in f) + "endloop\nendfacet\n" for f in faces)
write("stl", "square_ascii.stl", stl + "endsolid square\n")
binary = b"\0" * 80 + struct.pack("<I", len(faces))
for f in faces:
    binary += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *square[i]) for i in f) + b"\0\0"
write("stl", "square_binary.stl", binary)

asset_head = ("ply\nformat %s 1.0\ncomment prtsub_asset 1\ncomment sh_order 1\nelement vertex 3\nproperty float x\n"
              "property float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
              "property float t0\nelement face 1\nproperty list uchar int vertex_indices\nproperty int source_face\nend_header\n")
tri = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
write("asset", "triangle_ascii.ply", asset_head % "ascii" + "".join("%g %g %g 0 0 1 0.886\n" % p for p in tri) + "3 0 1 2 0\n")
write("asset", "triangle_binary.ply", (asset_head % "binary_little_endian").encode() +
      b"".join(struct.pack("<7f", *p, 0, 0, 1, 0.886) for p in tri) + struct.pack("<B3ii", 3, 0, 1, 2, 0))

for reader in ("gltf", "part"):
    seeds = os.path.join(os.path.dirname(os.path.abspath(__file__)), "seeds", reader)
    os.makedirs(os.path.join(out, reader), exist_ok=True)
    for name in sorted(os.listdir(seeds)):
        shutil.copy(os.path.join(seeds, name), os.path.join(out, reader, name))
