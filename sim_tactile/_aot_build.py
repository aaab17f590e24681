"""``sim-tactile kernels build``: the package's kernels compiled ahead of time
(:mod:`sim_tactile._aot` serves them), from what numba has compiled and cached in the kernel
folder (:mod:`sim_tactile._jit`)."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path

from . import _aot
from ._jit import _LOADED, PACKAGE, _marker, kernel_root, numba_module, stamp_folder


def _kernels_of(module: str) -> dict[str, object]:
    """The numba dispatchers of ``module``'s kernels, by name (imported)."""
    import importlib

    mod = importlib.import_module(module)
    out = {}
    for name, obj in vars(mod).items():
        disp = obj.dispatcher if isinstance(obj, _aot.Kernel) else obj
        fn = getattr(disp, "py_func", None)
        if fn is not None and fn.__module__ == module and hasattr(disp, "overloads"):
            out[name] = disp
    return out


def _cached_signatures(disp) -> list:
    """The signatures numba has cached for ``disp`` at the current code version, on this
    CPU (its index's entries whose code and target are today's)."""
    cache = disp._cache
    codegen = disp.targetctx.codegen()
    out = []
    for key in cache._cache_file._load_index():
        sig = key[0]
        if cache._index_key(sig, codegen) == key:
            out.append(sig)
    return out


def build_ahead(modules=None, log: Callable[[str], None] = lambda s: None) -> list[dict]:
    """Compile ahead of time (:mod:`sim_tactile._aot`) every signature numba has cached for
    ``modules`` (default: every module of the package with a kernel folder at its current
    code version) into each module's extension; returns, per module, what was built (or
    why not). Replaces an extension that is there."""
    from .errors import MissingDependencyError

    cpu = _aot.cpu_key()
    if cpu is None:
        raise MissingDependencyError(
            "kernels are built ahead of time only where the CPU can be named (/proc/cpuinfo, "
            "Linux): numba serves them here, as before"
        )
    numba = numba_module()
    try:
        from numba.pycc import CC
    except ImportError as exc:
        raise MissingDependencyError(
            f"numba {numba.__version__} has no pycc ({exc}): the kernels cannot be built ahead "
            "of time with it; numba serves them, as before"
        ) from exc
    root = kernel_root()
    if modules is None:
        modules = sorted(
            d.name
            for d in (root.iterdir() if root.is_dir() else ())
            if d.is_dir() and d.name.split(".")[0] == PACKAGE
        )
    root.mkdir(parents=True, exist_ok=True)
    _marker(cpu).write_text(
        "kernels built ahead of time for this CPU (sim-tactile kernels build)\n"
    )
    _LOADED.clear()  # this process looks again
    done = []
    for module in modules:
        try:
            where = stamp_folder(module)
        except Exception as exc:  # not a module of this version of the package
            done.append({"module": module, "built": 0, "why": f"not a module ({exc})"})
            continue
        if not where.is_dir():
            done.append({"module": module, "built": 0, "why": "nothing compiled yet"})
            continue
        exports, kernels = [], {}
        for name, disp in sorted(_kernels_of(module).items()):
            for sig in _cached_signatures(disp):
                specs = [_aot.spec_of(t) for t in sig]
                if None in specs:
                    continue
                disp.compile(sig)  # loaded from numba's cache: the return type
                full = disp.overloads[tuple(sig)].signature
                export = f"{name}__{len(exports)}"
                exports.append((export, full, disp.py_func))
                kernels.setdefault(name, []).append({"export": export, "args": specs})
        if not exports:
            done.append({"module": module, "built": 0, "why": "no signature it can serve"})
            continue
        try:
            _compile_extension(CC, numba, module, where, exports, kernels, cpu)
        except Exception as exc:  # a C compiler missing or failing: numba serves the module
            why = (
                f"pycc failed ({type(exc).__name__}: {(str(exc).strip().splitlines() or [''])[0]})"
            )
            done.append({"module": module, "built": 0, "why": why})
            log(f"{module}: {why}")
            continue
        done.append({"module": module, "built": len(exports), "kernels": sorted(kernels)})
        log(f"{module}: {len(exports)} signature(s) of {len(kernels)} kernel(s)")
    return done


def _compile_extension(CC, numba, module: str, where: Path, exports, kernels, cpu: str) -> None:
    """pycc's extension of ``exports`` (name, signature, function) and its index for the
    CPU ``cpu``, staged in the module's kernel folder ``where`` and moved into place whole."""
    import hashlib
    import json
    import shutil
    import sys
    import tempfile

    tag = hashlib.sha256(f"{module}:{where.name}".encode()).hexdigest()[:12]
    ext = f"_sim_tactile_aot_{tag}"
    staged = Path(tempfile.mkdtemp(prefix=".aot-", dir=where))
    try:
        cc = CC(ext)
        cc.output_dir = str(staged)
        cc.target_cpu = "host"  # numba's JIT compiles for this CPU too
        cc.verbose = False
        for export, full, fn in exports:
            cc.export(export, full)(fn)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", numba.NumbaPendingDeprecationWarning)
            cc.compile()
        (so,) = staged.glob(f"{ext}*.so")
        doc = {
            "format": _aot.FORMAT,
            "module": module,
            "stamp": where.name,
            "python": sys.implementation.cache_tag,
            "cpu": cpu,
            "numba": numba.__version__,
            "file": so.name,
            "sha256": hashlib.sha256(so.read_bytes()).hexdigest(),
            "kernels": kernels,
        }
        (staged / _aot.INDEX).write_text(json.dumps(doc, indent=1, sort_keys=True))
        for f in staged.iterdir():  # pycc's intermediate files
            if f.name not in (so.name, _aot.INDEX):
                shutil.rmtree(f) if f.is_dir() else f.unlink()
        final = _aot.folder(where, cpu)
        if final.exists():  # the one it replaces, out of the way first
            final.rename(staged.with_name(staged.name + "-old"))
        staged.rename(final)
    finally:
        shutil.rmtree(staged, ignore_errors=True)
        shutil.rmtree(staged.with_name(staged.name + "-old"), ignore_errors=True)


__all__ = ["build_ahead"]
