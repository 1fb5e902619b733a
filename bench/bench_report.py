"""The one way a benchmark hands its measurements to ``scripts/record.py``: printed, and written as JSON."""

from __future__ import annotations

import json
from pathlib import Path


def write_report(report: dict, path: Path, echo: bool = True) -> None:
    """Write ``report`` to ``path`` (folders made as needed), and print it first when ``echo``."""
    text = json.dumps(report, indent=1)
    if echo:
        print(text)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
