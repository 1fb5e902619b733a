r"""Compensation of a linkage's deviation by its bores: what to print so that the loaded print follows the ideal path
(``docs/formulation.md``, Eq. (D4); issue #35).

The coupler of a flexible print leaves the ideal path (its weight, its own bore errors). Bore corrections :math:`e`
(twist, offset and axial shift of every bore, :class:`~ffrf.scenes.linkage_description.BoreError`) move its path by
:math:`S_i e` to first order at pose :math:`i` (Eq. (D1), :func:`ffrf.scenes.path_sensitivity.bore_sensitivity`), so
the corrections that bring it closest to the ideal path over the motion in the least-squares sense solve

.. math:: \min_e \sum_i |d_i + S_i e|^2, \qquad |e_j| \le b_j,

with bounds :math:`b_j` on each correction (:data:`MAX_TWIST`, :data:`MAX_SHIFT` by default): without them the
minimum is reached by large corrections that cancel each other to first order (the two bores of one link turned
alike turn the link as a whole), far outside where the first order holds. A fixed geometry cannot follow a sag that
changes with the pose: what remains, ``predicted_m``, says how much can be removed. The corrections are checked by a
forward run of the corrected print (``remesh``: the parts as printed), which is the number to trust.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import lsq_linear

from ffrf.scenes.linkage_description import BoreError, LinkageOptions
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.scenes.path_sensitivity import bore_sensitivity
from kinematics.single_loop import SingleLoop

__all__ = ["MAX_SHIFT", "MAX_TWIST", "Compensation", "compensate", "with_corrections"]

#: Default bounds of a correction: twist (rad) and offset or axial shift (m), about where the first order of the bore
#: errors holds on the paper's Bennett (docs/studies.md: within 3 % at twice the study's 0.5 deg and 0.1 mm).
MAX_TWIST = np.radians(0.5)
MAX_SHIFT = 0.2e-3


@dataclass(frozen=True)
class Compensation:
    """Bore ``corrections`` to print (added to the linkage's own bore errors, :func:`with_corrections`); the largest
    deviation from the ideal path before (m), as the first order predicts it after (``predicted_m``), the predicted
    deviation at each pose ``(poses, 3)`` at ``drive_angle`` (rad), and the seconds it took."""

    corrections: tuple[BoreError, ...]
    before_m: float
    predicted_m: float
    drive_angle: NDArray[np.float64]
    predicted: NDArray[np.float64]
    seconds: float


def with_corrections(options: LinkageOptions, corrections: tuple[BoreError, ...]) -> LinkageOptions:
    """``options`` with ``corrections`` added to its bore errors, bore by bore (a bore given twice: summed)."""
    by_bore = {(e.joint, e.link): e for e in options.bore_errors}
    for c in corrections:
        old = by_bore.get((c.joint, c.link), BoreError(c.joint, c.link))
        by_bore[c.joint, c.link] = replace(
            old, twist=old.twist + c.twist, offset=old.offset + c.offset, axial=old.axial + c.axial
        )
    return replace(options, bore_errors=tuple(by_bore.values()))


def compensate(
    loop: SingleLoop,
    options: LinkageOptions,
    outputs: int = 121,
    max_twist: float = MAX_TWIST,
    max_shift: float = MAX_SHIFT,
) -> Compensation:
    """The bore corrections (module docstring) for the linkage ``loop`` built with ``options``: its quasi-static path
    at ``outputs`` poses (bore errors as misfits, the model the derivatives are of), the derivatives of its coupler
    point by every bore's three errors, and the bounded least-squares problem (scipy's ``lsq_linear``, bounded-variable
    least squares: an active-set method, deterministic)."""
    started = time.perf_counter()
    options = replace(options, bore_error_model="misfit")
    scene = build_linkage(loop, options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=outputs, sensors="path")
    assert result.multipliers is not None  # a quasi-static run keeps its equilibria's multipliers
    exact = bore_sensitivity(scene, loop, options, result.time, result.q, result.multipliers)
    deviation = np.asarray(result.sensors["coupler_deviation"], dtype=float)
    slopes = exact.coupler_point.reshape(-1, len(exact.parameters))
    bounds = np.array([max_twist if name.startswith("twist") else max_shift for name in exact.parameters])
    solution = lsq_linear(slopes, -deviation.reshape(-1), bounds=(-bounds, bounds), method="bvls")
    predicted = deviation + (slopes @ solution.x).reshape(deviation.shape)
    fields: dict[tuple[int, int], dict[str, float]] = {}
    for name, value in zip(exact.parameters, solution.x, strict=True):
        field, joint, link = name.split()
        fields.setdefault((int(joint.removeprefix("joint")), int(link.removeprefix("link"))), {})[field] = float(value)
    corrections = tuple(
        BoreError(joint, link, twist=f["twist"], offset=f["offset"], axial=f["axial"])
        for (joint, link), f in fields.items()
    )
    return Compensation(
        corrections,
        float(np.linalg.norm(deviation, axis=1).max()),
        float(np.linalg.norm(predicted, axis=1).max()),
        exact.drive_angle,
        predicted,
        time.perf_counter() - started,
    )
