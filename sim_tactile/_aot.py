"""Kernels compiled ahead of time: the same machine code as numba's, without numba's start.

numba's import and start (its typing and lowering registries, LLVM, and each cached kernel
linked in) cost 0.55-0.65 s of every command that runs a kernel, before any of the
package's own work: most of a small data set's fixed cost. ``sim-tactile kernels build``
compiles, with numba's ``pycc``, every signature that numba has compiled and cached for a
module of the package (its kernel folder, :func:`~sim_tactile._jit.kernel_root`, at the
module's current code version) into one extension module per module, for this machine's
CPU; a later process loads it in about a millisecond and calls it without importing numba.

An extension serves a call only where numba would have compiled the very same signature
for it: each argument is checked as numba's ``typeof`` types it (an array's dtype, number
of dimensions, layout, whether it is writable and aligned; a float, an int in int64's
range, a bool; a tuple's and a named tuple's class and items, each in turn). numba's
compiled code reads memory as its signature says, and pycc's entry points check nothing
(a non-contiguous array where a contiguous one was compiled reads the wrong elements; an
array of float32 crashes the interpreter), so a call that matches no signature goes to
numba's own dispatcher, compiled or loaded as always. The code, its target CPU and its
optimisation are numba's; ``tests/test_aot.py`` holds the extension's slides equal to the
JIT's, bit for bit.

Where it lies: ``<kernel folder>/<module>/<code version>/aot-<cpu>/``, an extension and a
``kernels.json`` that names it with its sha256 (checked before it is loaded: a damaged or
truncated file is passed over, with a warning, and numba serves), the code version, this
Python's ABI and the signatures each entry point serves. An edit of the module, or of
anything it imports, is another code version, so an extension is never older than its
source. The extension is machine code: the kernel folder is trusted as code is.

``SIM_TACTILE_AOT=0`` turns the extensions off (numba serves every call).
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import json
import os
import platform
import sys
import warnings
from pathlib import Path

import numpy as np

from .errors import CacheWarning

#: The environment variable that turns the extensions off ("0").
ENV = "SIM_TACTILE_AOT"
#: The description of a folder's extension.
INDEX = "kernels.json"
#: Written into every index; an index of another format is passed over.
FORMAT = 1


def enabled() -> bool:
    return os.environ.get(ENV, "1") != "0"


def cpu_key() -> str | None:
    """A name for this machine's CPU, as the compiled code depends on it (the model and its
    instruction-set flags, the architecture and this Python's ABI); None where it cannot be
    read (no ``/proc/cpuinfo``): no extension is then used or built. (A process reads it
    once: :func:`sim_tactile._jit._state` keeps it and passes it on.)"""
    try:
        text = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return None
    first = text.split("\n\n", 1)[0]
    keep = [
        line.split(":", 1)[1].strip()
        for line in first.splitlines()
        if line.split(":", 1)[0].strip() in ("model name", "flags", "Features", "CPU part")
    ]
    if not keep:
        return None
    h = hashlib.sha256(
        "\n".join([platform.machine(), sys.implementation.cache_tag, *keep]).encode()
    )
    return h.hexdigest()[:12]


def folder(stamp_folder: Path, cpu: str | None) -> Path | None:
    """Where the extension of a module's code version (its kernel folder ``stamp_folder``)
    lies on the CPU ``cpu`` (:func:`cpu_key`); None where the CPU cannot be named."""
    return None if cpu is None else Path(stamp_folder) / f"aot-{cpu}"


# -- the check of a call's arguments, as numba's typeof would type them ------------------------
#: ndarray.flags.num's bits: C- and F-contiguous, aligned, writeable (numba's layout is "C"
#: where the array is C-contiguous, else "F" where F-contiguous, else "A")
_C, _F, _ALIGNED, _WRITEABLE = 0x1, 0x2, 0x100, 0x400


def _int(a) -> bool:
    return (type(a) is int and -(2**63) <= a < 2**63) or type(a) is np.int64


def _class(path: str) -> type:
    module, _, name = path.partition(":")
    if module.split(".")[0] != "sim_tactile":
        raise ValueError(f"{path} is not a class of the package")
    obj = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    if not isinstance(obj, type):
        raise TypeError(f"{path} is not a class")
    return obj


def matcher(specs):
    """Whether a call's positional arguments are those of one compiled signature: one
    function, written out from the signature's specs (:func:`spec_of`) as a chain of tests
    (the names of the spec's values, never its text), so that a call costs some 0.15 us an
    array."""
    consts: dict[str, object] = {"ndarray": np.ndarray, "_int": _int, "f8": np.float64}
    consts["b1"] = np.bool_
    lines = [f"    if type(args) is not tuple or len(args) != {len(specs)}: return False"]
    counter = [0]

    def const(value) -> str:
        name = f"k{len(consts)}"
        consts[name] = value
        return name

    def emit(expr: str, spec) -> None:
        v = f"v{counter[0]}"
        counter[0] += 1
        lines.append(f"    {v} = {expr}")
        kind = spec[0]
        if kind == "a":
            _, dtype, ndim, layout, mutable, aligned = spec
            dt = const(np.dtype(str(dtype)))
            if layout not in ("C", "F", "A"):
                raise ValueError(f"unknown layout {layout!r}")
            mask = (_C if layout == "C" else _C | _F) | _ALIGNED | _WRITEABLE
            want = {"C": _C, "F": _F, "A": 0}[layout]
            want |= (_ALIGNED if aligned else 0) | (_WRITEABLE if mutable else 0)
            lines.append(
                f"    if type({v}) is not ndarray or {v}.ndim != {int(ndim)} "
                f"or ({v}.flags.num & {mask}) != {want}: return False"
            )
            # a dtype equal to the signature's need not be its object (an unpickled array's)
            lines.append(f"    if {v}.dtype is not {dt} and {v}.dtype != {dt}: return False")
        elif kind == "f":
            lines.append(f"    if type({v}) is not float and type({v}) is not f8: return False")
        elif kind == "i":
            lines.append(f"    if not _int({v}): return False")
        elif kind == "b":
            lines.append(f"    if type({v}) is not bool and type({v}) is not b1: return False")
        elif kind in ("t", "n"):
            cls = "tuple" if kind == "t" else const(_class(str(spec[1])))
            items = spec[-1]
            lines.append(f"    if type({v}) is not {cls} or len({v}) != {len(items)}: return False")
            for k, item in enumerate(items):
                emit(f"{v}[{k}]", item)
        else:
            raise ValueError(f"unknown argument spec {spec!r}")

    for k, spec in enumerate(specs):
        emit(f"args[{k}]", spec)
    # the source holds names, indices and integers only: the spec's dtypes and classes are
    # values in the namespace, never text
    source = "def ok(args):\n" + "\n".join(lines) + "\n    return True\n"
    namespace = dict(consts)
    exec(compile(source, "<sim_tactile._aot matcher>", "exec"), namespace)  # noqa: S102
    return namespace["ok"]


class LazyMatcher:
    """:func:`matcher` of ``specs``, written out at its first call: a process loads every
    signature of the modules it imports and calls few of them, and writing one out (its
    source compiled) takes some 0.5 ms: 93 of them were 0.05 s of every command's start-up.
    A spec :func:`matcher` refuses is refused at that call."""

    __slots__ = ("_ok", "specs")

    def __init__(self, specs) -> None:
        self.specs = specs
        self._ok = None

    def __call__(self, args) -> bool:
        ok = self._ok
        if ok is None:
            ok = self._ok = matcher(self.specs)
        return ok(args)


def spec_of(ty):
    """The JSON spec of a numba type as an argument (see :func:`matcher`); None for a type no
    extension serves (numba's dispatcher then does)."""
    from numba.core import types

    if isinstance(ty, types.Array):
        if ty.layout not in "CFA" or not isinstance(
            ty.dtype, (types.Float, types.Integer, types.Boolean)
        ):
            return None
        dtype = "bool" if isinstance(ty.dtype, types.Boolean) else str(ty.dtype)
        return ["a", np.dtype(dtype).str, ty.ndim, ty.layout, ty.mutable, ty.aligned]
    if ty == types.float64:
        return ["f"]
    if ty == types.int64:
        return ["i"]
    if ty == types.boolean:
        return ["b"]
    if isinstance(ty, (types.NamedTuple, types.NamedUniTuple)):
        cls = ty.instance_class
        items = [spec_of(t) for t in ty.types]
        if None in items or "<locals>" in cls.__qualname__:
            return None
        return ["n", f"{cls.__module__}:{cls.__qualname__}", items]
    if isinstance(ty, (types.Tuple, types.UniTuple)):
        items = [spec_of(t) for t in ty.types]
        return None if None in items else ["t", items]
    return None


# -- loading --------------------------------------------------------------------------------
def _warn(message: str) -> None:
    warnings.warn(message, CacheWarning, stacklevel=4)


def load(where: Path | None, cpu: str | None) -> dict[str, list] | None:
    """The entry points of the extension in ``where`` (:func:`folder`), by kernel: for each,
    ``(matcher, function)`` pairs; None where there is none, or it is not this code
    version's, this Python's, the CPU ``cpu``'s (:func:`cpu_key`) or whole. (Whether the
    extensions are enabled at all is the caller's question: :func:`sim_tactile._jit._state`
    asks it.)"""
    if where is None:
        return None
    index = where / INDEX
    try:
        doc = json.loads(index.read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as exc:
        _warn(f"ahead-of-time kernels {index} cannot be read ({type(exc).__name__}); numba serves")
        return None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        return None
    if doc.get("python") != sys.implementation.cache_tag or doc.get("cpu") != cpu:
        return None
    so = where / str(doc.get("file", ""))
    try:
        raw = so.read_bytes()
    except OSError:
        _warn(f"ahead-of-time kernels {so} are missing; numba serves")
        return None
    if hashlib.sha256(raw).hexdigest() != doc.get("sha256"):
        _warn(f"ahead-of-time kernels {so} do not match their digest (damaged?); numba serves")
        return None
    name = so.name.split(".", 1)[0]
    loader = importlib.machinery.ExtensionFileLoader(name, str(so))
    spec = importlib.util.spec_from_file_location(name, str(so), loader=loader)
    try:
        ext = importlib.util.module_from_spec(spec)
        loader.exec_module(ext)
    except ImportError as exc:
        _warn(f"ahead-of-time kernels {so} cannot be loaded ({exc}); numba serves")
        return None
    out: dict[str, list] = {}
    for kernel, entries in doc.get("kernels", {}).items():
        out[kernel] = [(LazyMatcher(e["args"]), getattr(ext, e["export"])) for e in entries]
    return out


class Kernel:
    """A kernel of a module that has an extension: its compiled entry points serve the calls
    whose arguments match one of their signatures, numba's dispatcher (made on first need,
    by ``make()``) every other, and every attribute a dispatcher has."""

    def __init__(self, py_func, make, entries) -> None:
        self.py_func = py_func
        self._make = make
        self._entries = tuple(entries)
        self._disp = None
        self.__name__ = py_func.__name__
        self.__qualname__ = py_func.__qualname__
        self.__module__ = py_func.__module__
        self.__doc__ = py_func.__doc__
        self.__wrapped__ = py_func

    @property
    def dispatcher(self):
        """numba's dispatcher of the kernel (numba is imported on the first call for it)."""
        if self._disp is None:
            self._disp = self._make()
        return self._disp

    @property
    def served_ahead(self) -> int:
        """How many signatures the extension serves."""
        return len(self._entries)

    def __call__(self, *args, **kwargs):
        if not kwargs:
            entries = self._entries
            for k, (ok, fn) in enumerate(entries):
                if ok(args):
                    if k:  # the signature of the last call first: a kernel is called alike
                        self._entries = (entries[k], *entries[:k], *entries[k + 1 :])
                    return fn(*args)
        if self._disp is None and self._entries:  # built ahead, but not for these arguments
            _warn(
                f"kernel {self.__module__}.{self.__qualname__} was not compiled ahead of time "
                "for these arguments' types, so numba serves it (its start-up costs about "
                "0.6 s a command); run 'sim-tactile kernels build' again after this command"
            )
        return self.dispatcher(*args, **kwargs)

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.dispatcher, name)

    def __repr__(self) -> str:
        return f"<ahead-of-time kernel {self.__module__}.{self.__qualname__}>"
