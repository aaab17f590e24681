"""TOML text from JSON-like data, for the files the package writes for users to read and
edit (sensor definitions, plate parameters, calibrations). Reading is :mod:`tomllib`'s.

Floats are written with ``repr``, so a file read back gives the same numbers to the bit.
``None`` has no TOML form: a key whose value is None is left out (the reader's default).
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

from .errors import ConfigError

#: The largest text file (TOML or JSON) read as a user's definition [bytes]: a sensor file of
#: 4096 taxels is about 0.5 MB; a file this size is read and parsed in well under a second.
MAX_TEXT_BYTES = 8 * 2**20


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


def read_file(path, what: str) -> dict:
    """A user's TOML file as data (``what``: how errors name it, e.g. "sensor file"): it must
    end in .toml, exist and parse."""
    import tomllib

    path = Path(path)
    if path.suffix.lower() != ".toml":
        raise ConfigError(f"{what} {str(path)!r}: valid: a file ending in .toml")
    if not path.is_file():
        raise ConfigError(f"{what} {str(path)!r} does not exist")
    check_text_size(path, what)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{what} {str(path)!r} is not valid TOML: {exc}") from None
    except RecursionError:
        raise ConfigError(f"{what} {str(path)!r}: its values nest too deeply to read") from None


def check_text_size(path: Path, what: str) -> None:
    """ConfigError if the file is larger than :data:`MAX_TEXT_BYTES` (before it is read)."""
    size = path.stat().st_size
    if size > MAX_TEXT_BYTES:
        raise ConfigError(
            f"{what} {str(path)!r} is {size / 2**20:.4g} MiB; valid: at most "
            f"{MAX_TEXT_BYTES / 2**20:g} MiB"
        )


def write_file(data: dict, path, what: str, header: str = ""):
    """Write ``data`` as a TOML file at ``path`` (ending in .toml), to a temporary name first
    so that a failed write leaves nothing half written; the path."""
    path = Path(path)
    if path.suffix != ".toml":
        raise ConfigError(f"{what} {str(path)!r}: valid: a name ending in .toml")
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(dumps(data, header), encoding="utf-8")
    tmp.replace(path)
    return path


def asset_path(*parts: str) -> Path:
    """A file or folder of the presets' data (the project's ``assets/``, installed as the
    package ``sim_tactile.assets``)."""
    from importlib.resources import files

    return Path(str(files("sim_tactile.assets").joinpath(*parts)))


@cache
def asset_data(*parts: str) -> dict:
    """A TOML file of :func:`asset_path` as data, read once a process (the package's own
    files); callers build their objects anew from it and do not change it."""
    import tomllib

    return tomllib.loads(asset_path(*parts).read_text(encoding="utf-8"))
