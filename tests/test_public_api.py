"""What users may touch: every public package declares ``__all__``, each of its names resolves
and says what it is, and the API reference lists exactly these names, on one page per entry
point (``docs/_gen.py``). A package is public, internal (said why) or private by name."""

from __future__ import annotations

import ast
import importlib
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

import sim_tactile

ROOT = Path(sim_tactile.__file__).parent
DOCS = ROOT.parent / "docs"
sys.path.insert(0, str(DOCS))

import _gen  # noqa: E402

#: A row of a reference page's table of public names: ``* - :py:role:`name <target>```.
_ROW = re.compile(r"^   \* - :py:(\w+):`(\w+) <([\w.]+)>`")
#: A public name documented on a page.
_DOCUMENTED = re.compile(r"^\.\. (?:autofunction|autoclass|autoexception):: ([\w.]+)$", re.M)


def _declares_all(path: Path) -> bool:
    """Whether the module at ``path`` assigns ``__all__`` at its top level."""
    for node in ast.parse(path.read_text()).body:
        targets = node.targets if isinstance(node, ast.Assign) else [getattr(node, "target", 0)]
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            return True
    return False


def _unclassified(root: Path, public: set[str], internal: set[str]) -> list[str]:
    """What is wrong with the packages under ``root`` (named from its folder's name): a
    package neither public, internal nor private by name; a public one without ``__all__``;
    a listed one that does not exist."""
    base = root.name
    found = {}
    for init in sorted(root.rglob("__init__.py")):
        name = ".".join((base, *init.relative_to(root).parent.parts))
        found[name] = init
    modules = {
        ".".join((base, *p.relative_to(root).with_suffix("").parts)): p for p in root.rglob("*.py")
    }
    wrong = []
    for name in found:
        if any(part.startswith("_") for part in name.split(".")):
            continue
        if name not in public and name not in internal:
            wrong.append(f"{name}: neither public nor internal")
    for name in sorted(public):
        path = found.get(name) or modules.get(name)
        if path is None:
            wrong.append(f"{name}: listed, but no such package or module")
        elif not _declares_all(path):
            wrong.append(f"{name}: public, without __all__")
    wrong += [f"{n}: listed internal, but no such package" for n in sorted(internal - set(found))]
    return wrong


def test_every_package_is_public_internal_or_private():
    public = set(_gen.public_packages())
    assert len(public) == len(_gen.public_packages())  # each listed once
    assert _unclassified(ROOT, public, set(_gen.INTERNAL_PACKAGES)) == []
    assert all(why.strip() for why in _gen.INTERNAL_PACKAGES.values())


def test_the_package_check_fails_each_way(tmp_path):
    pkg = tmp_path / "pkg"
    for folder in ("", "a", "b", "_c", "a/d"):
        (pkg / folder).mkdir(exist_ok=True)
        (pkg / folder / "__init__.py").write_text('"""x"""\n')
    (pkg / "a" / "__init__.py").write_text('__all__ = ["x"]\nx = 1\n')
    (pkg / "m.py").write_text("y = 2\n")
    wrong = _unclassified(pkg, {"pkg.a", "pkg.b", "pkg.m", "pkg.gone"}, {"pkg", "pkg.nope"})
    assert sorted(w.split(":")[0] for w in wrong) == [
        "pkg.a.d",  # unclassified (pkg._c is private by name)
        "pkg.b",  # public, no __all__
        "pkg.gone",  # no such
        "pkg.m",  # public module, no __all__
        "pkg.nope",  # no such internal package
    ]


def _has_own_doc(obj: object) -> bool:
    doc = obj.__doc__ if inspect.isclass(obj) else inspect.getdoc(obj)
    return bool(doc and doc.strip())


def test_each_public_name_resolves_and_says_what_it_is():
    missing = []
    for package in _gen.public_packages():
        mod = importlib.import_module(package)
        assert mod.__doc__ and mod.__doc__.strip(), package
        assert len(set(mod.__all__)) == len(mod.__all__), package
        for name in mod.__all__:
            obj = getattr(mod, name)  # AttributeError names what does not resolve
            role, _ = _gen.canonical(package, name)
            if role == "data":
                documented = bool(_gen.data_doc(package, name)[1])  # its #: comment
            else:
                documented = _has_own_doc(obj)
            if not documented:
                missing.append(f"{package}.{name}")
    assert missing == []


def _rows(text: str) -> dict[str, tuple[str, str]]:
    return {m[2]: (m[1], m[3]) for line in text.splitlines() if (m := _ROW.match(line))}


@pytest.mark.slow
def test_the_reference_lists_exactly_the_public_names():
    """Each entry point's page tables its ``__all__``, no more, no less, each linked where
    it is documented; each public class and function is documented on one page only."""
    pages = {p: _gen.entry_page(p) for p in _gen.ENTRY_POINTS}
    extending = _gen.extending_page()
    sections = re.split(r"^``(sim_tactile[\w.]*)``\n-+\n", extending, flags=re.M)
    pages |= dict(zip(sections[1::2], sections[2::2], strict=True))
    assert set(pages) == set(_gen.public_packages())
    documented: list[str] = []
    for package, text in pages.items():
        rows = _rows(text)
        assert sorted(rows) == sorted(importlib.import_module(package).__all__), package
        for name, (role, target) in rows.items():
            assert (role, target) == _gen.canonical(package, name), (package, name)
        documented += _DOCUMENTED.findall(text)
    homes = _gen.homes()
    assert sorted(documented) == sorted(homes)  # every class and function once
    for package in _gen.ENTRY_POINTS:
        assert f"   {package}\n" in _gen_index()


def _gen_index() -> str:
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        _gen.write_api(Path(d))
        return (Path(d) / "index.rst").read_text()


def test_the_seams_are_on_the_extending_page():
    page = _gen.extending_page()
    for name, (package, _) in _gen.SEAMS.items():
        assert name in importlib.import_module(package).__all__, name
        assert f":py:func:`{name} <{_gen.canonical(package, name)[1]}>`" in page, name


def test_a_name_is_at_home_where_it_is_defined():
    """``ConfigError`` (exported by ``sim_tactile`` too) is documented under
    ``sim_tactile.errors``; ``Protocol`` (exported by ``sim`` and its floor ``sim.plan``) on
    the users' page of ``sim``."""
    homes = _gen.homes()
    assert homes["sim_tactile.errors.ConfigError"] == "sim_tactile.errors"
    assert homes["sim_tactile.sim.plan.protocol.Protocol"] == "sim_tactile.sim"
    assert homes["sim_tactile.sim.skin.models.make_skin"] == "sim_tactile.sim.skin"


def test_the_lazy_packages_load_nothing_heavy_until_a_name_is_read():
    """Importing an entry point whose names load their module on first use loads neither
    torch nor MuJoCo; reading a name gives the object its module defines."""
    code = (
        "import sys, sim_tactile.learn, sim_tactile.formats, sim_tactile.scene, "
        "sim_tactile.bench, sim_tactile.sim.step, sim_tactile.sim.collide, sim_tactile.sim.skin; "
        "print('torch' in sys.modules, 'mujoco' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
    import sim_tactile.scene as scene
    from sim_tactile.scene.nodes import skin_grid

    assert scene.skin_grid is skin_grid and "skin_grid" in dir(scene)
