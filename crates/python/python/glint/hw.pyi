"""Type stubs for glint.hw."""

from typing import Any, Dict, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

class Unit:
    """The specular unit of one configuration (crates/hw)."""

    def __init__(self, config: Optional[Union[Dict[str, Any], str]] = None) -> None:
        """None for the default configuration, or a dict / JSON string of fields."""
    @property
    def config(self) -> Dict[str, Any]: ...
    @property
    def latency(self) -> int: ...
    @property
    def full_scale(self) -> int: ...
    @property
    def cos_code_range(self) -> Tuple[int, int]: ...
    @overload
    def cos_codes(self, cos: float) -> int: ...
    @overload
    def cos_codes(self, cos: npt.NDArray[np.float64]) -> npt.NDArray[np.int64]: ...
    def eval(
        self,
        cos_codes: Union[int, npt.NDArray[np.integer[Any]]],
        n: Union[int, npt.NDArray[np.integer[Any]]],
        ks: Sequence[int],
    ) -> npt.NDArray[np.uint64]:
        """R, G, B output codes, shape cos_codes.shape + (3,)."""
