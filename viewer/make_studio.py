#!/usr/bin/env python3
"""Writes assets/studio.png, the viewer's bundled environment: a 128x64 lat-long (prtsub's
mapping, docs/rendering.md) of a photo studio made up here: a dim grey room brighter overhead, a
warm softbox high on one side, a cool strip light opposite and a darker floor. 8-bit sRGB, no
colour chunks, so browsers and OpenImageIO decode the same numbers. usage: make_studio.py"""
import math, os, struct, zlib

W, H = 128, 64

def srgb(v):
    v = min(max(v, 0.0), 1.0)
    return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055

def radiance(u, v):
    theta, phi = math.pi * v, 2 * math.pi * u
    d = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
    up = d[1]
    base = 0.08 + 0.10 * max(up, 0) if up >= 0 else 0.04
    rgb = [base * 0.95, base, base * 1.05]
    key = (0.55, 0.6, 0.58)  # warm softbox, up and to one side
    n = math.sqrt(sum(k * k for k in key))
    if sum(a * b / n for a, b in zip(d, key)) > math.cos(math.radians(18)):
        rgb = [1.0, 0.85, 0.65]
    if abs(u - 0.37) < 0.04 and 0.25 < v < 0.55:  # cool strip opposite
        rgb = [0.35, 0.45, 0.6]
    return rgb

rows = b""
for r in range(H):
    rows += b"\0" + bytes(int(round(255 * srgb(c))) for col in range(W) for c in radiance((col + 0.5) / W, (r + 0.5) / H))

def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b"")
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "assets", "studio.png")
with open(out, "wb") as f:
    f.write(png)
print(out, len(png), "bytes")
