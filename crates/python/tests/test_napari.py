"""The napari plugin (crates/python/napari-glint, issue 45): its readers' layer data
and metadata, and the dock widget "Render with glint" adding a rendered layer, with
napari's own test fixture (make_napari_viewer) on headless Qt (pytest-qt).

Qt's offscreen platform (QT_QPA_PLATFORM=offscreen) has no OpenGL, and napari's canvas
(vispy) needs it: adding a layer to a viewer fails there. So without a display these
tests start Xvfb (mesa's software GL; scripts/install-deps installs it) and use Qt's
xcb platform on it; without Xvfb they fall back to offscreen, where only the readers
work (strict mode fails instead).

The plugin is not pip-installed into the test venv (that would need a build backend):
its source is put on sys.path and its npe2 manifest registered with napari's plugin
manager, which is what installing it does through the entry point."""

import importlib.util
import os
import pathlib
import sys

import numpy as np
import pytest

from conftest import ran, record, require_module, strict

def _display():
    """A display for Qt: the one set, else an Xvfb of our own (stopped at exit)."""
    import atexit
    import shutil
    import subprocess

    if os.environ.get("DISPLAY") or os.environ.get("QT_QPA_PLATFORM"):
        return
    if shutil.which("Xvfb") is None:
        if strict():
            raise RuntimeError("missing: Xvfb (scripts/install-deps; strict mode)")
        os.environ["QT_QPA_PLATFORM"] = "offscreen"
        return
    read, write = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "1280x1024x24",
                             "-nolisten", "tcp"], pass_fds=(write,), stderr=subprocess.DEVNULL)
    os.close(write)
    with os.fdopen(read) as f:
        number = f.readline().strip()
    atexit.register(proc.terminate)
    os.environ["DISPLAY"] = f":{number}"
    os.environ["QT_QPA_PLATFORM"] = "xcb"


PLUGIN = pathlib.Path(__file__).resolve().parents[1] / "napari-glint" / "src"

_needed = [m for m in ("napari", "npe2", "pytestqt", "magicgui") if importlib.util.find_spec(m) is None]
if _needed:
    what = f"Python modules {_needed} (crates/python/tests/requirements.txt)"
    if strict():
        raise ImportError(f"missing: {what} (strict mode: GLINT_STRICT or CI is set)")
    record(f"SKIPPED {what}")
    pytest.skip(what, allow_module_level=True)
_display()
sys.path.insert(0, str(PLUGIN))
import napari_glint  # noqa: E402
from napari_glint import _reader  # noqa: E402

import glint  # noqa: E402


@pytest.fixture(scope="module")
def registered():
    import npe2

    pm = npe2.PluginManager.instance()
    if "napari-glint" not in pm:
        pm.register(npe2.PluginManifest.from_file(PLUGIN / "napari_glint" / "napari.yaml"))
    return pm


def test_dicom_seg_reads_as_labels_with_names_colours_and_affine(tmp_path, registered):
    pydicom = require_module("pydicom")
    hd = require_module("highdicom")
    import test_seg

    ct = test_seg.ct_series(pydicom, tmp_path / "ct")
    m = test_seg.masks()
    test_seg.write_seg(hd, ct, m, tmp_path / "seg.dcm")
    reader = _reader.get_reader(str(tmp_path / "seg.dcm"))
    assert reader is not None
    [(data, meta, kind)] = reader(str(tmp_path / "seg.dcm"))
    assert kind == "labels"
    want = glint.read(str(tmp_path / "seg.dcm"))
    assert data.shape == want.shape
    assert np.array_equal(np.unique(data), [0, 1, 2, 3])
    assert np.allclose(meta["affine"], want.affine)
    assert meta["metadata"]["spacing"] == pytest.approx(want.spacing)
    names = dict(zip(meta["features"]["index"], meta["features"]["name"]))
    assert [names[i] for i in (1, 2, 3)] == ["Liver", "Aorta", "Kidney"]
    # The colours highdicom stored (as CIELab) come back close to the sRGB given.
    for value, (_, rgb) in test_seg.SEGMENTS.items():
        got = np.array(meta["colormap"].color_dict[value][:3]) * 255
        assert np.abs(got - rgb).max() <= 2, (value, got, rgb)
    # The CT series directory: an image with its affine.
    [(ct_data, ct_meta, ct_kind)] = _reader.get_reader(str(tmp_path / "ct"))(str(tmp_path / "ct"))
    ct_vol = glint.read(str(tmp_path / "ct"))
    assert ct_kind == "image" and ct_data.shape == ct_vol.shape == (test_seg.COLS, test_seg.ROWS, test_seg.SLICES)
    assert np.array_equal(ct_data, ct_vol.samples)
    assert np.allclose(ct_meta["affine"], ct_vol.affine)
    ran("napari reader: DICOM series and SEG")


