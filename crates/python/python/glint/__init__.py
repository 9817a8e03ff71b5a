"""glint: render 3D biomedical images with cheap, accurate specular lobes.

``glint.read(path)`` reads NIfTI, NRRD and DICOM volumes into a :class:`Volume`;
``Volume.from_array`` wraps data already in memory; ``glint.render(volume, scene)``
renders a :class:`Scene` (a :class:`Renderer` keeps the classification across views);
``glint.turntable(scene, n, path)`` writes n views round it as a GIF, an MP4 or PNG frames;
``glint.compare`` measures what a cheap lobe changes in the image; ``glint.lobe`` evaluates any
specular lobe on a numpy array; ``glint.hw.Unit`` is the device model; ``glint.batch`` renders
a whole study on Dask (``pip install glint[dask]``), as ``glint batch`` does on one machine;
``glint.Viewer`` is an interactive view in a notebook (``pip install glint[notebook]``). Every function
releases the GIL while it works and raises ``ValueError``/``OSError``/``TypeError``
with the one-line messages of the ``glint`` command.
"""

from glint._glint import (
    Image,
    Renderer,
    Scene,
    Volume,
    compare,
    lobe,
    lobe_kinds,
    read,
    render,
    turntable,
)
from glint import hw



def __getattr__(name):
    # glint.batch is imported on first use (python -m glint.batch runs it fresh, and
    # it is callable: glint.batch(...) is glint.batch.run(...)).
    if name == "batch":
        import importlib

        return importlib.import_module("glint.batch")
    if name == "Viewer":
        # glint.Viewer needs the notebook extra (jupyter_rfb, ipywidgets): imported on
        # first use, so `import glint` works without them.
        from glint.notebook import Viewer

        return Viewer
    raise AttributeError(f"module 'glint' has no attribute {name!r}")


__all__ = [
    "Image",
    "Renderer",
    "Scene",
    "Viewer",
    "Volume",
    "batch",
    "compare",
    "hw",
    "lobe",
    "lobe_kinds",
    "read",
    "render",
    "turntable",
]
