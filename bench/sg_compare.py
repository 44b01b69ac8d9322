#!/usr/bin/env python3
"""Spherical-Gaussian lobes against SH orders 3 and 4 (issue 15, point 3, the encoding alone).

At every render vertex of each mesh, with no interpolation: the shading under a light, encoded
four ways, against the truth. The truth is order-10 transfer at 4096 rays relit by the light at
order 10 (every light here is taken band-limited at order 10, so the comparison is exact within
that world). SH-3 and SH-4 are an independent order-4 bake (another seed, 4096 rays), its first 9
and 16 values; SG-9 and SG-12 are prtsub.sg_transfer's non-negative lobes at 2048 rays, relit by
sg_light (and SG-12 signed, the same without the non-negative clamp). Error: RMS over vertices of the shading error, in percent of the truth's RMS.

usage: PYTHONPATH=build/python /usr/bin/python3 bench/sg_compare.py MESH...
"""
import sys

import numpy as np
import prtsub

LIGHTS = {
    "sky": prtsub.sky([0, 1, 0]),
    "sun 5deg": prtsub.sun([0.3, 1, 0.2], 5.0),
    "sky+sun": prtsub.sky([0, 1, 0]) + prtsub.sun([0.3, 1, 0.2], 5.0),
    "random 1": prtsub.random_light(1),
    "random 2": prtsub.random_light(2),
    "random 3": prtsub.random_light(3),
}


def main():
    print(f"{'mesh':16s} {'light':10s} {'SH-3 (9)':>9s} {'SG-9 (9)':>9s} {'SG-12 (12)':>10s} {'SG-12 signed':>12s} {'SH-4 (16)':>9s}")
    for path in sys.argv[1:]:
        mesh = prtsub.load_mesh(path)
        truth = np.asarray(prtsub.bake(mesh, order=10, rays=4096, fit="point", seed=7).transfer)
        sh = np.asarray(prtsub.bake(mesh, order=4, rays=4096, fit="point", seed=1).transfer)
        sg = {n: prtsub.sg_transfer(mesh, n, rays=2048, seed=3) for n in (9, 12)}
        signed = prtsub.sg_transfer(mesh, 12, rays=2048, seed=3, non_negative=False)
        if truth.shape[0] != sh.shape[0] or truth.shape[0] != sg[9].shape[0]:
            sys.exit(f"{path}: the bakes' vertices differ from the mesh's")
        name = path.rsplit("/", 1)[-1].rsplit(".", 1)[0]
        for light_name, light in LIGHTS.items():
            l10 = light.coefficients(10)[:, 0]
            s = truth @ l10
            norm = np.sqrt(np.mean(s ** 2))
            err = lambda x: 100 * np.sqrt(np.mean((x - s) ** 2)) / norm
            row = [err(sh[:, :9] @ l10[:9]), err(sg[9] @ prtsub.sg_light(light, 9)[:, 0]),
                   err(sg[12] @ prtsub.sg_light(light, 12)[:, 0]), err(signed @ prtsub.sg_light(light, 12)[:, 0]), err(sh @ l10[:16])]
            print(f"{name:16s} {light_name:10s} {row[0]:9.2f} {row[1]:9.2f} {row[2]:10.2f} {row[3]:12.2f} {row[4]:9.2f}", flush=True)


if __name__ == "__main__":
    main()
