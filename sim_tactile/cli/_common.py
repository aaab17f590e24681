"""What every command shares: logging to stderr, one JSON document on stdout."""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import pickle  # only for its error: numba reads its own cache index with it
import sys
from collections.abc import Callable, Iterator, Sequence

from ..errors import ConfigError


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def emit(args: argparse.Namespace, payload: object, text: Callable[[], str]) -> None:
    """Print ``payload`` as JSON under ``--json``, else ``text()`` for people."""
    if args.json:
        json.dump(finite_json(payload), sys.stdout, indent=2, sort_keys=False)
        sys.stdout.write("\n")
    else:
        print(text())


def finite_json(obj: object) -> object:
    """The document with non-finite floats as None: stdout must stay valid JSON."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [finite_json(v) for v in obj]
    return obj


def names_arg(value: str | None, option: str, valid: Sequence[str]) -> list[str] | None:
    """A comma-separated list of names, each one of ``valid`` (None: not given)."""
    if value is None:
        return None
    names = [n.strip() for n in value.split(",") if n.strip()]
    bad = [n for n in names if n not in valid]
    if bad or not names:
        raise ConfigError(
            f"{option} {value!r}: {bad[0] if bad else 'nothing'} is not valid; valid: "
            f"a comma-separated list of {', '.join(valid)}"
        )
    return names


class LazyHelpFormatter(argparse.HelpFormatter):
    """Takes an option's help as a function too, called only when the help is printed: a
    help text that names what a heavy module declares (ablate's parameters) costs nothing
    to a command that does not print it (``--version`` took 1.9 s importing scikit-learn)."""

    def _format_action(self, action: argparse.Action) -> str:
        if callable(action.help):
            action.help = action.help()
        return super()._format_action(action)


def add_group(parent, name: str, help: str):
    """A command of subcommands (``sim-tactile NAME SUBCOMMAND``), one of which must be
    given; returns the subparsers to add them to (:func:`add_command`)."""
    group = parent.add_parser(name, help=help, description=help)
    return group.add_subparsers(dest=f"{name}_command", required=True)


def add_command(
    parent, name: str, func, help: str, *, compiles: bool = False
) -> argparse.ArgumentParser:
    """A subcommand with ``--json`` that runs ``func(args)``; ``compiles``: it may compile
    the package's kernels (then :func:`compile_notice` watches it)."""
    sp = parent.add_parser(name, help=help, description=help, formatter_class=LazyHelpFormatter)
    sp.add_argument(
        "--json",
        action="store_true",
        help="Print one JSON document on stdout (progress and logs go to stderr).",
    )
    sp.add_argument(
        "--debug",
        action="store_true",
        default=argparse.SUPPRESS,
        help="Show the traceback of an error instead of its one-line reason.",
    )
    sp.set_defaults(func=func, compiles=compiles)
    return sp


def add_knob_args(parser: argparse.ArgumentParser) -> None:
    """A flag for each public knob of how a slide is computed (``--solve-every``, ...), with
    the help and range that :data:`~sim_tactile.sim.plan.options.KNOBS` declares; an
    absent flag leaves its knob at its default."""
    from ..sim.plan.options import KNOBS

    types = {"int": int, "float": float, "choice": str}
    for k in KNOBS:
        if not k.public:
            continue
        parser.add_argument(
            "--" + k.name.replace("_", "-"),
            type=types[k.kind],
            default=None,
            choices=k.choices or None,
            help=f"{k.help[0].upper()}{k.help[1:]}; {k.valid()}.",
        )


def options_of(args: argparse.Namespace):
    """The :class:`~sim_tactile.sim.plan.options.StepOptions` of the knob flags that
    :func:`add_knob_args` added (the absent ones at their defaults)."""
    from ..sim.plan.options import KNOBS, StepOptions

    given = {k.name: getattr(args, k.name, None) for k in KNOBS if k.public}
    return StepOptions(**{n: x for n, x in given.items() if x is not None})


#: About how long the simulator's numba kernels take to compile on a first run (measured on
#: 2 cores: 80-110 s for `sim-tactile run finger7-v1 --quick` in a fresh installation).
COMPILE_NOTICE = (
    "sim-tactile: compiling the package's kernels once on this installation (about 1.5-2 "
    "minutes on 2 cores for a simulation's); they are cached, and later runs start in seconds."
)


def kernels_to_compile(modules: Sequence[str] = ("sim_tactile.sim.slide",)) -> int | None:
    """How many of the compiled kernels that ``modules`` load have no usable compiled copy
    on disk: no cache index yet, or one that numba would not load (another numba, or a stamp
    other than the kernel's :func:`~sim_tactile._jit.kernel_stamp`: an edited, upgraded or
    freshly installed package). None where that cannot be told (a numba without the cache
    API read here). Imports ``modules``. (An upper bound of what a command compiles: it
    counts kernels the command may never call; :func:`compile_notice` watches the compiles
    themselves.)"""
    import importlib

    for name in modules:
        importlib.import_module(name)
    try:
        from numba.core.registry import CPUDispatcher
    except ImportError:
        return None
    from .._aot import Kernel

    kernels = {
        id(obj): obj
        for name, mod in list(sys.modules.items())
        if name.startswith("sim_tactile.") and mod is not None
        for obj in list(vars(mod).values())
        if isinstance(obj, (CPUDispatcher, Kernel))  # once each, also where imported
    }
    # a kernel built ahead of time (sim_tactile/_aot.py) compiles nothing for what it serves
    return sum(
        not (getattr(k, "served_ahead", 0) or _cached_on_disk(getattr(k, "dispatcher", k)))
        for k in kernels.values()
    )


def _cached_on_disk(dispatcher) -> bool:
    """Whether numba would load ``dispatcher`` from its disk cache: its index exists and was
    written by this numba under the stamp that the kernel's cache (sim_tactile/_jit.py's
    versioned locator) expects now. Reads the index as numba's own loader does."""
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if cache_file is None:
        return True  # not cached to disk (cache=False), or another numba: nothing to say
    try:
        return bool(cache_file._load_index())  # {} when absent, stale or another version
    except (OSError, EOFError, ValueError, pickle.UnpicklingError):  # numba compiles afresh
        return False


@contextlib.contextmanager
def compile_notice(say: Callable[[str], None] = log) -> Iterator[None]:
    """Say :data:`COMPILE_NOTICE` when, and only when, a kernel of this package starts to
    compile while the block runs: numba's ``numba:compile`` event, which it fires on a
    cache miss, never for a kernel it loads from disk. Once a command, also across the
    worker processes it forks (a flag in memory they share)."""
    import multiprocessing

    from .._jit import numba_module, when_numba

    if "numba" in sys.modules:  # imported already (by numba's kernels, or by a caller)
        numba_module()

    said, lock = multiprocessing.RawValue("b", 0), multiprocessing.Lock()
    registered = []  # (event module, listener), once numba is imported (never, where the
    # kernels are served ahead of time: nothing then compiles)
    active = [True]

    def register(numba) -> None:
        if not active[0]:
            return
        from numba.core import event

        class Notice(event.Listener):
            def on_start(self, ev) -> None:
                fn = getattr((ev.data or {}).get("dispatcher"), "py_func", None)
                if not str(getattr(fn, "__module__", "")).startswith("sim_tactile."):
                    return
                with lock:
                    first, said.value = not said.value, 1
                if first:
                    say(COMPILE_NOTICE)

            def on_end(self, ev) -> None:
                pass

        listener = Notice()
        event.register("numba:compile", listener)
        registered.append((event, listener))

    when_numba(register)
    try:
        yield
    finally:
        active[0] = False
        for event, listener in registered:
            event.unregister("numba:compile", listener)


PLATE_HELP = (
    "The plate: a preset's name ('sim-tactile plates list'), a plate file (.toml; copy one of "
    "assets/plates), a part (.step, .stp, .stl, or a CadQuery script .py[:function], in mm "
    "unless units=...) or a height map (.npy in m, 16-bit .png), with options after '?' (see "
    "--plate-frame)."
)
PLATE_FRAME_HELP = (
    "The options of a part or height map, as comma-separated key=value: units (mm, m, um, "
    "in), up (+z, -z, +x, -x, +y, -y: the part's axis that points up), rotate_deg (about z), "
    "scale, pixel_m (the height map's sample spacing), z_scale_m (a PNG's metres per count), "
    "thickness_m, fill_overhangs (true or false), holes (true or false: keep a map's NaN "
    "samples or a hole through a part as intended holes), timeout_s (a script's time limit) "
    "and name."
)


def add_plate_args(parser: argparse.ArgumentParser, **kw) -> None:
    """``--plate`` and ``--plate-frame``."""
    parser.add_argument("--plate", help=PLATE_HELP, **kw)
    parser.add_argument("--plate-frame", default=None, help=PLATE_FRAME_HELP)


def plate_of(plate: str, frame: str | None) -> str:
    """The plate reference of ``--plate`` with ``--plate-frame``'s options."""
    if frame is None:
        return plate
    from ..plates.parts.user import is_user_plate, parse_ref

    if not is_user_plate(plate):
        raise ConfigError(
            f"--plate-frame applies to a part or height map (.step, .stp, .stl, .py, .npy, "
            f".png), not to {plate!r}"
        )
    opts = {}
    for item in frame.split(","):
        key, eq, val = item.partition("=")
        if not eq or not key.strip():
            raise ConfigError(f"--plate-frame {frame!r}: {item!r} is not key=value")
        opts[key.strip()] = val.strip()
    return parse_ref(plate, **opts).ref()
