"""The package's shape: no import cycle between any two modules (imports inside functions
count), modules and functions of a readable size. The layers themselves are import-linter's
contracts in pyproject.toml, checked by ``lint-imports`` in ``make test``."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import sim_tactile

grimp = pytest.importorskip("grimp", reason="grimp comes with the test extra import-linter")

ROOT = Path(sim_tactile.__file__).parent
#: Longest module [lines]: past this a module is two modules.
MAX_MODULE_LINES = 500
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


def test_modules_are_small():
    long = {
        str(p.relative_to(ROOT)): n
        for p in _sources()
        if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES
    }
    assert long == {}


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
