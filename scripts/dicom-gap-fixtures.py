#!/usr/bin/env python3
"""Writes the DICOM fixtures of crates/io/tests/dicom_gaps.rs into
crates/io/tests/data/dicom-gaps/, made with pydicom from its own test files, and their
reference.tsv: what pydicom decodes from each (scripts/pydicom-table.py's columns).

- j2k_empty_first_fragment.dcm: MR_small_jp2klossless.dcm with its codestream moved to
  a second fragment after an empty one (some exporters write this; glint refused it).
- pixel_spacing_zero.dcm: CT_small.dcm with PixelSpacing 0\\0 (secondary captures, some
  CR/DX); glint reads it as 1 mm with a note.
- one_bit_frames.dcm: 1-bit pixels (BitsAllocated 1, as DICOM SEG), 5 x 3 pixels x 3
  frames: 15 bits a frame, so frames start inside bytes (packed across frames).

Usage, after scripts/fetch-samples, in the venv of scripts/pydicom-table.py:

    /tmp/venv/bin/python scripts/dicom-gap-fixtures.py ~/.cache/glint/samples/pydicom
"""
import os
import subprocess
import sys

import numpy as np
import pydicom
from pydicom.encaps import encapsulate, generate_frames
from pydicom.pixels import pack_bits
from pydicom.uid import ExplicitVRLittleEndian

src = sys.argv[1]
here = os.path.dirname(os.path.abspath(__file__))
out = os.path.join(here, "..", "crates", "io", "tests", "data", "dicom-gaps")
os.makedirs(out, exist_ok=True)

ds = pydicom.dcmread(os.path.join(src, "MR_small_jp2klossless.dcm"))
frame = next(generate_frames(ds.PixelData, number_of_frames=1))
# An empty Basic Offset Table, an empty fragment, then the codestream (PS3.5 A.4).
item = lambda b: b"\xfe\xff\x00\xe0" + len(b).to_bytes(4, "little") + b  # noqa: E731
ds.PixelData = item(b"") + item(b"") + item(frame if len(frame) % 2 == 0 else frame + b"\0")
ds["PixelData"].is_undefined_length = True
ds.save_as(os.path.join(out, "j2k_empty_first_fragment.dcm"), enforce_file_format=True)

ds = pydicom.dcmread(os.path.join(src, "CT_small.dcm"))
ds.PixelSpacing = [0, 0]
ds.save_as(os.path.join(out, "pixel_spacing_zero.dcm"), enforce_file_format=True)

ds = pydicom.dcmread(os.path.join(src, "CT_small.dcm"))
rng = np.random.default_rng(1)
bits = rng.integers(0, 2, (3, 3, 5)).astype(np.uint8)
ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
ds.Rows, ds.Columns, ds.NumberOfFrames = 3, 5, 3
ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 1, 1, 0, 0
ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
for k in ("RescaleSlope", "RescaleIntercept", "WindowCenter", "WindowWidth"):
    if k in ds:
        del ds[k]
ds.PixelData = pack_bits(bits)
ds["PixelData"].VR = "OB"
ds.save_as(os.path.join(out, "one_bit_frames.dcm"), enforce_file_format=True)

table = subprocess.run(
    [sys.executable, os.path.join(here, "pydicom-table.py"), out],
    check=True,
    capture_output=True,
    text=True,
).stdout
lines = [l for l in table.splitlines() if not l.startswith("reference.tsv")]
with open(os.path.join(out, "reference.tsv"), "w") as f:
    f.write("\n".join(lines) + "\n")
print(table)
