"""glint.Scene, glint.render and glint.Renderer against `glint render`."""

import ast
import io
import json
import pathlib
import pickle
import re
import threading

import numpy as np
import pytest
from PIL import Image as PILImage

import glint
from conftest import cli_error_line, run_glint


def cli_render(glint_bin, scene, tmp_path, name="cli"):
    """The PNG `glint render --scene` writes for scene, decoded to uint8 (H, W, 3)."""
    scene_file = tmp_path / f"{name}.json"
    scene_file.write_text(scene.to_json())
    png = tmp_path / f"{name}.png"
    proc = run_glint(glint_bin, "render", "--scene", str(scene_file), "--quiet", "-o", str(png))
    assert proc.returncode == 0, proc.stderr
    with PILImage.open(png) as im:
        assert im.mode == "RGB"
        return np.asarray(im)


@pytest.fixture(scope="module")
def brain_scene(mni_path):
    return glint.Scene(input=str(mni_path), preset="mr-t2-brain", size=(160, 120),
                       camera={"view": "left"}, lobe={"kind": "exact", "n": 30})


def test_render_equals_cli_byte_for_byte(glint_bin, mni_path, brain_scene, tmp_path):
    want = cli_render(glint_bin, brain_scene, tmp_path)
    got = glint.render(mni_path, brain_scene)
    assert got.dtype == np.uint8 and got.shape == (120, 160, 3)
    assert want.shape == got.shape
    assert np.array_equal(got, want)
    # The brain seen from the left: in the middle, on a black background, wider than
    # high (a head's profile in a 160x120 frame).
    lit = got.max(axis=2) > 10
    assert lit[50:70, 70:90].all() and not lit[0].any() and not lit[:, 0].any()
    rows, cols = np.nonzero(lit)
    assert cols.max() - cols.min() > rows.max() - rows.min()


def test_renderer_keeps_classification_and_matches_cli(glint_bin, mni_path, brain_scene, tmp_path):
    renderer = glint.Renderer(glint.read(mni_path))
    first = renderer.render(brain_scene)
    # Which stages ran, not how long they took (no wall-time assertion, issue 34).
    assert "classify" in first.stages and "frame" in first.stages
    assert set(first.timings) == {"read", "field", "classify", "frame"}
    views = []
    for view in ("anterior", "superior"):
        image = renderer.render(brain_scene, camera={"view": view}, lobe={"kind": "k"})
        assert "classify" not in image.stages  # same transfer function: reused
        assert image.timings["classify"] == 0.0 and "frame" in image.stages
        views.append((brain_scene.replace(camera={"view": view}, lobe={"kind": "k"}), image))
    # A new transfer function classifies again.
    assert "classify" in renderer.render(brain_scene, preset="mr-default").stages
    for i, (scene, image) in enumerate(views):
        assert np.array_equal(image.array, cli_render(glint_bin, scene, tmp_path, f"v{i}"))
        # The resolved scene renders the same image on the command line.
        assert np.array_equal(np.asarray(image), cli_render(glint_bin, image.scene, tmp_path, f"r{i}"))


def test_in_memory_volume_renders_like_the_file(mni_path, brain_scene):
    import nibabel as nib

    img = nib.load(str(mni_path))
    vol = glint.Volume.from_array(np.asanyarray(img.dataobj), affine=img.affine)
    small = brain_scene.replace(size=(64, 48))
    assert np.array_equal(glint.render(vol, small), glint.render(mni_path, small))


def test_image_png_and_save(mni_path, brain_scene, tmp_path):
    image = glint.Renderer(mni_path).render(brain_scene, size=(40, 30))
    assert (image.width, image.height) == (40, 30)
    with PILImage.open(io.BytesIO(image._repr_png_())) as im:
        assert np.array_equal(np.asarray(im), image.array)
    image.save(tmp_path / "x.png")
    with PILImage.open(tmp_path / "x.png") as im:
        assert np.array_equal(np.asarray(im), image.array)
    assert image.alpha.shape == (30, 40) and image.alpha.dtype == np.float32
    assert 0.0 <= image.alpha.min() and image.alpha.max() <= 1.0
    with pytest.raises(OSError):
        image.save(tmp_path / "no-such-dir" / "x.png")
    assert not (tmp_path / "no-such-dir").exists()


