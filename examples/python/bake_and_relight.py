"""Bakes the bundled Spot mesh from Python, saves it as glTF, and relights it under a sky and
a sun circling about the vertical axis, writing each frame as a PPM image (no imaging package
needed). usage: python3 bake_and_relight.py [OUT_DIR]   (PYTHONPATH at the built module)"""
import os
import sys

import numpy as np

import prtsub

here = os.path.dirname(os.path.abspath(__file__))
out = sys.argv[1] if len(sys.argv) > 1 else "."
os.makedirs(out, exist_ok=True)

mesh = prtsub.load_mesh(os.path.join(here, "..", "spot", "spot_control_mesh.obj"))
asset = prtsub.bake(mesh, order=4, rays=128)
print(asset, "in %.2f s, %d rays; predicted error %.2f%%" % (
    asset.stats["seconds_total"], asset.stats["rays"], asset.stats["predicted_error_percent"]))
prtsub.save(asset, os.path.join(out, "spot_prt.glb"), quantize=True)

for i, degrees in enumerate(range(0, 360, 90)):
    light = prtsub.sky() + prtsub.sun((1, 1, 0.3), radius_deg=2).rotated((0, 1, 0), degrees)
    frame = prtsub.render(asset, light, size=(320, 240))
    rgb = np.clip(frame[..., :3], 0, 1) ** (1 / 2.2)  # a plain gamma, enough to look at
    path = os.path.join(out, "spot_%03d.ppm" % degrees)
    with open(path, "wb") as f:
        f.write(b"P6 320 240 255\n" + (rgb * 255 + 0.5).astype(np.uint8).tobytes())
    print("%s: mean radiance %.4f" % (path, frame[..., :3][frame[..., 3] > 0].mean()))
