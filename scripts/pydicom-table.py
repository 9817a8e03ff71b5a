#!/usr/bin/env python3
"""Record what pydicom reports for every file of its own test suite data, as the table
crates/io/tests/data/pydicom-corpus.tsv that glint's DICOM corpus test checks against.

Run once, in a venv, after scripts/fetch-samples:

    python3 -m venv /tmp/venv
    /tmp/venv/bin/pip install pydicom==3.0.2 numpy pylibjpeg pylibjpeg-libjpeg \
        pylibjpeg-openjpeg pylibjpeg-rle pyjpegls
    /tmp/venv/bin/python scripts/pydicom-table.py ~/.cache/glint/samples/pydicom \
        > crates/io/tests/data/pydicom-corpus.tsv

Columns: file (relative), expect, dims (columns x rows x frames), spacing (mm: between
columns, between rows, between slices), min, max, sum, checksum (sum over frames and
pixels p of (p % 65521 + 1) * value; independent of frame order), reason.

`expect` is `read` when pydicom decodes a single-sample (grayscale) image with 8, 16 or
32 bits allocated whose frames can be placed (per-frame positions, one position and a
spacing, or none at all, which glint stacks in frame order). Otherwise `refuse`, and
`reason` is a substring glint's message must contain; the rules are glint's documented
choices (docs/formats.md), applied here to what pydicom reads, not to glint's output.
Values are the stored values (pydicom 3 pixel_array, no rescale).
"""

import os
import sys

import numpy as np
import pydicom
from pydicom.uid import JPEGLSLossless, JPEGLSNearLossless

JPEG_LS = {JPEGLSLossless, JPEGLSNearLossless}
JPEG_LOSSY = {"1.2.840.10008.1.2.4.50", "1.2.840.10008.1.2.4.51"}
TS_NO_DECODER = {
    "1.2.840.10008.1.2.4.100": "no pixel data decoder",  # MPEG2
    "1.2.840.10008.1.2.4.102": "no pixel data decoder",  # MPEG-4
}


def slice_step(ds):
    """glint's slice spacing rule for one file, from pydicom's attributes."""
    frames = int(getattr(ds, "NumberOfFrames", 1) or 1)
    gfov = getattr(ds, "GridFrameOffsetVector", None)
    if frames > 1 and gfov is not None and len(gfov) == frames and "ImagePositionPatient" in ds:
        off = sorted(float(x) for x in gfov)
        return (off[-1] - off[0]) / (frames - 1)
    pffg = getattr(ds, "PerFrameFunctionalGroupsSequence", None)
    if frames > 1 and pffg is not None and len(pffg) == frames:
        pos = []
        for it in pffg:
            pps = getattr(it, "PlanePositionSequence", None)
            if pps:
                pos.append([float(x) for x in pps[0].ImagePositionPatient])
        if len(pos) == frames:
            iop = orientation(ds)
            n = np.cross(iop[:3], iop[3:])
            along = sorted(float(np.dot(p, n)) for p in pos)
            return (along[-1] - along[0]) / (frames - 1)
    sbs = find(ds, "PixelMeasuresSequence", "SpacingBetweenSlices")
    st = find(ds, "PixelMeasuresSequence", "SliceThickness")
    has_pos = "ImagePositionPatient" in ds or find(ds, "PlanePositionSequence", "ImagePositionPatient") is not None
    if frames > 1 and not has_pos:
        return float(sbs) if sbs and float(sbs) > 0 else 1.0
    for v in (sbs, st):
        if v not in (None, "") and float(v) > 0:
            return float(v)
    return 1.0


def find(ds, group, name):
    """Top level, then shared, then first per-frame functional group (as glint does)."""
    if name in ds and ds[name].value not in (None, ""):
        return ds[name].value
    for fg in ("SharedFunctionalGroupsSequence", "PerFrameFunctionalGroupsSequence"):
        seq = getattr(ds, fg, None)
        if seq:
            g = getattr(seq[0], group, None)
            if g and name in g[0]:
                return g[0][name].value
    return None


def orientation(ds):
    iop = find(ds, "PlaneOrientationSequence", "ImageOrientationPatient")
    return np.array([float(x) for x in iop]) if iop else np.array([1.0, 0, 0, 0, 1, 0])


