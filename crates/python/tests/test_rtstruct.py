"""RT structure sets as label maps (issue 47): a small synthetic CT series and an RT
structure set written with pydicom (the maintained DICOM library, pinned) from contours
traced from known numpy masks, read by glint and checked against the masks: voxel
counts per ROI, names and colours exact, volumes in ml, the overlap rule, renders over
the CT, and the refusals.

Tolerance: a contour traced along voxel edges (the box, the body outline) encloses
exactly the mask's voxel centres, so those counts are exact. Round ROIs are traced as
64-gons through points of the circle: the polygon lies inside the circle by at most
r (1 - cos(pi / 64)) = 0.12 % of r, so only voxel centres within that band of the
boundary may be lost; the counts must agree with the mask within 3 %."""

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
VOXEL_ML = PIXEL[0] * PIXEL[1] * STEP / 1000
RTSTRUCT = "1.2.840.10008.5.1.4.1.1.481.3"
# ROINumber -> (ROIName, ROIDisplayColor).
ROIS = {
    1: ("PTV box", (255, 0, 0)),
    2: ("Sphere", (0, 200, 0)),
    3: ("Ring", (30, 60, 250)),
    4: ("External", (200, 180, 20)),
    5: ("Empty", (9, 99, 199)),
    6: ("Isocenter", (250, 250, 250)),
}
SPHERE = ((5, 18.0, 13.0), 4.1)  # centre (slice, row, column), radius mm
RING = ((0, 9.0, 10.0), 4.1, 2.1)  # centre (slice, row, column), outer, inner radius mm
# (Radii off the lattice: 2 mm and 4 mm fall on voxel centres of this grid.)
RING_SLICES = (0, 1)
SIDES = 64


def lps(k, j, i):
    """The LPS position (mm) of continuous voxel index (column i, row j, slice k)."""
    return [ORIGIN[0] + i * PIXEL[1], ORIGIN[1] + j * PIXEL[0], ORIGIN[2] + k * STEP]


def mm_grid():
    """Voxel centres' offsets in mm along slices, rows, columns."""
    k, j, i = np.meshgrid(np.arange(SLICES), np.arange(ROWS), np.arange(COLS), indexing="ij")
    return k * STEP, j * PIXEL[0], i * PIXEL[1]


def masks():
    """The known masks, ROINumber -> (slices, rows, columns) bool."""
    z, y, x = mm_grid()
    box = np.zeros((SLICES, ROWS, COLS), bool)
    box[2:8, 3:12, 2:9] = True
    (sk, sj, si), r = SPHERE
    sphere = (z - sk * STEP) ** 2 + (y - sj * PIXEL[0]) ** 2 + (x - si * PIXEL[1]) ** 2 <= r * r
    (_, rj, ri), outer, inner = RING
    d2 = (y - rj * PIXEL[0]) ** 2 + (x - ri * PIXEL[1]) ** 2
    ring = (d2 <= outer**2) & (d2 > inner**2) & np.isin(z / STEP, RING_SLICES)
    body = np.ones((SLICES, ROWS, COLS), bool)
    return {1: box, 2: sphere, 3: ring, 4: body}


def rectangle(k, j0, j1, i0, i1):
    """A contour along the outer edges of voxels j0..j1, i0..i1 (inclusive)."""
    corners = [(j0 - 0.5, i0 - 0.5), (j0 - 0.5, i1 + 0.5), (j1 + 0.5, i1 + 0.5), (j1 + 0.5, i0 - 0.5)]
    return [c for j, i in corners for c in lps(k, j, i)]


def circle(k, j, i, r_mm):
    """A 64-gon through points of the circle of radius r_mm around voxel (k, j, i)."""
    out = []
    for a in np.linspace(0, 2 * np.pi, SIDES, endpoint=False):
        p = lps(k, j, i)
        out += [p[0] + r_mm * np.cos(a), p[1] + r_mm * np.sin(a), p[2]]
    return out


def contours():
    """ROINumber -> [(ContourGeometricType, ContourData)], traced from the masks'
    definitions; ROI 5 has none, ROI 6 only a POINT."""
    out = {n: [] for n in ROIS}
    for k in range(2, 8):
        out[1].append(("CLOSED_PLANAR", rectangle(k, 3, 11, 2, 8)))
    (sk, sj, si), r = SPHERE
    for k in range(SLICES):
        dz = (k - sk) * STEP
        if dz * dz < r * r:
            out[2].append(("CLOSED_PLANAR", circle(k, sj, si, np.sqrt(r * r - dz * dz))))
    (_, rj, ri), outer, inner = RING
    for k in RING_SLICES:
        # Two contours of one ROI on one slice: the inner one is a hole (even-odd).
        out[3].append(("CLOSED_PLANAR", circle(k, rj, ri, outer)))
        out[3].append(("CLOSED_PLANAR", circle(k, rj, ri, inner)))
    for k in range(SLICES):
        out[4].append(("CLOSED_PLANAR", rectangle(k, 0, ROWS - 1, 0, COLS - 1)))
    out[6].append(("POINT", lps(5, 12, 10)))
    return out


