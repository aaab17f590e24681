"""The device of the batched contact solve (:mod:`.batched`): a name checked into a torch
device, or one clear error.

torch is an optional dependency: this module imports it only inside
:func:`require_device`, so importing it (or anything of the CPU path) loads no torch. A GPU
that is asked for and absent is an error, never a silent fall back to the CPU: a data set
made on the CPU when a GPU was asked for would take many times the time planned for it.
"""

from __future__ import annotations

import importlib
import re
from typing import Any

from ....errors import ConfigError

#: The device names :func:`require_device` takes (``cuda:N``: the GPU of index ``N``).
DEVICES = ("cpu", "cuda", "cuda:N")
#: What installs torch with CUDA (the core install has no torch; the ``learn`` extra brings a
#: CPU build on most machines).
CUDA_INSTALL = (
    "pip install torch, a build with CUDA (PyTorch's install selector gives the command for "
    "your CUDA version)"
)

_NAME = re.compile(r"^(cpu|cuda)(?::(\d+))?$")


def check_device_name(name: str) -> str:
    """``name`` if it is a device name (:data:`DEVICES`), else ConfigError; imports nothing."""
    m = _NAME.match(name) if isinstance(name, str) else None
    if m is None or (m.group(1) == "cpu" and m.group(2) is not None):
        raise ConfigError(f"device = {name!r} is not a device; valid: {', '.join(DEVICES)}")
    return name


def require_device(name: str) -> Any:
    """The ``torch.device`` of ``name`` (``cpu``, ``cuda`` or ``cuda:N``), or ConfigError in
    one line: an unknown name; torch absent; ``cuda`` asked for where torch has no CUDA or
    sees no GPU; ``cuda:N`` past the GPUs it sees."""
    check_device_name(name)
    try:
        torch = importlib.import_module("torch")
    except ImportError:
        if name == "cpu":
            raise ConfigError(
                "device = 'cpu' for the batched contact solve needs torch, which is not "
                "installed: pip install 'sim-tactile[learn]' (or leave the device unset: the "
                "numpy solve needs no torch)"
            ) from None
        raise ConfigError(
            f"device = {name!r} needs torch with CUDA, and torch is not installed: {CUDA_INSTALL}"
        ) from None
    if name == "cpu":
        return torch.device("cpu")
    if not torch.cuda.is_available():
        build = getattr(torch.version, "cuda", None)
        why = (
            f"torch {torch.__version__} is a build without CUDA"
            if not build
            else f"torch {torch.__version__} (CUDA {build}) sees no GPU (no driver, or "
            "CUDA_VISIBLE_DEVICES hides them)"
        )
        raise ConfigError(
            f"device = {name!r} but {why}; valid here: cpu, or {CUDA_INSTALL} on a machine "
            "with a GPU"
        )
    count = torch.cuda.device_count()
    index = int(name.partition(":")[2] or 0)
    if index >= count:
        raise ConfigError(
            f"device = {name!r} but torch sees {count} GPU{'s' if count != 1 else ''}; "
            f"valid: cuda, cuda:0 to cuda:{count - 1}"
        )
    return torch.device(name)
