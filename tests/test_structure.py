"""The package's shape: no import cycle between any two modules (imports inside functions
count), functions of a readable size, and every module past the size cap listed with the
concept that makes it long. The layers themselves are import-linter's
contracts in pyproject.toml, checked by ``lint-imports`` in ``make test``."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import sim_tactile

grimp = pytest.importorskip("grimp", reason="grimp comes with the test extra import-linter")

ROOT = Path(sim_tactile.__file__).parent
#: A module past this many lines [lines] must say why it is one module (:data:`LONG_MODULES`):
#: a cap is a smoke alarm, not a rule to split by. A module is as long as its one concept
#: needs; when it reaches the cap, split it along a concept and name that concept, or list it.
MAX_MODULE_LINES = 500
#: The modules over :data:`MAX_MODULE_LINES`, each with the one concept that makes it long. A
#: module over the cap that is not here fails, and so does one here that is back under it.
LONG_MODULES: dict[str, str] = {
    "generate.py": "one resumable write of a data set: the target resolved, the store opened or "
    "resumed (its index checked and repaired), the backend drained into it, the run recorded; "
    "every step reads and updates the one run's state (_Run)",
    "sim/skin/contact/spectral.py": "one solver: the spectral contact solve (Polonsky and "
    "Keer's iteration) with its product in double and single precision, its starts, joins and "
    "cycle guard, the block solve of a pad touching a patch, and the numpy reference of its "
    "iteration, which the batched solve and the tests compare against",
    "tasks/runner.py": "one task's run, end to end: the task resolved and its data loaded, each "
    "row evaluated under the protocol, the report, the figures, the result files and the "
    "spiking network's export written from the one run's rows",
}
#: Longest function [lines] (declared data tables are module-level values, not functions).
MAX_FUNCTION_LINES = 100


def _cycles(graph) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), or a module
    that imports itself."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.find_modules_directly_imported_by(v):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.find_modules_directly_imported_by(v):
                out.append(sorted(comp))

    for m in sorted(graph.modules):
        if m not in index:
            visit(m)
    return out


def test_no_import_cycle_between_modules():
    graph = grimp.build_graph("sim_tactile", exclude_type_checking_imports=True, cache_dir=None)
    assert _cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle():
    graph = grimp.ImportGraph()
    for a, b in (("p.a", "p.b"), ("p.b", "p.c"), ("p.c", "p.a"), ("p.c", "p.d")):
        graph.add_import(importer=a, imported=b)
    assert _cycles(graph) == [["p.a", "p.b", "p.c"]]


def _sources():
    return sorted(p for p in ROOT.rglob("*.py") if "__pycache__" not in p.parts)


def _long_modules(root: Path, listed: dict[str, str]) -> dict[str, str]:
    """What is wrong with the list of long modules of ``root``: a module over the cap that
    is not listed, or a listed one that is not over it (each with its line count)."""
    lines = {
        p.relative_to(root).as_posix(): len(p.read_text().splitlines())
        for p in sorted(q for q in root.rglob("*.py") if "__pycache__" not in q.parts)
    }
    wrong = {m: f"{n} lines, not listed" for m, n in lines.items() if n > MAX_MODULE_LINES}
    wrong = {m: w for m, w in wrong.items() if m not in listed}
    for m in listed:
        n = lines.get(m, 0)
        if n <= MAX_MODULE_LINES:
            wrong[m] = f"listed, but {n} lines (no longer long: take it off the list)"
    return wrong


def test_a_long_module_says_why():
    assert all(why.strip() for why in LONG_MODULES.values())
    assert _long_modules(ROOT, LONG_MODULES) == {}


def test_the_long_module_check_fails_both_ways(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n" * (MAX_MODULE_LINES + 1))
    (tmp_path / "b.py").write_text("x = 1\n")
    assert set(_long_modules(tmp_path, {})) == {"a.py"}
    assert _long_modules(tmp_path, {"a.py": "one concept"}) == {}
    assert set(_long_modules(tmp_path, {"a.py": "one", "b.py": "short"})) == {"b.py"}


def test_functions_are_short():
    long = []
    for p in _sources():
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long.append(f"{p.relative_to(ROOT)}::{node.name} ({n} lines)")
    assert long == []


def test_every_package_is_installed():
    """pyproject.toml lists the packages (the top-level assets/ installs as
    sim_tactile.assets): every package of the source tree must be among them, or a wheel
    would leave it out."""
    import tomllib

    listed = set(
        tomllib.loads((ROOT.parent / "pyproject.toml").read_text())["tool"]["setuptools"][
            "packages"
        ]
    )
    found = {
        ".".join(p.relative_to(ROOT.parent).parent.parts)
        for p in ROOT.rglob("__init__.py")
        if "__pycache__" not in p.parts
    }
    assert found - listed == set()
    assert "sim_tactile.assets" in listed and (ROOT.parent / "assets" / "__init__.py").is_file()


def _array_defaults(source: str) -> list[str]:
    """``name: default`` of each compiled kernel (``@njit``) whose argument defaults to
    anything but a literal."""
    out = []
    for n in ast.walk(ast.parse(source)):
        if not isinstance(n, ast.FunctionDef):
            continue
        names = [d.func if isinstance(d, ast.Call) else d for d in n.decorator_list]
        if not any(getattr(d, "id", getattr(d, "attr", None)) == "njit" for d in names):
            continue
        for d in n.args.defaults + [k for k in n.args.kw_defaults if k is not None]:
            if not isinstance(d, ast.Constant):
                out.append(f"{n.name}: {ast.unparse(d)}")
    return out


def test_no_kernel_defaults_an_argument_to_an_array():
    """numba keeps no compiled kernel called with an omitted argument whose default is an
    array: it compiles that kernel, and every kernel that calls it, again in each process
    (the plate-anchored lattice paid 4 s a run so). Kernels take such arguments explicitly."""
    found = {
        str(p.relative_to(ROOT)): bad
        for p in sorted(ROOT.rglob("*.py"))
        if (bad := _array_defaults(p.read_text()))
    }
    assert found == {}


def test_the_kernel_default_check_finds_one():
    src = "NO = None\n@njit\ndef f(a, b=NO, c=0.0):\n    return a\n"
    assert _array_defaults(src) == ["f: NO"]
