"""glint.read and glint.Volume against nibabel, and the error paths."""

import gzip
import pickle
import threading

import nibabel as nib
import numpy as np
import pytest

import glint
from conftest import cli_error_line


def test_read_matches_nibabel(mni_path):
    img = nib.load(str(mni_path))
    vol = glint.read(mni_path)
    assert vol.shape == img.shape
    assert vol.format == "NIfTI"
    assert vol.path == mni_path
    # Stored samples: same type and values as nibabel's unscaled data, same axis order.
    raw = np.asanyarray(img.dataobj.get_unscaled())
    assert vol.dtype == str(img.get_data_dtype())
    np.testing.assert_array_equal(vol.samples, raw)
    # Physical values: exactly get_fdata().
    np.testing.assert_array_equal(vol.fdata(), img.get_fdata())
    # nibabel's affine is the sform here (sform_code > 0), float32 header values.
    assert int(img.header["sform_code"]) > 0
    assert "affine from sform" in vol.notes
    np.testing.assert_array_equal(vol.affine, img.affine)
    np.testing.assert_allclose(vol.spacing, img.header.get_zooms(), rtol=1e-6)
    lo, hi = vol.range()
    assert (lo, hi) == (img.get_fdata().min(), img.get_fdata().max())


def test_samples_are_a_read_only_view(mni_path):
    vol = glint.read(mni_path)
    s = vol.samples
    assert not s.flags.writeable and s.flags.f_contiguous
    with pytest.raises(ValueError):
        s[0, 0, 0] = 1
    # The view keeps the volume alive.
    del vol
    assert s.sum() > 0


@pytest.mark.parametrize("order", ["C", "F"])
def test_from_array_axis_order(order):
    rng = np.random.default_rng(7)
    arr = np.asarray(rng.integers(-1000, 1000, size=(5, 6, 7)), dtype=np.int16, order=order)
    vol = glint.Volume.from_array(arr, spacing=(0.5, 1.0, 2.0))
    assert vol.shape == (5, 6, 7) and vol.dtype == "int16"
    np.testing.assert_array_equal(vol.samples, arr)
    assert vol.samples[4, 1, 6] == arr[4, 1, 6]
    np.testing.assert_array_equal(vol.affine, np.diag([0.5, 1.0, 2.0, 1.0]))
    assert vol.spacing == (0.5, 1.0, 2.0)
    assert vol.format is None and vol.path is None


@pytest.mark.parametrize("dtype", ["uint8", "int16", "float32", "float64"])
@pytest.mark.parametrize("shape", [(1, 1, 1), (33, 2, 65), (64, 3, 32), (1, 40, 70), (70, 1, 1), (37, 41, 43)])
def test_from_array_c_order_tiles(shape, dtype):
    # C-ordered arrays are reordered tile by tile (32 x 32): shapes that are and are not
    # multiples of the tile, axes of one sample, every element width.
    arr = np.arange(np.prod(shape), dtype=np.int64).reshape(shape).astype(dtype)
    assert arr.flags.c_contiguous
    vol = glint.Volume.from_array(arr)
    np.testing.assert_array_equal(vol.samples, arr)
    assert vol.samples.flags.f_contiguous


def test_from_nibabel_image_round_trip(mni_path, tmp_path):
    img = nib.load(str(mni_path))
    data = img.get_fdata(dtype=np.float32)
    vol = glint.Volume.from_array(data, affine=img.affine, units="a.u.")
    np.testing.assert_array_equal(vol.samples, data)
    np.testing.assert_array_equal(vol.affine, img.affine)
    assert vol.units == "a.u."
    # Written by nibabel and read by glint: same samples and affine again.
    out = tmp_path / "copy.nii"
    nib.save(nib.Nifti1Image(data, img.affine), str(out))
    back = glint.read(out)
    np.testing.assert_array_equal(back.samples, data)
    np.testing.assert_allclose(back.affine, img.affine, atol=1e-5)


def test_slope_and_intercept():
    arr = np.arange(24, dtype=np.uint8).reshape(2, 3, 4)
    vol = glint.Volume.from_array(arr, slope=2.0, intercept=-1024.0, units="HU")
    np.testing.assert_array_equal(vol.fdata(), 2.0 * arr - 1024.0)
    assert vol.range() == (-1024.0, 2.0 * 23 - 1024.0)


