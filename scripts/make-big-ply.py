#!/usr/bin/env python3
"""Writes a binary little-endian PLY of 1,000,000 vertices (float x y z) and 1,000,000
triangles (uchar count, int indices): 25 MB, for the PLY memory figures in docs/formats.md.
Usage: python3 scripts/make-big-ply.py OUT.ply"""
import struct
import sys

n = 1_000_000
with open(sys.argv[1], "wb") as f:
    f.write(
        b"ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
        b"property float y\nproperty float z\nelement face %d\n"
        b"property list uchar int vertex_indices\nend_header\n" % (n, n)
    )
    f.write(b"".join(struct.pack("<3f", i % 1000, i // 1000, (i * 7) % 13) for i in range(n)))
    f.write(b"".join(struct.pack("<B3i", 3, i, (i + 1) % n, (i + 1000) % n) for i in range(n)))
