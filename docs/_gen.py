"""Pages of the manual generated from the code at build time (``docs/conf.py`` calls them):
the API reference (one page per module, and one per public package listing its ``__all__``),
one page per benchmark task, from the task registry, and the leaderboard's page, from the
result files in ``leaderboard/`` at the repository's root.

The API reference is curated by the code: one page per public entry point
(:data:`ENTRY_POINTS`), a paragraph on what it is for (its docstring) and then the names of
its ``__all__``, each documented once, on the page of the entry point it is most at home in
(:func:`homes`), and linked from every other page that exports it; one page for those who
extend the simulator (:data:`EXTENDING`, :data:`SEAMS`). A name is public when it is in one
of these ``__all__``; anything else may move without notice. Every other module has a page
for the maintainers, outside the manual's table of contents (``modules.rst``, an orphan
page), so that a docstring's reference to an internal name still has a target.

Nothing here is written by hand, so the reference follows the code: a name added to an
``__all__``, a new module or a new task appears on the next build.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import sys
from functools import cache
from pathlib import Path

ROOT = "sim_tactile"
#: modules left out of the maintainers' module pages: the command line (its own page, from
#: the parser)
SKIP = ("sim_tactile.cli",)
#: The public entry points, in the reference's order: the packages and the few modules users
#: import, each declaring what they may touch in ``__all__``.
ENTRY_POINTS = (
    "sim_tactile",
    "sim_tactile.plates",
    "sim_tactile.sensors",
    "sim_tactile.scene",
    "sim_tactile.sim",
    "sim_tactile.slides",
    "sim_tactile.tasks",
    "sim_tactile.encoders",
    "sim_tactile.spikes",
    "sim_tactile.learn",
    "sim_tactile.datasets",
    "sim_tactile.formats",
    "sim_tactile.calibrate",
    "sim_tactile.bench",
    "sim_tactile.records",
    "sim_tactile.errors",
    "sim_tactile.cache",
    "sim_tactile.generate",
)
#: The floors of ``sim/`` (and the contact solvers under the skin), for those who extend the
#: simulator: each declares ``__all__``; one page, ``extending``, documents them.
EXTENDING = (
    "sim_tactile.sim.plan",
    "sim_tactile.sim.collide",
    "sim_tactile.sim.skin",
    "sim_tactile.sim.skin.contact",
    "sim_tactile.sim.step",
)
#: The seams' entry points: the one function that chooses among each seam's models, and the
#: entry point that exports it.
SEAMS = {
    "make_collider": ("sim_tactile.sim.collide", "each skin node's depth in the plate"),
    "make_skin": ("sim_tactile.sim.skin", "the nodes' pressures from their depths"),
    "make_held_step": ("sim_tactile.sim.step", "one step under the held force"),
    "surface_of": ("sim_tactile.plates", "a plate's surface: one per kind of texture"),
    "make_backend": ("sim_tactile.slides", "where slides run"),
}
#: The packages that are neither an entry point nor private by name, and why: their public
#: names, if any, are in an entry point's ``__all__``.
INTERNAL_PACKAGES = {
    "sim_tactile.cli": "the command line; its reference is the command-line page",
    "sim_tactile.plates.define": "a folder of sim_tactile.plates, whose __all__ it serves",
    "sim_tactile.plates.read": "a folder of sim_tactile.plates, whose __all__ it serves",
    "sim_tactile.plates.parts": "a folder of sim_tactile.plates, whose __all__ it serves",
    "sim_tactile.plates.make": "a folder of sim_tactile.plates, whose __all__ it serves",
    "sim_tactile.tasks.defs": "the tasks' definitions, read through sim_tactile.tasks",
}


def mount_assets(root: Path) -> None:
    """Make ``sim_tactile.assets`` (the presets' files) importable from the source tree at
    ``root``, where it is not already: the build imports the tree's package, which an
    editable install maps ``assets/`` into and a regular install (``pip install
    ".[docs]"``) does not (``No module named 'sim_tactile.assets'``). As
    ``[tool.setuptools.package-dir]`` maps it: the folder ``root/assets`` is the package."""
    import importlib.util

    try:
        if importlib.util.find_spec(f"{ROOT}.assets") is not None:
            return
    except ImportError:
        pass
    init = root / "assets" / "__init__.py"
    spec = importlib.util.spec_from_file_location(
        f"{ROOT}.assets", init, submodule_search_locations=[str(init.parent)]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)


def modules() -> list[str]:
    """Every public module of the package (no name part starting with ``_``), sorted."""
    pkg = importlib.import_module(ROOT)
    names = [ROOT]
    for info in pkgutil.walk_packages(pkg.__path__, prefix=f"{ROOT}."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue
        if info.name.startswith(SKIP):
            continue
        names.append(info.name)
    return sorted(names)


def public_packages() -> list[str]:
    """The entry points and the extending floors: every package or module whose ``__all__``
    names public names."""
    return [*ENTRY_POINTS, *EXTENDING]


def canonical(package: str, name: str) -> tuple[str, str]:
    """The role and the fully qualified name under which ``package.name`` is documented:
    where it is defined (a class, a function, a module), or the package itself (data)."""
    obj = getattr(importlib.import_module(package), name)
    if inspect.ismodule(obj):
        return "mod", obj.__name__
    if inspect.isclass(obj):
        role = "exc" if issubclass(obj, BaseException) else "class"
        return role, f"{obj.__module__}.{obj.__qualname__}"
    if inspect.isroutine(obj) or hasattr(obj, "py_func") or hasattr(obj, "__wrapped__"):
        mod = getattr(obj, "__module__", None) or package
        qual = getattr(obj, "__qualname__", name)
        return "func", f"{mod}.{qual}"
    return "data", f"{package}.{name}"


@cache
def homes() -> dict[str, str]:
    """The page that documents each public class and function, by its documented name: of
    the entry points that export it (the extending floors only if no entry point does), the
    one whose name is the longest prefix of where it is defined, else the first. Data are
    documented on every page that exports them (as ``package.name``); modules on the
    maintainers' pages."""
    found: dict[str, list[str]] = {}
    for package in public_packages():
        for name in importlib.import_module(package).__all__:
            role, target = canonical(package, name)
            if role not in ("data", "mod"):
                found.setdefault(target, []).append(package)
    out = {}
    for target, packages in found.items():
        users = [p for p in packages if p in ENTRY_POINTS] or packages
        prefixes = [p for p in users if target.startswith(p + ".")]
        out[target] = max(prefixes, key=len) if prefixes else users[0]
    return out


def _summary(obj: object) -> str:
    """The first paragraph of a docstring, its roles as literals (the table has no module
    context to resolve them in; the linked page has)."""
    return _summary_text(inspect.getdoc(obj) or "")


def _summary_text(doc: str) -> str:
    """:func:`_summary` of a docstring's text."""
    first = doc.split("\n\n")[0].replace("\n", " ").strip()
    first = re.sub(r":[a-z]+:`~?\.?([^`<]*?)(?: <[^>]*>)?`", lambda m: f"``{m[1]}``", first)
    parts = first.split("``")  # escape reST's markup outside the literals
    for k in range(0, len(parts), 2):
        parts[k] = parts[k].replace("*", "\\*").replace("|", "\\|").replace("_ ", "\\_ ")
    return "``".join(parts)


def _title(text: str, char: str = "=") -> list[str]:
    return [text, char * len(text), ""]


def module_page(name: str) -> str:
    """A maintainers' page of one module: its docstring and its own members, less those
    documented on a public page."""
    lines = _title(f"``{name}``")
    lines += [f".. automodule:: {name}", "   :members:", "   :ignore-module-all:"]
    public = sorted(t.rpartition(".")[2] for t in homes() if t.rpartition(".")[0] == name)
    if public:
        lines.append(f"   :exclude-members: {', '.join(public)}")
    return "\n".join([*lines, ""]) + "\n"


def public_section(package: str, char: str = "-") -> list[str]:
    """An entry point's docstring, the table of its public names (each linked to where it is
    documented), and the documentation of those at home here."""
    mod = importlib.import_module(package)
    lines = [f".. automodule:: {package}", ""]
    lines += [f"Import the names below from ``{package}``.", ""]
    rows, here = [], []
    for name in sorted(mod.__all__, key=str.lower):
        role, target = canonical(package, name)
        obj = getattr(mod, name)
        if role == "data":
            here.append((name, role, target))
            doc = data_doc(package, name)[1]
            rows.append((f":py:data:`{name} <{target}>`", _summary_text(" ".join(doc))))
            continue
        rows.append((f":py:{role}:`{name} <{target}>`", _summary(obj)))
        if homes().get(target) == package and all(t != target for _, _, t in here):
            here.append((name, role, target))  # an alias (datasets.open) documented once
    lines += [".. list-table::", "   :header-rows: 1", "   :widths: 30 70", ""]
    lines += ["   * - name", "     - what it is"]
    for ref, text in rows:
        lines += [f"   * - {ref}", f"     - {text}"]
    lines.append("")
    for name, role, target in here:
        if role == "data":
            home, doc = data_doc(package, name)
            # the name relative to the package that automodule made current (a dotted name
            # would be taken as relative to it too, and registered twice over)
            lines += [f".. py:data:: {name}", f"   :module: {package}", ""]
            lines += [f"   {line}" if line else "" for line in doc]
            lines += ["", f"   Defined in :py:mod:`{home}`.", ""]
        elif role == "func":
            lines += [f".. autofunction:: {target}", ""]
        else:
            directive = "autoexception" if role == "exc" else "autoclass"
            lines += [f".. {directive}:: {target}", "   :members:", ""]
    return lines


def entry_page(package: str) -> str:
    """The reference page of one public entry point."""
    return "\n".join([*_title(f"``{package}``"), *public_section(package)]) + "\n"


def extending_page() -> str:
    """One page for those who extend the simulator: the seams' choosers, then each floor of
    ``sim/`` with its public names."""
    lines = _title("Extending the simulator")
    lines += [
        "The simulation is built in floors, each importing only those below it, and a new",
        "model plugs in at a seam: the one function that chooses among the seam's models",
        "(:doc:`/how-to/extend` says how). The floors keep their names; each declares its",
        "public names in ``__all__``.",
        "",
        ".. list-table::",
        "   :header-rows: 1",
        "   :widths: 30 70",
        "",
        "   * - seam",
        "     - what it chooses",
    ]
    for name, (package, what) in SEAMS.items():
        _, target = canonical(package, name)
        lines += [f"   * - :py:func:`{name} <{target}>` (``{package}``)", f"     - {what}"]
    lines.append("")
    for package in EXTENDING:
        lines += _title(f"``{package}``", "-")
        lines += public_section(package)
    return "\n".join(lines) + "\n"


def data_doc(package: str, name: str) -> tuple[str, list[str]]:
    """Where the package's data ``name`` is defined, and its ``#:`` comment there: the
    deepest module of the package that holds it under that name, else any module of
    :data:`ROOT` that does."""
    from sphinx.pycode import ModuleAnalyzer

    obj = getattr(importlib.import_module(package), name)
    homes_ = [
        m
        for m, mod in sorted(sys.modules.items())
        # (a moved module's deprecated old name, without a spec, is passed over)
        if m.startswith(ROOT) and mod.__spec__ is not None and getattr(mod, name, None) is obj
    ]
    homes_.sort(key=lambda m: (not m.startswith(package), -m.count(".")))
    for home in homes_:
        try:
            docs = ModuleAnalyzer.for_module(home).find_attr_docs()
        except Exception:  # no source to read
            continue
        if ("", name) in docs:
            return home, [line for line in docs[("", name)] if line is not None]
    return (homes_[0] if homes_ else package), []


def write_api(out_dir: Path) -> list[str]:
    """Write the API reference into ``out_dir``: ``index.rst`` and a page per entry point,
    ``extending.rst``, and the maintainers' ``modules.rst`` with a page per other module;
    returns the names of the pages in the reference's table of contents."""
    out_dir.mkdir(parents=True, exist_ok=True)
    inner = [m for m in modules() if m not in public_packages()]
    pages = [*ENTRY_POINTS, "extending", "modules", *inner]
    for old in out_dir.glob("*.rst"):  # a module moved or gone leaves no stale page
        if old.stem not in pages and old.stem != "index":
            old.unlink()
    for name in ENTRY_POINTS:
        _write(out_dir / f"{name}.rst", entry_page(name))
    _write(out_dir / "extending.rst", extending_page())
    for name in inner:
        _write(out_dir / f"{name}.rst", module_page(name))
    maintainers = [":orphan:", "", *_title("Every module")]
    maintainers += [
        "For maintainers: each module that is not a public entry point, with what it defines",
        "(less the public names, documented in the :doc:`API reference <index>`). These paths",
        "are not public: they may move without notice.",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
        *(f"   {n}" for n in inner),
        "",
    ]
    _write(out_dir / "modules.rst", "\n".join(maintainers))
    index = _title("API reference")
    index += [
        "One page per public entry point: what it is for, then its public names, the names",
        "of its ``__all__``. A name is public when it is on one of these pages; anything",
        "else may move without notice. Those who extend the simulator find its floors and",
        "seams on one page. (Maintainers: :doc:`every module <modules>`.)",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
        *(f"   {n}" for n in ENTRY_POINTS),
        "   extending",
        "",
    ]
    _write(out_dir / "index.rst", "\n".join(index))
    return [*ENTRY_POINTS, "extending"]


def _write(path: Path, text: str) -> None:
    """Write only when the text changed (Sphinx then rebuilds only what moved)."""
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def version_history(task_id: str) -> list[str]:
    """The "Version history" section of a task's page: every version of its family, oldest
    first, with what it changed (``TaskSpec.history``) and what superseded it."""
    from sim_tactile.tasks import get_task
    from sim_tactile.tasks.registry import family_versions, successor

    lines = ["", "## Version history", ""]
    for v in family_versions(task_id):
        name = f"`{v}` (this page)" if v == task_id else f"[`{v}`]({v}.md)"
        newer = successor(v)
        state = f"superseded by [`{newer}`]({newer}.md)" if newer else "current"
        lines.append(f"- {name}, {state}:")
        lines += [f"  {h}" for h in get_task(v).history] or ["  (no entry)"]
    return lines


def task_page(task_id: str) -> str:
    """A task's page: its summary, remarks, paper cells, tracks, version history, the ablate
    parameters it uses and its whole pinned definition, from the registry."""
    import json

    from sim_tactile.cli.tasks import about, task_summary
    from sim_tactile.tasks import get_task
    from sim_tactile.tasks.ablate import PARAM_HELP, used_params
    from sim_tactile.tasks.registry import latest, suite

    spec, s = get_task(task_id), task_summary(task_id)
    lines = [f"# `{task_id}`", "", spec.title, ""]
    if latest(task_id) != task_id:
        new = latest(task_id)
        lines += [
            ":::{warning}",
            f"Superseded by [`{new}`]({new}.md): `{task_id}` still runs as released, and "
            "warns once that it is out of date.",
            ":::",
            "",
        ]
    lines += [
        f"- paper: {spec.reference}",
        f"- sensor: `{s['sensor']}`; classes: {s['classes']}; slides: {s['slides']} "
        f"(quick: {s['quick_slides']})",
        f"- classifiers: {', '.join(f'`{c}`' for c in spec.classifiers) or '(its parts)'}; "
        f"split {spec.split}",
        f"- run it: `sim-tactile run {task_id} --out out/{task_id}`"
        + (" --data PATH" if spec.needs_data_path else ""),
        f"- needs: {', '.join(s['needs']) or 'the core install'}; its quick form "
        f"(`--quick`) takes {about(s['quick_s'])} on 2 cores",
    ]
    if spec.parts:
        lines.append(f"- parts: {', '.join(f'`{p}`' for p in spec.parts)}")
    if s["aliases"]:
        lines.append(f"- also known as: {', '.join(f'`{a}`' for a in s['aliases'])}")
    if task_id in suite("core-v1"):
        lines.append("- in the suite `core-v1` (`sim-tactile tasks --suite core-v1`)")
    if not spec.parts:
        lines.append(
            "- tracks: *closed* (this task's data, encoder and protocol; only the classifier "
            "is yours) and *open* (anything else); see [the leaderboard](../../results/"
            "leaderboard.md)"
        )
    if spec.remarks:
        lines += ["", "## Remarks", ""] + [f"- {r}" for r in spec.remarks]
    if spec.paper:
        lines += ["", "## The paper's numbers", ""]
        lines += [
            f"- `{k}`: {c.mean}" + (f" ({c.std})" if c.std is not None else "") + f", {c.source}"
            for k, c in spec.paper.items()
        ]
    lines += version_history(task_id)
    used = [p for p in PARAM_HELP if p in used_params(spec)]
    lines += ["", "## Ablation parameters", ""]
    lines += (
        [f"- `{p}`: {PARAM_HELP[p]}" for p in used] if used else ["None: ablate one of its parts."]
    )
    lines += ["", "## The whole definition", "", "```json"]
    lines += json.dumps(spec.describe(), indent=2, default=str).splitlines() + ["```", ""]
    return "\n".join(lines)


def write_tasks(out_dir: Path) -> list[str]:
    """Write ``out_dir/<task>.md`` for every registered task and an index."""
    from sim_tactile.cli.tasks import about, task_summary
    from sim_tactile.tasks import task_ids
    from sim_tactile.tasks.registry import suite

    out_dir.mkdir(parents=True, exist_ok=True)
    ids = list(task_ids())
    for t in ids:
        _write(out_dir / f"{t}.md", task_page(t))
    rows = [task_summary(t) for t in ids]
    core = ", ".join(f"[`{t}`]({t}.md)" for t in suite("core-v1"))
    index = ["# The tasks", "", "Generated from the task registry (`sim-tactile tasks`).", ""]
    index += [
        f"The suite **core-v1** lists the ids a paper should report: {core} "
        "(`sim-tactile tasks --suite core-v1`). A superseded id still runs as released and "
        "warns once, naming the id that supersedes it.",
        "",
        "| task | paper | sensor | classes | slides | needs | quick | status |",
        "|---|---|---|---|---|---|---|---|",
    ]
    index += [
        f"| [`{r['id']}`]({r['id']}.md) | {r['paper']} | `{r['sensor']}` | {r['classes']} "
        f"| {r['slides']} | {', '.join(r['needs']) or '-'} | {about(r['quick_s'])} | "
        + (f"superseded by `{r['superseded_by']}`" if r["superseded_by"] else "current")
        + " |"
        for r in rows
    ]
    index += ["", "```{toctree}", ":hidden:", "", *ids, "```", ""]
    _write(out_dir / "index.md", "\n".join(index))
    return ids


def write_leaderboard(folder: Path, page: Path) -> None:
    """Write the leaderboard's page from the result files in ``folder`` (each checked: a
    refused entry fails the build)."""
    from sim_tactile.tasks.leaderboard import page as leaderboard_page

    _write(page, leaderboard_page(folder))
