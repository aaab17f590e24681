"""Tables for people: one Markdown and one plain-text renderer for every report.

Cells are strings; a row is a list of cells; the first row of a table is its header.
"""

from __future__ import annotations

from collections.abc import Sequence


def _clean(cell: object) -> str:
    return str(cell).replace("|", "/").replace("\n", " ")


def markdown_table(head: Sequence[object], rows: Sequence[Sequence[object]]) -> list[str]:
    """The lines of a Markdown table (``|`` inside a cell becomes ``/``)."""
    out = ["| " + " | ".join(_clean(c) for c in head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        if len(r) != len(head):
            raise ValueError(f"a row of {len(r)} cells under a header of {len(head)}")
        out.append("| " + " | ".join(_clean(c) for c in r) + " |")
    return out


def text_table(
    head: Sequence[object], rows: Sequence[Sequence[object]], *, right: Sequence[int] = ()
) -> list[str]:
    """The lines of a plain-text table, columns padded to their widest cell (the columns in
    ``right`` aligned right), the last column left unpadded."""
    cells = [[str(c) for c in head]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[k]) for r in cells) for k in range(len(head))]
    lines = []
    for r in cells:
        parts = [
            (c.rjust(w) if k in right else c.ljust(w)) if k < len(r) - 1 else c
            for k, (c, w) in enumerate(zip(r, widths, strict=True))
        ]
        lines.append(" ".join(parts).rstrip())
    return lines