def dataset(pydicom, sop_class):
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid

    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = sop_class
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.SOPClassUID, ds.SOPInstanceUID = sop_class, meta.MediaStorageSOPInstanceUID
    ds.PatientName, ds.PatientID, ds.PatientBirthDate, ds.PatientSex = "Rt^Test", "rt1", "", "O"
    ds.StudyDate, ds.StudyTime, ds.StudyID, ds.AccessionNumber = "20260101", "120000", "1", ""
    ds.ReferringPhysicianName, ds.Manufacturer = "", "glint"
    return ds


def ct_series(pydicom, folder, study, series, frame):
    """A CT series of SLICES axial slices; returns their SOPInstanceUIDs."""
    from pydicom.uid import CTImageStorage

    folder.mkdir(exist_ok=True)
    rng = np.random.default_rng(7)
    uids = []
    for k in range(SLICES):
        ds = dataset(pydicom, CTImageStorage)
        ds.StudyInstanceUID, ds.SeriesInstanceUID, ds.FrameOfReferenceUID = study, series, frame
        ds.Modality, ds.SeriesNumber, ds.InstanceNumber = "CT", 1, k + 1
        ds.ImageType = ["ORIGINAL", "PRIMARY", "AXIAL"]
        ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
        ds.ImagePositionPatient = lps(k, 0, 0)
        ds.PixelSpacing = list(PIXEL)
        ds.SliceThickness = STEP
        ds.Rows, ds.Columns = ROWS, COLS
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
        ds.RescaleIntercept, ds.RescaleSlope = -1000, 1
        ds.PixelData = rng.integers(0, 50, (ROWS, COLS), dtype=np.int16).tobytes()
        ds.save_as(folder / f"ct{k:02d}.dcm", enforce_file_format=True)
        uids.append(ds.SOPInstanceUID)
    return uids


def write_rtstruct(pydicom, path, study, series, frame, ct_uids, rois=ROIS, shapes=None):
    """An RT structure set of the ROIs with the contours (PS3.3 A.19), by pydicom."""
    from pydicom.dataset import Dataset
    from pydicom.sequence import Sequence
    from pydicom.uid import CTImageStorage, generate_uid

    shapes = contours() if shapes is None else shapes
    ds = dataset(pydicom, RTSTRUCT)
    ds.StudyInstanceUID, ds.SeriesInstanceUID = study, generate_uid()
    ds.Modality, ds.SeriesNumber, ds.InstanceNumber = "RTSTRUCT", 2, 1
    ds.StructureSetLabel, ds.StructureSetDate, ds.StructureSetTime = "glint test", "20260101", "120000"
    images = []
    for uid in ct_uids:
        im = Dataset()
        im.ReferencedSOPClassUID, im.ReferencedSOPInstanceUID = CTImageStorage, uid
        images.append(im)
    se = Dataset()
    se.SeriesInstanceUID, se.ContourImageSequence = series, Sequence(images)
    st = Dataset()
    st.ReferencedSOPClassUID = "1.2.840.10008.3.1.2.3.1"
    st.ReferencedSOPInstanceUID = study
    st.RTReferencedSeriesSequence = Sequence([se])
    fr = Dataset()
    fr.FrameOfReferenceUID, fr.RTReferencedStudySequence = frame, Sequence([st])
    ds.ReferencedFrameOfReferenceSequence = Sequence([fr])
    ssroi, roicontour, observations = [], [], []
    for number, (name, colour) in rois.items():
        r = Dataset()
        r.ROINumber, r.ReferencedFrameOfReferenceUID, r.ROIName = number, frame, name
        r.ROIGenerationAlgorithm = "MANUAL"
        ssroi.append(r)
        c = Dataset()
        c.ReferencedROINumber, c.ROIDisplayColor = number, list(colour)
        items = []
        for kind, data in shapes.get(number, []):
            ct = Dataset()
            ct.ContourGeometricType = kind
            ct.NumberOfContourPoints = len(data) // 3
            ct.ContourData = [f"{v:.6g}" for v in data]
            items.append(ct)
        if items:
            c.ContourSequence = Sequence(items)
        roicontour.append(c)
        o = Dataset()
        o.ObservationNumber, o.ReferencedROINumber = number, number
        o.RTROIInterpretedType, o.ROIInterpreter = "ORGAN", ""
        observations.append(o)
    ds.StructureSetROISequence = Sequence(ssroi)
    ds.ROIContourSequence = Sequence(roicontour)
    ds.RTROIObservationsSequence = Sequence(observations)
    ds.save_as(path, enforce_file_format=True)


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """An export folder (CT slices and the structure set side by side) and a second CT
    series of another frame of reference."""
    pydicom = require_module("pydicom")
    from pydicom.uid import generate_uid

    root = tmp_path_factory.mktemp("rtstruct")
    study, series, frame = generate_uid(), generate_uid(), generate_uid()
    export = root / "export"
    uids = ct_series(pydicom, export, study, series, frame)
    write_rtstruct(pydicom, export / "rs.dcm", study, series, frame, uids)
    ct_series(pydicom, root / "other", generate_uid(), generate_uid(), generate_uid())
    return root, (study, series, frame, uids)


