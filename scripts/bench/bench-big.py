#!/usr/bin/env python3
"""Writes an N^3 int16 NIfTI-1 file for scripts/bench/bench-big: a sphere of value
1000 * (1 - r) inside r < 0.8 and -1000 outside (r from the centre, 1 at a face's
centre), 1 mm voxels, written slice by slice (numpy only; the 348-byte header by hand
after the NIfTI-1 standard, nifti1.h).

Usage: bench-big.py N OUT.nii
"""
import os
import struct
import sys

import numpy as np

n, out = int(sys.argv[1]), sys.argv[2]
hdr = bytearray(348)
struct.pack_into("<i", hdr, 0, 348)  # sizeof_hdr
struct.pack_into("<8h", hdr, 40, 3, n, n, n, 1, 1, 1, 1)  # dim
struct.pack_into("<hh", hdr, 70, 4, 16)  # datatype INT16, bitpix
struct.pack_into("<8f", hdr, 76, 1, 1, 1, 1, 0, 0, 0, 0)  # pixdim
struct.pack_into("<f", hdr, 108, 352)  # vox_offset
struct.pack_into("<f", hdr, 112, 1.0)  # scl_slope
struct.pack_into("<h", hdr, 254, 1)  # sform_code
for row, v in enumerate([(1, 0, 0, -n / 2), (0, 1, 0, -n / 2), (0, 0, 1, -n / 2)]):
    struct.pack_into("<4f", hdr, 280 + 16 * row, *v)  # srow_x, srow_y, srow_z
hdr[344:348] = b"n+1\0"
x = np.linspace(-1, 1, n, dtype=np.float32)
X, Y = np.meshgrid(x, x, indexing="xy")  # rows j (y), columns i (x): x fastest
with open(out + ".part", "wb") as f:
    f.write(bytes(hdr) + b"\0" * 4)
    for k in range(n):
        r = np.sqrt(X * X + Y * Y + x[k] * x[k])
        f.write(np.where(r < 0.8, 1000 * (1 - r), -1000).astype("<i2").tobytes())
os.replace(out + ".part", out)
