"""Public names that load their module on first use (PEP 562), for the packages whose
``__init__`` imports none of their modules: importing the package stays cheap (``Protocol``
from :mod:`sim_tactile.sim` loads no MuJoCo, :mod:`sim_tactile.learn` no torch), and a
module's code version (and a compiled kernel's cache stamp) follows only what the module
itself imports, not its package's public names.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable


def lazy_exports(
    package: str, exports: dict[str, str]
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of ``package`` whose public names are the keys of
    ``exports``, each the name of the module (relative to ``package``) that defines it."""

    def __getattr__(name: str) -> object:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        setattr(sys.modules[package], name, value)  # the next look-up finds it directly
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
