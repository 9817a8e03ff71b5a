#!/usr/bin/env python3
"""Record what pydicom reports for every file of its own test suite data, as the table
crates/io/tests/data/pydicom-corpus.tsv that glint's DICOM corpus test checks against.

Run once, in a venv, after scripts/fetch-samples, for each corpus (pydicom's own test
files, and the pydicom-data wheel's):

    python3 -m venv /tmp/venv
    /tmp/venv/bin/pip install pydicom==3.0.2 numpy pylibjpeg pylibjpeg-libjpeg \
        pylibjpeg-openjpeg pylibjpeg-rle pyjpegls
    /tmp/venv/bin/python scripts/pydicom-table.py ~/.cache/glint/samples/pydicom \
        > crates/io/tests/data/pydicom-corpus.tsv
    /tmp/venv/bin/python scripts/pydicom-table.py ~/.cache/glint/samples/pydicom-data \
        > crates/io/tests/data/pydicom-data-corpus.tsv

Columns: file (relative), expect, dims (columns x rows x frames), spacing (mm: between
columns, between rows, between slices), min, max, sum, checksum (sum over frames and
pixels p of (p % 65521 + 1) * value; independent of frame order), reason.

`expect` is `read` when pydicom decodes a grey image (1 sample per pixel, 1, 8, 16 or
32 bits allocated) or a colour one (3 samples per pixel: RGB, YBR_FULL, YBR_FULL_422,
YBR_ICT, YBR_RCT) whose frames can be placed (per-frame positions, one position and a
spacing, or none at all, which glint stacks in frame order). Otherwise `refuse`, and
`reason` is a substring glint's message must contain; the rules are glint's documented
choices (docs/formats.md), applied here to what pydicom reads, not to glint's output.
Values are the stored values (pydicom 3 pixel_array, no rescale; colour as RGB, which
pydicom's default as_rgb=True gives). For colour, min/max/sum are over the three
channels and the checksum weights channel c (0 red, 1 green, 2 blue) by c + 1 on top.
For a `read` row of lossy DCT JPEG (whose decoders may round differently), `reason`
holds `tolerance N`: the largest per-sample difference allowed (see LOSSY below).
"""

import io
import os
import sys
import warnings

import numpy as np
import pydicom
from pydicom.uid import JPEGLSLossless, JPEGLSNearLossless

JPEG_LS = {JPEGLSLossless, JPEGLSNearLossless}
JPEG_LOSSY = {"1.2.840.10008.1.2.4.50", "1.2.840.10008.1.2.4.51"}
COLOUR = {"RGB", "YBR_FULL", "YBR_FULL_422", "YBR_ICT", "YBR_RCT"}
# Per-sample tolerance for lossy DCT JPEG: grey, 1 (ITU T.81 A.3.3 leaves the IDCT to
# the implementation within IEEE 1180's peak error of 1, so two decoders may differ by
# 1 after rounding); colour, also the chroma upsampling (T.81 A.1.1 leaves it open:
# libjpeg's "fancy" triangle filter vs jpeg-decoder's) and the YCbCr conversion's
# rounding, measured at most 5 on these corpora by crates/io/tests/pydicom_corpus.rs.
LOSSY_GREY = 1
LOSSY_COLOUR = 5
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
    # pydicom: RuntimeError from libjpeg ("Invalid SOS parameters" in libjpeg-turbo): a
    # damaged 12-bit scan header; JPGExtended.dcm is the intact file.
    "JPEG-lossy.dcm": "Invalid SOS parameters",
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