def rows_of(glint_bin, path, *extra):
    info = glint_json(glint_bin, "info", str(path), "--labels", "--json", *extra)
    return info, {r["value"]: r for r in info["labels"]}


def test_info_lists_each_roi_with_its_name_colour_voxels_and_ml(data, glint_bin):
    root, _ = data
    info, rows = rows_of(glint_bin, root / "export" / "rs.dcm")
    assert sorted(rows) == sorted(ROIS)
    for number, (name, colour) in ROIS.items():
        assert rows[number]["name"] == name
        assert tuple(rows[number]["color"]) == colour
        assert rows[number]["ml"] == pytest.approx(rows[number]["voxels"] * VOXEL_ML)
    m = masks()
    # Traced along voxel edges: exact.
    assert rows[1]["voxels"] == m[1].sum()
    assert rows[4]["voxels"] == m[4].sum() == ROWS * COLS * SLICES
    # 64-gons through the circle: within 3 %.
    for n in (2, 3):
        assert rows[n]["voxels"] == pytest.approx(m[n].sum(), rel=0.03), (n, m[n].sum())
    # The hole is a hole: the ring holds fewer voxels than its outer disc.
    assert rows[3]["voxels"] < 0.85 * np.pi * (RING[1] ** 2) / (PIXEL[0] * PIXEL[1]) * len(RING_SLICES)
    # No contours, only a point: listed with 0 ml and a note.
    assert (rows[5]["voxels"], rows[5]["ml"], rows[5]["note"]) == (0, 0.0, "no closed contour")
    assert (rows[6]["voxels"], rows[6]["note"]) == (0, "no closed contour")
    assert info["label_table"]["entries"] == len(ROIS)
    notes = " | ".join(info["notes"])
    assert "skipped 1 POINT/OPEN_PLANAR/OPEN_NONPLANAR contour(s)" in notes
    assert "ROI 5 'Empty' has no closed contour" in notes
    # The text listing too.
    text = run_glint(glint_bin, "info", str(root / "export" / "rs.dcm"), "--labels")
    assert text.returncode == 0, text.stderr
    assert "PTV box" in text.stdout and "#1e3cfa" in text.stdout and "(no closed contour)" in text.stdout


def test_the_label_map_is_on_the_ct_grid_and_smaller_rois_keep_shared_voxels(data, glint_bin):
    root, _ = data
    rs = root / "export" / "rs.dcm"
    info = glint_json(glint_bin, "info", str(rs), "--json")
    assert info["dims"] == [COLS, ROWS, SLICES]
    affine = np.array(info["affine_voxel_to_ras_mm"])
    assert np.allclose(affine[:3, 3], np.array(ORIGIN) * [-1, -1, 1], atol=1e-4)
    # Every organ lies inside the body outline (and in no other organ): the voxels in
    # more than one ROI are the organs' own, and the organs (smaller) keep them, so
    # every label is in the map.
    _, rows = rows_of(glint_bin, rs)
    note = next(n for n in info["notes"] if "in more than one ROI" in n)
    assert int(note.split()[0]) == rows[1]["voxels"] + rows[2]["voxels"] + rows[3]["voxels"]
    assert "the smallest ROI keeps them" in note
    assert info["range"] == [1.0, 4.0]


