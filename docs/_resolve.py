"""Resolve a docstring's cross-reference the way Python resolves the name.

The docstrings name objects as their modules see them: ``:class:`Sensor``` in a module that
imports ``Sensor``, ``:func:`sim_tactile.plates.surface_of``` by the package that re-exports
it. The API reference documents each object once, where it is defined. When Sphinx finds no
target under the written name, this looks the name up in Python (in the module of the
docstring, then in its class, then up its packages), takes the object it names, and links to
where that object is documented. A name that Python cannot find, or whose object is not
documented, stays unresolved, and the build's ``-W`` reports it. An object that exists without an entry of
its own (a private helper, an undocumented constant) links to its module's page.
"""

from __future__ import annotations

import importlib
import inspect

from sphinx.util.nodes import make_refnode


def _import_path(dotted: str) -> object | None:
    """The object at a dotted path: the longest importable module prefix, then attributes."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        except Exception:  # a module that fails to import is not a target
            return None
        if obj.__spec__ is None:  # a moved module's deprecated old name: not a target (the
            continue  # package's attribute of that name may be: plates.build, the function)
        for attr in parts[cut:]:
            obj = getattr(obj, attr, None)
            if obj is None:
                return None
        return obj
    return None


def _candidates(target: str, module: str | None, cls: str | None) -> list[str]:
    """Where Python would look for ``target`` written in ``module`` (inside ``cls``)."""
    out = [target]
    if module:
        parts = module.split(".")
        if cls:
            out.append(f"{module}.{cls}.{target}")
        for cut in range(len(parts), 0, -1):
            out.append(".".join(parts[:cut]) + "." + target)
    return out


def _names(obj: object, found_as: str) -> list[str]:
    """The names under which ``obj`` may be documented: where it is defined first."""
    out = []
    if inspect.ismodule(obj):
        out.append(obj.__name__)
    qual = getattr(obj, "__qualname__", None)
    mod = getattr(obj, "__module__", None)
    if isinstance(qual, str) and isinstance(mod, str):
        out.append(f"{mod}.{qual}")
    fget = getattr(obj, "fget", None)  # a property
    if fget is not None:
        out.append(f"{fget.__module__}.{fget.__qualname__}")
    out.append(found_as)
    return out


def resolve(app, env, node, contnode):
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"].lstrip(".~")
    module, cls = node.get("py:module"), node.get("py:class")
    objects = env.get_domain("py").objects
    modules = env.get_domain("py").modules
    for path in _candidates(target, module, cls):
        # a class's attribute read from the class itself (a property, a method)
        head, _, attr = path.rpartition(".")
        owner = _import_path(head) if head else None
        obj = inspect.getattr_static(owner, attr, None) if inspect.isclass(owner) else None
        if obj is None:
            obj = _import_path(path)
        if obj is None:
            continue
        names = _names(obj, path)
        if inspect.isclass(owner):
            names.insert(0, f"{owner.__module__}.{owner.__qualname__}.{attr}")
        if not (inspect.ismodule(obj) or inspect.isclass(obj) or callable(obj)):
            # data: documented in the module that defines it, found by identity
            names += [
                n
                for n in objects
                if n.endswith(f".{attr}")
                and _import_path(n.rpartition(".")[0]) is not None
                and getattr(_import_path(n.rpartition(".")[0]), attr, None) is obj
            ]
        for name in names:
            if name in objects:
                entry = objects[name]
                return make_refnode(
                    app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, name
                )
        # it exists, without an entry of its own (a private helper, an undocumented
        # constant): link to the page of the module that holds it
        home = head
        if inspect.isclass(obj) or inspect.isfunction(obj) or hasattr(obj, "py_func"):
            home = obj.__module__
        while home and home not in modules:  # a private module: its package's page
            home = home.rpartition(".")[0]
        if home:
            entry = modules[home]
            return make_refnode(
                app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, home
            )
        return None
    return None


def setup(app):
    app.connect("missing-reference", resolve)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
