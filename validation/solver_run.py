"""One solver's run of a linkage in the form the cross-validation compares (:mod:`validation.bennett_validation`,
:mod:`validation.bennett_metrics`): rows at the output times, the coupler, the tracked nodes and the driving torque."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

__all__ = ["SolverRun"]


@dataclass
class SolverRun:
    """One solver's run on one system: rows at ``time``; sensors in SI."""

    label: str
    time: NDArray[np.float64]
    drive_angle: NDArray[np.float64]
    q: NDArray[np.float64]  # our layout and basis
    coupler: NDArray[np.float64]  # (n, 3)
    tracked: NDArray[np.float64]  # (n, 9, 3): links 1..3, three nodes each
    torque: NDArray[np.float64]  # (n,) N m
    setup_s: float
    solve_s: float
    extra: dict = field(default_factory=dict)
