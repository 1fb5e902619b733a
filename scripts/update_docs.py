"""Rewrite the measured figures of README.md and docs/*.md from the result files they link to.

A measured figure in the docs is a Markdown link into a result file, the fragment a JSON pointer:

    [0.134 mm](results/bennett_variants_default.json#/results/variants/pla/max_coupler_deviation_mm)

The path is relative to the Markdown file. The unit written in the link's text decides the display
scale (m, mm, um, nm; s, ms, us; N m, N mm; Pa, MPa; J, mJ; deg, rad; %, x for ratios; nothing for
plain numbers; Hz). The value in the file is in SI units unless the pointer names its unit as a suffix
of a key (``..._mm``, ``..._Nmm``, ``..._MPa``, ``wall_time_s/build``, ``ms_per_step``): the last key
with a unit decides. The number keeps the form its author wrote: as many decimals, or the same number
of mantissa decimals in scientific notation (``4.5e-10``).

    .venv/bin/python scripts/update_docs.py           # rewrite every figure from its file
    .venv/bin/python scripts/update_docs.py --check   # list every disagreement, exit status 1 if any

Tables that are whole outputs of one measurement are generated between ``<!-- table NAME -->`` and
``<!-- /table -->`` by the function ``table_NAME`` of ``scripts/doc_tables.py``; the check compares those blocks too.

``--check`` also lists the result files older than the code they measure (``python -m bench stale``,
``bench/staleness.py``): recorded from a dirty tree, or a path their benchmark measures changed since their commit.
``tests/test_docs/test_doc_figures.py`` runs the figures' check only: a change to the engine makes every result file
stale until it is recorded again (``python -m bench record``), which takes hours, not a test's minutes.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from doc_tables import TABLES, format_like  # noqa: E402 - scripts/ is not a package: found via the path above

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

#: Unit -> (dimension, factor to SI).
UNITS: dict[str, tuple[str, float]] = {
    "m": ("length", 1.0),
    "mm": ("length", 1e-3),
    "um": ("length", 1e-6),
    "nm": ("length", 1e-9),
    "s": ("time", 1.0),
    "ms": ("time", 1e-3),
    "us": ("time", 1e-6),
    "min": ("time", 60.0),
    "N m": ("torque", 1.0),
    "N mm": ("torque", 1e-3),
    "Pa": ("stress", 1.0),
    "MPa": ("stress", 1e6),
    "J": ("energy", 1.0),
    "mJ": ("energy", 1e-3),
    "rad": ("angle", 1.0),
    "deg": ("angle", math.pi / 180),
    "": ("ratio", 1.0),
    "x": ("ratio", 1.0),
    "%": ("ratio", 1e-2),
    "Hz": ("frequency", 1.0),
    "rad^2/s^2": ("squared frequency", 1.0),
    "MiB": ("memory", 1.0),
    "GiB": ("memory", 1024.0),
}
#: Unit suffix of a key in a result file -> unit.
KEY_SUFFIXES = {
    "_m": "m",
    "_mm": "mm",
    "_um": "um",
    "_nm": "nm",
    "_s": "s",
    "_ms": "ms",
    "_us": "us",
    "_Nm": "N m",
    "_Nmm": "N mm",
    "_pa": "Pa",
    "_Pa": "Pa",
    "_MPa": "MPa",
    "_j": "J",
    "_J": "J",
    "_mJ": "mJ",
    "_rad": "rad",
    "_deg": "deg",
    "_percent": "%",
    "_hz": "Hz",
    "_mb": "MiB",
}
LINK = re.compile(r"\[(?P<text>[^\[\]]+)\]\((?P<path>[^()\s#]*results/[^()\s#]+\.json)#(?P<pointer>/[^()\s]*)\)")
NUMBER = re.compile(r"^(?P<number>[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?)\s?(?P<unit>.*)$")


@dataclass
class Figure:
    """One link of a Markdown file into a result file."""

    doc: Path
    line: int
    text: str
    path: str
    pointer: str
    span: tuple[int, int]

    def where(self) -> str:
        return f"{_shown(self.doc)}:{self.line}"


def _shown(doc: Path) -> str:
    return str(doc.relative_to(ROOT)) if doc.is_relative_to(ROOT) else str(doc)


def resolve(document, pointer: str):
    """The value at a JSON pointer (RFC 6901) in ``document``; KeyError naming the missing key."""
    value = document
    for token in pointer.lstrip("/").split("/") if pointer != "/" else []:
        token = token.replace("~1", "/").replace("~0", "~")
        if isinstance(value, list):
            if not token.isdigit() or int(token) >= len(value):
                raise KeyError(f"no item {token!r} in a list of {len(value)}")
            value = value[int(token)]
        elif isinstance(value, dict):
            if token not in value:
                raise KeyError(f"no key {token!r} (keys: {', '.join(list(value)[:12])})")
            value = value[token]
        else:
            raise KeyError(f"{token!r} below a number")
    return value


def stored_unit(pointer: str) -> str | None:
    """The unit a result file stores the value in, from the last key of ``pointer`` with a unit suffix."""
    for token in reversed(pointer.lstrip("/").split("/")):
        for suffix, unit in sorted(KEY_SUFFIXES.items(), key=lambda kv: -len(kv[0])):
            if token.endswith(suffix) or token.startswith(suffix[1:] + "_per_"):  # ..._ms, ms_per_step
                return unit
    return None


def figures(doc: Path) -> list[Figure]:
    """Every link of ``doc`` into a result file."""
    found = []
    text = doc.read_text()
    for match in LINK.finditer(text):
        line = text.count("\n", 0, match.start()) + 1
        found.append(Figure(doc, line, match["text"], match["path"], match["pointer"], match.span("text")))
    return found


def expected_text(figure: Figure) -> str:
    """The link's text as the result file says it should read; ValueError why it cannot."""
    file = (figure.doc.parent / figure.path).resolve()
    if not file.is_file():
        raise ValueError(f"no result file {figure.path}")
    try:
        value = resolve(json.loads(file.read_text()), figure.pointer)
    except KeyError as error:
        raise ValueError(f"{figure.path}#{figure.pointer}: {error.args[0]}") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{figure.path}#{figure.pointer} is not a number: {str(value)[:60]}")
    written = NUMBER.match(figure.text)
    if written is None:
        raise ValueError(f"link text {figure.text!r} is not a number with a unit")
    unit = written["unit"]
    if unit not in UNITS:
        raise ValueError(f"unknown unit {unit!r} in {figure.text!r} (known: {', '.join(u for u in UNITS if u)})")
    dimension, factor = UNITS[unit]
    source = stored_unit(figure.pointer)
    if source is None:
        si = float(value)
    else:
        if UNITS[source][0] != dimension:
            raise ValueError(f"{figure.text!r} shows {dimension}, but {figure.pointer} is stored in {source}")
        si = float(value) * UNITS[source][1]
    number = format_like(written["number"], si / factor)
    return f"{number} {unit}".strip() if unit not in ("x", "%") else f"{number}{unit}"


