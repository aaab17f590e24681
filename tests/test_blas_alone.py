"""The kernels' BLAS and LAPACK tables loaded without scipy.linalg (``_jit.blas_alone``):
a dense contact solve imports no scipy.linalg, answers as before, and scipy.linalg imported
afterwards works on the same modules."""

from __future__ import annotations

import json
import subprocess
import sys

_PROBE = """
import json, sys
import numpy as np
from sim_tactile.scene.elastic import compliance_matrix
from sim_tactile.sim.skin.contact import ActiveSet
xs = (np.arange(12) - 6) * 0.5e-3
X, Y = np.meshgrid(xs, xs)
xy = np.column_stack([X.ravel(), Y.ravel()])
C = compliance_matrix(xy, 0.5e-3, 0.3e6, pitch_y_m=0.5e-3)
pen = 1e-4 - 0.2 * (xy ** 2).sum(axis=1)
solver = ActiveSet(C, np.linalg.inv(C))  # loads the tables where it is asked to
p, _ = solver.solve_force(pen, 2e4)  # the kernels' first products and inverses
p2, _ = solver.solve_force(pen - 3e-5 * (xy[:, 0] > 0), 2e4)  # a set that changes
during = "scipy.linalg" in sys.modules
tables = [m for m in ("scipy.linalg.cython_blas", "scipy.linalg.cython_lapack") if m in sys.modules]
import scipy.linalg
from scipy.linalg import cython_lapack
from scipy.linalg import lu_factor
lu_factor(C[:4, :4])  # scipy.linalg's own LAPACK, after the tables were loaded alone
S = np.flatnonzero(p > 0)
print(json.dumps({
    "during": during, "tables": tables, "p": p.tolist(), "p2": p2.tolist(),
    "same": cython_lapack is sys.modules["scipy.linalg.cython_lapack"],
    "n": int(S.size),
}))
"""


def _probe(env_extra: str) -> dict:
    code = env_extra + _PROBE
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_dense_solve_loads_no_scipy_linalg_and_answers_as_with_it():
    alone = _probe("")
    assert alone["during"] is False, "a dense solve imported scipy.linalg"
    assert alone["tables"] == ["scipy.linalg.cython_blas", "scipy.linalg.cython_lapack"]
    assert alone["same"] is True  # scipy.linalg, imported later, takes the loaded module
    # the same solves with scipy.linalg imported first: the same numbers, bit for bit
    first = _probe("import scipy.linalg\n")
    assert first["during"] is True and first["n"] == alone["n"] > 10
    assert first["p"] == alone["p"] and first["p2"] == alone["p2"]
