"""How far a run's steps may turn its drive: the rule behind :func:`ffrf.scenes.assembly.quasi_static_step` and
:func:`ffrf.scenes.assembly.dynamic_step`, and behind the run-length estimates of :mod:`ffrf.scenes.limits`."""

from __future__ import annotations

import math

__all__ = ["DRIVE_ANGLE_PER_STEP", "MAX_DRIVE_STEP", "MAX_DYNAMIC_STEP", "PATH_STEPS_WITHOUT_DRIVE"]

#: Largest turn of a drive (rad) between two equilibria of a quasi-static run. Longer steps let Newton land on
#: another assembly branch: the PLA collisions_free_6r (P1, 12 mm) fails at 15 deg and passes at 7.5 deg.
MAX_DRIVE_STEP = math.radians(3.0)
#: Turn of the fastest drive per generalized-alpha step of a dynamic run without a step of its own, and the longest
#: such step (s): 0.06 deg is 10 ms at 1 rpm, where the default Bennett's coupler path over a revolution is within
#: 1.4e-10 m of 2 ms steps' (``bench/dynamic_step_rule.py``, ``docs/speed_vs_error.md``); 10 ms is the longest step
#: that sweep and the Exudyn twins checked.
DRIVE_ANGLE_PER_STEP = math.radians(0.06)
MAX_DYNAMIC_STEP = 1e-2
#: Path steps over a quasi-static run without a drive (loads that change with time), Eq. (S10): a fixed count, so
#: that the path, and where it stops or folds, depends on the scene alone, not on its outputs. A fold is located by
#: continuation from where the path stops (Eq. (S6)), so the count sets the cost more than the fold: the von Mises
#: truss scene (tests/test_textbook, to 1.5 times its limit load) folds within 2.2e-9 of the closed-form limit load
#: with 40 steps (11 s) and 2.5e-8 with 120 (88 s, each step a few tangent factorisations); a smooth load history
#: is followed well by the fourth-order predictor (Eq. (S2)) at 2.5 % of the run per step.
PATH_STEPS_WITHOUT_DRIVE = 40
