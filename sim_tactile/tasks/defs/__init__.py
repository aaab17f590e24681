"""The versioned benchmark tasks, one module per paper (importing this registers them)."""

from __future__ import annotations

from . import finger7, multilayer3, real, roughness8, textures20  # noqa: F401  (register)
