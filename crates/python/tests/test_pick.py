"""glint.Renderer.pick: the 3D point a pixel shows, checked against an analytic ball
whose value is its depth below the surface (issue 43 item 2)."""

import numpy as np
import pytest

import glint

N, SPACING, R = 32, 1.5, 15.0
CENTRE = SPACING * (N - 1) / 2


@pytest.fixture(scope="module")
def ball():
    """The ball as int16 with a rescale (value = 0.1 * stored - 100, in 'HU'), and
    its stored samples."""
    idx = np.indices((N, N, N)).astype(np.float64) * SPACING
    depth = R - np.sqrt(((idx - CENTRE) ** 2).sum(axis=0))
    stored = np.round(depth * 10 + 1000).astype(np.int16)
    vol = glint.Volume.from_array(stored, spacing=(SPACING,) * 3, slope=0.1,
                                  intercept=-100.0, units="HU")
    return vol, stored


FIELDS = dict(mode="iso", iso=0.0, size=(64, 48), camera={"projection": "orthographic"})


def test_pick_returns_the_balls_front_point_voxel_value_and_units(ball):
    vol, stored = ball
    r = glint.Renderer(vol)
    p = r.pick(32, 24, **FIELDS)
    assert p["object"] == {"kind": "volume"}
    assert (p["x"], p["y"]) == (32.0, 24.0)
    w = np.array(p["world_mm"])
    # On the sphere within half a voxel, facing the anterior (+y) camera.
    assert abs(np.linalg.norm(w - CENTRE) - R) < SPACING / 2
    assert w[1] - CENTRE > 0.9 * R
    assert np.allclose(np.array(p["voxel"]) * SPACING, w, atol=1e-3)
    i, j, k = p["voxel_nearest"]
    assert p["value"] == pytest.approx(0.1 * stored[i, j, k] - 100.0, abs=1e-4)
    assert p["units"] == "HU"
    assert p["label"] is None
    assert abs(p["interpolated"]) < 0.1


def test_pick_is_none_where_nothing_shows_and_refuses_points_off_the_image(ball):
    vol, _ = ball
    r = glint.Renderer(vol)
    assert r.pick(0.5, 0.5, **FIELDS) is None
    with pytest.raises(ValueError, match="off the 64x48 image"):
        r.pick(64, 10, **FIELDS)
    with pytest.raises(ValueError, match="threshold"):
        r.pick(32, 24, opacity=1.0, **FIELDS)


def test_a_scene_object_and_the_composite_threshold(ball):
    vol, _ = ball
    r = glint.Renderer(vol)
    scene = glint.Scene(size=(64, 48), transfer_function={
        "opacity": [[-100, 0], [0, 0], [0.05, 1], [100, 1]],
        "color": [[-100, 1, 1, 1], [100, 1, 1, 1]]})
    near = r.pick(32, 24, scene)
    deep = r.pick(32, 24, scene, opacity=0.99)
    assert near["object"]["kind"] == "volume" and near["opacity"] == pytest.approx(0.5)
    # A higher threshold is reached no nearer along the ray.
    assert deep["depth_mm"] >= near["depth_mm"]
