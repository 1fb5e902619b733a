"""Step-size control of generalized-alpha by a local error estimate of the positions (Eqs. (G5), (G8))."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ffrf.system.multibody import MultibodySystem

__all__ = ["DisplacementScales", "StepControl", "displacement_error", "local_error"]


def local_error(beta: float, h: float, qdd_new: NDArray, qdd_old: NDArray) -> NDArray:
    r"""Eq. (G5): the local error estimate :math:`e = (\beta - \tfrac16)h^2(\ddot q_{n+1} - \ddot q_n)` of the
    positions after a step of length ``h`` (each coordinate in its own unit)."""
    return (beta - 1.0 / 6.0) * h * h * (qdd_new - qdd_old)


@dataclass(frozen=True)
class StepControl:
    r"""Optional step-size control (``docs/formulation.md``, Eq. (G5)).

    After each converged step the local error of the positions is estimated as
    :math:`e = (\beta - \tfrac16)h^2(\ddot q_{n+1} - \ddot q_n)` (Zienkiewicz and Xie 1991,
    for the Newmark family, which generalized-alpha's update belongs to), and the step is
    accepted when :math:`\max_i |e_i| / (\mathrm{atol} + \mathrm{rtol}|q_i|) \le 1`. The next
    step is scaled by :math:`0.9\,r^{-1/3}` (the error is :math:`O(h^3)`), limited to
    [0.2, 2] and to [``min_step``, ``max_step``]; a rejected step or a Newton failure halves it.
    Steps are shortened to land on every output time. Use it with ``rho_inf < 1``: with
    ``rho_inf = 1`` unresolved high-frequency modes keep undamped oscillations in the
    accelerations, which no acceleration-based estimate can tell from truncation error.
    Measured on the flexible bar pendulum (``tests/test_ffrf_body/test_step_control.py``): the
    tip error follows the tolerance (2.4e-5, 7.1e-6, 1.5e-6 m at 1e-5, 1e-6, 1e-7) with as many
    steps as a uniform step of the same accuracy needs; its gain is on runs whose time scale
    changes (ramps, impacts, the start of a motion).
    """

    atol: float = 1e-6
    rtol: float = 1e-6
    min_step: float = 1e-8
    max_step: float = float("inf")

    def error_ratio(self, beta: float, h: float, qdd_new: NDArray, qdd_old: NDArray, q: NDArray) -> float:
        error = local_error(beta, h, qdd_new, qdd_old)
        return float(np.max(np.abs(error) / (self.atol + self.rtol * np.abs(q))))

    def next_step(self, h: float, ratio: float) -> float:
        factor = 2.0 if ratio <= 0.0 else min(2.0, max(0.2, 0.9 * ratio ** (-1.0 / 3.0)))
        return min(self.max_step, max(self.min_step, factor * h))


@dataclass(frozen=True)
class DisplacementScales:
    """What turns the (G5) estimates of all bodies' coordinates into metres (Eq. (G8)), gathered once per run so
    that a step's measure is a few array operations: the indices of the positions ``R`` (bodies x 3) and Euler
    parameters ``p`` (bodies x 4), each body's radius of gyration about its frame's origin (m), the indices of the
    modal coordinates and a block-diagonal ``F`` with ``|F_b e_b|^2 = e_b^T (Psi^T M Psi / m) e_b`` per body, and
    where each body's modes start among them (bodies with modes only)."""

    positions: NDArray
    rotations: NDArray
    radii: NDArray
    modal: NDArray
    factor: NDArray
    mode_starts: NDArray

    @classmethod
    def of(cls, system: MultibodySystem) -> DisplacementScales:
        offsets = [int(o) for o in system.offsets[:-1]]
        radii: list[float] = []
        modal: list[int] = []
        blocks: list[NDArray] = []
        starts: list[int] = []
        for body, offset in zip(system.bodies, offsets, strict=True):
            mm = body.moments
            mass = max(mm.mass, np.finfo(float).tiny)
            radii.append(np.sqrt(max(float(np.trace(mm.x2)), 0.0) / mass))
            if mm.n_modes:
                values, vectors = np.linalg.eigh(mm.reduced_mass / mass)  # its square root, even if semidefinite
                starts.append(len(modal))
                modal.extend(range(offset + 7, offset + 7 + mm.n_modes))
                blocks.append(np.sqrt(np.maximum(values, 0.0))[:, None] * vectors.T)
        return cls(
            np.array([[o + i for i in range(3)] for o in offsets], dtype=np.int64),
            np.array([[o + 3 + i for i in range(4)] for o in offsets], dtype=np.int64),
            np.array(radii),
            np.array(modal, dtype=np.int64),
            scipy.linalg.block_diag(*blocks) if blocks else np.zeros((0, 0)),
            np.array(starts, dtype=np.int64),
        )


def displacement_error(beta: float, h: float, qdd_new: NDArray, qdd_old: NDArray, scales: DisplacementScales) -> float:
    r"""Eq. (G8): the largest local error estimate (G5) of a step, every coordinate of every body in metres: the
    position's largest component, the rotation's :math:`2|e_p|` times the radius of gyration, and the modal
    coordinates' mass-weighted displacement :math:`\sqrt{e_\zeta^T \Psi^T M \Psi e_\zeta / m}` (the root mean square
    over the body's material of the elastic displacement the error makes)."""
    error = local_error(beta, h, qdd_new, qdd_old)
    largest = max(
        float(np.abs(error[scales.positions]).max(initial=0.0)),
        float((2.0 * scales.radii * np.linalg.norm(error[scales.rotations], axis=1)).max(initial=0.0)),
    )
    if scales.modal.size:
        squares = (scales.factor @ error[scales.modal]) ** 2
        largest = max(largest, float(np.sqrt(np.add.reduceat(squares, scales.mode_starts).max())))
    return largest
