"""Exudyn's run of a twin as plain data (:class:`TwinRun`), read by the cross-validation with the same fields as
our runs' :class:`ffrf.output.result.Result`: ``time``, ``q``, ``sensors`` and ``metadata`` (:data:`ComparedRun`).

Our solver's runs in :mod:`validation` are :class:`~ffrf.output.result.Result` s (the engine's one result type);
only the twin's are not, because a Result is a run of our solver: its ``save``, ``summary`` and ``verification``
read our scene and our checks of ourselves, which an Exudyn run has not. What the twin gives is what its sensors
recorded, in our layout and names, so that the comparisons need no conversion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.output.result import Result

__all__ = ["TwinRun", "ComparedRun", "run_metadata", "solution_time", "twin_run"]


@dataclass(frozen=True)
class TwinRun:
    """Exudyn's run of a twin (module docstring): rows at ``time`` (t = 0 included); ``q``: the coordinates in our
    layout and basis (absolute; Euler parameters with our sign); ``sensors``: name -> array (rows = times), named as
    our Results' sensors; ``metadata``: :func:`run_metadata` and what the twin adds (its notes)."""

    time: NDArray[np.float64]
    q: NDArray[np.float64]
    sensors: dict[str, NDArray[np.float64]]
    metadata: dict


#: A run the cross-validation compares: ours (a Result) or the twin's; both are read by the fields above.
ComparedRun = Result | TwinRun


def run_metadata(label: str, solver: str, setup_s: float, solve_s: float, newton_iterations: int) -> dict:
    """The metadata every compared run carries, ours and the twin's: its ``label`` (which of the compared systems),
    the ``solver`` (with Exudyn's version), ``timings_s`` (``setup``: building; ``solve``: the run) and the total
    ``newton_iterations`` (-1 where the solver does not tell)."""
    return {
        "label": label,
        "solver": solver,
        "timings_s": {"setup": setup_s, "solve": solve_s},
        "newton_iterations": newton_iterations,
    }


def solution_time(run: ComparedRun) -> float:
    """A run's wall time of its solution with the assembly it started from, where one is recorded
    (``timings_s["assembly"]``), in s."""
    timings = run.metadata["timings_s"]
    return timings["solve"] + timings.get("assembly", 0.0)


def twin_run(
    time: NDArray[np.float64], q: NDArray[np.float64], sensors: dict[str, NDArray[np.float64]], metadata: dict
) -> TwinRun:
    """The twin's run from what its sensors recorded (rows at ``time``, ``q`` in our layout and basis), checked to
    be rows at the same times; ``metadata``: :func:`run_metadata` with the twin's notes."""
    time = np.asarray(time, dtype=float)
    for name, values in {"q": q, **sensors}.items():
        if len(values) != len(time):
            raise ValueError(f"the twin's {name} has {len(values)} rows for {len(time)} output times")
    return TwinRun(time, np.asarray(q, dtype=float), dict(sensors), metadata)
