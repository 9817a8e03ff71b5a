"""napari-glint: glint's readers and renderer in napari (an npe2 plugin).

``napari_glint.read(path)`` gives the layer data tuples napari's reader contract asks
for; the dock widget "Render with glint" is :class:`napari_glint.RenderWidget`.
"""

from napari_glint._reader import get_reader, read
from napari_glint._widget import RenderWidget, render_layer

__all__ = ["RenderWidget", "get_reader", "read", "render_layer"]
