"""Write the golden recordings ``tests/data/golden_slides.npz`` (one short slide of every
task's sensor and plate kind: each collider path, the reduced and full skin, L0 to L2, the
force controls, the probe rig).

    python tools/golden_slides.py [--check]

``tests/test_golden_slides.py`` demands these arrays bit for bit, so a refactor that keeps the
arithmetic keeps them. Regenerate only for a change that alters recordings on purpose, and
say why in its commit. ``--check`` compares instead of writing (exit 1 on a difference).

Bit for bit holds on the BLAS kernel the file was written with (``blas_core``, OpenBLAS's
choice for the CPU, recorded in the file). Another CPU takes another kernel, whose blocked LU
rounds in another order: measured, the file written under OpenBLAS's ``SkylakeX`` kernel and
read under its ``Haswell`` kernel (an AMD EPYC) differs in the per-sample forces by at most
4.6e-12 of the largest force, and not at all in the float32 data and the paths. On another
kernel the comparison is then to :data:`OTHER_KERNEL_RTOL`. To compare bit for bit on a
CPU that has the recorded kernel's instructions, set ``OPENBLAS_CORETYPE`` to it.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from sim_tactile.cache import ArtefactCache
from sim_tactile.hashing import derive_seed
from sim_tactile.plates import get_plate
from sim_tactile.sim import StepOptions
from sim_tactile.slides import SlideJob
from sim_tactile.tasks import get_task

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "golden_slides.npz"
#: Largest difference, relative to the array's largest magnitude, accepted where the BLAS
#: kernel is not the file's: 200x the 4.6e-12 measured between OpenBLAS's SkylakeX and Haswell
#: kernels on every case (float64 forces), and 8 float32 roundings for the float32 data.
OTHER_KERNEL_RTOL = {"float64": 1e-9, "float32": 1e-6}
#: (name, task, plate, slide, window [s] or None for the task's, overrides)
CASES = [
    ("finger7-ridges4", "finger7-v1", "finger7/ridges-4", 0, None, {}),
    ("finger7-bumps4x4", "finger7-v1", "finger7/bumps-4x4", 1, None, {}),
    ("finger7-flat", "finger7-v1", "finger7/flat", 0, 0.4, {}),
    ("finger7-ridges4-L0", "finger7-v1", "finger7/ridges-4", 0, 0.5, {"fidelity": "L0"}),
    ("finger7-ridges4-L2", "finger7-v1", "finger7/ridges-4", 0, 0.3, {"fidelity": "L2"}),
    ("finger7-ridges4-ideal", "finger7-v1", "finger7/ridges-4", 2, 0.5, {"ideal": True}),
    (
        "finger7-ridges4-dynamic",
        "finger7-v1",
        "finger7/ridges-4",
        0,
        0.4,
        {"force_control": "dynamic"},
    ),
    ("multilayer3-grating9", "multilayer3-v1", "multilayer3/grating-9", 0, 0.35, {}),
    ("multilayer3-hemi", "multilayer3-v1", "multilayer3/hemispheres-6x6", 0, 0.5, {}),
    ("roughness8-ra50", "roughness8-v1", "roughness8/ra-50", 0, 0.12, {}),
    ("roughness8-ra0.4", "roughness8-v1", "roughness8/ra-0.4", 3, 0.08, {}),
    ("biotac-grating3", "textures20-biotac19-v1", "textures20/grating-3.0mm", 0, 1.0, {}),
    ("biotac-hemi6", "textures20-biotac19-v1", "textures20/hemispheres-6.0mm", 0, 1.0, {}),
    ("icub-grating4", "textures20-icub60-v1", "textures20/grating-4.0mm", 0, 0.4, {}),
    # the probe rig (its whole 5 s window) and the curved finger under position control
    ("multilayer3v2-grating9", "multilayer3-v2", "multilayer3/grating-9", 0, None, {}),
    ("finger7v2-bumps4x4", "finger7-v2", "finger7/bumps-4x4", 0, 1.3, {}),
]


def case_job(case: dict) -> SlideJob:
    """The slide of a case: the task's own seed, protocol and sensor, the window shortened,
    on the per-step path (the reference every faster path is measured against; its phase
    table is tested against it in tests/test_sim_phase_table.py)."""
    ss = get_task(case["task"]).get_data
    seed = derive_seed(0, ss.plates.index(case["plate"]), case["slide"], bits=63)
    proto = ss.window_protocol()
    if case["duration_s"] is not None:
        proto = replace(proto, duration_s=case["duration_s"])
    if "force_control" in case:
        proto = replace(proto, force_control=case["force_control"])
    return SlideJob(
        get_plate(case["plate"]),
        ss.sensor_def(),
        proto,
        seed,
        case.get("fidelity", ss.fidelity),
        case.get("ideal", ss.ideal),
        ss.finger,
        pitch_m=ss.pitch_m,
        rig=ss.rig,
        options=StepOptions(path="per-step"),
    )


def _path(meta: dict) -> list:
    """The pad's path (the probe's on the rig)."""
    return meta["x_pad_m"] if "x_pad_m" in meta else meta["x_probe_m"]


def blas_core() -> str:
    """OpenBLAS's kernel in this process (``"unknown"`` when threadpoolctl cannot tell)."""
    from sim_tactile.hashing import blas_kernel

    return blas_kernel()


