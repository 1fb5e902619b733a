"""From a record to DH parameters, and statistics over repeated runs (paper, Tab. dh_deviation)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.scenes.limits import length_unit_problem
from kinematics import PAPER_ALPHA

from .branches import fit_link_axis
from .circle_fit import IdentificationError
from .loop import IdentifiedLoop, identify_dh
from .records import LinkRecord, clean_record, moving_average

__all__ = ["RecordIdentification", "RunStatistics", "identify_record", "run_statistics"]


@dataclass(frozen=True)
class RecordIdentification:
    """Identification of one record, with how many driver revolutions it held."""

    loop: IdentifiedLoop
    revolutions: float
    frames_used: int
    source: str


def identify_record(
    record: LinkRecord, window: int = 10, nominal_alpha: ArrayLike = PAPER_ALPHA
) -> RecordIdentification:
    """Clean, filter (centred moving average, ``window`` frames) and identify one record."""
    missing = [k for k in (1, 2, 3) if k not in record.points]
    if missing:
        raise IdentificationError(f"{record.source}: links {missing} are not tracked; links 1, 2 and 3 are needed")
    cleaned = moving_average(clean_record(record), window)
    loop = identify_dh(cleaned.points, nominal_alpha)
    problem = length_unit_problem([*map(float, loop.dh.a), *map(float, loop.dh.d)], "the record's length unit (--unit)")
    if problem is not None:  # plausible, not impossible: a warning, and the table as identified
        warnings.warn(f"{record.source}: identified {problem}", UserWarning, stacklevel=2)
    # Revolutions of the driven link 3 about the base (angle span / 2 pi).
    revolutions = float(np.ptp(fit_link_axis(cleaned.points[3], "link 3").angles) / (2 * np.pi))
    return RecordIdentification(loop, revolutions, cleaned.n_frames, record.source)


@dataclass(frozen=True)
class RunStatistics:
    """Mean and sample standard deviation (ddof = 1; zero for a single run) over runs."""

    n_runs: int
    mean: dict[str, NDArray[np.float64]]
    std: dict[str, NDArray[np.float64]]


def run_statistics(loops: list[IdentifiedLoop]) -> RunStatistics:
    """Statistics of ``a``, ``alpha``, ``d``, the Bennett ratios and the axis-3 deviation."""
    if not loops:
        raise ValueError("no identified runs to summarise")
    values = {
        "a": np.array([loop.dh.a for loop in loops]),
        "alpha": np.array([loop.dh.alpha for loop in loops]),
        "d": np.array([loop.dh.d for loop in loops]),
        "ratios": np.array([list(loop.ratios.values()) for loop in loops]),
        "axis3_twist_deviation": np.array([[loop.axis3_twist_deviation] for loop in loops]),
    }
    ddof = 1 if len(loops) > 1 else 0
    return RunStatistics(
        n_runs=len(loops),
        mean={k: v.mean(axis=0) for k, v in values.items()},
        std={k: v.std(axis=0, ddof=ddof) for k, v in values.items()},
    )
