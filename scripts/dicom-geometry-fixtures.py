#!/usr/bin/env python3
"""Writes the DICOM series of crates/io/tests/dicom_geometry.rs into
crates/io/tests/data/dicom-geometry/, made with pydicom (an independent writer), and
expected.tsv: for each series the voxel-to-RAS affine computed here with numpy directly
from the header values written (PS3.3 C.7.6.2.1.1: column i along the row direction
times the column spacing, j along the column direction times the row spacing, k the
step between the first and last ImagePositionPatient over n - 1; LPS to RAS negates x
and y), and the pixel value of slice k (in position order).

Series (4 columns x 3 rows, 16-bit signed, value = 100 * k + 10 * row + column):
- oblique: ImageOrientationPatient rotated 30 degrees about z then 20 about x, slices
  along the normal at 2.5 mm.
- tilt: axial, gantry tilted 15 degrees: each slice moves 2 mm in z and 2 tan 15 in y,
  so the slice axis is not the normal (a sheared affine).
- shuffled: 6 axial slices whose file names and InstanceNumbers are a permutation
  unrelated to their positions (the reader must sort by position).
- step_inside / step_outside: 5 slices 2 mm apart but one step of 2.09 mm (4.5% off the
  median, inside glint's 5% tolerance) or 2.11 mm (5.5%, outside).

Usage (a venv with pydicom 3 and numpy): python scripts/dicom-geometry-fixtures.py
"""
import math
import os

import numpy as np
import pydicom
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.uid import CTImageStorage, ExplicitVRLittleEndian, generate_uid

here = os.path.dirname(os.path.abspath(__file__))
out = os.path.join(here, "..", "crates", "io", "tests", "data", "dicom-geometry")
ROWS, COLS = 3, 4
SPACING = (0.8, 0.6)  # PixelSpacing: between rows, between columns


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def slice_ds(series_uid, instance, iop, ipp, k):
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = CTImageStorage
    meta.MediaStorageSOPInstanceUID = generate_uid(entropy_srcs=[series_uid, str(instance)])
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.SOPClassUID = CTImageStorage
    ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.SeriesInstanceUID = series_uid
    ds.StudyInstanceUID = generate_uid(entropy_srcs=["glint study"])
    ds.Modality = "CT"
    ds.InstanceNumber = instance
    ds.Rows, ds.Columns = ROWS, COLS
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
    ds.PixelSpacing = [f"{SPACING[0]:.6f}", f"{SPACING[1]:.6f}"]
    ds.ImageOrientationPatient = [f"{x:.8f}" for x in iop]
    ds.ImagePositionPatient = [f"{x:.6f}" for x in ipp]
    rows, cols = np.meshgrid(np.arange(ROWS), np.arange(COLS), indexing="ij")
    ds.PixelData = (100 * k + 10 * rows + cols).astype("<i2").tobytes()
    return ds


def series(name, iop, positions, order=None):
    """Writes the slices (k in position order) under names and InstanceNumbers `order`."""
    d = os.path.join(out, name)
    os.makedirs(d, exist_ok=True)
    for f in os.listdir(d):
        os.remove(os.path.join(d, f))
    uid = generate_uid(entropy_srcs=["glint", name])
    order = order or list(range(len(positions)))
    written = []
    for k, p in enumerate(positions):
        ds = slice_ds(uid, order[k] + 1, iop, p, k)
        ds.save_as(os.path.join(d, f"im{order[k]:02d}.dcm"), enforce_file_format=True)
        written.append(pydicom.dcmread(os.path.join(d, f"im{order[k]:02d}.dcm")))
    return written


def affine(slices):
    """The RAS affine from the headers as read back by pydicom."""
    iop = np.array([float(x) for x in slices[0].ImageOrientationPatient])
    row_dir, col_dir = iop[:3], iop[3:]
    dr, dc = (float(x) for x in slices[0].PixelSpacing)
    first = np.array([float(x) for x in slices[0].ImagePositionPatient])
    last = np.array([float(x) for x in slices[-1].ImagePositionPatient])
    a = np.eye(4)
    a[:3, 0] = row_dir * dc
    a[:3, 1] = col_dir * dr
    a[:3, 2] = (last - first) / (len(slices) - 1)
    a[:3, 3] = first
    return np.diag([-1.0, -1.0, 1.0, 1.0]) @ a


rows = []
rot = rot_x(math.radians(20)) @ rot_z(math.radians(30))
iop = np.concatenate([rot[:, 0], rot[:, 1]])
normal = np.cross(rot[:, 0], rot[:, 1])
origin = np.array([-12.5, 30.0, 7.0])
written = series("oblique", iop, [origin + 2.5 * k * normal for k in range(5)])
rows.append(("oblique", affine(written)))

axial = [1.0, 0, 0, 0, 1.0, 0]
tilt = math.radians(15)
written = series("tilt", axial, [np.array([3.0, -20.0 + 2.0 * math.tan(tilt) * k, 2.0 * k]) for k in range(5)])
rows.append(("tilt", affine(written)))

order = [3, 0, 5, 1, 4, 2]
written = series("shuffled", axial, [np.array([0.0, 0.0, -10.0 + 1.5 * k]) for k in range(6)], order)
rows.append(("shuffled", affine(written)))

for name, odd in [("step_inside", 2.09), ("step_outside", 2.11)]:
    zs = [0.0, 2.0, 4.0, 4.0 + odd, 6.0 + odd]
    written = series(name, axial, [np.array([0.0, 0.0, z]) for z in zs])
    rows.append((name, affine(written)))

with open(os.path.join(out, "expected.tsv"), "w") as f:
    f.write(f"# written by scripts/dicom-geometry-fixtures.py with pydicom {pydicom.__version__}\n")
    f.write("# series\trow-major 4x4 RAS affine (16 numbers, from the headers with numpy)\n")
    for name, a in rows:
        f.write(name + "\t" + " ".join(f"{x:.9f}" for x in a.reshape(-1)) + "\n")
