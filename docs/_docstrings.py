"""Read the package's docstrings as they are written for ``help()``, and give Sphinx reST.

The docstrings are plain text with Sphinx roles. Three habits of that text are not reST,
and are translated here rather than rewritten in the code:

- Markdown pipe tables (a header row, a ``|---|`` rule, rows) become list tables;
- a ``|x|`` (an absolute value, a norm) is text, not a substitution;
- a line that ends in ``:`` and is followed by an indented block (``Args:``, ``Returns:``,
  a list of cases) gets the blank line reST needs before the block;
- ``name: text`` lines with hanging indents (the parameters and attributes, one a line)
  become a bullet list, each item on one line.
"""

from __future__ import annotations

import re

_RULE = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")
_LITERAL = re.compile(r"(``.*?``|`[^`]*`)")


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def _table(rows: list[str], indent: str) -> list[str]:
    head, body = _cells(rows[0]), [_cells(r) for r in rows[2:]]
    out = [f"{indent}.. list-table::", f"{indent}   :header-rows: 1", ""]
    for row in [head, *body]:
        row = row + [""] * (len(head) - len(row))
        out.append(f"{indent}   * - {row[0]}")
        out += [f"{indent}     - {cell}" for cell in row[1 : len(head)]]
    return [*out, ""]


def _escape_bars(line: str) -> str:
    parts = _LITERAL.split(line)
    return "".join(p if _LITERAL.fullmatch(p) else p.replace("|", "\\|") for p in parts)


_FIELD = re.compile(r"^(\s*)([A-Za-z_*`][\w ,/*()`\[\]=-]{0,40}?): (\S.*)$")


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _unwrap(lines: list[str]) -> list[str]:
    """Hanging continuation lines joined to the line they continue (literal blocks kept)."""
    out: list[str] = []
    literal_at = None  # the indent of the paragraph that opened a literal block
    for line in lines:
        if literal_at is not None:
            if line.strip() and _indent(line) <= literal_at:
                literal_at = None
            else:
                out.append(line)
                continue
        prev = out[-1] if out else ""
        if (
            line.strip()
            and prev.strip()
            and _indent(line) > _indent(prev)
            and not prev.rstrip().endswith(":")
            and not line.lstrip().startswith(("- ", "* ", ">>>", "|"))
            and not prev.lstrip().startswith(("|", ".. "))
        ):
            out[-1] = prev.rstrip() + " " + line.strip()
            continue
        out.append(line)
        if line.rstrip().endswith("::"):
            literal_at = _indent(line)
    return out


def _fields(lines: list[str]) -> list[str]:
    """Runs of two or more ``name: text`` lines that open a block, as bullet items."""
    out: list[str] = []
    i = 0
    while i < len(lines):
        j = i
        while (
            j < len(lines)
            and _FIELD.match(lines[j])
            and "::" not in lines[j]
            and lines[j].count("``") % 2 == 0
        ):
            j += 1
        opens = i == 0 or not lines[i - 1].strip() or lines[i - 1].rstrip().endswith(":")
        if j - i >= 2 and opens:
            if out and out[-1].strip():
                out.append("")
            for line in lines[i:j]:
                m = _FIELD.match(line)
                out.append(f"{m[1]}- {m[2]}: {m[3]}")
            if j < len(lines) and lines[j].strip():
                out.append("")
            i = j
            continue
        out.append(lines[i])
        i += 1
    return out


def to_rest(lines: list[str]) -> list[str]:
    """The docstring's lines as reST (see the module)."""
    lines = _fields(_unwrap(lines))
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if line.lstrip().startswith("|") and _RULE.match(nxt):
            j = i + 2
            while j < len(lines) and lines[j].lstrip().startswith("|"):
                j += 1
            indent = line[: len(line) - len(line.lstrip())]
            if out and out[-1].strip():
                out.append("")
            out += _table(lines[i:j], indent)
            i = j
            continue
        last = next((x for x in reversed(out) if x.strip()), "")
        if line.strip() and out and out[-1].strip() and _indent(line) < _indent(last):
            out.append("")  # a block ends: reST wants a blank line before what follows
        out.append(_escape_bars(line))
        depth = len(line) - len(line.lstrip())
        if (
            line.rstrip().endswith(":")
            and not line.rstrip().endswith("::")
            and nxt.strip()
            and len(nxt) - len(nxt.lstrip()) > depth
        ):
            out.append("")
        i += 1
    return out


def process(app, what, name, obj, options, lines) -> None:
    lines[:] = to_rest(list(lines))
