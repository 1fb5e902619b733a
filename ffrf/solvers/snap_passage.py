r"""Where a snap goes when the traced path shows no landing: a dynamic passage at the fold's t
(``docs/formulation.md``, Eq. (S11)).

Past a fold (Eq. (S6)) the structure jumps at fixed t. Where the path traced through the fold does not come back to
a stable equilibrium at that t (it ends first, or what it meets is unstable), the jump itself is followed: from the
fold, nudged along its softest mode (Eq. (B1), :math:`\mu \approx 0`) as far as the traced path's first point
beyond the fold, the bodies move from rest under the loads held at the fold's t (generalized-alpha,
``held_time``). The passage ends once the kinetic energy has passed its first peak, where the motion crosses the
bottom of the well it has fallen into; the structure is then settled from that state (pseudo-transient continuation,
Eq. (P6)), which gives the equilibrium of that well: the landing that damping would bring the swinging structure to,
if it dissipates the swing before the structure climbs out of the well again.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import NewtonDivergence, StaticDivergence
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.pseudo_transient import settle
from ffrf.solvers.stability import equilibrium_stability, lowest_mode
from ffrf.solvers.step_control import StepControl
from ffrf.system.multibody import MultibodySystem

__all__ = ["Passage", "dynamic_passage"]

log = logging.getLogger(__name__)

#: Outputs per stretch of a passage: the kinetic energy's peak is found to within this share of the stretch.
STRETCH_OUTPUTS = 64
#: Stretches of a passage, each twice as long as the one before (the first 2 pi over the unstable branch's rate),
#: before the passage is given up.
MAX_STRETCHES = 8
#: The kinetic energy has passed its first peak once it is below this share of it.
PEAK_PASSED = 0.5
#: Local error (Eq. (G5)) a passage's step may make, absolute and relative: the passage has to find the well the
#: structure falls into, not the swing's detail (the landing is then settled to Newton's tolerance).
PASSAGE_TOLERANCE = 1e-5
PASSAGE_CONTROL = StepControl(atol=PASSAGE_TOLERANCE, rtol=PASSAGE_TOLERANCE)


@dataclass(frozen=True)
class Passage:
    """The landing equilibrium ``(q, multipliers)`` a passage settles on, the time from the nudge to the kinetic
    energy's peak (s), that peak (J) and the integration steps taken."""

    q: NDArray[np.float64]
    multipliers: NDArray[np.float64]
    peak_time_s: float
    peak_kinetic_energy_j: float
    steps: int


def dynamic_passage(
    system: MultibodySystem,
    fold_t: float,
    fold_q: NDArray,
    fold_multipliers: NDArray,
    beyond: tuple[float, NDArray, NDArray],
) -> Passage | None:
    """The passage of Eq. (S11) from the fold ``(fold_q, fold_multipliers)`` at ``fold_t``; ``beyond`` is the traced
    path's first equilibrium ``(t, q, multipliers)`` past the fold, on the unstable branch. ``None`` if the passage
    does not leave the fold, its integration fails, its kinetic energy does not pass a peak within
    :data:`MAX_STRETCHES` stretches, or the settling fails."""
    t_beyond, q_beyond, lam_beyond = beyond
    mode = lowest_mode(system, fold_q, fold_multipliers, fold_t)
    mass = system.mass_matrix(fold_q)
    nudge = float(mode.x @ mass @ (np.asarray(q_beyond) - fold_q))  # x is mass-normalised: the mode's amplitude
    branch = equilibrium_stability(system, q_beyond, lam_beyond, t_beyond, count=1).squared_frequencies
    if nudge == 0.0 or branch.size == 0 or branch[0] == 0.0:
        return None
    stretch = 2.0 * np.pi / np.sqrt(abs(float(branch[0])))  # e-folding rate of the unstable branch there
    q, qd = fold_q + nudge * mode.x, np.zeros_like(fold_q)
    elapsed, steps = 0.0, 0
    peak = (0.0, q, 0.0)  # (kinetic energy, q, time) at the largest kinetic energy so far
    for _ in range(MAX_STRETCHES):
        try:
            run = generalized_alpha(
                system, q, qd, stretch, stretch / STRETCH_OUTPUTS, step_control=PASSAGE_CONTROL, held_time=fold_t
            )
        except NewtonDivergence as error:
            log.info("dynamic passage from the fold at t = %.6g stopped: %s", fold_t, error)
            return None
        steps += len(run.newton_iterations)
        for t, q_out, qd_out in zip(run.time[1:], run.q[1:], run.qd[1:], strict=True):
            kinetic = system.energies(q_out, qd_out, fold_t)["kinetic"]
            if kinetic > peak[0]:
                peak = (kinetic, q_out, elapsed + t)
            elif kinetic < PEAK_PASSED * peak[0]:
                return _settled(system, fold_t, fold_q, mass, abs(nudge), peak, steps)
        q, qd, elapsed, stretch = run.q[-1], run.qd[-1], elapsed + stretch, 2.0 * stretch
    log.info("dynamic passage from the fold at t = %.6g: no peak of the kinetic energy in %.3g s", fold_t, elapsed)
    return None


def _settled(
    system: MultibodySystem,
    fold_t: float,
    fold_q: NDArray,
    mass: NDArray,
    nudge: float,
    peak: tuple[float, NDArray, float],
    steps: int,
) -> Passage | None:
    """The equilibrium settled on from the passage's state at its kinetic energy's peak, if it lies farther from the
    fold than the nudge (mass norm), so is not the fold again."""
    kinetic, q_peak, time = peak
    try:
        landing = settle(system, q_peak, fold_t)
    except StaticDivergence as error:
        log.info("dynamic passage from the fold at t = %.6g: settling failed: %s", fold_t, error)
        return None
    away = landing.q - fold_q
    if float(np.sqrt(max(away @ mass @ away, 0.0))) <= nudge:
        return None
    return Passage(landing.q, landing.multipliers, time, kinetic, steps)
