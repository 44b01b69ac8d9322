#!/usr/bin/env python3
"""Writes the generated scenes of the benchmarks into DIR: the two contact-shadow scenes of the
refinement benchmark, spot_on_ground.obj (Spot's control mesh standing on a square ground quad)
and icosphere_on_plane.obj (a level-1 icosphere resting on a two-triangle plane, as in the
tests), icosphere4.obj (a lone level-4 icosphere: smooth, unoccluded transfer for the fit), and
voxel_world.obj (a 96x96 heightmap of unit cubes, seeded, with only the exposed faces: columns
that touch diagonally share edges of four faces, a voxel world's non-manifold edges), and
cornell_coloured.ply (the shared Cornell box with its classic albedos as 8-bit sRGB vertex
colours: the left wall red, the right green, the rest white; every triangle has its own
corners, so a colour never bleeds across a wall's edge).

usage: make_scenes.py SHARED_SCENES_DIR OUT_DIR"""
import math
import os
import sys


def read_obj(path):
    verts, faces = [], []
    for line in open(path):
        p = line.split()
        if not p:
            continue
        if p[0] == "v":
            verts.append(tuple(float(x) for x in p[1:4]))
        elif p[0] == "f":
            faces.append(tuple(int(x.split("/")[0]) for x in p[1:]))
    return verts, faces


def write_obj(path, verts, faces, comment):
    with open(path, "w") as f:
        f.write("# " + comment + "\n")
        for v in verts:
            f.write("v %.17g %.17g %.17g\n" % v)
        for face in faces:
            f.write("f " + " ".join(str(i) for i in face) + "\n")


def ground(verts, faces, up, half):
    """Appends a two-triangle square facing +up under the mesh, `half` times its extent."""
    lo = [min(v[k] for v in verts) for k in range(3)]
    hi = [max(v[k] for v in verts) for k in range(3)]
    c = [(a + b) / 2 for a, b in zip(lo, hi)]
    r = half * max(hi[k] - lo[k] for k in range(3) if k != up)
    a, b = [k for k in range(3) if k != up]
    base = len(verts)
    for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        p = [0.0, 0.0, 0.0]
        p[up], p[a], p[b] = lo[up], c[a] + sa * r, c[b] + sb * r
        verts.append(tuple(p))
    quad = [base + 1, base + 2, base + 3, base + 4]
    # Orientation: normal +up for (a, b, up) right-handed order.
    right_handed = (a, b, up) in ((0, 1, 2), (1, 2, 0), (2, 0, 1))
    if not right_handed:
        quad.reverse()
    faces.append((quad[0], quad[1], quad[2]))
    faces.append((quad[0], quad[2], quad[3]))


