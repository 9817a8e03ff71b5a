#!/usr/bin/env python3
"""Write small greyscale JPEG-compressed DICOM fixtures, and what pydicom decodes from
them, into crates/io/tests/data/jpeg/ for crates/io/tests/dicom_jpeg.rs.

pydicom's own test files (pydicom-corpus.tsv) hold no greyscale JPEG baseline or
lossless image, so glint's JPEG decoding (dicom-pixeldata 0.10 with jpeg-decoder 0.3)
was never compared with another decoder. These fixtures are made here: a smooth pattern
with an edge per frame, encoded by libjpeg-turbo 3 (imagecodecs' jpeg8_encode),
encapsulated by pydicom, then decoded by pydicom (pylibjpeg: Thomas Richter's libjpeg)
to record the reference. Run through scripts/jpeg-fixtures, which makes the venv with
the pinned wheels; deterministic (fixed UIDs, no dates), so a re-run rewrites the same
bytes.

Writes, for each fixture, NAME.dcm (or the directory NAME/ of single-frame files) and a
line of reference.tsv with the columns of pydicom-corpus.tsv: file, expect, dims
(columns x rows x frames), spacing (mm: columns, rows, slices), min, max, sum, checksum
(sum over frames and pixels p of (p % 65521 + 1) * value), reason (for `refuse`: a
substring of glint's message). Stored values (no rescale), as pydicom 3 returns them.
Lossy fixtures also get NAME.pydicom.raw: pydicom's decode, every voxel, in file frame
order, row-major, as little-endian samples of the fixture's bits allocated, because
decoders may round a lossy image differently (the test measures by how much).
"""

import hashlib
import os
import sys
import uuid

import imagecodecs
import numpy as np
import pydicom
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.encaps import encapsulate, encapsulate_extended, generate_frames
from pydicom.pixels import pixel_array
from pydicom.uid import (
    JPEGBaseline8Bit,
    JPEGExtended12Bit,
    JPEGLossless,
    JPEGLosslessSV1,
    CTImageStorage,
    MRImageStorage,
)

COLS, ROWS, FRAMES = 40, 32, 3
PIXEL_SPACING = (0.7, 0.6)  # row spacing (between rows), column spacing: PS3.3 C.7.6.2.1.1
SLICE_SPACING = 2.5
QUALITY = 90  # libjpeg quality for the lossy fixtures


def uid(*parts):
    """A fixed UID under 2.25 (PS3.5 B.2: a UUID as a decimal integer)."""
    return "2.25." + str(uuid.uuid5(uuid.NAMESPACE_URL, "glint-jpeg-fixture/" + "/".join(parts)).int)


def pattern(bits, signed, k):
    """Frame k: a smooth bump plus a vertical edge that moves with k, spanning the full
    range of `bits` (both extremes occur), as the stored integers."""
    y, x = np.mgrid[0:ROWS, 0:COLS].astype(np.float64)
    smooth = 0.5 + 0.5 * np.sin(x / 5.0 + k) * np.cos((y - 3 * k) / 7.0)
    edge = (x >= 17 + 3 * k).astype(np.float64)
    t = np.clip(0.55 * smooth + 0.45 * edge, 0.0, 1.0)
    t[0, 0], t[-1, -1] = 0.0, 1.0
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    return np.rint(lo + t * (hi - lo)).astype(np.int64)


def encode(frame, bits, lossless, predictor, sof1=False):
    """One frame as a JPEG codestream (libjpeg-turbo through imagecodecs). Signed values
    are coded as their `bits`-bit two's complement pattern (PS3.5 8.2.1)."""
    dtype = np.uint8 if bits <= 8 else np.uint16
    stored = (frame & ((1 << bits) - 1)).astype(dtype)
    if lossless:
        out = imagecodecs.jpeg8_encode(stored, lossless=True, predictor=predictor, bitspersample=bits)
    else:
        out = imagecodecs.jpeg8_encode(stored, level=QUALITY, bitspersample=bits)
    out = bytearray(out)
    if sof1:
        # libjpeg-turbo writes 8-bit DCT as baseline (SOF0); an extended-process
        # decoder (SOF1) reads the same segments (ITU T.81 B.2.2, Table B.1: only the
        # limits differ), so relabelling gives a valid process 2 codestream.
        at = bytes(out).index(b"\xff\xc0")
        out[at + 1] = 0xC1
    return bytes(out)


