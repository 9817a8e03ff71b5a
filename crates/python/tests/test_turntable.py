"""glint.turntable against `glint render --turntable`: the same frames, the same errors."""

import json

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
    for n, name, exc in [(1, "a.gif", ValueError), (4, "a.xyz", ValueError)]:
        path = tmp_path / name
        with pytest.raises(exc) as info:
            glint.turntable(small_scene(), n, path)
        line = cli_error_line(glint_bin, "render", "-q", "--turntable", str(n), "-o", str(path))
        assert str(info.value) == line
    with pytest.raises(ValueError, match="1..=120"):
        glint.turntable(small_scene(), 4, tmp_path / "a.gif", fps=0)
    assert list(tmp_path.iterdir()) == []


KEYS = [{"azimuth": 0, "elevation": 0, "zoom": 1}, {"azimuth": 90, "elevation": 40, "zoom": 4}]


def test_keys_give_the_commands_camera_path_frames(glint_bin, tmp_path):
    scene = small_scene()
    glint.turntable(scene, 3, f"{tmp_path / 'py'}/", keys=KEYS)
    keys = tmp_path / "keys.json"
    keys.write_text(json.dumps(KEYS))
    scene_file = tmp_path / "scene.json"
    scene_file.write_text(scene.to_json())
    proc = run_glint(glint_bin, "render", "-q", "--scene", str(scene_file), "--camera-path",
                     str(keys), "--frames", "3", "-o", f"{tmp_path / 'cli'}/")
    assert proc.returncode == 0, proc.stderr
    for k in range(3):
        name = f"frame-{k:04}.png"
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    # The middle frame is the still half way: azimuth 45, elevation 20, zoom 2.
    half = glint.render(None, scene, camera={"azimuth": 45, "elevation": 20, "zoom": 2})
    with PILImage.open(tmp_path / "py" / "frame-0001.png") as im:
        assert np.array_equal(np.asarray(im), half)
    # A file of keys is read as the command reads it.
    glint.turntable(scene, 3, f"{tmp_path / 'file'}/", keys=keys)
    assert (tmp_path / "file" / "frame-0002.png").read_bytes() == \
        (tmp_path / "cli" / "frame-0002.png").read_bytes()


def test_webp_decodes_to_the_png_frames(tmp_path):
    glint.turntable(small_scene(), 3, tmp_path / "spin.webp", fps=20)
    glint.turntable(small_scene(), 3, f"{tmp_path / 'frames'}/")
    with PILImage.open(tmp_path / "spin.webp") as im:
        assert im.size == (40, 32) and im.n_frames == 3
        for k in range(3):
            im.seek(k)
            with PILImage.open(tmp_path / "frames" / f"frame-{k:04}.png") as png:
                assert np.array_equal(np.asarray(im.convert("RGB")), np.asarray(png.convert("RGB")))


def test_bad_keys_raise_the_commands_line_and_write_nothing(glint_bin, tmp_path):
    key = {"azimuth": 0, "elevation": 0, "zoom": 1}
    for keys, needle in [([key], "1 keys: expected 2.."),
                         ([key, {"azimuth": 0, "elevation": 0}], "missing field `zoom`"),
                         ([key, {**key, "target": [0, 0, 0]}], "unknown field `target`")]:
        out = tmp_path / "out"
        out.mkdir()
        path = out / "a.gif"
        with pytest.raises(ValueError, match=needle):
            glint.turntable(small_scene(), 4, path, keys=keys)
        file = tmp_path / "keys.json"
        file.write_text(json.dumps(keys))
        with pytest.raises(ValueError) as info:
            glint.turntable(small_scene(), 4, path, keys=file)
        line = cli_error_line(glint_bin, "render", "-q", "--camera-path", str(file), "--frames",
                              "4", "-o", str(path))
        assert str(info.value) == line
        assert list(out.iterdir()) == []
        out.rmdir()
