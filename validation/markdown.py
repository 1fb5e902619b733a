"""The Markdown pieces of the validation reports: a length in the unit that reads best, numbers in
scientific notation, tables, and the table of checks against targets."""

from __future__ import annotations

__all__ = ["format_length", "format_sci", "markdown_table", "checks_table"]


def format_length(x: float) -> str:
    """A length in the unit that reads best: nm, um or mm."""
    if abs(x) < 1e-6:
        return f"{1e9 * x:.3g} nm"
    return f"{1e6 * x:.3g} um" if abs(x) < 1e-3 else f"{1e3 * x:.4g} mm"


def format_sci(x: float) -> str:
    """``x`` with three significant digits in scientific notation."""
    return f"{x:.2e}"


def markdown_table(header: list[str], rows: list[list]) -> str:
    """A Markdown table: one line per row, cells as ``str``."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def checks_table(checks: list[dict]) -> str:
    """The checks (``name``, ``value``, ``target``, ``passed``) with the missed ones in bold."""
    return markdown_table(
        ["check", "measured", "target", ""],
        [
            [c["name"], format_sci(c["value"]), f"{c['target']:g}", "met" if c["passed"] else "**missed**"]
            for c in checks
        ],
    )