def dataset(name, ts, bits_stored, signed, frames, instance=1, z=0.0):
    """A CT (signed) or MR image with the geometry glint needs to make a volume: one
    position and a slice spacing for multi-frame files, a position per file otherwise."""
    meta = FileMetaDataset()
    sop_class = CTImageStorage if signed else MRImageStorage
    meta.MediaStorageSOPClassUID = sop_class
    meta.MediaStorageSOPInstanceUID = uid(name, str(instance))
    meta.TransferSyntaxUID = ts
    ds = Dataset()
    ds.file_meta = meta
    ds.SOPClassUID = sop_class
    ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.Modality = "CT" if signed else "MR"
    ds.PatientName = "Fixture^JPEG"
    ds.PatientID = "glint-jpeg"
    ds.StudyInstanceUID = uid(name, "study")
    ds.SeriesInstanceUID = uid(name, "series")
    ds.SeriesNumber = 1
    ds.InstanceNumber = instance
    ds.ImageType = ["DERIVED", "SECONDARY"]
    ds.FrameOfReferenceUID = uid(name, "frame")
    ds.ImagePositionPatient = [-14.0, -9.5, z]
    ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
    ds.PixelSpacing = list(PIXEL_SPACING)
    ds.SliceThickness = SLICE_SPACING
    if frames > 1:
        ds.NumberOfFrames = frames
        ds.SpacingBetweenSlices = SLICE_SPACING
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.Rows, ds.Columns = ROWS, COLS
    ds.BitsAllocated = 8 if bits_stored <= 8 else 16
    ds.BitsStored = bits_stored
    ds.HighBit = bits_stored - 1
    ds.PixelRepresentation = int(signed)
    if signed:
        ds.RescaleIntercept, ds.RescaleSlope = -1024, 1
    return ds


def write(path, ds, codestreams, how):
    """Encapsulates the frames (PS3.5 A.4) and writes the file."""
    if how == "extended":
        data, eot, lengths = encapsulate_extended(codestreams)
        ds.ExtendedOffsetTable, ds.ExtendedOffsetTableLengths = eot, lengths
    elif how == "two-fragments":
        data = encapsulate(codestreams, fragments_per_frame=2, has_bot=True)
    else:
        data = encapsulate(codestreams, has_bot=True)
    ds.PixelData = data
    ds["PixelData"].VR = "OB"
    ds["PixelData"].is_undefined_length = True
    ds.save_as(path, enforce_file_format=True)


# name, transfer syntax, bits stored, signed, lossless predictor (0: lossy DCT),
# encapsulation, single-frame files in a directory, expected refusal (None: read).
FIXTURES = [
    ("baseline8", JPEGBaseline8Bit, 8, False, 0, "bot", False, None),
    ("extended8", JPEGExtended12Bit, 8, False, 0, "two-fragments", False, None),
    ("extended12", JPEGExtended12Bit, 12, False, 0, "bot", False, None),
    ("lossless-sv1-16", JPEGLosslessSV1, 16, False, 1, "extended", False, None),
    ("lossless-sv1-12-signed", JPEGLosslessSV1, 12, True, 1, "bot", False, None),
    ("lossless-sv1-series", JPEGLosslessSV1, 16, True, 1, "bot", True, None),
    ("lossless-p7-8", JPEGLossless, 8, False, 7, "bot", False, None),
    ("lossless-p2-p6-16", JPEGLossless, 16, False, (2, 4, 6), "bot", False, None),
]


