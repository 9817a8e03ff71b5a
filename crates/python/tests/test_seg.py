"""DICOM SEG as a label map (issue 33): Segmentation objects written by highdicom (an
independent writer, built on pydicom) from a small synthetic CT series, read by glint
and checked against the numpy masks given to highdicom: voxel counts per segment, the
segment names, the colours (given as sRGB, stored as CIELab), where the voxels are in
the CT's frame, and a render over the CT in each segment's colour."""

import json

import numpy as np
import pytest

from conftest import cli_error_line, glint_json, require_module, run_glint

ROWS, COLS, SLICES = 24, 20, 10
# Pixel spacing (between rows, between columns) and slice step in mm, and the first
# slice's ImagePositionPatient (LPS mm): nothing isotropic or at the origin.
PIXEL = (0.8, 0.6)
STEP = 1.5
ORIGIN = (-10.0, 20.0, 30.0)
# Segment number -> (SegmentLabel, sRGB colour given to highdicom).
SEGMENTS = {1: ("Liver", (221, 130, 101)), 2: ("Aorta", (224, 97, 76)), 3: ("Kidney", (185, 102, 83))}
# The FRACTIONAL segments' colours are left to glint (none given).


def ct_series(pydicom, folder):
    """A CT series of SLICES axial slices (pydicom), as glint and highdicom read it."""
    from pydicom.dataset import FileMetaDataset, Dataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid, CTImageStorage

    folder.mkdir()
    study, series, frame = generate_uid(), generate_uid(), generate_uid()
    rng = np.random.default_rng(7)
    out = []
    for k in range(SLICES):
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = CTImageStorage
        meta.MediaStorageSOPInstanceUID = generate_uid()
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        ds = Dataset()
        ds.file_meta = meta
        ds.SOPClassUID, ds.SOPInstanceUID = CTImageStorage, meta.MediaStorageSOPInstanceUID
        ds.StudyInstanceUID, ds.SeriesInstanceUID, ds.FrameOfReferenceUID = study, series, frame
        ds.PatientName, ds.PatientID, ds.PatientBirthDate, ds.PatientSex = "Seg^Test", "seg1", "", "O"
        ds.StudyDate, ds.StudyTime, ds.StudyID, ds.AccessionNumber = "20260101", "120000", "1", ""
        ds.ReferringPhysicianName, ds.Manufacturer = "", "glint"
        ds.Modality, ds.SeriesNumber, ds.InstanceNumber = "CT", 1, k + 1
        ds.ImageType = ["ORIGINAL", "PRIMARY", "AXIAL"]
        ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
        ds.ImagePositionPatient = [ORIGIN[0], ORIGIN[1], ORIGIN[2] + STEP * k]
        ds.PixelSpacing = list(PIXEL)
        ds.SliceThickness = STEP
        ds.Rows, ds.Columns = ROWS, COLS
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
        ds.RescaleIntercept, ds.RescaleSlope = 0, 1
        ds.PixelData = rng.integers(-50, 50, (ROWS, COLS), dtype=np.int16).tobytes()
        path = folder / f"ct{k:02d}.dcm"
        ds.save_as(path, enforce_file_format=True)
        out.append(pydicom.dcmread(path))
    return out


def masks():
    """Three boxes, (slices, rows, columns, segment): segment 1 leaves the first two
    slices empty (highdicom omits empty frames, so frames are sparse), segments 2 and 3
    overlap by one column (glint keeps the higher SegmentNumber there)."""
    m = np.zeros((SLICES, ROWS, COLS, 3), dtype=bool)
    m[2:8, 3:12, 2:9, 0] = True
    m[1:6, 14:20, 10:15, 1] = True
    m[4:9, 14:20, 14:18, 2] = True
    return m


def label_map(m):
    """What glint should read: the segment number, the higher one where two overlap."""
    out = np.zeros(m.shape[:3], dtype=np.uint16)
    for s in range(m.shape[3]):
        out[m[..., s]] = s + 1
    return out


def write_seg(hd, ct, m, path, fractional=False):
    """A Segmentation of `ct` with the masks `m` (BINARY, or FRACTIONAL with the masks
    as 0.2 / 0.7 fractions) written by highdicom."""
    from pydicom.sr.codedict import codes

    descriptions = []
    for number, (name, rgb) in SEGMENTS.items():
        colour = None if fractional else hd.color.CIELabColor.from_rgb(*rgb)
        descriptions.append(
            hd.seg.SegmentDescription(
                segment_number=number,
                segment_label=name,
                segmented_property_category=codes.SCT.Organ,
                segmented_property_type=codes.SCT.Organ,
                algorithm_type=hd.seg.SegmentAlgorithmTypeValues.MANUAL,
                display_color=colour,
            )
        )
    pixels = np.where(m, 0.7, 0.2).astype(np.float32) if fractional else m.astype(np.uint8)
    seg = hd.seg.Segmentation(
        source_images=ct,
        pixel_array=pixels,
        segmentation_type=hd.seg.SegmentationTypeValues.FRACTIONAL if fractional else hd.seg.SegmentationTypeValues.BINARY,
        segment_descriptions=descriptions,
        series_instance_uid=hd.UID(),
        series_number=2,
        sop_instance_uid=hd.UID(),
        instance_number=1,
        manufacturer="glint",
        manufacturer_model_name="test",
        software_versions="0",
        device_serial_number="0",
        max_fractional_value=255,
    )
    seg.save_as(path)


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    pydicom = require_module("pydicom")
    hd = require_module("highdicom")
    root = tmp_path_factory.mktemp("seg")
    ct = ct_series(pydicom, root / "ct")
    m = masks()
    write_seg(hd, ct, m, root / "seg.dcm")
    write_seg(hd, ct, m, root / "fractional.dcm", fractional=True)
    return root, m


