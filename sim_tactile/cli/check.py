"""``sim-tactile check RESULT.json ...``: result files validated against their tasks."""

from __future__ import annotations

import argparse

from ._common import add_command, emit, log


def cmd_check(args: argparse.Namespace) -> int:
    """Check each file; exit 0 when all are valid, 1 when one is refused (each refusal one
    line on stderr)."""
    from ..tasks.check import check_file

    files = []
    for path in args.files:
        refusals = check_file(path)
        files.append({"path": str(path), "ok": not refusals, "refusals": refusals})
        for line in refusals:
            log(f"{path}: {line}")
    refused = [f for f in files if not f["ok"]]
    if refused:
        log(f"sim-tactile: check: {len(refused)} of {len(files)} file(s) refused")

    def text() -> str:
        return "\n".join(
            f"{f['path']}: " + ("ok" if f["ok"] else f"refused ({len(f['refusals'])} reason(s))")
            for f in files
        )

    emit(args, {"ok": not refused, "files": files}, text)
    return 1 if refused else 0


def add_parsers(sub) -> None:
    ck = add_command(
        sub,
        "check",
        cmd_check,
        "Validate result files against their registered tasks: the task's id, version and "
        "split digests, the protocol's fixed fields, the repeats and each interval recomputed "
        "from them, and the closed track's rules.",
    )
    ck.add_argument(
        "files",
        nargs="+",
        metavar="RESULT.json",
        help="Result files written by 'sim-tactile run' (OUT/results/) or tasks.evaluate.",
    )