def make(out, fixture):
    """Writes one fixture; returns [(path, dataset), ...] and the original frames."""
    name, ts, bits, signed, predictor, how, series, _ = fixture
    frames = [pattern(bits, signed, k) for k in range(FRAMES)]
    preds = predictor if isinstance(predictor, tuple) else (predictor,) * FRAMES
    streams = [
        encode(f, bits, p > 0, p, sof1=(name == "extended8")) for f, p in zip(frames, preds)
    ]
    if series:
        os.makedirs(os.path.join(out, name), exist_ok=True)
        files = []
        # Written in reverse order of position: the reader must sort.
        for k in range(FRAMES):
            path = os.path.join(out, name, f"slice{FRAMES - k}.dcm")
            ds = dataset(name, ts, bits, signed, 1, instance=k + 1, z=k * SLICE_SPACING)
            write(path, ds, [streams[k]], how)
            files.append(path)
        return files, frames
    path = os.path.join(out, name + ".dcm")
    write(path, dataset(name, ts, bits, signed, FRAMES), streams, how)
    return [path], frames


def decode(files):
    """pydicom's decode of the files (frames in position order), with pylibjpeg."""
    parts = []
    for path in files:
        ds = pydicom.dcmread(path)
        arr = pixel_array(ds, decoding_plugin="pylibjpeg").astype(np.int64)
        parts.append((float(ds.ImagePositionPatient[2]), arr.reshape(-1, ROWS, COLS)))
    parts.sort(key=lambda p: p[0])
    return np.concatenate([a for _, a in parts])


def row(name, arr, refusal):
    idx = (np.arange(ROWS * COLS) % 65521 + 1).reshape(ROWS, COLS)
    spacing = [PIXEL_SPACING[1], PIXEL_SPACING[0], SLICE_SPACING]
    return [
        name,
        "refuse" if refusal else "read",
        f"{COLS}x{ROWS}x{arr.shape[0]}",
        ",".join(f"{s:.6g}" for s in spacing),
        str(int(arr.min())),
        str(int(arr.max())),
        str(int(arr.sum())),
        str(int(sum(int((idx * f).sum()) for f in arr))),
        refusal or "",
    ]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "crates/io/tests/data/jpeg"
    os.makedirs(out, exist_ok=True)
    lines = [
        f"# pydicom {pydicom.__version__} decode (pylibjpeg plugin) of fixtures encoded by "
        f"imagecodecs {imagecodecs.__version__} ({imagecodecs.jpeg8_version()}); "
        "see scripts/jpeg-fixtures.py",
        "file\texpect\tdims\tspacing\tmin\tmax\tsum\tchecksum\treason",
    ]
    for fixture in FIXTURES:
        name, _, bits, _, predictor, _, series, refusal = fixture
        files, frames = make(out, fixture)
        ref = decode(files)
        original = np.stack(frames)
        lossy = predictor == 0
        err = int(np.abs(ref - original).max())
        if not lossy and err != 0:
            sys.exit(f"{name}: pydicom's decode differs from the encoded values by {err}")
        note = ""
        if lossy:
            # The same codestreams decoded by libjpeg-turbo, for the record.
            turbo = np.concatenate(
                [np.asarray(imagecodecs.jpeg8_decode(c)).reshape(1, ROWS, COLS)
                 for p in files for c in _frames_of(p)]
            ).astype(np.int64)
            note = f", libjpeg-turbo vs pydicom max |diff| {int(np.abs(turbo - ref).max())}"
            dtype = "<u1" if bits <= 8 else "<u2"
            ref.astype(dtype).tofile(os.path.join(out, name + ".pydicom.raw"))
        size = sum(os.path.getsize(p) for p in files)
        print(
            f"{name}: {len(files)} file(s), {size} bytes, pydicom vs encoded max |diff| {err}{note}",
            file=sys.stderr,
        )
        lines.append("\t".join(row(name if series else name + ".dcm", ref, refusal)))
    with open(os.path.join(out, "reference.tsv"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out, "reference.tsv"), "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    print(f"reference.tsv sha256 {digest[:16]}", file=sys.stderr)


def _frames_of(path):
    """The codestreams of a file's frames."""
    ds = pydicom.dcmread(path)
    return list(generate_frames(ds.PixelData, number_of_frames=int(ds.get("NumberOfFrames", 1))))


if __name__ == "__main__":
    main()
