#!/usr/bin/env python3
"""Writes the 2048 x 2048 x 1024 uint16 OME-Zarr stack of issue 31 (x y z; 8 GiB
uncompressed) with a five-level pyramid, slab by slab (64 planes of level 0 at a time,
never the whole volume in memory), for scripts/bench/bench-big.

A synthetic light-sheet-like picture on a dark background (0): a lattice of nuclei
(balls of radius 14 voxels every 96, brightness varying with position), a thin
spherical shell (an "embryo" membrane) and a torus (a "gut"), so that every level
shows structure; mostly background, so Blosc (zstd, bit shuffle) stores it small.
Levels halve x, y and z (means of 2x2x2 blocks), NGFF 0.5 on Zarr v3, written by the
Python `zarr` and `ome-zarr` packages (pinned as in scripts/fixtures/zarr-fixtures.py).

Usage: python bench-big-zarr.py OUT.zarr [X Y Z]
  (venv: pip install zarr==3.1.3 ome-zarr==0.12.2 numcodecs==0.16.6 numpy==2.4.6)
"""
import os
import shutil
import sys

import numpy as np
import zarr
from ome_zarr.format import FormatV05
from ome_zarr.writer import write_multiscales_metadata

out = sys.argv[1]
nx, ny, nz = (int(a) for a in sys.argv[2:5]) if len(sys.argv) > 4 else (2048, 2048, 1024)
levels, slab = 5, 64
assert nz % slab == 0 and slab % 2 ** (levels - 1) == 0
shutil.rmtree(out, ignore_errors=True)
root = zarr.open_group(out, mode="w", zarr_format=3)
blosc = zarr.codecs.BloscCodec(cname="zstd", clevel=3, shuffle="bitshuffle")
arrays = []
for lv in range(levels):
    f = 2 ** lv
    shape = (nz // f, ny // f, nx // f)
    chunks = (slab // f, min(256, shape[1]), min(256, shape[2]))
    arrays.append(root.create_array(str(lv), shape=shape, chunks=chunks, dtype="uint16",
                                    compressors=[blosc], fill_value=0))
# Coordinates in level-0 voxels; the picture scales with the smallest edge.
s = min(nx, ny, nz) / 1024.0
cx, cy, cz = nx / 2, ny / 2, nz / 2
ys, xs = np.mgrid[0:ny, 0:nx].astype(np.float32)
lattice, radius = 96 * s, 14 * s


# What does not change along z, once.
qx, qy = (xs % lattice) - lattice / 2, (ys % lattice) - lattice / 2
qxy = qx * qx + qy * qy
bright = 1500 + 1500 * np.sin(xs / (300 * s)) * np.cos(ys / (400 * s))
rx, ry = (xs - cx) / (0.95 * cx), (ys - cy) / (0.95 * cy)
rxy = rx * rx + ry * ry
ring = (np.sqrt(rxy) - 0.45) ** 2
del xs, ys, qx, qy, rx, ry


def plane(z):
    """Level 0's plane z as uint16."""
    qz = (z % lattice) - lattice / 2
    d2 = (qxy + qz * qz) / (radius * radius)
    nuclei = np.where(d2 < 1, (bright + 2 * z) * (1 - d2) + 800, 0)
    rz = (z - cz) / (0.95 * cz)
    r = np.sqrt(rxy + rz * rz)
    v = np.where(r < 0.9, nuclei, 0)
    v = np.where(np.abs(r - 0.9) < 0.012, 9000.0, v)
    v = np.where(ring + (rz * 2) ** 2 < 0.08 ** 2, 5000.0, v)
    return np.clip(v, 0, 65535).astype(np.uint16)


for z0 in range(0, nz, slab):
    data = np.stack([plane(z) for z in range(z0, z0 + slab)])
    for lv in range(levels):
        if lv > 0:
            d = data.astype(np.float32)
            d = (d[0::2] + d[1::2]) / 2
            d = (d[:, 0::2] + d[:, 1::2]) / 2
            d = (d[:, :, 0::2] + d[:, :, 1::2]) / 2
            data = np.rint(d).astype(np.uint16)
        f = 2 ** lv
        arrays[lv][z0 // f:(z0 + slab) // f] = data
    print(f"planes {z0 + slab}/{nz}", file=sys.stderr, flush=True)

datasets = [{"path": str(lv), "coordinateTransformations": [
    {"type": "scale", "scale": [2.0 ** lv * 0.002, 2.0 ** lv * 0.001, 2.0 ** lv * 0.001]}]}
    for lv in range(levels)]
write_multiscales_metadata(root, datasets, fmt=FormatV05(), axes=[
    {"name": "z", "type": "space", "unit": "millimeter"},
    {"name": "y", "type": "space", "unit": "millimeter"},
    {"name": "x", "type": "space", "unit": "millimeter"}], name="synthetic stack")
total = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(out) for f in fs)
print(f"{out}: {nx}x{ny}x{nz} uint16, {levels} levels, {total / 2**20:.0f} MiB on disk")
