"""The bit-accurate model of glint's specular unit (crates/hw): ``glint.hw.Unit``."""

from glint._glint import hw as _hw

Unit = _hw.Unit

__all__ = ["Unit"]
