"""Type stubs for the glint package (the native module glint._glint)."""

import os
from typing import Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

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
        """'NIfTI-1', 'NRRD' or 'DICOM' for files, None for arrays."""
    @property
    def path(self) -> Optional[str]: ...
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
