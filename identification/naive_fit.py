r"""Why not fit the DH parameters directly? The ill-conditioned naive identification.

The "naive" alternative to the paper's geometric method fits all twelve DH parameters
(:math:`a_i, \alpha_i, d_i`) plus the tracked point's coordinates in the coupler frame to
the measured coupler path, given the driver angle. Its forward model must close the loop
for every parameter guess; off the Bennett manifold a rigid loop cannot move at all, so
the model uses the closest rigid closure (:func:`kinematics.rigid_mobility`).

Near a Bennett linkage the Bennett condition couples the parameters: some parameter
combinations barely change the path (for the paper's linkage, at first order the path
does not see the length ``a_2`` at all: the closure misfit it creates is absorbed without
moving joints 0 and 1), so the Jacobian of the path with
respect to the parameters is ill-conditioned and a least-squares fit wanders along those
directions under noise. The geometric method identifies each axis from a circle instead,
one well-posed fit at a time. :func:`naive_path_jacobian` measures this.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kinematics import dh_matrix, rigid_mobility

__all__ = ["PARAMETER_NAMES", "NaiveJacobian", "coupler_path_model", "naive_path_jacobian"]

PARAMETER_NAMES = tuple(
    [f"a{i}" for i in range(4)] + [f"alpha{i}" for i in range(4)] + [f"d{i}" for i in range(4)] + ["cx", "cy", "cz"]
)


def coupler_path_model(parameters: ArrayLike, n_angles: int = 24) -> NDArray[np.float64]:
    """Coupler point path ``(n_angles * 3,)`` in the base DH frame 3, joint 3 turning one revolution.

    ``parameters`` = (a0..a3, alpha0..alpha3, d0..d3, c) with ``c`` the point in coupler frame 1.
    """
    p = np.asarray(parameters, dtype=float)
    a, alpha, d, point = p[:4], p[4:8], p[8:12], p[12:15]
    closure = rigid_mobility(a, alpha, d, driver_joint=3, n_angles=n_angles)
    path = []
    for theta in closure.joint_angles:
        frame = dh_matrix(a[3], alpha[3], d[0], theta[0]) @ dh_matrix(a[0], alpha[0], d[1], theta[1])
        path.append(frame[:3, :3] @ point + frame[:3, 3])
    return np.concatenate(path)


@dataclass(frozen=True)
class NaiveJacobian:
    """Singular values of the (length-scaled) path Jacobian and its weakest parameter directions."""

    singular_values: NDArray[np.float64]
    weakest_directions: NDArray[np.float64]

    @property
    def condition_number(self) -> float:
        return float(self.singular_values[0] / self.singular_values[-1])

    def describe(self, count: int = 3) -> list[str]:
        lines = []
        for s, v in zip(self.singular_values[::-1][:count], self.weakest_directions[:count], strict=True):
            parts = ", ".join(f"{v[i]:+.2f} {PARAMETER_NAMES[i]}" for i in np.argsort(-np.abs(v))[:4])
            lines.append(f"singular value {s:.2e}: {parts}")
        return lines


def naive_path_jacobian(
    parameters: ArrayLike, n_angles: int = 24, step: float = 1e-6, length: float | None = None
) -> NaiveJacobian:
    """Forward-difference Jacobian of :func:`coupler_path_model`; twist columns are scaled by
    ``length`` (default: mean of ``a``) so all columns are in metres per unit change."""
    p = np.asarray(parameters, dtype=float)
    length = float(np.mean(p[:4])) if length is None else length
    base = coupler_path_model(p, n_angles)
    columns = [(coupler_path_model(p + step * e, n_angles) - base) / step for e in np.eye(p.size)]
    jacobian = np.array(columns).T
    jacobian[:, 4:8] *= length
    _, singular_values, vt = np.linalg.svd(jacobian, full_matrices=False)
    return NaiveJacobian(singular_values, vt[::-1])