def test_mgz_reads_with_its_affine(tmp_path):
    nib = require_module("nibabel")
    data = np.arange(4 * 5 * 6, dtype=np.float32).reshape(4, 5, 6)
    affine = np.array([[-1.5, 0, 0, 10], [0, 0, 2.0, -20], [0, -1.0, 0, 30], [0, 0, 0, 1]])
    nib.save(nib.MGHImage(data, affine), tmp_path / "t.mgz")
    [(got, meta, kind)] = _reader.get_reader(str(tmp_path / "t.mgz"))(str(tmp_path / "t.mgz"))
    assert kind == "image"
    assert np.array_equal(got, data)
    assert np.allclose(meta["affine"], affine)
    assert meta["metadata"]["spacing"] == pytest.approx((1.5, 1.0, 2.0))
    assert meta["metadata"]["format"] and "MGH" in meta["metadata"]["format"].upper()


def test_gifti_surface_reads_as_vertices_and_faces(tmp_path):
    nib = require_module("nibabel")
    verts = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], np.float32)
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.int32)
    img = nib.gifti.GiftiImage(darrays=[
        nib.gifti.GiftiDataArray(verts, intent="NIFTI_INTENT_POINTSET", datatype="NIFTI_TYPE_FLOAT32"),
        nib.gifti.GiftiDataArray(faces, intent="NIFTI_INTENT_TRIANGLE", datatype="NIFTI_TYPE_INT32"),
    ])
    nib.save(img, tmp_path / "tet.surf.gii")
    [(data, meta, kind)] = _reader.read(str(tmp_path / "tet.surf.gii"))
    assert kind == "surface"
    assert np.allclose(data[0], verts) and np.array_equal(data[1], faces)
    assert meta["metadata"]["units"] == "mm"


def test_reader_declines_what_napari_reads_and_missing_paths(tmp_path):
    (tmp_path / "a.tif").write_bytes(b"")
    assert _reader.get_reader(str(tmp_path / "a.tif")) is None
    assert _reader.get_reader(str(tmp_path / "missing.mgz")) is None
    assert _reader.get_reader(str(tmp_path)) is None  # a directory of no DICOM


def test_napari_opens_a_file_through_the_plugin(make_napari_viewer, tmp_path, registered):
    nib = require_module("nibabel")
    data = np.zeros((8, 8, 8), np.float32)
    data[2:6, 2:6, 2:6] = 1.0
    nib.save(nib.MGHImage(data, np.diag([2.0, 2.0, 2.0, 1.0])), tmp_path / "cube.mgz")
    viewer = make_napari_viewer()
    layers = viewer.open(str(tmp_path / "cube.mgz"), plugin="napari-glint")
    assert len(layers) == 1 and layers[0].data.shape == (8, 8, 8)
    assert np.allclose(layers[0].affine.affine_matrix, np.diag([2.0, 2.0, 2.0, 1.0]))


def test_render_widget_adds_a_rendered_layer(make_napari_viewer, registered):
    viewer = make_napari_viewer()
    vol = np.zeros((24, 24, 24), np.float32)
    vol[6:18, 6:18, 6:18] = 100.0
    viewer.add_image(vol, name="cube", scale=(1.0, 1.0, 1.0))
    _, widget = viewer.window.add_plugin_dock_widget("napari-glint", "Render with glint")
    widget.size_box.value = 48
    for model in ("local", "shadows"):
        widget.lighting_box.value = model
        layer = widget.render()
        assert layer is not None, widget.status_box.value
        assert layer.rgb and layer.data.shape == (48, 48, 3) and layer.data.dtype == np.uint8
        assert layer.data.max() > 0  # the cube is lit
    assert [l.name for l in viewer.layers] == ["cube", "cube (glint local)", "cube (glint shadows)"]
    # Shadowed and local light differ.
    assert not np.array_equal(viewer.layers[1].data, viewer.layers[2].data)
    ran("napari dock widget: Render with glint")
