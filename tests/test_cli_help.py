"""The command line introduces itself: whole-sentence help, ``tasks``, ``--version`` and the
first run's notice that the kernels compile."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import pytest

import sim_tactile
from sim_tactile.cli import build_parser
from sim_tactile.cli._common import COMPILE_NOTICE
from sim_tactile.cli.tasks import paper_of, task_summary
from sim_tactile.tasks import get_task, task_ids
from sim_tactile.tasks.ablate import PARAM_HELP, PARAMS


def _helps(parser: argparse.ArgumentParser, path: str) -> list[tuple[str, str]]:
    """(where, text) of every description and help of the parser and its subcommands."""
    out = [(f"{path} (description)", parser.description or "")]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            out += [(f"{path} {c.dest}", c.help or "") for c in action._choices_actions]
            for name, sub in action.choices.items():
                out += _helps(sub, f"{path} {name}")
        elif action.help != argparse.SUPPRESS:
            text = action.help() if callable(action.help) else action.help  # a lazy one
            out.append((f"{path} {'/'.join(action.option_strings) or action.dest}", text))
    return out


def test_every_help_text_is_a_whole_sentence():
    bad = [
        (where, text)
        for where, text in _helps(build_parser(), "sim-tactile")
        if not (text[:1].isupper() and text.rstrip().endswith((".", ".)")))
    ]
    assert bad == []


def test_version_is_the_package_version(cli):
    assert cli(["--version"]).stdout.strip() == f"sim-tactile {sim_tactile.__version__}"


def test_building_the_command_line_imports_no_heavy_library():
    """Start-up: the parser of every command is built without scikit-learn, MuJoCo, numba or
    torch (--version took 1.9 s importing scikit-learn for a help text)."""
    import subprocess
    import sys

    code = (
        "import sys; from sim_tactile.cli import build_parser; build_parser(); "
        "print(sorted(m for m in ('sklearn', 'mujoco', 'numba', 'torch', 'scipy') "
        "if m in sys.modules))"
    )
    out = subprocess.check_output([sys.executable, "-c", code], text=True).strip()
    assert out == "[]"


def test_the_command_line_leaves_mujocos_opengl_unloaded_unless_asked():
    """Start-up: MuJoCo's OpenGL back-end (glfw, cffi; some 50 ms of every simulating
    command) is not loaded by the command line, which never renders; an environment that
    names a back-end keeps it."""
    import os
    import subprocess
    import sys

    code = (
        "import os, sys; import sim_tactile.cli; import mujoco; "
        "print(os.environ['MUJOCO_GL'], 'glfw' in sys.modules)"
    )
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    out = subprocess.check_output([sys.executable, "-c", code], text=True, env=env).split()
    assert out == ["disable", "False"]
    env["MUJOCO_GL"] = "egl"
    out = subprocess.check_output([sys.executable, "-c", code], text=True, env=env).split()
    assert out[0] == "egl"


def test_the_command_line_starts_openblas_on_one_thread_unless_the_environment_says():
    """Start-up: the command line's BLAS runs on one thread (its parallelism is its worker
    processes; OpenBLAS's idle threads spin on the CPU); a thread count that the environment
    names, through any of the variables OpenBLAS reads, is kept."""
    import os
    import subprocess
    import sys

    code = (
        "import sim_tactile.cli, numpy; from threadpoolctl import threadpool_info; "
        "print(sorted({i['num_threads'] for i in threadpool_info() "
        "if i['internal_api'] == 'openblas'}))"
    )
    names = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")
    env = {k: v for k, v in os.environ.items() if k not in names}
    out = subprocess.check_output([sys.executable, "-c", code], text=True, env=env).strip()
    assert out == "[1]"
    for name in names:
        out = subprocess.check_output(
            [sys.executable, "-c", code], text=True, env={**env, name: "2"}
        ).strip()
        assert out == "[2]", name


@pytest.mark.slow
def test_tasks_lists_every_registered_task_one_line_each(cli):
    lines = cli(["tasks"]).stdout.strip().split("\n\n")[0].splitlines()
    assert lines[0].split() == ["id", "paper", "sensor", "classes", "slides", "needs", "quick"]
    assert [line.split()[0] for line in lines[1:]] == list(task_ids())
    row = {line.split()[0]: line for line in lines[1:]}
    assert "torch, --data" in row["biotac20-real-v1"] and "~" in row["biotac20-real-v1"]
    assert " - " in row["finger7-v1"] and "torch" not in row["finger7-v1"]


@pytest.mark.slow
def test_tasks_says_what_each_needs_and_how_long_its_quick_form_takes(cli):
    """Which tasks need torch (a network among their rows) or --data, and each quick
    form's measured wall time (a suite: its parts'), from `sim-tactile tasks --json`."""
    from sim_tactile.cli.tasks import QUICK_WALL_S, about

    rows = {r["id"]: r for r in json.loads(cli(["tasks", "--json"]).stdout)}
    assert rows["biotac20-real-v1"]["needs"] == ["torch", "--data"]
    assert rows["textures20-v1"]["needs"] == ["torch"] and rows["finger7-v1"]["needs"] == []
    measured = {t for t, s in QUICK_WALL_S.items() if s is not None}
    assert measured >= {t for t in task_ids() if not get_task(t).parts} - {"icub20-real-v1"}
    parts = get_task("textures20-v1").parts
    assert rows["textures20-v1"]["quick_s"] == sum(QUICK_WALL_S[p] for p in parts)
    assert (about(38.3), about(150.0), about(None)) == ("~40 s", "~2 min", "?")


@pytest.mark.slow
def test_tasks_json_gives_id_paper_sensor_classes_and_slides(cli):
    rows = json.loads(cli(["tasks", "--json"]).stdout)
    by_id = {r["id"]: r for r in rows}
    assert list(by_id) == list(task_ids())
    f7 = by_id["finger7-v1"]
    assert (f7["sensor"], f7["classes"], f7["slides"], f7["quick_slides"]) == (
        "grid3x3",
        7,
        7 * 32,
        7 * 8,
    )
    assert f7["paper"].startswith("Texture discrimination using a flexible tactile sensor")
    assert by_id["biotac20-real-v1"]["sensor"] == "biotac19"
    assert by_id["icub20-real-v1"]["slides"] == 20 * 50
    suite = by_id["textures20-v1"]
    assert suite["sensor"] == "biotac19+icub60" and suite["slides"] == 2 * 20 * 50
    for r in rows:
        assert {"id", "paper", "sensor", "classes", "slides"} <= set(r)
        assert r["paper"] and r["sensor"] and "?" not in r["sensor"], r


def test_paper_of_takes_the_title_without_the_authors():
    ref = "A. B. Smith, C. Jones: A study of touch, IROS 2020 (seed paper 000)"
    assert paper_of(ref) == ("A study of touch, IROS 2020", "000")
    assert paper_of("Touch: a soft approach (seed paper 001): details") == ("Touch", "001")


def test_every_ablate_parameter_is_explained():
    assert set(PARAM_HELP) == set(PARAMS)
    assert task_summary("finger7-v1")["id"] == get_task("finger7-v1").id


def test_first_run_counts_the_kernels_not_compiled_here(tmp_path):
    """With an empty numba cache every cached kernel is still to compile, and the run says
    so; the count is what the notice rests on."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    code = (
        "from sim_tactile.cli._common import kernels_to_compile as k;"
        "print(k(('sim_tactile.sim.skin.contact.kernels',)))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert int(out.stdout.strip()) > 0
    assert "compiling" in COMPILE_NOTICE and "minutes" in COMPILE_NOTICE


