"""Type stubs for the glint package (the native module glint._glint)."""

import os
import pathlib
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

from glint import batch as batch
from glint import hw as hw

_Path = Union[str, "os.PathLike[str]"]
LobeName = Literal["exact", "k", "g", "schlick", "gauss", "minimax"]

class Volume:
    """A 3-D scalar volume; samples indexed [i, j, k] like nibabel's get_fdata()."""

    @staticmethod
    def from_array(
        array: npt.NDArray[np.generic],
        spacing: Optional[Sequence[float]] = None,
        affine: Optional[npt.ArrayLike] = None,
        slope: float = 1.0,
        intercept: float = 0.0,
        units: Optional[str] = None,
    ) -> Volume:
        """A volume from a C- or Fortran-contiguous 3-D array indexed [i, j, k]
        (uint8, int8, uint16, int16, uint32, int32, float32 or float64; copied).
        ``affine`` maps (i, j, k, 1) to RAS+ mm; without it the affine is
        diag(spacing) (spacing defaults to 1 mm)."""
    @property
    def shape(self) -> Tuple[int, int, int]: ...
    @property
    def dtype(self) -> str:
        """The stored sample type, e.g. 'int16'."""
    @property
    def samples(self) -> npt.NDArray[np.generic]:
        """The stored samples, a read-only view [i, j, k] (no copy)."""
    def fdata(self) -> npt.NDArray[np.float64]:
        """slope * samples + intercept as a new float64 array (nibabel's get_fdata())."""
    @property
    def spacing(self) -> Tuple[float, float, float]: ...
    @property
    def affine(self) -> npt.NDArray[np.float64]:
        """Voxel (i, j, k, 1) to world RAS+ mm, 4x4 (a new array)."""
    @property
    def slope(self) -> float: ...
    @property
    def intercept(self) -> float: ...
    @property
    def units(self) -> Optional[str]: ...
    @property
    def notes(self) -> list[str]: ...
    @property
    def format(self) -> Optional[str]:
        """'NIfTI', 'NRRD' or 'DICOM' for files, None for arrays."""
    @property
    def path(self) -> Optional[pathlib.Path]: ...
    def range(self) -> Tuple[float, float]:
        """Smallest and largest physical value (NaN ignored)."""
    def __reduce__(self) -> tuple[object, tuple[object, ...]]: ...

def read(path: _Path, max_voxels: Optional[int] = None) -> Volume:
    """Reads a NIfTI (.nii, .nii.gz), NRRD (.nrrd, .nhdr) or DICOM (file or directory)
    volume. Raises OSError (FileNotFoundError, ...) or ValueError."""

@overload
def lobe(kind: LobeName | str, cos: float, n: float, v: int = 4) -> float: ...
@overload
def lobe(
    kind: LobeName | str, cos: npt.NDArray[np.float32], n: float, v: int = 4
) -> npt.NDArray[np.float32]: ...
@overload
def lobe(
    kind: LobeName | str, cos: npt.NDArray[np.float64], n: float, v: int = 4
) -> npt.NDArray[np.float64]: ...
def lobe_kinds() -> list[str]:
    """The lobe names glint.lobe accepts."""

class Scene:
    """A render described completely; the fields and JSON of `glint render --scene`.

    Immutable: ``replace(**fields)`` returns a changed copy. Fields read back as plain
    Python values (dicts, lists, str, numbers); unset optional fields are None.
    """

    def __init__(self, **fields: Any) -> None:
        """The default scene with the given fields replaced, e.g.
        ``Scene(preset="mr-t2-brain", size=(256, 256), camera={"view": "left"},
        lobe={"kind": "exact", "n": 40})``; a str ``input`` is a file path.
        Unknown fields or bad values raise ValueError."""
    @staticmethod
    def from_json(text: str) -> Scene: ...
    def to_json(self) -> str: ...
    @staticmethod
    def load(path: _Path) -> Scene:
        """Reads a scene file; relative paths in it are relative to the file."""
    def save(self, path: _Path) -> None:
        """Writes the scene file atomically, with absolute paths."""
    def to_dict(self) -> Dict[str, Any]: ...
    def replace(self, **fields: Any) -> Scene:
        """A copy with fields patched: camera, lobe and material merged field by field."""
    version: int
    input: Union[Dict[str, Any], Literal["none"]]
    meshes: List[Dict[str, Any]]
    # A label map drawn over the volume: {"path": ..., "table", "show", "hide",
    # "smoothing", "legend", "render_as": "surfaces"|"volume"|"both", "opacity"}.
    labels: Optional[Dict[str, Any]]
    ssaa: Optional[int]
    mode: Literal["composite", "iso", "mip", "surface"]
    iso: Optional[float]
    preset: Optional[str]
    transfer_function: Optional[Dict[str, Any]]
    # {"window": width, "level": centre}: the transfer function's opacity ramp
    # stretched to this window (None: the function as it is).
    window_level: Optional[Dict[str, float]]
    material: Dict[str, Any]
    lobe: Dict[str, Any]
    lights: List[Dict[str, float]]
    # The light-transport model and its settings: {"model": "local"|"shadows"|"path",
    # "spp", "bounces", "seed", "environment", "anisotropy", "occlusion", "sampler",
    # "time_budget", "show_environment", "denoise", "environment_map",
    # "environment_rotation", "environment_intensity", "surface_weight", "area_lights":
    # [{"shape": {"sphere": {"radius": mm}} | {"rect": {"size": [w, h]}},
    #   "frame": "volume"|"camera", "position": [x, y, z], "radiance": [r, g, b]}]};
    # None: `local`.
    lighting: Optional[Dict[str, Any]]
    camera: Dict[str, Any]
    size: List[int]
    step: float
    gate: float
    skip_empty: bool
    prefilter: Literal["binomial", "none"]
    # How the field is reconstructed between voxels (tricubic: a cubic B-spline).
    filter: Literal["trilinear", "tricubic"]
    sampling: Literal["point", "pre-integrated"]
    opacity_unit: Optional[float]
    background: List[float]
    # Stops: the radiance scaled by 2**exposure before the tone curve.
    exposure: float
    tone: Literal["linear", "aces", "agx"]
    # Clip planes {"point": [x, y, z], "normal": [x, y, z]} in patient mm, the crop box
    # {"min": [...], "max": [...]}, and whether cut faces are capped.
    clip: List[Dict[str, Any]]
    crop: Optional[Dict[str, Any]]
    clip_caps: bool
    # Where frames are rendered (docs/gpu.md); this module's builds have no GPU back
    # end, so `gpu` is refused and `auto` renders on the CPU.
    device: Literal["cpu", "gpu", "auto"]
    derived: Optional[Dict[str, Any]]
    def __reduce__(self) -> tuple[object, tuple[object, ...]]: ...

