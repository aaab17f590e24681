"""Pages of the manual generated from the code at build time (``docs/conf.py`` calls them):
the API reference (one page per module, and one per public package listing its ``__all__``),
one page per benchmark task, from the task registry, and the leaderboard's page, from the
result files in ``leaderboard/`` at the repository's root.

Nothing here is written by hand, so the reference follows the code: a name added to a
package's ``__all__``, a new module or a new task appears on the next build.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import sys
from pathlib import Path

ROOT = "sim_tactile"
#: modules left out of the API reference: the command line (its own page, from the parser)
#: and the numba kernels' private modules
SKIP = ("sim_tactile.cli",)


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
    """The packages and modules that declare a public surface (``__all__``)."""
    out = []
    for name in modules():
        mod = importlib.import_module(name)
        if hasattr(mod, "__path__") and hasattr(mod, "__all__"):
            out.append(name)
    return out


def canonical(package: str, name: str) -> tuple[str, str]:
    """The role and the fully qualified name under which ``package.name`` is documented:
    where it is defined (a class, a function, a module), or the package itself (data)."""
    obj = getattr(importlib.import_module(package), name)
    if inspect.ismodule(obj):
        return "mod", obj.__name__
    if inspect.isclass(obj):
        role = "exc" if issubclass(obj, BaseException) else "class"
        return role, f"{obj.__module__}.{obj.__qualname__}"
    if inspect.isfunction(obj) or inspect.isbuiltin(obj) or hasattr(obj, "py_func"):
        mod = getattr(obj, "__module__", None) or package
        qual = getattr(obj, "__qualname__", name)
        return "func", f"{mod}.{qual}"
    return "data", f"{package}.{name}"


def _summary(obj: object) -> str:
    """The first paragraph of a docstring, its roles as literals (the table has no module
    context to resolve them in; the linked page has)."""
    doc = inspect.getdoc(obj) or ""
    first = doc.split("\n\n")[0].replace("\n", " ").strip()
    first = re.sub(r":[a-z]+:`~?\.?([^`<]*?)(?: <[^>]*>)?`", lambda m: f"``{m[1]}``", first)
    parts = first.split("``")  # escape reST's markup outside the literals
    for k in range(0, len(parts), 2):
        parts[k] = parts[k].replace("*", "\\*").replace("|", "\\|").replace("_ ", "\\_ ")
    return "``".join(parts)


def _title(text: str, char: str = "=") -> list[str]:
    return [text, char * len(text), ""]


def module_page(name: str) -> str:
    """The reST page of one module: its docstring and its own members."""
    mod = importlib.import_module(name)
    lines = _title(f"``{name}``")
    if hasattr(mod, "__path__") and hasattr(mod, "__all__"):
        # a package's public names are documented where they are defined; its table links them
        # (and what the package itself defines)
        lines += [f".. automodule:: {name}", "   :members:", "   :ignore-module-all:", ""]
        lines += package_table(name)
    else:
        # the module's own members only: a name it imports is documented at its home
        lines += [f".. automodule:: {name}", "   :members:", "   :ignore-module-all:", ""]
    return "\n".join(lines) + "\n"


def package_table(package: str) -> list[str]:
    """A table of a package's public names (``__all__``), each linked to its documentation;
    the package's own data are documented here."""
    mod = importlib.import_module(package)
    rows, data = [], []
    for name in sorted(mod.__all__, key=str.lower):
        role, target = canonical(package, name)
        if role == "data":
            data.append(name)
        obj = getattr(mod, name)
        rows.append((f":py:{role}:`{name} <{target}>`", _summary(obj) if role != "data" else ""))
    out = ["The public names", "----------------", ""]
    out += [".. list-table::", "   :header-rows: 1", "   :widths: 30 70", ""]
    out += ["   * - name", "     - what it is"]
    for ref, text in rows:
        out += [f"   * - {ref}", f"     - {text}"]
    out.append("")
    for name in data:
        home, doc = data_doc(package, name)
        # the name relative to the package that automodule made current (a dotted name
        # would be taken as relative to it too, and registered twice over)
        out += [f".. py:data:: {name}", f"   :module: {package}", ""]
        out += [f"   {line}" if line else "" for line in doc]
        out += ["", f"   Defined in :py:mod:`{home}`.", ""]
    return out


def data_doc(package: str, name: str) -> tuple[str, list[str]]:
    """Where the package's data ``name`` is defined, and its ``#:`` comment there."""
    from sphinx.pycode import ModuleAnalyzer

    obj = getattr(importlib.import_module(package), name)
    homes = [
        m
        for m, mod in sorted(sys.modules.items())
        if m.startswith(package) and getattr(mod, name, None) is obj
    ]
    for home in sorted(homes, key=lambda m: -m.count(".")):  # the deepest: where it is made
        try:
            docs = ModuleAnalyzer.for_module(home).find_attr_docs()
        except Exception:  # no source to read
            continue
        if ("", name) in docs:
            return home, [line for line in docs[("", name)] if line is not None]
    return (sorted(homes, key=lambda m: -m.count("."))[0] if homes else package), []


def write_api(out_dir: Path) -> list[str]:
    """Write ``out_dir/<module>.rst`` for every module and an index; returns the modules."""
    out_dir.mkdir(parents=True, exist_ok=True)
    names = modules()
    for old in out_dir.glob("*.rst"):  # a module moved or gone leaves no stale page
        if old.stem not in names and old.stem != "index":
            old.unlink()
    for name in names:
        _write(out_dir / f"{name}.rst", module_page(name))
    public = public_packages()
    index = _title("API reference")
    index += [
        "Generated from the docstrings. The packages below declare their public names in",
        "``__all__``; the modules under them document everything else the package holds.",
        "",
        "Public packages",
        "---------------",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
        *(f"   {n}" for n in public),
        "",
        "Every module",
        "------------",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
        *(f"   {n}" for n in names if n not in public),
        "",
    ]
    _write(out_dir / "index.rst", "\n".join(index))
    return names


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

    from sim_tactile.cli.tasks import task_summary
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
    from sim_tactile.cli.tasks import task_summary
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
    ]
    index += ["| task | paper | sensor | classes | slides | status |", "|---|---|---|---|---|---|"]
    index += [
        f"| [`{r['id']}`]({r['id']}.md) | {r['paper']} | `{r['sensor']}` | {r['classes']} "
        f"| {r['slides']} | "
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
