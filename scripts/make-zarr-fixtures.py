#!/usr/bin/env python3
"""Writes the OME-Zarr fixtures of crates/io/tests/zarr.rs with the Python `ome-zarr`
and `zarr` packages (independent writers), into crates/io/tests/data/zarr/, and what
zarr-python reads back from each level as reference.tsv: one line per store and level
with the level's x, y, z sizes, dtype, voxel size (x y z), the sum of its values and
eight voxels as i,j,k=value (i along x, the fastest axis).

Usage: /tmp/venv/bin/python scripts/make-zarr-fixtures.py
  (venv: pip install zarr==3.1.3 ome-zarr==0.12.2 numcodecs==0.16.6 numpy==2.4.6)

Stores (a 64 x 48 x 10 volume, z y x on disk, values from a fixed seed):
  v04-blosc.zarr   NGFF 0.4, Zarr v2, blosc (ome-zarr's default), 5 levels (y, x halved)
  v05-zstd.zarr    NGFF 0.5, Zarr v3, zstd, 5 levels
  v04-gzip-czyx.zarr  NGFF 0.4, Zarr v2, gzip, axes c z y x with 2 channels, 1 level
  bad-pyramid.zarr   level 1 announced larger than level 0 (inconsistent metadata)
  bad-codec.zarr     a compressor id no reader knows
  missing-chunk.zarr NGFF 0.4, Zarr v2, chunks of 32 x 16 x 5 (12 of them), 1 level, the
                     chunk at x 32.., y 16..32, z 0..5 deleted (read as the fill value 0)
"""
import json
import os
import shutil

import numpy as np
import zarr
from numcodecs import GZip, Zstd
from ome_zarr.format import FormatV04, FormatV05
from ome_zarr.io import parse_url
from ome_zarr.writer import write_image

out = os.path.join(os.path.dirname(__file__), "..", "crates", "io", "tests", "data", "zarr")
shutil.rmtree(out, ignore_errors=True)
os.makedirs(out)
rng = np.random.default_rng(31)
data = rng.integers(0, 4000, size=(10, 48, 64), dtype=np.uint16)
data[3:7, 10:40, 20:50] += 30000


def write(name, arr, fmt, zarr_format, axes, storage_options=None, scaler="default"):
    path = os.path.join(out, name)
    store = parse_url(path, mode="w", fmt=fmt).store
    root = zarr.group(store=store, zarr_format=zarr_format)
    kw = {} if scaler == "default" else {"scaler": None}
    write_image(arr, group=root, axes=axes, fmt=fmt, storage_options=storage_options, **kw)
    return path


stores = [
    write("v04-blosc.zarr", data, FormatV04(), 2, "zyx"),
    write("v05-zstd.zarr", data, FormatV05(), 3, "zyx",
          storage_options={"compressors": [zarr.codecs.ZstdCodec(level=3)]}),
    write("v04-gzip-czyx.zarr", np.stack([data, data // 2]), FormatV04(), 2, "czyx",
          storage_options={"compressor": GZip(level=5)}, scaler=None),
]

# Inconsistent pyramid: the levels' order swapped in the metadata.
bad = write("bad-pyramid.zarr", data, FormatV04(), 2, "zyx")
attrs = json.load(open(os.path.join(bad, ".zattrs")))
ds = attrs["multiscales"][0]["datasets"]
ds[0]["path"], ds[1]["path"] = ds[1]["path"], ds[0]["path"]
json.dump(attrs, open(os.path.join(bad, ".zattrs"), "w"), indent=2)
# Unknown codec: level 0's compressor renamed.
bad = write("bad-codec.zarr", data, FormatV04(), 2, "zyx", scaler=None)
meta = json.load(open(os.path.join(bad, "0", ".zarray")))
meta["compressor"] = {"id": "no-such-codec"}
json.dump(meta, open(os.path.join(bad, "0", ".zarray"), "w"), indent=2)

# A missing chunk: 12 chunks of 5 x 16 x 32 (z y x), the one at z 0, y 1, x 1 removed.
miss = write("missing-chunk.zarr", data, FormatV04(), 2, "zyx",
             storage_options={"chunks": (5, 16, 32)}, scaler=None)
os.remove(os.path.join(miss, "0", "0", "1", "1"))

lines = []
for path in stores:
    root = zarr.open_group(path, mode="r")
    ms = (root.attrs.get("ome") or dict(root.attrs))["multiscales"][0]
    for level, d in enumerate(ms["datasets"]):
        a = np.asarray(root[d["path"]])
        if a.ndim == 4:
            a = a[0]
        z, y, x = a.shape
        scale = d["coordinateTransformations"][0]["scale"][-3:]
        picks = [(0, 0, 0), (x - 1, y - 1, z - 1), (x // 2, y // 3, z // 2), (1, 0, 0),
                 (0, 1, 0), (0, 0, 1), (x - 1, 0, z // 3), (x // 3, y - 1, 0)]
        vox = " ".join(f"{i},{j},{k}={int(a[k, j, i])}" for i, j, k in picks)
        lines.append("\t".join([os.path.basename(path), str(level), f"{x} {y} {z}", str(a.dtype),
                                " ".join(str(s) for s in scale[::-1]), str(int(a.sum(dtype=np.int64))), vox]))
with open(os.path.join(out, "reference.tsv"), "w") as f:
    f.write("\n".join(lines) + "\n")
print("\n".join(lines))
