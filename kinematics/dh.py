r"""Denavit-Hartenberg parameters of closed single loops, in the paper's convention.

The paper (Sect. "Recovery of Motion Polynomials from DH parameters", after Lynch and
Park, Modern Robotics, App. C) moves from axis ``i-1`` to axis ``i`` by

.. math:: f_{i-1}^{i}(\theta_i) = r_x(\alpha_{i-1})\, t_x(a_{i-1})\, t_z(d_i)\, r_z(\theta_i),
          \qquad (\mathrm{DH})

with :math:`r_x(\alpha) = \cos\frac\alpha2 + \sin\frac\alpha2\mathbf i`,
:math:`t_x(a) = 1 - \varepsilon\frac a2\mathbf i`, :math:`t_z(d) = 1 - \varepsilon\frac d2\mathbf k`,
:math:`r_z(\theta) = \cos\frac\theta2 + \sin\frac\theta2\mathbf k`. In matrix form this is
``Rx(alpha) Tx(a) Tz(d) Rz(theta)``. Frame ``i`` has its z-axis on joint axis
:math:`h_i` and its x-axis along the common normal from :math:`h_i` to :math:`h_{i+1}`;
``a_i >= 0`` is the length of that normal, :math:`\alpha_i` the twist from :math:`h_i`
to :math:`h_{i+1}` about it, :math:`d_i` the offset along :math:`h_i` between the
normals to :math:`h_{i-1}` and :math:`h_{i+1}`, :math:`\theta_i` the joint angle.
Indices are cyclic (``h_n = h_0``); a loop is closed when (paper, closure equation)

.. math:: f_{n-1}^{0}(\theta_0)\, f_0^1(\theta_1) \cdots f_{n-2}^{n-1}(\theta_{n-1}) = 1.

World frame of :func:`dh_axes`: z along :math:`h_0`, origin at the foot of the normal
:math:`a_0` on :math:`h_0`, and x-axis *opposite* to frame 0's x-axis (a half turn about
:math:`h_0`). This is the frame in which the paper writes :math:`h_0 \dots h_3`; in the
folded home configuration of a 4R loop its x-axis points from :math:`h_0` towards
:math:`h_3`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .dual_quaternion import DualQuaternion
from .pluecker import Line, common_normal

__all__ = [
    "DHParameters",
    "ClosureResidual",
    "LoopClosureError",
    "dh_transform",
    "dh_matrix",
    "dh_axes",
    "open_loop_axes",
    "dh_from_axes",
    "loop_closure_residual",
    "home_configuration",
    "wrap_angle",
]


class LoopClosureError(ValueError):
    """The DH chain does not close into a loop."""


@dataclass(frozen=True)
class DHParameters:
    """DH parameters of an n-joint loop (metres, radians); ``theta`` are joint angles."""

    a: NDArray[np.float64]
    alpha: NDArray[np.float64]
    d: NDArray[np.float64]
    theta: NDArray[np.float64]


class ClosureResidual(NamedTuple):
    """How far a DH chain is from closing: translation (m) and rotation angle (rad)."""

    translation: NDArray[np.float64]
    rotation: NDArray[np.float64]


def wrap_angle(angle: ArrayLike) -> NDArray[np.float64]:
    """Angles wrapped to ``(-pi, pi]``.

    >>> bool(wrap_angle(-np.pi) == np.pi), bool(wrap_angle(3 * np.pi) == np.pi), float(wrap_angle(0.5))
    (True, True, 0.5)
    """
    angle = np.asarray(angle, dtype=float)
    wrapped = np.mod(angle + np.pi, 2.0 * np.pi) - np.pi
    return np.where(wrapped == -np.pi, np.pi, wrapped)


def _params(a: ArrayLike, alpha: ArrayLike, d: ArrayLike, theta: ArrayLike) -> tuple[NDArray, ...]:
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (a, alpha, d, theta)))
    return arrays


def dh_transform(a: ArrayLike, alpha: ArrayLike, d: ArrayLike, theta: ArrayLike) -> DualQuaternion:
    r"""Eq. (DH) as a dual quaternion :math:`r_x(\alpha) t_x(a) t_z(d) r_z(\theta)` (broadcasts).

    The same displacement as :func:`dh_matrix`:

    >>> bool(np.allclose(dh_transform(0.1, 0.3, 0.02, 1.2).to_matrix(), dh_matrix(0.1, 0.3, 0.02, 1.2)))
    True
    """
    a, alpha, d, theta = _params(a, alpha, d, theta)
    zero, one = np.zeros_like(a), np.ones_like(a)
    r_x = DualQuaternion(np.stack([np.cos(alpha / 2), np.sin(alpha / 2), zero, zero, zero, zero, zero, zero], -1))
    t_x = DualQuaternion(np.stack([one, zero, zero, zero, zero, -a / 2, zero, zero], -1))
    t_z = DualQuaternion(np.stack([one, zero, zero, zero, zero, zero, zero, -d / 2], -1))
    r_z = DualQuaternion(np.stack([np.cos(theta / 2), zero, zero, np.sin(theta / 2), zero, zero, zero, zero], -1))
    return r_x * t_x * t_z * r_z


def dh_matrix(a: ArrayLike, alpha: ArrayLike, d: ArrayLike, theta: ArrayLike) -> NDArray[np.float64]:
    """Eq. (DH) as 4x4 matrices ``Rx(alpha) Tx(a) Tz(d) Rz(theta)`` (broadcasts).

    A twist of 90 degrees turns the next axis from z to -y; the common normal a = 0.1 shifts it along x:

    >>> (dh_matrix(0.1, np.pi / 2, 0.0, 0.0).round(12) + 0.0).tolist()
    [[1.0, 0.0, 0.0, 0.1], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
    """
    a, alpha, d, theta = _params(a, alpha, d, theta)
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
    m = np.zeros(a.shape + (4, 4))
    m[..., 0, :] = np.stack([ct, -st, np.zeros_like(a), a], -1)
    m[..., 1, :] = np.stack([ca * st, ca * ct, -sa, -sa * d], -1)
    m[..., 2, :] = np.stack([sa * st, sa * ct, ca, ca * d], -1)
    m[..., 3, 3] = 1.0
    return m


def _loop_arrays(
    a: ArrayLike, alpha: ArrayLike, d: ArrayLike | None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    a = np.atleast_1d(np.asarray(a, dtype=float))
    alpha = np.atleast_1d(np.asarray(alpha, dtype=float))
    n = a.shape[0]
    d = np.zeros(n) if d is None else np.broadcast_to(np.asarray(d, dtype=float), (n,)).copy()
    if a.ndim != 1 or alpha.shape != (n,) or n < 2:
        raise ValueError(f"a and alpha must be 1-D with the same length n >= 2, got {a.shape} and {alpha.shape}")
    if np.any(a < 0):
        raise ValueError(f"DH lengths a_i must be >= 0 (flip the twist sign instead), got {a}")
    for name, x in (("a", a), ("alpha", alpha), ("d", d)):
        if not np.all(np.isfinite(x)):
            raise ValueError(f"DH parameter {name} contains NaN or infinity: {x}")
    return a, alpha, d


def home_configuration(n: int) -> NDArray[np.float64]:
    r"""Folded home configuration :math:`\theta = (0, \pi, 0, \pi)` of a 4R loop with ``d = 0``.

    With ``d = 0`` every factor :math:`A_i = Rx(\alpha_i) Tx(a_i)` is a screw about the
    x-axis, so all :math:`A_i` commute and :math:`Rz(\pi) A_i Rz(\pi) = A_i^{-1}`. The
    closure product becomes :math:`A_3 A_0 A_1^{-1} A_2^{-1}`, which is the identity
    exactly when :math:`a_3 + a_0 = a_1 + a_2` and :math:`\alpha_3 + \alpha_0 = \alpha_1 +
    \alpha_2`: every Bennett linkage, but not the paper's misaligned base
    (:math:`\alpha_3 = 91^\circ`). All common normals then lie on one line; this is the
    configuration behind the paper's :math:`h_0 \dots h_3` (normals of :math:`h_3h_0` and
    :math:`h_0h_1` collinear).
    """
    if n != 4:
        raise ValueError(f"the folded home configuration is defined for 4R loops only; give theta for n = {n}")
    return np.array([0.0, np.pi, 0.0, np.pi])


def _chain(a, alpha, d, theta) -> NDArray[np.float64]:
    """Frames ``F_0 .. F_n`` (4x4) of the chain relative to frame 0: ``F_i = F_{i-1} f_{i-1}^i(theta_i)``."""
    n = a.shape[0]
    frames = [np.eye(4)]
    for i in range(1, n + 1):
        frames.append(frames[-1] @ dh_matrix(a[i - 1], alpha[i - 1], d[i % n], theta[i % n]))
    return np.array(frames)


def loop_closure_residual(a: ArrayLike, alpha: ArrayLike, d: ArrayLike | None, thetas: ArrayLike) -> ClosureResidual:
    r"""Residual of the closure equation :math:`f_{n-1}^0(\theta_0) f_0^1(\theta_1)\cdots = 1`.

    ``thetas`` has shape ``(..., n)``; returns the translation (m) and rotation angle
    (rad) of the loop product, each of shape ``(...)``. Both are zero for a closed loop.
    """
    a, alpha, d = _loop_arrays(a, alpha, d)
    thetas = np.asarray(thetas, dtype=float)
    n = a.shape[0]
    if thetas.shape[-1] != n:
        raise ValueError(f"thetas must end with n = {n} joint angles, got shape {thetas.shape}")
    product = dh_matrix(a[n - 1], alpha[n - 1], d[0], thetas[..., 0])
    for i in range(1, n):
        product = product @ dh_matrix(a[i - 1], alpha[i - 1], d[i], thetas[..., i])
    translation = np.linalg.norm(product[..., :3, 3], axis=-1)
    cos_angle = np.clip((np.trace(product[..., :3, :3], axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    # arccos loses accuracy near 0; use |R - R^T| (= 2 sin(angle)) there.
    skew = product[..., :3, :3] - np.swapaxes(product[..., :3, :3], -1, -2)
    sin_angle = np.linalg.norm(skew, axis=(-2, -1)) / (2.0 * np.sqrt(2.0))
    rotation = np.arctan2(sin_angle, cos_angle)
    return ClosureResidual(translation, rotation)


# Half turn about z: the paper's world frame relative to DH frame 0 (see module docstring).
_WORLD_FROM_FRAME0 = np.diag([-1.0, -1.0, 1.0, 1.0])


def dh_axes(
    a: ArrayLike,
    alpha: ArrayLike,
    d: ArrayLike | None = None,
    theta: ArrayLike | None = None,
    tol: float = 1e-10,
) -> list[Line]:
    r"""Joint axes :math:`h_0 \dots h_{n-1}` of a closed loop, in the paper's world frame.

    ``theta`` defaults to the folded home configuration (:func:`home_configuration`);
    for the paper's table this returns exactly the paper's :math:`h_0 \dots h_3`.
    Raises :class:`LoopClosureError` if the chain does not close at ``theta``
    (residual above ``tol`` relative to the largest length).
    """
    a, alpha, d = _loop_arrays(a, alpha, d)
    n = a.shape[0]
    if theta is None:
        if np.any(d != 0.0):
            raise ValueError("give theta: the folded home configuration closes only for d = 0")
        theta = home_configuration(n)
    theta = np.asarray(theta, dtype=float)
    if theta.shape != (n,):
        raise ValueError(f"theta must have n = {n} entries, got shape {theta.shape}")
    scale = max(float(np.max(a)), float(np.max(np.abs(d))), 1e-300)
    residual = loop_closure_residual(a, alpha, d, theta)
    if residual.translation > tol * scale or residual.rotation > tol:
        raise LoopClosureError(
            f"the DH chain does not close at theta = {np.round(np.degrees(theta), 6)} deg: "
            f"translation residual {residual.translation:.3e} m, rotation residual "
            f"{np.degrees(residual.rotation):.3e} deg; give joint angles that close the loop"
        )
    frames = _WORLD_FROM_FRAME0 @ _chain(a, alpha, d, theta)
    return [Line.from_point_direction(f[:3, 3], f[:3, 2]) for f in frames[:n]]


def open_loop_axes(
    a: ArrayLike,
    alpha: ArrayLike,
    d: ArrayLike | None = None,
    theta: ArrayLike | None = None,
) -> tuple[list[Line], Line]:
    r"""Axes of a loop that may not close, and where its closing link wants its first axis.

    Returns ``(axes, closing_axis)``: ``axes`` are :math:`h_0 \dots h_{n-1}` chained forward
    from :math:`h_0` through links ``0 .. n-2``; ``closing_axis`` is the axis
    :math:`h_{n-1}'` that the closing link (parameters ``a_{n-1}, alpha_{n-1}, d_0,
    theta_0``) puts relative to :math:`h_0`, i.e. frame :math:`F_0\,(f_{n-1}^0)^{-1}`.
    The two coincide when the loop closes; otherwise their gap is the assembly misfit
    that elastic links must absorb (the paper's base link with :math:`\alpha_3 = 91^\circ`).
    ``theta`` defaults to the folded home configuration.
    """
    a, alpha, d = _loop_arrays(a, alpha, d)
    n = a.shape[0]
    theta = home_configuration(n) if theta is None else np.asarray(theta, dtype=float)
    frames = _WORLD_FROM_FRAME0 @ _chain(a, alpha, d, theta)
    closing = _WORLD_FROM_FRAME0 @ np.linalg.inv(dh_matrix(a[n - 1], alpha[n - 1], d[0], theta[0]))
    axes = [Line.from_point_direction(f[:3, 3], f[:3, 2]) for f in frames[:n]]
    return axes, Line.from_point_direction(closing[:3, 3], closing[:3, 2])


def dh_from_axes(lines: list[Line], tol: float = 1e-12) -> DHParameters:
    r"""DH parameters of the closed loop of lines :math:`h_0 \dots h_{n-1}` (inverse of :func:`dh_axes`).

    For each pair :math:`(h_i, h_{i+1})`: ``a_i`` is the length of the common normal,
    :math:`x_i` its unit vector from :math:`h_i` to :math:`h_{i+1}` (for intersecting
    axes :math:`x_i = z_i \times z_{i+1}` normalised), :math:`\alpha_i =
    \operatorname{atan2}((z_i\times z_{i+1})\cdot x_i,\, z_i\cdot z_{i+1})`; ``d_i`` is the
    signed distance along :math:`z_i` from the foot of normal ``i-1`` to the foot of
    normal ``i``; :math:`\theta_i` the angle from :math:`x_{i-1}` to :math:`x_i` about
    :math:`z_i`. Parallel neighbours take the normal through the previous foot, which
    makes their ``d`` zero. This is the construction of Huczala et al. (2022) that the
    paper uses through Rational Linkages.
    """
    n = len(lines)
    if n < 3:
        raise ValueError(f"a closed loop needs at least 3 axes, got {n}")
    # Per pair (h_i, h_{i+1}), keyed by i: the normal's feet on h_{i+1} and on h_i, and its unit vector.
    feet_on_next: dict[int, NDArray[np.float64]] = {}
    feet_on_self: dict[int, NDArray[np.float64]] = {}
    units: dict[int, NDArray[np.float64]] = {}
    # Start with the pair (h_{n-1}, h_0) so that a parallel pair (h_0, h_1) can reuse its foot.
    for i in [n - 1] + list(range(n - 1)):
        previous_foot = feet_on_next.get((i - 1) % n)
        normal = common_normal(lines[i], lines[(i + 1) % n], reference=previous_foot, tol=tol)
        if normal.kind == "coincident" or normal.unit is None:  # unit is None exactly for coincident axes
            raise ValueError(f"axes h_{i} and h_{(i + 1) % n} coincide: the DH parameters are undefined")
        feet_on_self[i], feet_on_next[i] = normal.foot0, normal.foot1
        units[i] = normal.unit
    a = np.array([np.linalg.norm(feet_on_next[i] - feet_on_self[i]) for i in range(n)])
    z = [line.direction for line in lines]
    alpha = np.array([np.arctan2(np.cross(z[i], z[(i + 1) % n]) @ units[i], z[i] @ z[(i + 1) % n]) for i in range(n)])
    d = np.array([(feet_on_self[i] - feet_on_next[(i - 1) % n]) @ z[i] for i in range(n)])
    theta = np.array(
        [np.arctan2(np.cross(units[(i - 1) % n], units[i]) @ z[i], units[(i - 1) % n] @ units[i]) for i in range(n)]
    )
    return DHParameters(a=a, alpha=alpha, d=d, theta=theta)
