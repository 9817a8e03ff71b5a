"""The dock widget "Render with glint": the current image layer (and a labels layer)
rendered by glint with the chosen lighting model, added as a new RGB layer, or a
turntable written with ``glint.turntable``."""

from __future__ import annotations

import numpy as np
from magicgui.widgets import ComboBox, Container, FileEdit, Label, PushButton, SpinBox

import glint
from glint import _glint


def _volume(layer):
    """A glint volume of an image layer: its data (3-D) and its affine (world mm)."""
    data = np.asarray(layer.data)
    if data.ndim != 3:
        raise ValueError(f"glint renders 3-D volumes; layer '{layer.name}' has shape {data.shape}")
    if data.dtype not in (np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32,
                          np.float32, np.float64):
        data = data.astype(np.float32)
    affine = np.asarray(layer.affine.affine_matrix, dtype=np.float64)
    scale = np.diag(list(np.asarray(layer.scale, dtype=np.float64)) + [1.0])
    return glint.Volume.from_array(np.ascontiguousarray(data), affine=affine @ scale)


def render_layer(image_layer, labels_layer=None, lighting="local", preset=None, size=256,
                 view="anterior"):
    """Renders an image layer (3-D) as glint renders a volume: an sRGB uint8 array
    (size, size, 3). A labels layer read from a file (its ``metadata['path']``) is
    drawn over it as ``glint render --labels`` draws it."""
    scene = glint.Scene(size=(size, size), camera={"view": view},
                        lighting={"model": lighting})
    if preset:
        scene = scene.replace(preset=preset)
    if labels_layer is not None:
        path = (labels_layer.metadata or {}).get("path")
        if not path:
            raise ValueError(
                f"labels layer '{labels_layer.name}' has no file: glint draws label maps "
                "read from a file (open it with the glint reader)")
        scene = scene.replace(labels={"path": str(path)})
    return glint.render(_volume(image_layer), scene).copy()


class RenderWidget(Container):
    """Image and labels layer, lighting model, preset, size; Render adds a layer,
    Turntable writes a GIF/MP4/PNG frames of the view."""

    def __init__(self, napari_viewer):
        import napari

        self._viewer = napari_viewer
        choices = _glint.view_choices()
        self.image_box = ComboBox(label="image", choices=self._layers(napari.layers.Image))
        self.labels_box = ComboBox(label="labels", choices=self._layers(napari.layers.Labels, True))
        self.lighting_box = ComboBox(label="lighting", choices=list(choices["lighting"]))
        self.preset_box = ComboBox(label="preset", choices=[""] + list(choices["presets"]))
        self.size_box = SpinBox(label="size", value=256, min=16, max=2048)
        self.turntable_path = FileEdit(label="turntable", mode="w", filter="*.gif *.mp4")
        self.render_button = PushButton(text="Render")
        self.turntable_button = PushButton(text="Save turntable")
        self.status_box = Label(value="")
        super().__init__(widgets=[self.image_box, self.labels_box, self.lighting_box, self.preset_box, self.size_box,
                                  self.render_button, self.turntable_path,
                                  self.turntable_button, self.status_box])
        self.render_button.changed.connect(self.render)
        self.turntable_button.changed.connect(self.turntable)
        napari_viewer.layers.events.inserted.connect(self._refresh)
        napari_viewer.layers.events.removed.connect(self._refresh)

    def _layers(self, kind, optional=False):
        def choices(_widget=None):
            names = [l.name for l in self._viewer.layers if isinstance(l, kind)]
            return ([""] if optional else []) + names
        return choices

    def _refresh(self, _event=None):
        self.image_box.reset_choices()
        self.labels_box.reset_choices()

    def _chosen(self):
        if not self.image_box.value:
            raise ValueError("no image layer: open a volume first")
        image = self._viewer.layers[self.image_box.value]
        labels = self._viewer.layers[self.labels_box.value] if self.labels_box.value else None
        return image, labels

    def render(self, _=None):
        """Renders the chosen layers; adds the image as a new RGB layer (returned)."""
        try:
            image, labels = self._chosen()
            rgb = render_layer(image, labels, self.lighting_box.value, self.preset_box.value or None,
                               int(self.size_box.value))
        except (ValueError, OSError) as e:
            self.status_box.value = str(e)
            return None
        self.status_box.value = f"rendered {image.name} ({self.lighting_box.value})"
        return self._viewer.add_image(rgb, rgb=True, name=f"{image.name} (glint {self.lighting_box.value})")

    def turntable(self, _=None):
        """Writes a 36-frame turntable of the chosen layers to the chosen path."""
        try:
            image, _labels = self._chosen()
            scene = glint.Scene(size=(int(self.size_box.value),) * 2,
                                lighting={"model": self.lighting_box.value})
            if self.preset_box.value:
                scene = scene.replace(preset=self.preset_box.value)
            glint.turntable(scene, 36, str(self.turntable_path.value), volume=_volume(image))
        except (ValueError, OSError) as e:
            self.status_box.value = str(e)
            return
        self.status_box.value = f"wrote {self.turntable_path.value}"