def test_scene_fields_json_and_pickle():
    default = glint.Scene()
    assert default == glint.Scene.from_json(default.to_json())
    assert default.size == [512, 512] and default.mode == "composite"
    assert default.preset is None and default.iso is None
    s = glint.Scene(size=(64, 32), lobe={"kind": "schlick", "n": 20}, mode="mip", step=0.25)
    assert s.size == [64, 32] and s.lobe["kind"] == "schlick" and s.lobe["n"] == 20
    assert json.loads(s.to_json())["lobe"]["kind"] == "schlick"
    assert s.to_dict()["step"] == 0.25
    assert s.replace(step=None).step == default.step
    assert pickle.loads(pickle.dumps(s)) == s
    assert s != default
    assert "camera" in dir(s)
    with pytest.raises(AttributeError):
        s.no_such_field
    assert default.sampling == "point" and default.prefilter == "binomial"
    pre = glint.Scene(sampling="pre-integrated")
    assert pre.sampling == "pre-integrated" and glint.Scene.from_json(pre.to_json()) == pre
    assert default.opacity_unit is None
    unit = glint.Scene(opacity_unit=1.5)
    assert unit.opacity_unit == 1.5 and glint.Scene.from_json(unit.to_json()) == unit
    with pytest.raises(ValueError):
        glint.Scene(sampling="linear")


def test_scene_errors_match_the_cli(glint_bin, tmp_path):
    for fields in ({"colour": 3}, {"version": 99}, {"lobe": {"kind": "nope"}}):
        with pytest.raises(ValueError) as err:
            glint.Scene(**fields)
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps({"version": 1, **fields}))
        line = cli_error_line(glint_bin, "render", "--scene", str(bad), "-o", str(tmp_path / "x.png"))
        # serde's position differs (the file holds fewer fields); the rest is the same,
        # once: the file, then the parser's message.
        at = re.compile(r" at line \d+ column \d+")
        assert at.sub("", line) == at.sub("", f"{bad}: {err.value}")
    with pytest.raises(TypeError):
        glint.Scene(size={1, 2})
    with pytest.raises(ValueError, match="invalid parameter"):
        glint.render(None, glint.Scene(size=(0, 10)))
    with pytest.raises(FileNotFoundError, match="I/O error"):
        glint.render("/no/such/file.nii.gz")
    with pytest.raises(TypeError, match="glint.Volume or a path"):
        glint.Renderer(3.5)


def test_renders_from_threads(mni_path, brain_scene):
    small = brain_scene.replace(size=(64, 64))
    want = glint.render(mni_path, small)
    renderer = glint.Renderer(mni_path)
    got = []

    def work(i):
        if i % 2:
            got.append(glint.render(mni_path, small))
        else:
            got.append(renderer.render(small).array)  # one renderer shared by threads

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(got) == 4
    for g in got:
        assert np.array_equal(g, want)


def test_a_hw_lobe_renders_like_the_cli(glint_bin, mni_path, brain_scene, tmp_path):
    """The scene JSON's hardware-unit lobe: v from the unit, a contradiction refused,
    and the same image as `glint render --scene`."""
    scene = brain_scene.replace(lobe={"kind": "hw", "n": 40, "hw": {"out_bits": 10}})
    assert scene.lobe["kind"] == "hw" and scene.lobe["v"] == 4
    assert scene.lobe["hw"]["out_bits"] == 10
    assert np.array_equal(glint.render(mni_path, scene), cli_render(glint_bin, scene, tmp_path))
    bad = brain_scene.replace(lobe={"kind": "hw", "v": 3})
    with pytest.raises(ValueError, match="contradicts"):
        glint.render(mni_path, bad)


@pytest.mark.parametrize("lighting", [{"model": "shadows", "occlusion": True},
                                      {"model": "path", "spp": 3, "seed": 5}])
