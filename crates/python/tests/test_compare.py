"""glint.compare against `glint compare --json`, and scene files and patches as the
command line and the viewer treat them."""

import json
import math

import pytest

import glint
from conftest import glint_json, run_glint


def without_times(doc):
    """The report without its wall-clock fields (they differ between any two runs)."""
    if isinstance(doc, dict):
        return {k: without_times(v) for k, v in doc.items() if not k.endswith("_ms")}
    if isinstance(doc, list):
        return [without_times(v) for v in doc]
    return doc


def test_compare_equals_the_cli_json(glint_bin, mni_path, tmp_path):
    scene = glint.Scene(input=str(mni_path), preset="mr-t2-brain", size=(96, 80),
                        camera={"view": "left"}, lobe={"n": 60})
    got = glint.compare(mni_path, scene, lobes=["k", "g", "schlick"])
    scene_file = tmp_path / "scene.json"
    scene_file.write_text(scene.to_json())
    want = glint_json(glint_bin, "compare", "--scene", str(scene_file), "--lobe", "k", "--lobe", "g",
                      "--lobe", "schlick", "--json", "--quiet", "-o", str(tmp_path / "cmp.png"))
    assert without_times(got) == without_times(want)
    # Not vacuous: three rows of real metrics, the cheap lobes close to exact but not equal.
    rows = got["comparisons"]
    assert [r["lobe"] for r in rows] == ["k", "g", "schlick"]
    for r in rows:
        assert r["n"] == 60
        assert 25 < r["image"]["psnr_db"] < math.inf
        assert 0.9 < r["image"]["ssim"] < 1.0
        assert r["image"]["delta_e"]["max"] > 0
    assert got["highlight"]["pixels"] > 0
    assert got["scene"]["lobe"]["kind"] == "exact"


def test_compare_on_a_path_scene_equals_the_cli_json(glint_bin, mni_path, tmp_path):
    # The command's path defaults (16 spp unless set, 128x128 unless a size or scene is
    # given) and its converged reference (16x the images' spp) come from glint-compare,
    # so glint.compare gives the command's report, the reference's rows included.
    scene = glint.Scene(input=str(mni_path), preset="mr-t2-brain", size=(40, 32),
                        camera={"view": "left"}, lighting={"model": "path", "spp": 2})
    got = glint.compare(mni_path, scene, lobes=["k"])
    scene_file = tmp_path / "scene.json"
    scene_file.write_text(scene.to_json())
    want = glint_json(glint_bin, "compare", "--scene", str(scene_file), "--lobe", "k",
                      "--json", "--quiet", "-o", str(tmp_path / "cmp.png"))
    assert without_times(got) == without_times(want)
    assert got["converged"]["spp"] == 32
    assert [r["lobe"] for r in got["converged"]["rows"]] == ["exact", "k"]
    # An explicit reference, and none.
    got = glint.compare(mni_path, scene, lobes=["k"], reference_spp=4)
    assert got["converged"]["spp"] == 4
    assert "converged" not in glint.compare(mni_path, scene, lobes=["k"], reference_spp=0)
    with pytest.raises(ValueError, match="must exceed"):
        glint.compare(mni_path, scene, lobes=["k"], reference_spp=2)


def test_compare_refuses_unknown_lobes(mni_path):
    with pytest.raises(ValueError, match="unknown lobe"):
        glint.compare(mni_path, glint.Scene(size=(16, 16)), lobes=["phongish"])


def test_scene_files_are_read_relative_to_the_file_and_saved_absolute(glint_bin, mni_path, tmp_path):
    data = tmp_path / "study"
    data.mkdir()
    (data / "brain.nii.gz").symlink_to(mni_path)
    (data / "scene.json").write_text(json.dumps(
        {"version": 1, "input": {"path": "brain.nii.gz"}, "preset": "mr-t2-brain", "size": [48, 40]}))
    scene = glint.Scene.load(data / "scene.json")
    assert scene.input == {"path": str(data / "brain.nii.gz")}
    saved = tmp_path / "elsewhere" / "saved.json"
    saved.parent.mkdir()
    glint.Scene(input="study/brain.nii.gz", size=(48, 40)).save(saved)
    # Relative paths are saved absolute (against the working directory).
    assert json.loads(saved.read_text())["input"]["path"].startswith("/")
    # The command line reads the same file with the same rule, from another directory.
    out = tmp_path / "cli.png"
    proc = run_glint(glint_bin, "render", "--scene", str(data / "scene.json"), "--quiet", "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    assert glint.render(None, scene).shape == (40, 48, 3)
    with pytest.raises(FileNotFoundError):
        glint.Scene.load(tmp_path / "missing.json")


def test_replace_merges_camera_lobe_and_material_as_the_viewer_does():
    s = glint.Scene(lobe={"kind": "exact", "n": 30, "v": 3}, camera={"view": "left", "zoom": 1.5})
    t = s.replace(lobe={"kind": "g"}, camera={"zoom": 2.0})
    assert t.lobe["kind"] == "g" and t.lobe["n"] == 30 and t.lobe["v"] == 3
    assert t.camera["view"] == "left" and t.camera["zoom"] == 2.0
    # None restores a default: a whole field, or an optional field inside an object.
    assert t.replace(lobe={"n": None}).lobe.get("n") is None
    assert t.replace(camera=None).camera == glint.Scene().camera
