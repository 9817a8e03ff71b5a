"""glint's `path` lighting as a pure medium (`lighting.surface_weight` 0) against Mitsuba
3's `volpath` on the same medium, lights and camera (issue 41 item 4; the cases and
units in scripts/mitsuba/medium.py, the converged figures in docs/lighting.md).

The statistical test: each renderer renders K independent batches (seeds 1..K) of SPP
samples per pixel at 32x32; per pixel and channel z = (mean_glint - mean_mitsuba) /
sqrt(se_glint^2 + se_mitsuba^2), the standard errors from the batches' spread (pixels
whose spread is float rounding only, e.g. the environment seen through empty space,
must agree to 4 times their rounding). The images agree when the mean of z^2 is at most
MAX_MEAN_Z2 (1 for normal errors; 1.17 with 8 batches each, as Student's t with ~14
degrees of freedom has; 1.20-1.25 measured; its spread over the ~1500 noisy values is
about 0.08) and the images' totals differ by at most 4 standard errors (about 0.4% of
the total here). A 5% error in the albedo fails (tested below: totals 27 standard
errors apart, mean z^2 3.6), as do a mirrored image or a light from the other side
(mean z^2 >= 5, tried while writing the test).
"""

import dataclasses
import pathlib
import sys

import pytest

import glint
from conftest import require_module

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[3] / "scripts" / "mitsuba"))
import medium as gm  # noqa: E402

SIZE = (32, 32)
GRID = 24
SPP = 32
K = 8
MAX_MEAN_Z2 = 1.6


def mitsuba():
    mi = require_module("mitsuba")
    mi.set_variant("scalar_rgb")
    return mi


def glint_batches(case):
    return gm.batches(lambda s: gm.render_glint(glint, case, SIZE, SPP, s)[0], K)


def mitsuba_batches(mi, case, folder):
    derived = gm.render_glint(glint, case, SIZE, 1, 0)[1]
    scene = gm.MitsubaCase(mi, case, derived, SIZE, folder)
    return gm.batches(lambda s: scene.render(SPP, s), K, first_seed=K + 1)


@pytest.mark.parametrize("name", ["ball-g0", "ball-g0.6", "blob-light"])
def test_pure_medium_agrees_with_mitsuba_volpath(name, tmp_path):
    mi = mitsuba()
    case = gm.cases(GRID)[name]
    m = mitsuba_batches(mi, case, tmp_path)
    a = gm.agreement(glint_batches(case), m)
    assert a.passes(MAX_MEAN_Z2), a
    if name == "ball-g0":
        # The test can fail: glint's albedo 5% low (0.855 for 0.9) is found.
        darker = dataclasses.replace(case, albedo=(0.855,) * 3)
        b = gm.agreement(glint_batches(darker), m)
        assert not b.passes(MAX_MEAN_Z2), b


def test_export_writes_the_medium_glint_classifies(tmp_path):
    mi = mitsuba()
    case = gm.cases(GRID)["blob-light"]
    volume = glint.Volume.from_array(case.values, spacing=(case.spacing,) * 3)
    out = gm.export_medium(glint, mi, volume, gm.glint_fields(case, SIZE, 1, 0), tmp_path)
    # The extinction per mm is sigma * v (the transfer function's design), the albedo
    # the case's, and Mitsuba reads the grids back as written.
    assert abs(out["sigma"] - case.sigma * case.values).max() < 1e-5 * case.sigma
    assert abs(out["albedo"] - case.albedo).max() < 1e-5
    assert out["lo_mm"] == [-0.5 * case.spacing] * 3
    density = mi.VolumeGrid(str(tmp_path / "density.vol"))
    albedo = mi.VolumeGrid(str(tmp_path / "albedo.vol"))
    assert list(density.size()) == [GRID] * 3 and density.channel_count() == 1
    assert albedo.channel_count() == 3
    assert abs(density.max() - out["sigma"].max()) < 1e-6