def test_lighting_round_trips_and_renders_deterministically(glint_bin, tmp_path, lighting):
    # The built-in head phantom, small: shadows and a few path samples take milliseconds.
    scene = glint.Scene(input={"phantom": {"name": "head", "size": 24}}, size=(24, 20),
                        lighting=lighting)
    assert scene.lighting == lighting
    assert glint.Scene.from_json(scene.to_json()) == scene
    assert json.loads(scene.to_json())["lighting"] == lighting
    assert pickle.loads(pickle.dumps(scene)) == scene
    first = glint.render(None, scene)
    assert np.array_equal(first, glint.render(None, scene)), "the same scene, another image"
    # The command reads the same scene and writes the same pixels.
    assert np.array_equal(first, cli_render(glint_bin, scene, tmp_path))
    assert not np.array_equal(first, glint.render(None, scene.replace(lighting=None))), \
        "the lighting model changed nothing"
    if lighting["model"] == "path":
        other = scene.replace(lighting={**lighting, "seed": 6})
        assert not np.array_equal(first, glint.render(None, other))


def test_linear_radiance_exposure_and_tone(glint_bin, tmp_path):
    scene = glint.Scene(input={"phantom": {"name": "head", "size": 20}}, size=(20, 16),
                        lighting={"model": "path", "spp": 2})
    radiance = glint.render(None, scene, linear=True)
    assert radiance.dtype == np.float32 and radiance.shape == (16, 20, 3)
    # The exposure and tone curve change the display image, not the radiance.
    agx = scene.replace(exposure=1.5, tone="agx")
    assert agx.tone == "agx" and scene.tone == "linear" and scene.exposure == 0.0
    assert np.array_equal(glint.render(None, agx, linear=True), radiance)
    assert not np.array_equal(glint.render(None, agx), glint.render(None, scene))
    # Linear at exposure 0 is the radiance encoded as sRGB, clipped.
    srgb = np.where(radiance <= 0.0031308, 12.92 * radiance,
                    1.055 * np.clip(radiance, 0, 1) ** (1 / 2.4) - 0.055)
    assert np.abs(np.clip(srgb, 0, 1) * 255 - glint.render(None, scene)).max() <= 1
    # A float file holds the radiance; the command writes the same floats.
    out = tmp_path / "x.pfm"
    (tmp_path / "s.json").write_text(scene.to_json())
    proc = run_glint(glint_bin, "render", "-q", "--scene", str(tmp_path / "s.json"), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    data = out.read_bytes()
    header = b"PF\n20 16\n-1.0\n"
    assert data.startswith(header)
    floats = np.frombuffer(data[len(header):], dtype="<f4").reshape(16, 20, 3)[::-1]
    assert np.array_equal(floats, radiance)
    with pytest.raises(ValueError):
        glint.Scene(tone="filmic")


def scene_struct_fields():
    """The field names of glint_render::Scene, read from its source (serde names them
    as written: the struct has no renames)."""
    src = (pathlib.Path(__file__).resolve().parents[2] / "render" / "src" / "scene"
           / "mod.rs").read_text()
    body = re.search(r"pub struct Scene \{(.*?)\n\}", src, flags=re.S).group(1)
    assert "rename" not in body
    return set(re.findall(r"^    pub (\w+):", body, flags=re.M))


def stub_scene_fields():
    """The attributes the type stub (glint/__init__.pyi) annotates on Scene."""
    stub = pathlib.Path(glint.__file__).with_name("__init__.pyi")
    if not stub.exists():  # an editable install: the stub beside the source
        stub = (pathlib.Path(__file__).resolve().parents[1] / "python" / "glint"
                / "__init__.pyi")
    tree = ast.parse(stub.read_text())
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Scene")
    return {n.target.id for n in cls.body if isinstance(n, ast.AnnAssign)}


def test_every_scene_field_reads_on_a_default_scene_and_the_stub_names_it():
    scene = glint.Scene()
    fields = {n for n in dir(scene) if not n.startswith("_") and not hasattr(glint.Scene, n)}
    assert fields == scene_struct_fields()
    assert stub_scene_fields() == fields
    default = json.loads(scene.to_json())
    for name in sorted(fields):
        value = getattr(scene, name)  # raises AttributeError where the list misses one
        if name in default:
            assert value == default[name], name
        elif value is not None:
            # An omitted field reads as its default: setting it to that value leaves
            # the scene (and its JSON) as it was.
            assert glint.Scene.from_json(json.dumps({**default, name: value})) == scene, name