def check_or_update(docs=DOCS, update: bool = False) -> list[str]:
    """Disagreements between the docs and their result files ("file:line: message"); with
    ``update`` the figures that can be read are rewritten."""
    problems = []
    for doc in docs:
        text = doc.read_text()
        edits = []
        for figure in figures(doc):
            try:
                want = expected_text(figure)
            except ValueError as error:
                problems.append(f"{figure.where()}: {error}")
                continue
            if want != figure.text:
                source = f"{figure.path}#{figure.pointer}"
                problems.append(f"{figure.where()}: [{figure.text}] should read [{want}] ({source})")
                edits.append((figure.span, want))
        if update and edits:
            for (start, end), want in sorted(edits, reverse=True):
                text = text[:start] + want + text[end:]
            doc.write_text(text)
    return problems


# ------------------------------------------------------------------------------------------------
# Generated tables
# ------------------------------------------------------------------------------------------------
TABLE = re.compile(r"(<!-- table (?P<name>[a-z_]+) -->\n)(?P<body>.*?)(<!-- /table -->)", re.S)


def check_or_update_tables(docs=DOCS, update: bool = False) -> list[str]:
    """Generated tables that differ from what their result files give; with ``update`` rewritten."""
    problems = []
    for doc in docs:
        text = doc.read_text()
        pieces, end = [], 0
        for match in TABLE.finditer(text):
            where = f"{_shown(doc)}:{text.count(chr(10), 0, match.start()) + 1}"
            body = match["body"]
            if match["name"] not in TABLES:
                problems.append(f"{where}: no table {match['name']!r} (known: {', '.join(TABLES)})")
            else:
                try:
                    body = TABLES[match["name"]]() + "\n"
                except (KeyError, TypeError, AttributeError) as error:
                    problems.append(f"{where}: table {match['name']} cannot be made: {error!r}")
                if body != match["body"]:
                    problems.append(f"{where}: table {match['name']} differs from its result files")
            pieces += [text[end : match.start("body")], body]
            end = match.end("body")
        new = "".join(pieces) + text[end:]
        if update and new != text:
            doc.write_text(new)
    return problems


def stale_result_files() -> list[str]:
    """The result files older than the code they measure, each with the reason (``bench/staleness.py``)."""
    sys.path.insert(0, str(ROOT))
    from bench.staleness import stale_results

    return [f"stale: {stale}" for stale in stale_results()]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--check",
        action="store_true",
        help="only list disagreements and stale result files; exit status 1 if any",
    )
    args = parser.parse_args(argv)
    problems = check_or_update_tables(update=not args.check) + check_or_update(update=not args.check)
    if args.check:
        problems += stale_result_files()
    for problem in problems:
        print(problem)
    if args.check:
        return 1 if problems else 0
    unresolved = [p for p in problems if "should read" not in p and "differs from" not in p]
    print(f"{len(problems) - len(unresolved)} figures or tables rewritten, {len(unresolved)} unresolved")
    return 1 if unresolved else 0


if __name__ == "__main__":
    sys.exit(main())
