#!/usr/bin/env python3
"""Reference values for crates/io/tests/gifti.rs, decoded by nibabel (not by glint).

Usage: python3 -m venv /tmp/venv && /tmp/venv/bin/pip install nibabel numpy
       /tmp/venv/bin/python scripts/gifti-reference.py ~/.cache/glint/samples/fsaverage5_sulc_left.gii.gz
Prints, per data array: intent, count, first five values, min, max, sum (float64).
"""
import sys

import nibabel
import numpy as np

print("nibabel", nibabel.__version__)
img = nibabel.load(sys.argv[1])
for i, da in enumerate(img.darrays):
    v = np.asarray(da.data, dtype=np.float64).ravel()
    print(i, nibabel.nifti1.intent_codes.niistring[da.intent], da.meta.get("Name"))
    print("  count", v.size)
    print("  first", [repr(float(x)) for x in v[:5]])
    print("  min", repr(float(v.min())), "max", repr(float(v.max())), "sum", repr(float(v.sum())))
    print("  index of max", int(v.argmax()), "index of min", int(v.argmin()))
