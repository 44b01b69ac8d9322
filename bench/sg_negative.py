#!/usr/bin/env python3
"""Negative light from SH and SG assets under a sun (issue 15, point 3): the share of covered pixels
of a Gouraud frame (320x240, the automatic camera) whose radiance is below zero, and the lowest
value relative to the frame's mean. Each asset is lit as an engine would light it: the 5-degree
sun projected to the asset's own SH order (SH-3, SH-4), or to SG assets' shading order and then
onto their lobes. Reads the assets bench/sg_frames.sh wrote.

usage: PYTHONPATH=build/python /usr/bin/python3 bench/sg_negative.py OUT_DIR SCENE...
       (SCENE: the name bench/sg_frames.sh gave, e.g. mori_knob; a z-up scene as house_on_site:z)
"""
import os
import sys

import numpy as np
import prtsub


def main():
    out, scenes = sys.argv[1], sys.argv[2:]
    print("| scene | SH-3 | SG-9 | SG-12 | SG-12 signed | SH-4 |")
    print("|---|---:|---:|---:|---:|---:|")
    for item in scenes:
        name, _, up = item.partition(":")
        direction = [0.4, -0.3, 1] if up == "z" else [0.4, 1, 0.3]  # bench/sg_frames.sh's sun, turned to a z-up scene
        row = f"| {name} |"
        for tag in ("sh3", "sg9", "sg12", "sg12s", "sh4"):
            a = prtsub.load(os.path.join(out, f"{name}_{tag}.ply"))
            img = prtsub.render(a, prtsub.sun(direction, 5.0), (320, 240))
            covered = img[..., 3] > 0
            r = img[..., 0][covered]
            row += " %.2f%% (min %.3f) |" % (100 * np.mean(r < 0), r.min() / r.mean())
        print(row)


if __name__ == "__main__":
    main()
