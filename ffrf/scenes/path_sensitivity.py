r"""Derivatives of a linkage's quasi-static path with respect to its links' materials (``docs/formulation.md``, (D1)).

At every output pose of a quasi-static run the equilibrium's response to each link's relative Young's modulus and
density comes from the implicit function theorem with the tangent Newton factored there
(:func:`ffrf.solvers.equilibrium_sensitivity.equilibrium_response`, exact: the mode basis does not depend on either).
The outputs are explicit, smooth functions of the equilibrium: the coupler point (the mean of the tool link's joint
points, :func:`ffrf.output.sensors.path_sensors`) and the driving torque (a multiplier). They are differentiated along
the response by central differences (Eq. (D2)): a step moving no coordinate by more than :data:`OUTPUT_STEP`, whose
truncation error (``OUTPUT_STEP**2`` relative) and round-off (about ``eps / OUTPUT_STEP`` of the output's scale)
stay near 1e-10 of the derivative, far below what a re-run's finite differences reach (about 1e-6).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.output.sensors import path_sensors
from ffrf.scenes.linkage_scene import LinkageScene
from ffrf.solvers.equilibrium_sensitivity import equilibrium_response, material_rates

__all__ = ["OUTPUT_STEP", "PathSensitivity", "material_sensitivity"]

#: Largest coordinate change (m, or Euler parameter, or modal coordinate) of Eq. (D2)'s central differences.
OUTPUT_STEP = 1e-6


@dataclass(frozen=True)
class PathSensitivity:
    """Per output pose (``drive_angle``, rad) the derivatives of the coupler point ``(poses, 3, k)`` (m) and of the
    driving torque ``(poses, k)`` (N m) with respect to the ``k`` ``parameters`` (per unit relative change: ``E
    link1`` is ``d/d ln E`` of link 1, the change per 100 % of E to first order)."""

    parameters: tuple[str, ...]
    drive_angle: NDArray[np.float64]
    coupler_point: NDArray[np.float64]
    driving_torque: NDArray[np.float64]


def material_sensitivity(
    scene: LinkageScene, time: NDArray, q: NDArray, multipliers: NDArray, links: tuple[int, ...] | None = None
) -> PathSensitivity:
    """The derivatives of the coupler point and driving torque at the equilibria ``q`` ``(poses, n)``,
    ``multipliers`` ``(poses, m)`` at ``time`` (a quasi-static run's rows) with respect to the relative Young's
    modulus and then density of each of ``links`` (default all; module docstring)."""
    system = scene.system
    links = tuple(range(len(system.bodies))) if links is None else tuple(links)
    time, q, multipliers = np.asarray(time, float), np.asarray(q, float), np.asarray(multipliers, float)
    names = tuple(f"E {system.bodies[k].name}" for k in links) + tuple(f"rho {system.bodies[k].name}" for k in links)
    poses, k = len(time), len(names)
    dq, dlam = np.empty((poses, k, q.shape[1])), np.empty((poses, k, multipliers.shape[1]))
    for row, t in enumerate(time):
        rates = material_rates(system, q[row], links)
        response_q, response_lam = equilibrium_response(system, q[row], multipliers[row], float(t), rates)
        dq[row], dlam[row] = response_q.T, response_lam.T
    # Eq. (D2): each (pose, parameter) pair stepped along its response, all in one evaluation per side
    step = OUTPUT_STEP / np.maximum(np.abs(dq).max(axis=2), np.finfo(float).tiny)  # (poses, k)
    times = np.repeat(time, k)
    sides = []
    for sign in (1.0, -1.0):
        shifted_q = (q[:, None, :] + sign * step[..., None] * dq).reshape(poses * k, -1)
        shifted_lam = (multipliers[:, None, :] + sign * step[..., None] * dlam).reshape(poses * k, -1)
        sides.append(path_sensors(scene, times, shifted_q, shifted_lam))
    denominator = 2.0 * step
    coupler = (sides[0]["coupler_point"] - sides[1]["coupler_point"]).reshape(poses, k, 3) / denominator[..., None]
    torque = (sides[0]["driving_torque"] - sides[1]["driving_torque"]).reshape(poses, k) / denominator
    angles = np.array([scene.drive_angle(float(t)) for t in time])
    return PathSensitivity(names, angles, np.transpose(coupler, (0, 2, 1)), torque)
