"""Sphinx configuration of the sim_tactile manual (``make docs``)."""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import _docstrings  # noqa: E402
import _gen  # noqa: E402

import sim_tactile  # noqa: E402  (this source tree's, which the manual documents)

_gen.mount_assets(HERE.parent)  # its presets too, installed or not (pip install ".[docs]")

project = "sim_tactile"
author = "the sim_tactile authors"
copyright = "the sim_tactile authors, Apache-2.0"  # noqa: A001
release = version = sim_tactile.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinxarg.ext",
    "_resolve",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**/README.md"]
myst_enable_extensions = ["colon_fence", "deflist", "dollarmath"]
myst_heading_anchors = 3

html_theme = "furo"
html_title = f"sim_tactile {release}"
html_static_path: list[str] = []

#: The extras' libraries that a module of the package imports when it is imported (the
#: torch Dataset's module imports torch; the others import theirs when called); where one is
#: not installed (`make docs` installs the [docs] extra only), autodoc and the generated
#: pages import a stand-in. (A stand-in of a library that others probe for, pyarrow for
#: pandas, would break them: only what the package needs is stood in for.)
OPTIONAL = ("torch",)


def _missing(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is None
    except (ImportError, ValueError):
        return True


autodoc_mock_imports = [m for m in OPTIONAL if _missing(m)]
autodoc_member_order = "bysource"
# the public names are documented under their entry point, which each page names once: the
# module a class is defined in is no part of its name for the reader
add_module_names = False
# a method without a docstring of its own shows none (not scikit-learn's, for example)
autodoc_inherit_docstrings = False
autodoc_typehints = "description"
autodoc_default_options = {"show-inheritance": True, "undoc-members": True}

# A broken cross-reference fails the build (make docs runs sphinx-build -W): every role in
# a docstring must name something documented here. Names of other projects are listed
# below, since the build has no network to read their inventories.
nitpicky = True
nitpick_ignore_regex = [
    (
        r"py:.*",
        r"(numpy|np|scipy|sklearn|mujoco|numba|zarr|torch|matplotlib|pathlib|collections"
        r"|typing|argparse|trimesh|cadquery|ray|concurrent|dataclasses|json|enum|tomllib|ast)\..*",
    ),
    (r"py:mod", r"(numpy|scipy|sklearn|mujoco|numba|zarr|torch|matplotlib|tomllib|trimesh|ray)"),
    (
        r"py:class",
        r"(Path|ndarray|np\.ndarray|NDArray|Callable|Sequence|Mapping|Iterator|Iterable"
        r"|Any|Generator|BaseEstimator|TransformerMixin|ClassifierMixin|Figure|Axes|Pipeline)",
    ),
    (r"py:class", r"(optional|array-like|array_like|callable|default.*)"),
]


def _generate(app) -> None:
    from sphinx.ext.autodoc.mock import mock

    with mock(app.config.autodoc_mock_imports):  # as autodoc imports the modules
        _gen.write_api(HERE / "reference" / "api")
        _gen.write_tasks(HERE / "reference" / "tasks")
    _gen.write_leaderboard(HERE.parent / "leaderboard", HERE / "results" / "leaderboard.md")


def _skip(app, what, name, obj, skip, options):
    # scikit-learn's generated metadata-routing methods (set_fit_request, ...): theirs
    if re.fullmatch(r"set_\w+_request", name):
        return True
    return None


def setup(app) -> None:
    app.connect("builder-inited", _generate)
    app.connect("autodoc-skip-member", _skip)
    app.connect("autodoc-process-docstring", _docstrings.process)