def test_a_ct_of_another_frame_of_reference_is_refused_in_one_line(data, glint_bin, tmp_path):
    root, _ = data
    out = tmp_path / "out.png"
    line = cli_error_line(glint_bin, "render", str(root / "other"), "--labels", str(root / "export" / "rs.dcm"), "--quiet", "-o", str(out))
    assert "frame of reference" in line and "is not the image's" in line, line
    assert not out.exists()


def test_the_export_renders_labelled_surfaces_and_a_label_volume_with_a_legend(data, glint_bin, tmp_path):
    from PIL import Image

    root, _ = data
    export = root / "export"
    rs = export / "rs.dcm"
    for how in ("surfaces", "volume"):
        out = tmp_path / f"{how}.png"
        proc = run_glint(
            glint_bin, "render", str(export), "--labels", str(rs), "--labels-as", how,
            "--hide", "External", "--size", "96x96", "-o", str(out),
        )
        assert proc.returncode == 0, proc.stderr
        # The reader's notes name the structure set the CT read skipped.
        assert "rs.dcm" in proc.stderr, proc.stderr
        rgb = np.asarray(Image.open(out).convert("RGB"), dtype=np.int32)
        # The box's red is drawn (lit: red dominant).
        red = (rgb[..., 0] > 100) & (rgb[..., 0] > 2 * rgb[..., 1]) & (rgb[..., 0] > 2 * rgb[..., 2])
        assert red.sum() > 20, (how, red.sum())


def malformed(pydicom, data, tmp_path, name, change):
    """The export's structure set with `change(contours)` applied, beside its CT."""
    import shutil

    root, (study, series, frame, uids) = data
    folder = tmp_path / name
    shutil.copytree(root / "export", folder)
    shapes = contours()
    change(shapes)
    write_rtstruct(pydicom, folder / "rs.dcm", study, series, frame, uids, shapes=shapes)
    return folder / "rs.dcm"


def test_bad_contours_are_refused_in_one_line_and_open_ones_skipped(data, glint_bin, tmp_path):
    pydicom = require_module("pydicom")
    root, (study, series, frame, uids) = data
    cases = {
        "odd": (lambda s: s[1].__setitem__(0, ("CLOSED_PLANAR", s[1][0][1][:-1])), "ContourData holds 11 numbers, not x/y/z triples"),
        "off": (lambda s: s[1].append(("CLOSED_PLANAR", rectangle(SLICES - 1 + 0.7, 3, 5, 3, 5))), "more than half the slice spacing (0.750 mm) outside"),
        "tilted": (lambda s: s[2].append(("CLOSED_PLANAR", lps(1, 2, 2) + lps(3, 2, 5) + lps(3, 6, 5))), "is not in one slice plane"),
        "short": (lambda s: s[1].append(("CLOSED_PLANAR", lps(1, 2, 2) + lps(1, 2, 5))), "a closed contour of 2 point(s) encloses nothing"),
        "kind": (lambda s: s[1].append(("CURVE", lps(1, 2, 2) * 3)), 'ContourGeometricType "CURVE"'),
    }
    for name, (change, expected) in cases.items():
        rs = malformed(pydicom, data, tmp_path, name, change)
        line = cli_error_line(glint_bin, "info", str(rs), "--labels")
        assert expected in line, (name, line)
        out = tmp_path / f"{name}.png"
        line = cli_error_line(glint_bin, "render", str(rs.parent), "--labels", str(rs), "-q", "-o", str(out))
        assert expected in line, (name, line)
        assert not out.exists()
    # Open contours are skipped with a note, not refused: they enclose no volume.
    rs = malformed(pydicom, data, tmp_path, "open", lambda s: s[1].append(("OPEN_PLANAR", rectangle(4, 3, 5, 3, 5))))
    _, rows = rows_of(glint_bin, rs)
    assert rows[1]["voxels"] == masks()[1].sum()
    # Non-numeric ContourData, and a NumberOfContourPoints far larger than the data
    # (nothing is sized by it).
    ds = pydicom.dcmread(root / "export" / "rs.dcm")
    ds.ROIContourSequence[0].ContourSequence[0].NumberOfContourPoints = 2**31 - 1
    bad = tmp_path / "count.dcm"
    ds.save_as(bad)
    line = cli_error_line(glint_bin, "info", str(bad), "--labels", "--json")
    assert "NumberOfContourPoints is 2147483647, ContourData holds 4 points" in line
    # A value of ContourData that is not a number (the file's bytes edited: pydicom
    # refuses to write one), same length so the element stays well formed.
    raw = (root / "export" / "rs.dcm").read_bytes()
    value = ds.ROIContourSequence[0].ContourSequence[0].ContourData[1]
    text = b"\\" + str(value).encode() + b"\\"
    assert text in raw, text
    (tmp_path / "nonnum").mkdir()
    bad = tmp_path / "nonnum" / "rs.dcm"
    bad.write_bytes(raw.replace(text, b"\\" + b"x" * (len(text) - 2) + b"\\", 1))
    line = cli_error_line(glint_bin, "info", str(bad), "--labels")
    assert "ContourData is not a list of numbers" in line, line
    # Another frame of reference on one ROI.
    ds = pydicom.dcmread(root / "export" / "rs.dcm")
    ds.StructureSetROISequence[1].ReferencedFrameOfReferenceUID = "1.2.3.4"
    bad = tmp_path / "export_for"
    import shutil

    shutil.copytree(root / "export", bad)
    ds.save_as(bad / "rs.dcm")
    line = cli_error_line(glint_bin, "info", str(bad / "rs.dcm"), "--labels")
    assert "ROI 2 'Sphere' is in frame of reference 1.2.3.4" in line, line


