"""Markdown for the reports: a table from a header and rows (no package imports)."""

from __future__ import annotations


def md_table(header, rows) -> str:
    """A Markdown table; a '|' inside a cell (|x|) is escaped."""
    def cell(c) -> str:
        return str(c).replace("|", "\\|")
    lines = ["| " + " | ".join(cell(h) for h in header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)
