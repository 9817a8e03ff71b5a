"""The reader: files glint reads and napari does not, as napari layer data.

Volumes (DICOM series and SEG, FreeSurfer MGH/MGZ, NRRD, NIfTI, OME-Zarr stores) are
read by ``glint.read``; GIFTI, STL, OBJ and PLY surfaces by glint's mesh reader. Every
layer is in world millimetres (RAS+): an image or labels layer carries the volume's
voxel-to-world ``affine`` (its spacing included), a surface its vertices as they are,
so a surface and the volume it came from line up. ``metadata`` keeps the spacing,
units, format, the reader's notes and the path; a labels layer also has its label
names (``features``) and colours (``colormap``), as ``glint view``'s legend lists them.
"""

from __future__ import annotations

import os
import pathlib

import numpy as np

import glint
from glint import _glint

#: Surface files (glint's mesh reader).
SURFACES = (".gii", ".gii.gz", ".stl", ".obj", ".ply")
#: Volume files napari reads itself (left to it); glint reads the rest.
NAPARI_OWN = (".tif", ".tiff", ".png", ".jpg", ".jpeg", ".npy", ".csv")


def _name(path: str) -> str:
    return path.lower().rstrip("/\\")


def _is_surface(path: str) -> bool:
    return _name(path).endswith(SURFACES)


def get_reader(path):
    """npe2's reader hook: ``read`` for a path glint reads (a list of paths: each),
    None for one it does not (napari then tries its other readers)."""
    paths = path if isinstance(path, list) else [path]
    for p in paths:
        p = os.fspath(p)
        name = _name(p)
        if name.endswith(NAPARI_OWN) or not os.path.exists(p):
            return None
        if os.path.isdir(p) and not (name.endswith(".zarr") or _looks_like_dicom_dir(p)):
            return None
    return lambda p: [layer for q in (p if isinstance(p, list) else [p]) for layer in read(q)]


def _looks_like_dicom_dir(path: str) -> bool:
    """A directory with a .dcm file, or a file starting with DICOM's preamble and magic."""
    for entry in sorted(os.scandir(path), key=lambda e: e.name)[:64]:
        if not entry.is_file():
            continue
        if entry.name.lower().endswith(".dcm"):
            return True
        with open(entry.path, "rb") as f:
            if f.read(132)[128:] == b"DICM":
                return True
    return False


def read(path, layer_type=None):
    """Layer data tuples ``(data, metadata, layer_type)`` for one file or directory:
    a surface, or a volume as an image, or as labels when ``layer_type`` says so, or
    the file is a label map glint knows as one (a DICOM SEG; an integer FreeSurfer
    segmentation, ``*aseg*``/``*aparc*``)."""
    path = os.fspath(path)
    name = pathlib.Path(path).name
    if _is_surface(path):
        vertices, faces, values = _glint.read_mesh(path)
        data = (vertices, faces) if values is None else (vertices, faces, values)
        meta = {"name": name, "metadata": {"path": path, "units": "mm", "format": "surface"}}
        return [(data, meta, "surface")]
    vol = glint.read(path)
    affine = np.asarray(vol.affine)
    metadata = {
        "path": path,
        "spacing": tuple(vol.spacing),
        "units": vol.units,
        "format": vol.format,
        "notes": list(vol.notes),
        "affine": affine,
    }
    kind = layer_type or ("labels" if _is_label_map(vol, name) else "image")
    if kind == "labels":
        data = np.asarray(vol.fdata()).astype(np.int32)
        table = _glint.label_table(path)
        meta = {
            "name": name,
            "affine": affine,
            "metadata": dict(metadata, labels=table),
            "features": {
                "index": [0] + [t["value"] for t in table],
                "name": ["background"] + [t["name"] for t in table],
            },
            "colormap": _colormap(table),
        }
        return [(data, meta, "labels")]
    same = vol.slope == 1.0 and vol.intercept == 0.0
    data = np.array(vol.samples) if same else vol.fdata().astype(np.float32)
    lo, hi = vol.range()
    meta = {
        "name": name,
        "affine": affine,
        "metadata": metadata,
        "contrast_limits": (float(lo), float(hi) if hi > lo else float(lo) + 1.0),
    }
    return [(data, meta, "image")]


def _is_label_map(vol, name: str) -> bool:
    fmt = (vol.format or "").upper()
    notes = " ".join(vol.notes).upper()
    if "SEG" in fmt or "SEGMENTATION" in notes:
        return True
    lowered = name.lower()
    integer = vol.dtype.startswith(("int", "uint"))
    return integer and any(k in lowered for k in ("aseg", "aparc", "seg", "label"))


def _colormap(table):
    """napari's direct label colour map: each value's colour, 0 transparent."""
    from napari.utils.colormaps import DirectLabelColormap

    colors = {0: (0.0, 0.0, 0.0, 0.0), None: (0.0, 0.0, 0.0, 0.0)}
    for t in table:
        h = t["color"].lstrip("#")
        colors[t["value"]] = tuple(int(h[i:i + 2], 16) / 255.0 for i in (0, 2, 4)) + (1.0,)
    return DirectLabelColormap(color_dict=colors)
