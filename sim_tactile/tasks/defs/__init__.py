"""The versioned benchmark tasks, one module per paper (importing this registers them), and
the named suites of their ids."""

from __future__ import annotations

from ..registry import register_suite
from . import finger7, multilayer3, real, roughness8, textures20  # noqa: F401  (register)

#: The ids a paper should report (``sim-tactile tasks --suite core-v1``): the current version
#: of every family, each sensor's part on its own (each has its own result files), and the
#: real-data tasks (they need the data set, ``--data PATH``). A suite's name, like a task id,
#: never changes meaning: a change is ``core-v2``.
CORE_V1 = (
    "finger7-v2",
    "multilayer3-v2",
    "roughness8-v1",
    "textures20-biotac19-v2",
    "textures20-icub60-v2",
    "biotac20-real-v1",
    "icub20-real-v1",
)
register_suite("core-v1", CORE_V1)