class Image:
    """A rendered image; shown inline by Jupyter."""

    @property
    def array(self) -> npt.NDArray[np.uint8]:
        """sRGB uint8, shape (height, width, 3): the pixels of glint render's PNG."""
    @property
    def linear(self) -> npt.NDArray[np.float32]:
        """Linear radiance, float32 (height, width, 3): before exposure, tone curve, sRGB."""
    @property
    def alpha(self) -> npt.NDArray[np.float32]: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def scene(self) -> Scene:
        """The resolved scene (every default chosen)."""
    @property
    def stages(self) -> List[str]:
        """The stages that ran for this image ("classify" absent when reused)."""
    @property
    def timings(self) -> Dict[str, float]:
        """Seconds: read, field, classify (0 when reused), frame."""
    def png(self) -> bytes: ...
    def _repr_png_(self) -> bytes: ...
    def save(self, path: _Path, sixteen_bit: bool = False) -> None: ...
    def __array__(self, dtype: Any = None, copy: Optional[bool] = None) -> npt.NDArray[Any]: ...

class Renderer:
    """Renders many scenes of one volume, keeping its classification across calls."""

    def __init__(self, volume: Union[Volume, _Path]) -> None: ...
    def render(self, scene: Optional[Scene] = None, **fields: Any) -> Image:
        """Renders scene (default Scene()) with fields replaced; its input is ignored."""
    def pick(
        self,
        x: float,
        y: float,
        scene: Optional[Scene] = None,
        opacity: float = 0.5,
        **fields: Any,
    ) -> Optional[Dict[str, Any]]:
        """The 3D point image point (x, y) (pixels from the top-left corner) of the
        scene's image shows, as ``glint pick`` prints it (object, world_mm, depth_mm,
        voxel, voxel_nearest, value, interpolated, units, label, opacity); None where
        nothing shows. A point off the image raises ValueError."""

def render(
    volume: Union[Volume, _Path, None] = None,
    scene: Optional[Scene] = None,
    linear: bool = False,
    **fields: Any,
) -> npt.NDArray[Any]:
    """Renders volume (None: the scene's input) with scene: sRGB uint8 (H, W, 3);
    linear=True: the linear radiance, float32 (H, W, 3), before exposure and tone."""

def turntable(
    scene: Optional[Scene],
    frames: int,
    path: _Path,
    fps: int = 24,
    volume: Union[Volume, _Path, None] = None,
    keys: Union[Sequence[Dict[str, Any]], _Path, None] = None,
    **fields: Any,
) -> None:
    """Writes frames views round scene (azimuth stepping 360/frames degrees; frame 0 is
    glint.render's image), or with keys along camera keys (dicts with azimuth, elevation
    and zoom, or a JSON file of them, as ``glint render --camera-path``), to path: .gif,
    .webp, .mp4 (through ffmpeg) or a directory of PNGs."""

def compare(
    volume: Union[Volume, _Path, None] = None,
    scene: Optional[Scene] = None,
    lobes: Sequence[str] = ("k",),
    reference_spp: Optional[int] = None,
    **fields: Any,
) -> Dict[str, Any]:
    """Exact cos^n against each lobe, as ``glint compare --json`` reports it (a path
    scene with the command's defaults and its converged reference)."""

class Viewer:
    """An inline, interactive view in a notebook (glint.notebook; pip install glint[notebook])."""
    def __init__(
        self,
        volume: Union[Volume, _Path, None] = None,
        scene: Optional[Scene] = None,
        size: Tuple[int, int] = (512, 512),
        settle: float = 0.15,
        **fields: Any,
    ) -> None: ...
    @property
    def scene(self) -> Scene:
        """The live scene; assign a Scene or a dict of fields to patch it."""
    @scene.setter
    def scene(self, value: Union[Scene, Dict[str, Any]]) -> None: ...
    def update(self, **fields: Any) -> None:
        """Patches the live scene; the widget and panel follow."""
    @property
    def labels(self) -> List[Dict[str, Any]]: ...
    @property
    def frames(self) -> int: ...
    def snapshot(self) -> npt.NDArray[np.uint8]:
        """The frame shown, sRGB uint8 (height, width, 3)."""
