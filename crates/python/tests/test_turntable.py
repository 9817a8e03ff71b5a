"""glint.turntable against `glint render --turntable`: the same frames, the same errors."""

import numpy as np
import pytest
from PIL import Image as PILImage

import glint
from conftest import cli_error_line, run_glint


def small_scene():
    """The Shepp-Logan head, small: asymmetric, so views round it differ."""
    return glint.Scene(input={"phantom": {"name": "shepp-logan", "size": 32}}, size=(40, 32))


def test_gif_has_the_frames_asked_for(tmp_path):
    gif = tmp_path / "spin.gif"
    glint.turntable(small_scene(), 4, gif, fps=25)
    with PILImage.open(gif) as im:
        assert im.size == (40, 32) and im.n_frames == 4
        frames = []
        for k in range(4):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB")))
    assert all(not np.array_equal(frames[0], f) for f in frames[1:])
    assert [p.name for p in tmp_path.iterdir()] == ["spin.gif"]


def test_png_frames_equal_the_command_and_frame_0_the_still(glint_bin, tmp_path):
    scene = small_scene()
    glint.turntable(scene, 3, f"{tmp_path / 'py'}/")
    scene_file = tmp_path / "scene.json"
    scene_file.write_text(scene.to_json())
    proc = run_glint(glint_bin, "render", "-q", "--scene", str(scene_file), "--turntable", "3",
                     "-o", f"{tmp_path / 'cli'}/")
    assert proc.returncode == 0, proc.stderr
    names = [f"frame-{k:04}.png" for k in range(3)]
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == names
    for name in names:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    with PILImage.open(tmp_path / "py" / names[0]) as im:
        assert np.array_equal(np.asarray(im), glint.render(None, scene))


def test_bad_turntables_raise_the_commands_line_and_write_nothing(glint_bin, tmp_path):
    for n, name, exc in [(1, "a.gif", ValueError), (4, "a.xyz", ValueError),
                         (4, "a.webp", ValueError)]:
        path = tmp_path / name
        with pytest.raises(exc) as info:
            glint.turntable(small_scene(), n, path)
        line = cli_error_line(glint_bin, "render", "-q", "--turntable", str(n), "-o", str(path))
        assert str(info.value) == line
    with pytest.raises(ValueError, match="1..=120"):
        glint.turntable(small_scene(), 4, tmp_path / "a.gif", fps=0)
    assert list(tmp_path.iterdir()) == []