def voxel_counts(labels):
    values, counts = np.unique(labels[labels > 0], return_counts=True)
    return {int(v): int(c) for v, c in zip(values, counts)}


def test_info_lists_the_segments_with_their_counts_names_and_colours(data, glint_bin):
    root, m = data
    info = glint_json(glint_bin, "info", str(root / "seg.dcm"), "--labels", "--json")
    rows = {r["value"]: r for r in info["labels"]}
    assert {v: r["voxels"] for v, r in rows.items()} == voxel_counts(label_map(m))
    for number, (name, rgb) in SEGMENTS.items():
        assert rows[number]["name"] == name
        assert rows[number]["in_table"]
        # sRGB -> 16-bit CIELab (highdicom) -> sRGB (glint): within rounding.
        assert np.max(np.abs(np.array(rows[number]["color"]) - rgb)) <= 1, (number, rows[number])
        assert rows[number]["ml"] == pytest.approx(rows[number]["voxels"] * PIXEL[0] * PIXEL[1] * STEP / 1000)
    assert info["label_table"]["entries"] == 3
    # FRACTIONAL: 0.7 is in a segment, 0.2 is not (threshold 0.5); no colour given:
    # generated ones.
    info = glint_json(glint_bin, "info", str(root / "fractional.dcm"), "--labels", "--json")
    assert {r["value"]: r["voxels"] for r in info["labels"]} == voxel_counts(label_map(m))
    assert [r["name"] for r in info["labels"]] == [n for n, _ in SEGMENTS.values()]


def test_the_label_grid_is_placed_in_the_ct_frame(data, glint_bin):
    """Every labelled voxel's world position (glint's affine, RAS) is where the mask
    puts it on the CT slices (LPS, from the positions given to pydicom)."""
    root, m = data
    info = glint_json(glint_bin, "info", str(root / "seg.dcm"), "--json")
    affine = np.array(info["affine_voxel_to_ras_mm"])
    dims = info["dims"]
    assert dims[:2] == [COLS, ROWS]
    expected = label_map(m)
    # The grid spans the slices that have frames (1 to 8 here).
    first = min(k for k in range(SLICES) if expected[k].any())
    last = max(k for k in range(SLICES) if expected[k].any())
    assert dims[2] == last - first + 1
    # Corner voxel (0, 0, 0) of glint's grid is column 0, row 0 of CT slice `first`.
    lps = np.array([ORIGIN[0], ORIGIN[1], ORIGIN[2] + STEP * first])
    ras = lps * [-1, -1, 1]
    assert np.allclose(affine[:3, 3], ras, atol=1e-4)
    assert np.allclose(np.abs(np.diag(affine)[:3]), [PIXEL[1], PIXEL[0], STEP], atol=1e-6)


def test_a_render_over_the_ct_shows_each_segment_colour(data, glint_bin, tmp_path):
    """Label volume over the CT (transparent), unshaded: every pixel is the background
    or one segment's colour, and every segment visible from the front is drawn."""
    from PIL import Image

    root, _ = data
    scene = {
        "input": {"path": str(root / "ct")},
        "labels": {"path": str(root / "seg.dcm"), "legend": False, "render_as": "volume"},
        "size": [64, 64],
        "camera": {"view": "inferior", "projection": "orthographic"},
        "material": {"ambient": 1.0, "diffuse": 0.0, "specular": 0.0, "shade": False},
        "transfer_function": {"opacity": [[-1000.0, 0.0], [1000.0, 0.0]], "color": [[0.0, 1.0, 1.0, 1.0]]},
    }
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    out = tmp_path / "seg.png"
    proc = run_glint(glint_bin, "render", "--scene", str(tmp_path / "scene.json"), "--quiet", "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    rgb = np.asarray(Image.open(out).convert("RGB"), dtype=np.int32).reshape(-1, 3)
    near = {n: np.all(np.abs(rgb - c) <= 2, axis=1) for n, (_, c) in SEGMENTS.items()}
    background = np.all(rgb <= 2, axis=1)
    for n, hits in near.items():
        assert hits.sum() > 20, (n, hits.sum())
    assert np.all(background | np.logical_or.reduce(list(near.values())))


def test_a_frame_off_the_grid_is_refused_in_one_line(data, glint_bin, tmp_path):
    pydicom = require_module("pydicom")
    root, _ = data
    ds = pydicom.dcmread(root / "seg.dcm")
    pos = ds.PerFrameFunctionalGroupsSequence[1].PlanePositionSequence[0]
    pos.ImagePositionPatient = [float(x) for x in pos.ImagePositionPatient[:2]] + [float(pos.ImagePositionPatient[2]) + STEP / 2]
    bad = tmp_path / "bad.dcm"
    ds.save_as(bad)
    line = cli_error_line(glint_bin, "info", str(bad), "--labels")
    assert "frame 2 lies between slices" in line
    ds = pydicom.dcmread(root / "seg.dcm")
    ds.PerFrameFunctionalGroupsSequence[0].SegmentIdentificationSequence[0].ReferencedSegmentNumber = 9
    ds.save_as(bad)
    line = cli_error_line(glint_bin, "info", str(bad), "--labels")
    assert "refers to segment 9" in line