def test_the_compile_notice_comes_with_a_compile_and_once():
    """The notice listens to numba's compiles: a kernel of this package that compiles says it
    once; one that is already compiled, or another package's, says nothing."""
    import numba

    from sim_tactile.cli._common import compile_notice

    def probe(x):
        return x + 1

    probe.__module__ = "sim_tactile._notice_probe"  # as if the package's own
    kernel = numba.njit(cache=False)(probe)
    said: list[str] = []
    with compile_notice(said.append):
        kernel(1)
        kernel(2.5)  # another signature: another compile, no second notice
    assert said == [COMPILE_NOTICE]
    with compile_notice(said.append):
        kernel(3)  # compiled already: nothing compiles
        numba.njit(cache=False)(lambda x: x * 2)(4)  # not the package's
    assert said == [COMPILE_NOTICE]


@pytest.mark.slow
def test_a_typo_says_no_compile_notice(tmp_path):
    """With no compiled kernel at all (an empty kernel cache), a mistyped task fails with
    its one line, and no notice: nothing compiled (the notice was printed first, always)."""
    env = dict(
        os.environ,
        SIM_TACTILE_KERNELS=str(tmp_path / "kernels"),
        NUMBA_CACHE_DIR=str(tmp_path / "numba"),
    )
    code = "import sys; from sim_tactile.cli import main; sys.exit(main())"
    out = subprocess.run(
        [sys.executable, "-c", code, "run", "finger7-v9", "--quick", "--out", str(tmp_path / "o")],
        env=env,
        capture_output=True,
        text=True,
    )
    assert out.returncode == 2 and "finger7-v9" in out.stderr
    assert "compiling" not in out.stderr, out.stderr
