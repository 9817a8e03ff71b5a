"""glint: render 3D biomedical images with cheap, accurate specular lobes.

``glint.read(path)`` reads NIfTI, NRRD and DICOM volumes into a :class:`Volume`;
``Volume.from_array`` wraps data already in memory; ``glint.render(volume, scene)``
renders a :class:`Scene` (a :class:`Renderer` keeps the classification across views);
``glint.compare`` measures what a cheap lobe changes in the image; ``glint.lobe`` evaluates any
specular lobe on a numpy array; ``glint.hw.Unit`` is the device model. Every function
releases the GIL while it works and raises ``ValueError``/``OSError``/``TypeError``
with the one-line messages of the ``glint`` command.
"""

from glint._glint import Image, Renderer, Scene, Volume, compare, lobe, lobe_kinds, read, render
from glint import hw

__all__ = [
    "Image",
    "Renderer",
    "Scene",
    "Volume",
    "compare",
    "hw",
    "lobe",
    "lobe_kinds",
    "read",
    "render",
]
