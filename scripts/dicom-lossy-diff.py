#!/usr/bin/env python3
"""Per-sample |glint - pydicom| for the lossy DCT JPEG files of the two DICOM corpora
(the rows of crates/io/tests/data/pydicom*-corpus.tsv with a tolerance): the figures of
docs/formats.md "DICOM conformance". Run from the repository root, in the venv of
scripts/pydicom-table.py, after scripts/fetch-samples:

    cargo build -p glint-io --example dump_dicom
    /tmp/venv/bin/python scripts/dicom-lossy-diff.py target/debug/examples/dump_dicom
"""
import os, subprocess, sys, numpy as np, pydicom, warnings
warnings.simplefilter("ignore")
base = os.path.expanduser("~/.cache/glint/samples")
exe = sys.argv[1]
for table, sub in (("pydicom-corpus.tsv", "pydicom"), ("pydicom-data-corpus.tsv", "pydicom-data")):
    for line in open(f"crates/io/tests/data/{table}"):
        f = line.rstrip("\n").split("\t")
        if len(f) < 9 or not f[8].startswith("tolerance"):
            continue
        path = os.path.join(base, sub, f[0])
        ds = pydicom.dcmread(path, force=True)
        a = ds.pixel_array.astype(np.int64).ravel()
        r = subprocess.run([exe, path, "/tmp/g.raw"], capture_output=True, text=True)
        dt = np.uint8 if int(ds.BitsAllocated) == 8 else np.uint16
        g = np.fromfile("/tmp/g.raw", dtype=dt).astype(np.int64)
        d = np.abs(a - g)
        print(f"{f[0]:40s} {ds.PhotometricInterpretation:13s} max {d.max()} mean {d.mean():.4f} differ {np.count_nonzero(d)}/{d.size}")
