#!/usr/bin/env python3
"""Writes the NIfTI-2, NIfTI-1 pair and ANALYZE 7.5 fixtures of crates/io/tests/nifti.rs
with nibabel (an independent writer), into crates/io/tests/data/.

Usage: /tmp/venv/bin/python scripts/make-nifti-fixtures.py   (venv with nibabel, numpy)
Every volume is 4 x 3 x 2 int16 with value(i, j, k) = i + 10 j + 100 k - 50.
"""
import os

import nibabel as nib
import numpy as np

out = os.path.join(os.path.dirname(__file__), "..", "crates", "io", "tests", "data")
os.makedirs(out, exist_ok=True)
i, j, k = np.meshgrid(np.arange(4), np.arange(3), np.arange(2), indexing="ij")
data = (i + 10 * j + 100 * k - 50).astype(np.int16)
affine = np.array(
    [[0.0, 0.0, -2.5, 10.0], [1.5, 0.0, 0.0, -4.0], [0.0, 2.0, 0.0, 7.25], [0, 0, 0, 1]]
)

img = nib.Nifti2Image(data, affine)
img.header.set_xyzt_units("mm")
img.header["scl_slope"] = 2.0
img.header["scl_inter"] = 1.0
nib.save(img, os.path.join(out, "n2.nii"))
nib.save(img, os.path.join(out, "n2.nii.gz"))
big = nib.Nifti2Image(data.astype(">i2"), affine, header=img.header.as_byteswapped(">"))
nib.save(big, os.path.join(out, "n2_big.nii"))

pair = nib.Nifti1Pair(data, affine)
pair.header.set_xyzt_units("mm")
nib.save(pair, os.path.join(out, "n1pair.hdr"))

analyze = nib.AnalyzeImage(data, np.diag([1.5, 2.0, 2.5, 1.0]))
nib.save(analyze, os.path.join(out, "analyze.hdr"))
print("nibabel", nib.__version__, "->", sorted(os.listdir(out)))