# Files pydicom itself cannot read or decode, or reads where glint's reason for refusing
# comes first; the expected substring of glint's refusal, and why.
OVERRIDES = {
    # pydicom: RuntimeError from openjpeg; the codestream header is damaged.
    "JPEG2000-embedded-sequence-delimiter.dcm": "JPEG 2000 codestream declares",
    # pydicom: ValueError, the pixel data is cut short; glint checks lengths first.
    "MR_truncated.dcm": "truncated",
    # pydicom reads the part before the cut; glint refuses a length beyond the file.
    "rtplan_truncated.dcm": "truncated",
    # An item length beyond the end of the file (pydicom stops there).
    "dicomdirtests/DICOMDIR-nooffset": "truncated",
    # Undefined-length UN holding an implicit-VR sequence (PS3.5 6.2.2): pydicom reads
    # it as implicit VR, dicom-rs 0.10 as explicit VR, which runs past the file.
    "UN_sequence.dcm": "truncated",
}


def looks_like_dicom(path):
    """glint's rule (docs/formats.md): "DICM" at 128 or 0, else a data set starting in
    group 0002-0010 in either byte order."""
    with open(path, "rb") as f:
        head = f.read(132)
    if head[128:132] == b"DICM" or head[:4] == b"DICM":
        return True
    if len(head) < 8:
        return False
    group = min(int.from_bytes(head[:2], "little"), int.from_bytes(head[:2], "big"))
    return 0 < group <= 0x10


def row(rel, path):
    refuse = lambda why: [rel, "refuse", "", "", "", "", "", "", why]  # noqa: E731
    if rel in OVERRIDES:
        return refuse(OVERRIDES[rel])
    if not looks_like_dicom(path):
        return refuse("not a DICOM file")
    try:
        ds = pydicom.dcmread(path, force=True)
    except Exception as e:  # noqa: BLE001 - any parse failure is a refusal
        return refuse(f"pydicom: {type(e).__name__}")
    if "PixelData" not in ds:
        return refuse("no PixelData")
    for name in ("Rows", "Columns", "BitsAllocated"):
        if ds.get(name) in (None, ""):
            return refuse(f"missing or bad {name}")
    nf = ds.get("NumberOfFrames")
    if nf not in (None, "") and not str(nf).strip().isdigit():
        return refuse("missing or bad NumberOfFrames")
    ts = str(getattr(getattr(ds, "file_meta", None), "TransferSyntaxUID", "") or "")
    spp = int(getattr(ds, "SamplesPerPixel", 1) or 1)
    bits = int(getattr(ds, "BitsAllocated", 0) or 0)
    if spp != 1:
        return [rel, "refuse", "", "", "", "", "", "", "samples per pixel"]
    if bits not in (8, 16, 32):
        return [rel, "refuse", "", "", "", "", "", "", "bits allocated"]
    if ts == "1.2.840.10008.1.2.5" and bits == 32:
        # dicom-rs 0.10's RLE decoder reads 8 and 16 bits allocated only.
        return refuse("BitsAllocated other than 8 or 16")
    if ts in JPEG_LOSSY and int(ds.BitsStored) > 8:
        return refuse("-bit lossy JPEG")
    if ts in JPEG_LS:
        return [rel, "refuse", "", "", "", "", "", "", "JPEG-LS not supported"]
    if ts in TS_NO_DECODER:
        return [rel, "refuse", "", "", "", "", "", "", TS_NO_DECODER[ts]]
    try:
        arr = ds.pixel_array
    except Exception as e:  # noqa: BLE001
        return [rel, "refuse", "", "", "", "", "", "", f"pydicom cannot decode: {type(e).__name__}"]
    frames = int(getattr(ds, "NumberOfFrames", 1) or 1)
    arr = arr.reshape(frames, int(ds.Rows), int(ds.Columns)).astype(np.int64)
    ps = find(ds, "PixelMeasuresSequence", "PixelSpacing")
    ps = [float(x) for x in ps] if ps else [1.0, 1.0]
    spacing = [ps[1], ps[0], slice_step(ds)]
    idx = (np.arange(arr.shape[1] * arr.shape[2]) % 65521 + 1).reshape(arr.shape[1:])
    checksum = int(sum(int((idx * f).sum()) for f in arr))
    return [
        rel,
        "read",
        f"{ds.Columns}x{ds.Rows}x{frames}",
        ",".join(f"{s:.6g}" for s in spacing),
        str(int(arr.min())),
        str(int(arr.max())),
        str(int(arr.sum())),
        str(checksum),
        "",
    ]


def main():
    root = sys.argv[1]
    print(f"# pydicom {pydicom.__version__} test files; see scripts/pydicom-table.py")
    print("file\texpect\tdims\tspacing\tmin\tmax\tsum\tchecksum\treason")
    files = []
    for d, _, names in os.walk(root):
        for n in names:
            files.append(os.path.relpath(os.path.join(d, n), root))
    for rel in sorted(files):
        print("\t".join(row(rel, os.path.join(root, rel))))


if __name__ == "__main__":
    main()