def read(path):
    """pydicom's read (force=True). Encapsulated pixel data whose sequence delimiter is
    missing at the end of the file (pydicom then drops PixelData with a warning, glint
    reads the fragments that are there) is read again with the delimiter restored, so
    the table holds pydicom's decode of the same fragments."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = pydicom.dcmread(path, force=True)
    if "PixelData" not in ds and any("(FFFE,E0DD)" in str(w.message) for w in caught):
        with open(path, "rb") as f:
            data = f.read() + b"\xfe\xff\xdd\xe0\x00\x00\x00\x00"
        ds = pydicom.dcmread(io.BytesIO(data), force=True)
    return ds


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
        ds = read(path)
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
    pi = str(getattr(ds, "PhotometricInterpretation", "MONOCHROME2")).upper()
    if spp not in (1, 3):
        return refuse("samples per pixel")
    if spp == 3 and pi not in COLOUR:
        return refuse("colour photometric interpretation")
    if bits not in ((1, 8, 16, 32) if spp == 1 else (8, 16, 32)):
        return refuse("bits allocated")
    if spp == 3 and bits > 8 and pi.startswith("YBR_FULL"):
        return refuse("YBR is converted to RGB for 8-bit samples only")
    if ts == "1.2.840.10008.1.2.5" and bits == 32:
        # dicom-rs 0.10's RLE decoder reads 8 and 16 bits allocated only.
        return refuse("BitsAllocated other than 8 or 16")
    if ts in TS_NO_DECODER:
        return [rel, "refuse", "", "", "", "", "", "", TS_NO_DECODER[ts]]
    if not str(getattr(getattr(ds, "file_meta", None), "TransferSyntaxUID", "") or ""):
        # No file meta group: pydicom cannot decode without a transfer syntax. The data
        # set was read in the encoding pydicom found, which for native pixel data is
        # the transfer syntax (what glint assumes too, with a note).
        ds.file_meta = getattr(ds, "file_meta", pydicom.dataset.FileMetaDataset())
        ds.file_meta.TransferSyntaxUID = (
            pydicom.uid.ImplicitVRLittleEndian
            if ds.is_implicit_VR
            else pydicom.uid.ExplicitVRLittleEndian
            if ds.is_little_endian
            else pydicom.uid.ExplicitVRBigEndian
        )
    try:
        arr = ds.pixel_array
    except Exception as e:  # noqa: BLE001
        return [rel, "refuse", "", "", "", "", "", "", f"pydicom cannot decode: {type(e).__name__}"]
    frames = int(getattr(ds, "NumberOfFrames", 1) or 1)
    shape = (frames, int(ds.Rows), int(ds.Columns)) + ((3,) if spp == 3 else ())
    arr = arr.reshape(shape).astype(np.int64)
    ps = find(ds, "PixelMeasuresSequence", "PixelSpacing")
    ps = [float(x) for x in ps] if ps else [1.0, 1.0]
    if ps == [0.0, 0.0]:
        # glint reads PixelSpacing 0\0 as missing: 1 mm (with a note).
        ps = [1.0, 1.0]
    spacing = [ps[1], ps[0], slice_step(ds)]
    idx = (np.arange(arr.shape[1] * arr.shape[2]) % 65521 + 1).reshape(arr.shape[1:3])
    if spp == 3:
        idx = idx[..., None] * np.array([1, 2, 3])
    checksum = int(sum(int((idx * f).sum()) for f in arr))
    lossy = ts in JPEG_LOSSY
    tolerance = f"tolerance {LOSSY_COLOUR if spp == 3 else LOSSY_GREY}" if lossy else ""
    return [
        rel,
        "read",
        f"{ds.Columns}x{ds.Rows}x{frames}",
        ",".join(f"{s:.6g}" for s in spacing),
        str(int(arr.min())),
        str(int(arr.max())),
        str(int(arr.sum())),
        str(checksum),
        tolerance,
    ]


def main():
    root = sys.argv[1]
    print(
        f"# pydicom {pydicom.__version__} decode of {os.path.basename(os.path.normpath(root))}; "
        "see scripts/pydicom-table.py"
    )
    print("file\texpect\tdims\tspacing\tmin\tmax\tsum\tchecksum\treason")
    files = []
    for d, _, names in os.walk(root):
        for n in names:
            # Hidden files: scripts/fetch-samples' completion markers.
            if not n.startswith("."):
                files.append(os.path.relpath(os.path.join(d, n), root))
    for rel in sorted(files):
        print("\t".join(row(rel, os.path.join(root, rel))))


if __name__ == "__main__":
    main()
