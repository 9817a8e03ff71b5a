"""Every glint-io writer's output read back by a reader glint did not write (issue 34):
nibabel for NIfTI-1 and GIFTI, pynrrd for NRRD, plyfile for PLY. The files come from
crates/io/examples/write_formats.rs (GLINT_WRITE_FORMATS, built by scripts/test-python);
the expected values are stated here, independently of glint.
"""

import os
import subprocess

import numpy as np
import pytest

from conftest import _missing, require_module

AFFINE = np.array(
    [[0.0, 0.0, -2.5, 10.0], [1.5, 0.0, 0.0, -4.0], [0.0, 2.0, 0.0, 7.25], [0, 0, 0, 1]]
)
I, J, K = np.meshgrid(np.arange(4), np.arange(3), np.arange(2), indexing="ij")
STORED = I + 10 * J + 100 * K - 50  # indexed [i, j, k]
POSITIONS = np.array([[0, 0, 0], [10, 0, 0], [0, 20, 0], [0, 0, 30]], dtype=np.float32)
TRIANGLES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
NORMALS = np.array([[0, 0, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
SCALARS = np.array([0.5, 1.5, 2.5, 3.5], dtype=np.float32)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    exe = os.environ.get("GLINT_WRITE_FORMATS")
    if not exe or not os.access(exe, os.X_OK):
        _missing(f"GLINT_WRITE_FORMATS={exe!r} (cargo build -p glint-io --example write_formats)")
    out = tmp_path_factory.mktemp("written")
    subprocess.run([exe, str(out)], check=True, timeout=60)
    return out


@pytest.mark.parametrize("name", ["vol.nii", "vol_be.nii.gz"])
def test_nifti1_by_nibabel(written, name):
    nib = require_module("nibabel")
    img = nib.load(str(written / name))
    assert isinstance(img, nib.Nifti1Image)
    assert img.shape == (4, 3, 2)
    assert np.array_equal(np.asarray(img.dataobj.get_unscaled()), STORED)
    assert np.array_equal(img.get_fdata(), 2.0 * STORED + 1.0)
    assert np.allclose(img.affine, AFFINE, atol=1e-6)
    assert int(img.header["sform_code"]) > 0
    assert img.header.get_xyzt_units()[0] == "mm"
    assert np.allclose(img.header.get_zooms()[:3], (1.5, 2.0, 2.5))


@pytest.mark.parametrize("name", ["vol.nrrd", "vol_gz.nrrd", "vol.nhdr"])
def test_nrrd_by_pynrrd(written, name):
    nrrd = require_module("nrrd")
    # index_order="F": data[i, j, k] with i fastest in the file, as NRRD stores it.
    data, header = nrrd.read(str(written / name), index_order="F")
    assert data.shape == (4, 3, 2)
    assert np.array_equal(data, STORED)
    # NRRD's space directions are the affine's columns, its origin the translation; the
    # space is RAS or LPS (x and y negated).
    space = header["space"]
    flip = np.array([1.0, 1.0, 1.0]) if space in ("right-anterior-superior", "RAS") else np.array([-1.0, -1.0, 1.0])
    assert space in ("right-anterior-superior", "RAS", "left-posterior-superior", "LPS"), space
    directions = np.asarray(header["space directions"], dtype=float)
    assert np.allclose(directions * flip, AFFINE[:3, :3].T, atol=1e-6)
    assert np.allclose(np.asarray(header["space origin"], dtype=float) * flip, AFFINE[:3, 3], atol=1e-6)


@pytest.mark.parametrize("name", ["mesh_le.ply", "mesh_be.ply", "mesh_ascii.ply"])
def test_ply_by_plyfile(written, name):
    plyfile = require_module("plyfile")
    ply = plyfile.PlyData.read(str(written / name))
    v = ply["vertex"].data
    assert np.array_equal(np.stack([v["x"], v["y"], v["z"]], axis=1), POSITIONS)
    assert np.array_equal(np.stack([v["nx"], v["ny"], v["nz"]], axis=1), NORMALS)
    scalar = [p.name for p in ply["vertex"].properties if p.name not in ("x", "y", "z", "nx", "ny", "nz")]
    assert len(scalar) == 1, scalar
    assert np.array_equal(v[scalar[0]], SCALARS)
    faces = np.stack(ply["face"].data["vertex_indices"])
    assert np.array_equal(faces, TRIANGLES)
    want = {"mesh_le.ply": "<", "mesh_be.ply": ">", "mesh_ascii.ply": "="}[name]
    assert ply.byte_order == want


@pytest.mark.parametrize("name", ["mesh_ascii.gii", "mesh_b64.gii", "mesh_gz.gii"])
def test_gifti_by_nibabel(written, name):
    nib = require_module("nibabel")
    img = nib.load(str(written / name))
    coords = img.get_arrays_from_intent("NIFTI_INTENT_POINTSET")
    faces = img.get_arrays_from_intent("NIFTI_INTENT_TRIANGLE")
    assert len(coords) == 1 and len(faces) == 1
    assert np.array_equal(coords[0].data, POSITIONS)
    assert np.array_equal(faces[0].data, TRIANGLES)
    # The encoding asked for is the one in the file.
    want = {"mesh_ascii.gii": "ASCII", "mesh_b64.gii": "Base64Binary", "mesh_gz.gii": "GZipBase64Binary"}[name]
    assert f'Encoding="{want}"' in (written / name).read_text()
