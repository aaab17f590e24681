"""``sim-tactile kernels build``: the package's compiled kernels, ahead of time."""

from __future__ import annotations

import argparse

from ._common import add_command, add_group, emit, log


def cmd_kernels_build(args: argparse.Namespace) -> int:
    """Compile every kernel signature that numba has cached at the current code version
    into one extension a module (:mod:`sim_tactile._aot`)."""
    from .._aot_build import build_ahead
    from .._jit import kernel_root

    modules = args.modules.split(",") if args.modules else None
    done = build_ahead(modules, log=log)
    built = [d for d in done if d["built"]]
    log(
        f"built {sum(d['built'] for d in built)} signature(s) of {len(built)} module(s) "
        f"ahead of time into {kernel_root()}"
    )

    def text() -> str:
        return "\n".join(
            f"{d['module']}: "
            + (f"{d['built']} signature(s)" if d["built"] else f"none ({d['why']})")
            for d in done
        )

    emit(args, {"kernel_folder": str(kernel_root()), "modules": done}, text)
    return 0


def add_parsers(sub) -> None:
    ksub = add_group(sub, "kernels", "Compile the package's kernels ahead of time.")
    b = add_command(
        ksub,
        "build",
        cmd_kernels_build,
        "Compile ahead of time every kernel signature that numba has compiled and cached here "
        "(run a command that simulates first), one extension a module, for this CPU: later "
        "commands load them in milliseconds, without numba's start-up (about 0.6 s a command). "
        "A kernel's module edited since is compiled by numba, as before; SIM_TACTILE_AOT=0 "
        "turns the extensions off.",
    )
    b.add_argument(
        "--modules",
        default=None,
        help="Comma-separated modules of the package (default: every one with kernels cached).",
    )
