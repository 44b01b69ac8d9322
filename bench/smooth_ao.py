"""Is there anything for a denoiser in an AO asset's vertex values? Writes copies of a PLY AO asset
with each value blended towards the mean of its edge neighbours (render vertices that share a
position count as one): x' = (1 - t) x + t * mean(neighbours), for each t given. Judge them with
prtsub eval against one fixed reference.

usage: PYTHONPATH=build/python /usr/bin/python3 bench/smooth_ao.py ASSET.ply OUT_STEM T...
writes OUT_STEM_T.ply for each T.
"""
import sys

import numpy as np
import prtsub


def main():
    src, stem = sys.argv[1], sys.argv[2]
    asset = prtsub.load(src)
    if asset.ao is None:
        sys.exit(f"{src}: not an AO asset")
    raw = open(src, "rb").read()
    start = raw.index(b"end_header\n") + len(b"end_header\n")
    header = raw[:start].decode("latin-1").split("\n")
    props = [l.split()[-1] for l in header if l.startswith("property float")]
    if "ao" not in props or any(l.startswith("property") and "float" not in l and "list" not in l and "source_face" not in l
                                for l in header):
        sys.exit(f"{src}: vertex layout not understood")
    n_props, V = len(props), asset.vertices.shape[0]
    column = props.index("ao")
    vert = np.frombuffer(raw, dtype="<f4", count=n_props * V, offset=start).reshape(V, n_props).copy()
    _, inv = np.unique(asset.vertices, axis=0, return_inverse=True)
    inv = inv.ravel()
    P = inv.max() + 1
    value, count = np.zeros(P), np.zeros(P)
    np.add.at(value, inv, vert[:, column])
    np.add.at(count, inv, 1)
    value /= count
    F = asset.faces.astype(np.int64)
    edges = np.unique(np.sort(inv[np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])], 1), axis=0)
    total, degree = np.zeros(P), np.zeros(P)
    np.add.at(total, edges[:, 0], value[edges[:, 1]])
    np.add.at(total, edges[:, 1], value[edges[:, 0]])
    np.add.at(degree, edges[:, 0], 1)
    np.add.at(degree, edges[:, 1], 1)
    mean = (total / np.maximum(degree, 1))[inv]
    for t in (float(x) for x in sys.argv[3:]):
        out = vert.copy()
        out[:, column] = ((1 - t) * vert[:, column] + t * mean).astype("<f4")
        with open(f"{stem}_{t:g}.ply", "wb") as f:
            f.write(raw[:start] + out.tobytes() + raw[start + 4 * n_props * V:])


if __name__ == "__main__":
    main()
