"""A label map as a scene layer from Python: the scene's `labels` field round-trips
through JSON, and renders as a label volume in the colour table's colours (issue 33)."""

import nibabel as nib
import numpy as np

import glint

# FreeSurferColorLUT.txt: 17 Left-Hippocampus (220, 216, 20), 18 Left-Amygdala
# (103, 255, 255).
HIPPOCAMPUS = (220, 216, 20)
AMYGDALA = (103, 255, 255)


def srgb_to_linear(c):
    """The sRGB transfer function's inverse (IEC 61966-2-1), as glint applies it."""
    c = np.asarray(c, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def two_blocks(path):
    """Two 6-voxel cubes side by side along x on 1 mm voxels: 17, then 18."""
    data = np.zeros((16, 16, 16), np.uint8)
    data[2:8, 5:11, 5:11] = 17
    data[8:14, 5:11, 5:11] = 18
    nib.save(nib.Nifti1Image(data, np.eye(4)), str(path))


def label_scene(path, **labels):
    """The map in its own frame, read as an intensity volume through a transparent
    transfer function, unshaded, so a pixel is a label's colour or the background."""
    return glint.Scene(
        input=str(path),
        labels={"path": str(path), "legend": False, **labels},
        size=(48, 48),
        camera={"view": "anterior", "projection": "orthographic"},
        material={"ambient": 1.0, "diffuse": 0.0, "specular": 0.0, "shade": False},
        transfer_function={"opacity": [[0.0, 0.0], [100.0, 0.0]], "color": [[0.0, 1.0, 1.0, 1.0]]},
    )


def test_label_layer_round_trips_and_renders_as_a_label_volume(tmp_path):
    path = tmp_path / "aseg.nii"
    two_blocks(path)
    scene = label_scene(path, render_as="volume", opacity={"Left-Amygdala": 1.0})
    back = glint.Scene.from_json(scene.to_json())
    assert back == scene
    assert back.labels["render_as"] == "volume"
    assert back.labels["opacity"] == {"Left-Amygdala": 1.0}
    image = np.asarray(glint.render(path, scene), dtype=np.float64)
    assert image.shape[:2] == (48, 48)
    rgb = image[..., :3].reshape(-1, 3)
    if rgb.max() > 1.0:
        rgb = srgb_to_linear(rgb)
    hippo, amyg = srgb_to_linear(HIPPOCAMPUS), srgb_to_linear(AMYGDALA)
    near = lambda c: np.all(np.abs(rgb - c) < 0.02, axis=1)
    black = np.all(rgb < 0.02, axis=1)
    assert near(hippo).sum() > 100 and near(amyg).sum() > 100
    # Nearest-label classification: nothing but the two colours and the background.
    assert np.all(near(hippo) | near(amyg) | black)
    # Hidden, a label is not drawn.
    hidden = np.asarray(glint.render(path, scene.replace(labels={**scene.labels, "hide": ["18"]})), dtype=np.float64)
    rgb = hidden[..., :3].reshape(-1, 3)
    if rgb.max() > 1.0:
        rgb = srgb_to_linear(rgb)
    assert not np.any(np.all(np.abs(rgb - amyg) < 0.02, axis=1))
