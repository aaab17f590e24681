"""The old names of the plates' modules, from before they moved into the four folders
(``define``, ``read``, ``parts``, ``make``). Deprecated: each old name still imports, for one
release, and hands every name on to the module it became, with a :class:`DeprecationWarning`
that names the new path; they go in the next release (CHANGELOG, "Breaking").

One table instead of a file per old name: :func:`register` puts a stand-in for each into
:data:`sys.modules`, so ``import sim_tactile.plates.spec`` and ``from sim_tactile.plates.spec
import Plate`` work, and the stand-in imports the new module only when a name is read from it
(``sim_tactile.plates.mjcf`` loads MuJoCo only when used, as before).
"""

from __future__ import annotations

import importlib
import sys
import types
import warnings

#: old module name (under ``sim_tactile.plates``) -> the folder it moved to
MOVED: dict[str, str] = {
    **dict.fromkeys(("spec", "geometry", "scales", "surface"), "define"),
    **dict.fromkeys(("files", "presets"), "read"),
    **dict.fromkeys(("user", "map_files", "mesh_map", "zbuffer", "cad_worker", "cad_run"), "parts"),
    **dict.fromkeys(("build", "cad", "mjcf", "render", "map_mesh", "verify", "probe"), "make"),
}


class _OldName(types.ModuleType):
    """A moved module's old name: every name read from it is the new module's, with a
    DeprecationWarning."""

    def __init__(self, old: str, new: str) -> None:
        super().__init__(old, f"Deprecated: moved to {new}; this name goes in the next release.")
        self._new = new

    def __getattr__(self, name: str):
        if name.startswith("__") and name != "__all__":
            raise AttributeError(name)  # the import system's questions: not forwarded
        warnings.warn(
            f"{self.__name__} is deprecated: import {name} from {self._new} (the old path "
            "goes in the next release)",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(importlib.import_module(self._new), name)


def register(package: str) -> None:
    """Put a stand-in for each old name of ``package``'s modules into :data:`sys.modules`."""
    for old, folder in MOVED.items():
        sys.modules.setdefault(
            f"{package}.{old}", _OldName(f"{package}.{old}", f"{package}.{folder}.{old}")
        )


def old_name(package: str, name: str) -> types.ModuleType:
    """The stand-in of the old module ``package.name``; AttributeError if none moved so."""
    if name not in MOVED:
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    return sys.modules[f"{package}.{name}"]