def differences(got: dict, want: dict, core: str) -> list[str]:
    """The arrays of ``got`` that differ from ``want`` (keys of each): bit for bit when this
    process's BLAS kernel ``core`` is the one ``want`` was written with, else beyond
    :data:`OTHER_KERNEL_RTOL` (with the relative difference)."""
    exact = core == want.get("blas_core")
    bad = []
    for k, a in got.items():
        if k in ("cases_json", "blas_core"):
            continue
        b = want[k]
        if a.dtype != b.dtype or a.shape != b.shape:
            bad.append(f"{k}: {a.dtype}{a.shape} against {b.dtype}{b.shape}")
        elif exact and a.tobytes() != b.tobytes():
            bad.append(f"{k}: not bit for bit (kernel {core})")
        elif not exact:
            scale = max(float(np.max(np.abs(b), initial=0.0)), np.finfo(b.dtype).tiny)
            rel = float(np.max(np.abs(a.astype(float) - b.astype(float)), initial=0.0)) / scale
            if not rel <= OTHER_KERNEL_RTOL[str(b.dtype)]:
                bad.append(
                    f"{k}: {rel:.3g} of its largest (kernel {core}, file {want['blas_core']})"
                )
    return bad


def record(cache: ArtefactCache) -> dict:
    arrays, cases = {}, []
    for name, task, plate, k, dur, over in CASES:
        case = {"name": name, "task": task, "plate": plate, "slide": k, "duration_s": dur}
        case.update(over)
        job = case_job(case)
        rec = job.simulate(cache).recording
        arrays[f"{name}/data"] = np.asarray(rec.data)
        arrays[f"{name}/normal_force_n"] = np.asarray(rec.meta["normal_force_n"])
        arrays[f"{name}/x_pad_m"] = np.asarray(_path(rec.meta))
        cases.append({**case, "seed": job.seed, "skin_problem": rec.meta["skin_problem"]})
        print(name, rec.data.shape, rec.meta["skin_problem"], file=sys.stderr)
    arrays["cases_json"] = np.array(json.dumps(cases))
    arrays["blas_core"] = np.array(blas_core())
    return arrays


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args()
    new = record(ArtefactCache.default())
    if args.check:
        with np.load(OUT, allow_pickle=False) as z:
            want = {k: z[k] for k in z.files}
        want["blas_core"] = str(want.get("blas_core", "unknown"))
        bad = differences(new, want, blas_core())
        print("same" if not bad else f"differ: {bad}")
        return 1 if bad else 0
    np.savez_compressed(OUT, **new)
    print(f"wrote {OUT}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