@pytest.mark.parametrize(
    "array,kwargs,exc,match",
    [
        (np.zeros((2, 2, 2), np.complex64), {}, TypeError, "unsupported sample type"),
        (np.zeros((2, 2, 2), np.int64), {}, TypeError, "unsupported sample type"),
        (np.zeros((2, 2, 2), bool), {}, TypeError, "unsupported sample type"),
        ([[[1.0]]], {}, TypeError, "numpy array"),
        (np.zeros((4, 4, 4), np.float32)[::2], {}, ValueError, "not contiguous"),
        (np.zeros((2, 2, 2, 3), np.float32), {}, ValueError, "3-D"),
        (np.zeros((2, 2), np.float32), {}, ValueError, "3-D"),
        (np.zeros((0, 2, 2), np.float32), {}, ValueError, r"shape \(0, 2, 2\) is empty"),
        (np.zeros((3, 2, 0), np.float32, order="F"), {}, ValueError, r"shape \(3, 2, 0\) is empty"),
        (np.zeros((2, 2, 2), np.float32), {"spacing": (1.0, float("nan"), 1.0)}, ValueError, "spacing"),
        (np.zeros((2, 2, 2), np.float32), {"spacing": (1.0, -1.0, 1.0)}, ValueError, "spacing"),
        (np.zeros((2, 2, 2), np.float32), {"affine": np.zeros((4, 4))}, ValueError, "last row"),
        (np.zeros((2, 2, 2), np.float32), {"affine": np.diag([1.0, 1.0, 0.0, 1.0])}, ValueError, "singular"),
        (np.zeros((2, 2, 2), np.float32), {"affine": np.full((4, 4), np.nan)}, ValueError, "non-finite"),
        (np.zeros((2, 2, 2), np.float32), {"affine": np.eye(3)}, ValueError, None),
        (np.zeros((2, 2, 2), np.float32), {"affine": np.eye(4), "spacing": (2, 1, 1)}, ValueError, "disagrees"),
        (np.zeros((2, 2, 2), np.float32), {"slope": 0.0}, ValueError, "slope"),
    ],
)
def test_from_array_rejects(array, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        glint.Volume.from_array(array, **kwargs)


def test_read_errors_match_the_cli(glint_bin, tmp_path, mni_path):
    missing = tmp_path / "missing.nii"
    with pytest.raises(FileNotFoundError) as err:
        glint.read(missing)
    assert str(err.value) == cli_error_line(glint_bin, "info", str(missing))
    assert isinstance(err.value.__cause__, FileNotFoundError)

    # A NIfTI file cut inside its samples: ValueError, the CLI's line.
    with gzip.open(mni_path) as f:
        head = f.read(100_000)
    cut = tmp_path / "cut.nii"
    cut.write_bytes(head)
    with pytest.raises(ValueError) as err:
        glint.read(cut)
    assert str(err.value) == cli_error_line(glint_bin, "info", str(cut))

    garbage = tmp_path / "garbage.nii.gz"
    garbage.write_bytes(b"\x1f\x8b" + b"\0" * 10)
    with pytest.raises(ValueError) as err:
        glint.read(garbage)
    assert str(err.value) == cli_error_line(glint_bin, "info", str(garbage))

    with pytest.raises(ValueError, match="too large"):
        glint.read(mni_path, max_voxels=1000)


def test_pickle_by_path_and_by_value(mni_path):
    vol = glint.read(mni_path)
    blob = pickle.dumps(vol)
    assert len(blob) < 1000  # the path, not 8.7 M samples
    back = pickle.loads(blob)
    assert back.path == vol.path
    np.testing.assert_array_equal(back.samples, vol.samples)

    arr = np.arange(60, dtype=np.float32).reshape(3, 4, 5)
    affine = np.array([[0, 2.0, 0, 10], [1.5, 0, 0, -3], [0, 0, 1, 7], [0, 0, 0, 1]])
    mem = glint.Volume.from_array(arr, affine=affine, slope=3.0, intercept=1.0, units="HU")
    back = pickle.loads(pickle.dumps(mem))
    np.testing.assert_array_equal(back.samples, arr)
    np.testing.assert_array_equal(back.affine, affine)
    assert (back.slope, back.intercept, back.units, back.spacing) == (3.0, 1.0, "HU", (1.5, 2.0, 1.0))


def test_threads_read_at_once(mni_path):
    want = glint.read(mni_path).fdata().sum()
    sums = []

    def work():
        sums.append(glint.read(mni_path).fdata().sum())

    threads = [threading.Thread(target=work) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sums == [want] * 4
