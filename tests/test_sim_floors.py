"""sim/ in floors: the planner loads neither MuJoCo nor numba, the package's names load their
module when asked for, and the held step is chosen in one function."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import sim_tactile

SIM = Path(sim_tactile.__file__).parent / "sim"


def _run(code: str) -> subprocess.CompletedProcess:
    # numba's kernels, not those built ahead of time (sim_tactile/_aot.py), which load no
    # numba where they serve
    env = {**os.environ, "SIM_TACTILE_AOT": "0"}
    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
        env=env,
    )


def test_the_planner_loads_neither_mujoco_nor_numba():
    """Every module of sim/plan/, imported in a fresh process, leaves MuJoCo and numba
    unloaded (import-linter's forbidden contract says the same of the import graph)."""
    modules = sorted(
        "sim_tactile.sim.plan." + p.stem
        for p in (SIM / "plan").glob("*.py")
        if p.stem != "__init__"
    )
    assert "sim_tactile.sim.plan.fidelity" in modules and len(modules) >= 5
    code = (
        "import importlib, sys\n"
        f"for m in {modules!r}:\n"
        "    importlib.import_module(m)\n"
        "print(sorted(k for k in ('mujoco', 'numba') if k in sys.modules))\n"
    )
    out = _run(code)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_the_check_can_fail_on_a_module_that_loads_numba():
    out = _run("import sys, sim_tactile.sim.collide.shapes; print('numba' in sys.modules)")
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "True"


def test_the_package_names_load_their_module_when_asked_for():
    """``from sim_tactile.sim import Protocol`` describes a slide without MuJoCo; ``simulate``
    is the function (not its module) and loads MuJoCo then; an unknown name is an
    AttributeError."""
    code = (
        "import sys\n"
        "import sim_tactile.sim as S\n"
        "from sim_tactile.sim import Fidelity, Protocol, SlideWindow, choose_fidelity\n"
        "print('mujoco' in sys.modules, 'numba' in sys.modules)\n"
        "from sim_tactile.sim import SimResult, StepOptions, prepare, press, simulate\n"
        "import sim_tactile.sim.slide as slide\n"
        "print('mujoco' in sys.modules, simulate is slide.simulate, S.simulate is simulate)\n"
        "print(Protocol().speed_m_s > 0, callable(press), sorted(S.__all__) == S.__all__)\n"
        "try:\n"
        "    S.no_such_name\n"
        "except AttributeError as e:\n"
        "    print('no_such_name' in str(e))\n"
    )
    out = _run(code)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split("\n")[:4] == [
        "False False",
        "True True True",
        "True True True",
        "True",
    ]


#: The held steps and where each may be built: the one function that chooses, and the static
#: press, whose step is always the plain loop (it reads the pressures it leaves).
_HELD_STEPS = {
    "AnchoredHeldStep": {"step/choose.py"},
    "ClippedHeldStep": {"step/choose.py"},
    "CompiledHeldStep": {"step/choose.py"},
    "PlainHeldStep": {"step/choose.py", "static_press.py"},
}


def _constructions(root: Path) -> dict[str, set[str]]:
    """Which files of ``root`` call each held-step class."""
    found: dict[str, set[str]] = {k: set() for k in _HELD_STEPS}
    for p in root.rglob("*.py"):
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
                if node.func.id in found:
                    found[node.func.id].add(p.relative_to(root).as_posix())
    return found


def test_the_held_step_is_chosen_in_one_function():
    assert _constructions(SIM) == _HELD_STEPS


def test_the_construction_finder_sees_a_second_chooser(tmp_path):
    (tmp_path / "step").mkdir()
    (tmp_path / "step" / "choose.py").write_text("x = CompiledHeldStep(1)\n")
    (tmp_path / "runner.py").write_text("def f():\n    return CompiledHeldStep(2)\n")
    assert _constructions(tmp_path)["CompiledHeldStep"] == {"step/choose.py", "runner.py"}