def test_the_viewer_legend_lists_the_rois_and_hides_one_by_name(data, glint_bin):
    """`glint view EXPORT --labels RS`: the hello's label list (the page's legend) holds
    the ROIs drawn, named and coloured by the structure set, and an update hiding one
    by its ROIName is taken (a frame follows, no error)."""
    import socket
    import subprocess
    import time

    require_module("tornado")  # a dask.distributed dependency, pinned with it
    from tornado import websocket
    from tornado.ioloop import IOLoop

    root, _ = data
    export = root / "export"
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen(
        [glint_bin, "view", str(export), "--labels", str(export / "rs.dcm"), "--port", str(port), "-q"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )

    async def talk():
        deadline = time.monotonic() + 120
        while True:
            try:
                c = await websocket.websocket_connect(f"ws://127.0.0.1:{port}/ws")
                break
            except OSError:
                assert proc.poll() is None and time.monotonic() < deadline, "glint view did not start"
                time.sleep(0.2)
        hello = None
        while hello is None:
            m = await c.read_message()
            if isinstance(m, str) and json.loads(m)["type"] == "hello":
                hello = json.loads(m)
        c.write_message(json.dumps({"type": "update", "seq": 1, "scene": {"labels": {"hide": ["PTV box"]}}}))
        # The update's frame (header: magic "GLNT", then seq as a little-endian u32)
        # comes with no error before it (an unknown name would be one). The first
        # state's frame may come first or, stopped by the update, not at all.
        while True:
            m = await c.read_message()
            assert m is not None, "the connection closed"
            if isinstance(m, bytes):
                assert m[:4] == b"GLNT", m[:16]
                if int.from_bytes(m[4:8], "little") >= 1:
                    break
            else:
                assert json.loads(m)["type"] != "error", m
        c.close()
        return hello

    try:
        hello = IOLoop.current().run_sync(talk, timeout=180)
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    listed = {e["value"]: (e["name"], e["color"]) for e in hello["labels"]}
    # The body outline gives up the organs' voxels; the ROIs without contours are
    # not drawn, so not listed.
    assert listed == {n: (ROIS[n][0], "#%02x%02x%02x" % ROIS[n][1]) for n in (1, 2, 3, 4)}


def test_python_draws_the_structure_set_over_its_ct(data):
    """From Python the structure set is a scene's labels path like any label map: a
    label volume over the (transparent) CT, unshaded, shows the box in its
    ROIDisplayColor and the sphere in its own."""
    glint = require_module("glint")
    root, _ = data
    export = root / "export"
    scene = glint.Scene(
        input=str(export),
        labels={"path": str(export / "rs.dcm"), "render_as": "volume", "hide": ["External"], "legend": False},
        size=(64, 64),
        camera={"view": "anterior", "projection": "orthographic"},
        material={"ambient": 1.0, "diffuse": 0.0, "specular": 0.0, "shade": False},
        transfer_function={"opacity": [[-1000.0, 0.0], [1000.0, 0.0]], "color": [[0.0, 1.0, 1.0, 1.0]]},
    )
    rgb = np.asarray(glint.render(str(export), scene), dtype=np.int32)[..., :3].reshape(-1, 3)
    near = lambda c: np.all(np.abs(rgb - c) <= 2, axis=1)
    assert near(ROIS[1][1]).sum() > 20 and near(ROIS[2][1]).sum() > 20
