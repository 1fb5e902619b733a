"""What a study's report says of its prints one by one, for the print shop (issue #37): the prints that did not
finish and why, the worst prints with their parameters, the drive angles where the maxima occur, how the main
percentiles settle as variants are added, and outputs in the units a reader uses (mm, MPa, N mm, mJ).

Pure functions of a study's row columns (name -> array, as :func:`ffrf.studies.report.analyse` reads them).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ffrf.studies.statistics import percentile_interval

__all__ = ["DISPLAY_UNITS", "convergence", "display", "unfinished_prints", "worst_prints"]

#: A column's SI suffix -> the unit the report shows it in, and the factor to it.
DISPLAY_UNITS = {"_m": ("mm", 1e3), "_Pa": ("MPa", 1e-6), "_Nm": ("N mm", 1e3), "_J": ("mJ", 1e3)}
#: Convergence is shown at this many numbers of variants, evenly spread up to all.
CONVERGENCE_POINTS = 10
#: The percentiles whose convergence is shown.
CONVERGING = (50, 95)


def display(name: str) -> tuple[str, str, float]:
    """An output column's name without its SI suffix, the unit it is shown in and the factor from SI to it
    (``("max_coupler_deviation", "mm", 1e3)``); a column without a known suffix keeps its name, no unit, 1."""
    for suffix, (unit, factor) in DISPLAY_UNITS.items():
        if name.endswith(suffix):
            return name[: -len(suffix)], unit, factor
    return name, "", 1.0


def _order(columns: dict[str, NDArray]) -> NDArray[np.intp]:
    """The rows in the design's order (sample, then block: A, B, AB0, ...), not the order they were written in."""
    return np.lexsort((columns["block"].astype(str), columns["sample"].astype(int)))


def _finite(value) -> float | None:
    """A row's number, ``None`` where it has none (null or NaN)."""
    number = np.asarray(value, dtype=object).astype(float)
    return float(number) if np.isfinite(number) else None


def _parameters(columns: dict[str, NDArray], names: list[str], row: int) -> dict[str, float]:
    return {n: float(columns[n][row]) for n in names}


def unfinished_prints(columns: dict[str, NDArray], names: list[str]) -> list[dict]:
    """Every print whose row is not ok, in the design's order: its id, whether it assembled, where its path ended
    (drive angle, deg; ``None`` where it did not start), the reason and its parameters."""
    out = []
    last = columns.get("last_drive_angle_deg")
    for row in _order(columns):
        if columns["status"][row] == "ok":
            continue
        angle = None if last is None else _finite(last[row])
        assembled = columns["assembles"][row]
        out.append(
            {
                "id": str(columns["id"][row]),
                "assembles": None if assembled is None else bool(assembled),
                "last_drive_angle_deg": angle,
                "reason": str(columns["reason"][row]),
                "parameters": _parameters(columns, names, row),
            }
        )
    return out


def worst_prints(columns: dict[str, NDArray], names: list[str], output: str, count: int = 5) -> list[dict]:
    """The ``count`` ok prints with the largest ``output`` (in the report's unit), the drive angle where it occurs
    where the rows say (deg), and their parameters, largest first."""
    ok = columns["status"] == "ok"
    values = np.where(ok, columns[output].astype(float), np.nan)
    order = np.argsort(-np.nan_to_num(values, nan=-np.inf), kind="stable")[: min(count, int(np.isfinite(values).sum()))]
    where = columns.get(f"{output.rsplit('_', 1)[0]}_at_deg")
    _, _, factor = display(output)
    return [
        {
            "id": str(columns["id"][row]),
            "value": factor * float(values[row]),
            "at_deg": None if where is None else _finite(where[row]),
            "parameters": _parameters(columns, names, row),
        }
        for row in order
    ]


def convergence(columns: dict[str, NDArray], values: NDArray, points: int = CONVERGENCE_POINTS) -> list[dict]:
    """The percentiles :data:`CONVERGING` of the finite ``values`` (one per row) with their 95 % intervals, from the
    first n rows in the design's order, at ``points`` evenly spread n up to all: how far the study's own numbers
    are from settling. Where too few rows bound an interval's end it is ``None``."""
    ordered = np.asarray(values, dtype=float)[_order(columns)]
    ordered = ordered[np.isfinite(ordered)]
    out = []
    for n in np.unique(np.linspace(0, ordered.size, points + 1).round().astype(int)[1:]):
        if n == 0:
            continue
        first = np.sort(ordered[:n])
        entry: dict = {"n": int(n)}
        for level in CONVERGING:
            low, high = percentile_interval(first, level)
            entry[f"p{level}"] = float(np.percentile(first, level))
            entry[f"p{level}_interval"] = [x if np.isfinite(x) else None for x in (low, high)]
        out.append(entry)
    return out
