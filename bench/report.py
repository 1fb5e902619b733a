"""The one way a benchmark hands its measurements to the runner (``python -m bench record``): written as JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def write_report(report: Any, path: Path, echo: bool = True) -> None:
    """Write ``report`` to ``path`` (folders made as needed), and print it first when ``echo``.

    numpy scalars that are not Python numbers (float32, integers) are written as floats.
    """
    text = json.dumps(report, indent=1, default=float)
    if echo:
        print(text)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
