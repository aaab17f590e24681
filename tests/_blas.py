"""A result of the package under another BLAS kernel, for the tests that hold it to be the
same on any machine.

OpenBLAS picks its kernel by the CPU (or by ``OPENBLAS_CORETYPE``), and the kernels sum in
different orders: a float that goes through a dot product, a solve or an eigenproblem moves
in its last digits from machine to machine, and an iterative fit (a bounded search, a fixed
point) stops elsewhere within its own tolerance. A test that compares such a float with a
stored one holds it to :data:`BLAS_RTOL`, and :func:`run_under_other_kernel` reruns the
computation in a fresh interpreter under another kernel than this process's.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

#: Relative tolerance for a fitted float compared across machines. The calibration's fits
#: stop within their own tolerances (the bounded search of ``calibrate.rest._diff_fit`` at
#: 1e-7 in log sigma), and there the kernel moves them: between OpenBLAS's SkylakeX and
#: Haswell kernels, on the real BioTac recordings, noise_std by 6.6e-8 and offset by 1.7e-7
#: (relative). 1e-6 is above that, and far below any change of the fit itself.
BLAS_RTOL = 1e-6
#: The kernel to compare with, and the one for a machine that runs that one already (both
#: run on any x86-64 CPU with AVX2, and AVX respectively).
OTHER_KERNELS = ("Haswell", "Sandybridge")
ROOT = Path(__file__).resolve().parents[1]
_ARCH = "from sim_tactile.hashing import blas_kernel; print(blas_kernel())"


def this_kernel() -> str:
    """The OpenBLAS kernel that numpy and scipy run in this process
    (:func:`sim_tactile.hashing.blas_kernel`; the test is skipped where they run no single
    known one)."""
    from sim_tactile.hashing import blas_kernel

    here = blas_kernel()
    if "+" in here or here == "unknown":
        pytest.skip(f"numpy and scipy run no single known BLAS kernel here ({here})")
    return here


def run_under_other_kernel(code: str, *args: str) -> tuple[str, str]:
    """Run ``code`` (Python, its arguments ``args`` in ``sys.argv[1:]``) in a fresh
    interpreter under another OpenBLAS kernel than this process's, with this checkout on
    its path: (that kernel, the code's standard output). Skipped where this CPU does not
    run the other kernel."""
    other = OTHER_KERNELS[1] if this_kernel() == OTHER_KERNELS[0] else OTHER_KERNELS[0]
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
    env = os.environ | {"OPENBLAS_CORETYPE": other, "PYTHONPATH": path}
    out = subprocess.run(
        [sys.executable, "-c", f"{code}\n{_ARCH}\n", *args],
        env=env,
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    *lines, arch = out.stdout.strip().splitlines()
    if arch != other:
        pytest.skip(f"OPENBLAS_CORETYPE={other} does not run on this CPU (ran {arch})")
    return other, "\n".join(lines)
