#!/usr/bin/env python3
"""Writes the FreeSurfer MGH/MGZ fixtures of crates/io/tests/mgh.rs with nibabel (an
independent writer), into crates/io/tests/data/mgh/, and what nibabel reads back from
each file as reference.tsv: one line per file with the shape, dtype, nibabel's affine
(img.affine, 16 values row by row), the first frame's values in file order (x fastest)
and the footer's TR, flip angle, TE, TI.

Usage: /tmp/venv/bin/python scripts/make-mgh-fixtures.py   (venv with nibabel 5.4.2, numpy)

Every volume is 5 x 4 x 3 (odd sizes, so the volume centre falls between voxels) with an
oblique affine; values from a fixed seed cover each type's sign and range.
"""
import gzip
import os

import nibabel as nib
import numpy as np

out = os.path.join(os.path.dirname(__file__), "..", "crates", "io", "tests", "data", "mgh")
os.makedirs(out, exist_ok=True)
rng = np.random.default_rng(33)
shape = (5, 4, 3)
# A rotation of 20 degrees about an oblique axis, zooms 0.9, 1.2, 2.5, and an offset.
theta = np.deg2rad(20.0)
axis = np.array([1.0, 2.0, 2.0]) / 3.0
k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
rot = np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k
affine = np.eye(4)
affine[:3, :3] = rot @ np.diag([0.9, 1.2, 2.5])
affine[:3, 3] = [-12.5, 30.25, 7.0]

cases = {
    "u8.mgz": rng.integers(0, 256, shape).astype(np.uint8),
    "i16.mgh": rng.integers(-32768, 32768, shape).astype(np.int16),
    "u16.mgz": rng.integers(0, 65536, shape).astype(np.uint16),
    "i32.mgz": rng.integers(-(2**31), 2**31, shape).astype(np.int32),
    "f32.mgh": rng.normal(0, 1000, shape).astype(np.float32),
    "frames.mgz": rng.normal(0, 10, shape + (3,)).astype(np.float32),
}
for name, data in cases.items():
    img = nib.MGHImage(data, affine)
    img.header["tr"] = 2300.0
    img.header["flip_angle"] = np.deg2rad(9.0)
    img.header["te"] = 2.98
    img.header["ti"] = 900.0
    nib.save(img, os.path.join(out, name))

# A header whose goodRASFlag is 0: nibabel (like FreeSurfer) then ignores the stored
# geometry and takes 1 mm coronal voxels centred on the origin.
with open(os.path.join(out, "i16.mgh"), "rb") as f:
    raw = bytearray(f.read())
raw[28:30] = b"\0\0"
with open(os.path.join(out, "noras.mgh"), "wb") as f:
    f.write(raw)
# The same gzip-compressed under the other extension FreeSurfer accepts.
with open(os.path.join(out, "i16.mgh.gz"), "wb") as f:
    f.write(gzip.compress(bytes(open(os.path.join(out, "i16.mgh"), "rb").read()), mtime=0))

lines = [
    f"# nibabel {nib.__version__}: what nib.load reads from each file; see "
    "scripts/make-mgh-fixtures.py",
    "file\tshape\tdtype\taffine\tvalues\ttr_flip_te_ti",
]
for name in sorted(os.listdir(out)):
    if name == "reference.tsv":
        continue
    path = os.path.join(out, name)
    if name.endswith(".mgh.gz"):
        # nib.load goes by the extension and knows .mgz only; the bytes are the same.
        img = nib.MGHImage.from_bytes(gzip.decompress(open(path, "rb").read()))
    else:
        img = nib.load(path)
    data = np.asanyarray(img.dataobj)
    first = data[..., 0] if data.ndim == 4 else data
    h = img.header
    lines.append(
        "\t".join(
            [
                name,
                "x".join(str(s) for s in data.shape),
                str(data.dtype),
                ",".join(repr(float(x)) for x in img.affine.ravel()),
                ",".join(repr(x.item()) for x in first.ravel(order="F")),
                ",".join(repr(float(h[k])) for k in ("tr", "flip_angle", "te", "ti")),
            ]
        )
    )
with open(os.path.join(out, "reference.tsv"), "w") as f:
    f.write("\n".join(lines) + "\n")
print("nibabel", nib.__version__, "->", sorted(os.listdir(out)))
