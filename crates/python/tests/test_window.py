"""Window and level through the scene (issue 43 item 3): the same image as
`glint render --window W --window-level L`, cleared by a preset, refused when bad."""

import numpy as np
import pytest
from PIL import Image as PILImage

import glint
from conftest import run_glint


def test_window_level_renders_like_the_cli(glint_bin, tmp_path):
    base = dict(input={"phantom": {"name": "shepp-logan", "size": 32}}, size=(40, 32), mode="mip")
    scene = glint.Scene(**base, window_level={"window": 0.1, "level": 0.25})
    assert scene.window_level == {"window": 0.1, "level": 0.25}
    assert glint.Scene(**base).window_level is None
    png = tmp_path / "cli.png"
    proc = run_glint(glint_bin, "render", "--phantom", "shepp-logan", "--phantom-size", "32",
                     "--size", "40x32", "--mode", "mip", "--window", "0.1", "--window-level", "0.25",
                     "--quiet", "-o", str(png))
    assert proc.returncode == 0, proc.stderr
    with PILImage.open(png) as im:
        cli = np.asarray(im)
    ours = glint.render(None, scene)
    plain = glint.render(None, glint.Scene(**base))
    assert np.array_equal(ours, cli)
    assert not np.array_equal(ours, plain)
    # A preset starts from its own window.
    assert scene.replace(preset="ct-bone").window_level is None
    with pytest.raises(ValueError, match="window 0"):
        glint.render(None, scene.replace(window_level={"window": 0, "level": 1}))
