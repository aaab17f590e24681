"""TOML text from JSON-like data, for the files the package writes for users to read and
edit (sensor definitions, plate parameters, calibrations). Reading is :mod:`tomllib`'s.

Floats are written with ``repr``, so a file read back gives the same numbers to the bit.
``None`` has no TOML form: a key whose value is None is left out (the reader's default).
"""

from __future__ import annotations

from .errors import ConfigError


def value(x) -> str:
    """One TOML value: a bool, string, integer, float or list of them (or of tables, inline)."""
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, str):
        return '"' + x.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if x != x or x in (float("inf"), float("-inf")):
            raise ConfigError(f"cannot write the non-finite number {x!r} to a TOML file")
        return repr(x)
    if isinstance(x, list | tuple):
        return "[" + ", ".join(value(y) for y in x) + "]"
    if isinstance(x, dict):
        return (
            "{" + ", ".join(f"{_key(k)} = {value(y)}" for k, y in x.items() if y is not None) + "}"
        )
    raise ConfigError(f"cannot write {x!r} ({type(x).__name__}) to a TOML file")


def _key(k: str) -> str:
    ok = k and all(c.isalnum() or c in "_-" for c in k)
    return k if ok else value(k)


def dumps(data: dict, header: str = "") -> str:
    """``data`` as a TOML document: scalars and lists first, then each table (a dict) under
    its own header, and each list of tables as an array of tables."""
    lines = [f"# {h}" if h else "#" for h in header.splitlines()] if header else []
    _table(data, [], lines)
    return "\n".join(lines).strip("\n") + "\n"


def _is_tables(x) -> bool:
    return isinstance(x, list) and bool(x) and all(isinstance(y, dict) for y in x)


def _table(d: dict, path: list[str], lines: list[str]) -> None:
    for k, x in d.items():
        if x is None or isinstance(x, dict) or _is_tables(x):
            continue
        lines.append(f"{_key(k)} = {value(x)}")
    for k, x in d.items():
        if isinstance(x, dict):
            plain = [y for y in x.values() if not (isinstance(y, dict) or _is_tables(y))]
            if plain or not x:  # a table of tables only needs no header of its own
                lines.append("")
                lines.append("[" + ".".join(_key(p) for p in [*path, k]) + "]")
            _table(x, [*path, k], lines)
        elif _is_tables(x):
            for y in x:
                lines.append("")
                lines.append("[[" + ".".join(_key(p) for p in [*path, k]) + "]]")
                _table(y, [*path, k], lines)