def icosphere(levels=1):
    t = (1 + math.sqrt(5)) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(x / math.sqrt(sum(c * c for c in p)) for x in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    mid = {}

    def midpoint(a, b):
        key = (min(a, b), max(a, b))
        if key not in mid:
            p = [(x + y) / 2 for x, y in zip(v[a], v[b])]
            n = math.sqrt(sum(c * c for c in p))
            v.append(tuple(c / n for c in p))
            mid[key] = len(v) - 1
        return mid[key]

    for _ in range(levels):
        g = []
        for a, b, c in f:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            g += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f, mid = g, {}
    return v, [(a + 1, b + 1, c + 1) for a, b, c in f]


def voxel_world(n=96, seed=7):
    # A rolling terrain of heights 1..6 (sum of seeded waves) plus seeded bumps of 0..2, with
    # seeded empty columns (a third), stepped into cubes: many columns touch only diagonally.
    import random
    rnd = random.Random(seed)
    waves = [(rnd.uniform(0.03, 0.2), rnd.uniform(0.03, 0.2), rnd.uniform(0, 6.3)) for _ in range(6)]
    heights = {}
    for i in range(n):
        for j in range(n):
            h = sum(math.sin(a * i + b * j + c) for a, b, c in waves) / len(waves)
            empty = rnd.random() < 1 / 3
            bump = rnd.randint(0, 2)
            heights[(i, j)] = 0 if empty else max(1, min(6, int(3.5 + 5 * h))) + bump
    def height(i, j):
        return heights.get((i, j), 0)
    index, verts, faces = {}, [], []
    def v(x, y, z):
        if (x, y, z) not in index:
            index[(x, y, z)] = len(verts) + 1
            verts.append((float(x), float(z), -float(y)))  # y up (a rotation, so windings hold)
        return index[(x, y, z)]
    def quad(a, b, c, d):
        faces.append((v(*a), v(*b), v(*c)))
        faces.append((v(*a), v(*c), v(*d)))
    for i in range(n):
        for j in range(n):
            h = height(i, j)
            if h == 0:
                continue
            quad((i, j, h), (i + 1, j, h), (i + 1, j + 1, h), (i, j + 1, h))  # top (+z in grid)
            quad((i, j, 0), (i, j + 1, 0), (i + 1, j + 1, 0), (i + 1, j, 0))  # bottom
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                hn = height(i + di, j + dj)
                for z in range(hn, h):  # exposed side cells
                    if di == 1:  # each side counter-clockwise seen from outside
                        quad((i + 1, j, z), (i + 1, j + 1, z), (i + 1, j + 1, z + 1), (i + 1, j, z + 1))
                    elif di == -1:
                        quad((i, j, z), (i, j, z + 1), (i, j + 1, z + 1), (i, j + 1, z))
                    elif dj == 1:
                        quad((i, j + 1, z), (i, j + 1, z + 1), (i + 1, j + 1, z + 1), (i + 1, j + 1, z))
                    else:
                        quad((i, j, z), (i + 1, j, z), (i + 1, j, z + 1), (i, j, z + 1))
    return verts, faces


# The Cornell box's albedos (linear), as the original scene gives them.
CORNELL = {"red": (0.63, 0.065, 0.05), "green": (0.14, 0.45, 0.091), "white": (0.725, 0.71, 0.68)}


def srgb8(c):
    e = 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
    return max(0, min(255, round(255 * e)))


def cornell_coloured(shared, path):
    v, f = read_obj(os.path.join(shared, "cornell_box.obj"))
    tris = []
    for face in f:  # fans, as prtsub triangulates
        for k in range(1, len(face) - 1):
            tris.append((face[0], face[k], face[k + 1]))
    with open(path, "w") as out:
        out.write("ply\nformat ascii 1.0\ncomment the shared cornell_box.obj with the Cornell albedos as sRGB vertex colours\n")
        out.write("element vertex %d\nproperty float x\nproperty float y\nproperty float z\n" % (3 * len(tris)))
        out.write("property uchar red\nproperty uchar green\nproperty uchar blue\n")
        out.write("element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(tris))
        for t in tris:
            xs = [v[i - 1][0] for i in t]
            name = "red" if max(xs) < -0.98 else "green" if min(xs) > 0.98 else "white"
            rgb = [srgb8(c) for c in CORNELL[name]]
            for i in t:
                out.write("%g %g %g %d %d %d\n" % (v[i - 1] + tuple(rgb)))
        for k in range(len(tris)):
            out.write("3 %d %d %d\n" % (3 * k, 3 * k + 1, 3 * k + 2))


def main():
    shared, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    v, f = read_obj(os.path.join(shared, "spot_control_mesh.obj"))
    ground(v, f, up=1, half=1.5)
    write_obj(os.path.join(out, "spot_on_ground.obj"), v, f, "Spot (public domain, Keenan Crane) on a ground quad")
    v, f = icosphere()
    v = list(v)
    v += [(-2.5, -2.5, -1.0), (2.5, -2.5, -1.0), (2.5, 2.5, -1.0), (-2.5, 2.5, -1.0)]
    n = len(v)
    f += [(n - 3, n - 2, n - 1), (n - 3, n - 1, n)]
    write_obj(os.path.join(out, "icosphere_on_plane.obj"), v, f, "level-1 icosphere resting on a two-triangle plane")
    v, f = icosphere(4)
    write_obj(os.path.join(out, "icosphere4.obj"), v, f, "level-4 icosphere, nothing else")
    v, f = voxel_world()
    write_obj(os.path.join(out, "voxel_world.obj"), v, f, "96x96 voxel heightmap, exposed faces only")
    cornell_coloured(shared, os.path.join(out, "cornell_coloured.ply"))


if __name__ == "__main__":
    main()
