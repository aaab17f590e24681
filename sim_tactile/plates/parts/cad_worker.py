"""The separate process that reads a user's STEP file or runs a user's CadQuery script and
writes the part's tessellation (vertices in the part's own units, triangles) as a ``.npz``.

Run only by :mod:`.user`, as ``python -m sim_tactile.plates.parts.cad_worker KIND SOURCE OUT
[FUNCTION]`` with ``KIND`` ``step`` or ``script``, under a time limit (:mod:`.cad_run`: in its own session, killed whole at the limit). A
script is code: it runs here, never in the caller's process, and only when the user names
it. This process makes itself the reaper of its orphans and, before it exits, kills every
process the script left behind (:func:`.cad_run.kill_session`). Exit status: 0 written; 3
the script or the reader raised (the reason on the last line of stderr); 4 the result is not
a CadQuery shape.
"""

from __future__ import annotations

import os
import runpy
import sys
import traceback

import numpy as np


def _shape_of(result):
    import cadquery as cq

    if isinstance(result, cq.Workplane):
        vals = [v for v in result.vals() if isinstance(v, cq.Shape)]
        if not vals:
            return None
        return vals[0] if len(vals) == 1 else cq.Compound.makeCompound(vals)
    if isinstance(result, cq.Shape):
        return result
    if isinstance(result, cq.Assembly):
        return result.toCompound()
    return None


def _load(kind: str, source: str, function: str):
    if kind == "step":
        import cadquery as cq

        return cq.importers.importStep(source)
    sys.path.insert(0, os.path.dirname(os.path.abspath(source)))  # its own modules beside it
    namespace = runpy.run_path(source, run_name="sim_tactile_plate_script")
    fn = namespace.get(function)
    if not callable(fn):
        names = sorted(k for k, val in namespace.items() if callable(val) and not k.startswith("_"))
        raise LookupError(
            f"the script defines no function {function}(); its functions: {', '.join(names) or 'none'}"
        )
    return fn()


def main(argv: list[str]) -> int:
    from .cad_run import become_subreaper, kill_session

    become_subreaper()
    try:
        return _main(argv)
    finally:
        kill_session(os.getpid(), spare=os.getpid())  # what the script left running


def _main(argv: list[str]) -> int:
    from .cad_run import STL_ANGULAR_TOLERANCE_RAD, STL_TOLERANCE_MM

    kind, source, out = argv[:3]
    function = argv[3] if len(argv) > 3 else "plate"
    try:
        result = _load(kind, source, function)
    except BaseException as exc:  # the user's code: report whatever it raised
        traceback.print_exc(file=sys.stderr)
        print(f"{type(exc).__name__}: {exc}", file=sys.stderr)
        return 3
    shape = _shape_of(result)
    if shape is None:
        print(
            f"{function}() returned {type(result).__name__}, not a cadquery Workplane, Shape or "
            "Assembly",
            file=sys.stderr,
        )
        return 4
    verts, tris = shape.tessellate(STL_TOLERANCE_MM, STL_ANGULAR_TOLERANCE_RAD)
    v = np.array([(p.x, p.y, p.z) for p in verts], dtype=np.float64).reshape(-1, 3)
    f = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    with open(out, "wb") as fh:
        np.savez(fh, vertices=v, faces=f)
    return 0


if __name__ == "__main__":  # pragma: no cover (run as a subprocess, tested through user.py)
    sys.exit(main(sys.argv[1:]))
