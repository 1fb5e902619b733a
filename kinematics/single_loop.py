r"""Any single loop of revolute joints: closure, mobility and motion by continuation.

A loop of ``n`` revolute joints is given by its joint axes :math:`h_0 \dots h_{n-1}` (Pluecker
lines, :mod:`kinematics.pluecker`) in one assembled *home* pose. Links are numbered as in the
paper: link 0 (the base) carries :math:`h_{n-1}` and :math:`h_0`, link ``k`` carries
:math:`h_{k-1}` and :math:`h_k`; joint ``i`` turns link ``i + 1`` against link ``i`` about
:math:`h_i`. With joint rotations :math:`\varphi_i` measured from the home pose, link ``k`` is
displaced by the product of exponentials (``docs/formulation.md``, (L1))

.. math:: \sigma_k = R_0(\varphi_0) R_1(\varphi_1)\cdots R_{k-1}(\varphi_{k-1}), \qquad
          R_i(\varphi) = \cos\tfrac\varphi2 + \sin\tfrac\varphi2\, h_i,

each :math:`R_i` a rotation about the *home* axis :math:`h_i` (the right factor acts first, so
the axes of earlier joints carry the later ones). The loop closes when (L2)

.. math:: \sigma_n = R_0(\varphi_0)\cdots R_{n-1}(\varphi_{n-1}) = \pm 1 ,

which is the paper's closure equation :math:`(t_0 - h_0)\cdots(t_{n-1} - h_{n-1}) \in \mathbb R`
with :math:`t_i = -\cot(\varphi_i/2)`. Differentiating (L2), the loop product moves with the
spatial twist :math:`\sum_i \dot\varphi_i \xi_i`, where :math:`\xi_i = (l_i, m_i)` are the
Pluecker coordinates of axis ``i`` in its current pose, :math:`\sigma_i h_i \tilde\sigma_i`
(L3). The closure Jacobian is the ``6 x n`` matrix of these lines; the loop's first-order
mobility is ``n - rank``. A loop that moves (a Bennett linkage, the 6R mechanisms of Rational
Linkages) keeps rank ``n - 1`` along its motion; where the rank drops further the pose is
singular (a bifurcation or a dead point of the loop).

The motion is traced by continuation (L4): predictor along the kernel of the Jacobian, corrector
by Gauss-Newton on the closure residual with the driving joint held. Nothing here needs a motion
polynomial, so misaligned (as-built) loops and loops from any source are treated alike; where a
motion polynomial exists (Bennett, Rational Linkages) it is an independent check of the result.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from .dh import DHParameters, LoopClosureError, dh_axes, dh_from_axes
from .dual_quaternion import DualQuaternion
from .pluecker import Line
from .quaternion import rotation_vector

__all__ = [
    "LoopFoldError",
    "close_near",
    "follow_driver",
    "joint_rates",
    "LoopMotion",
    "RateProfile",
    "rate_profile",
    "SingleLoop",
    "motion_tangents",
    "point_paths",
    "trace_motion",
]

#: Closure tolerance of the corrector, relative to the loop's size (translation) and in rad.
CLOSURE_TOLERANCE = 1e-13
#: Singular values of the closure Jacobian (lengths over the loop's size) below this times the largest count as zero.
RANK_RTOL = 1e-8


class LoopFoldError(ValueError):
    """The driving joint cannot turn further: the motion folds back (the joint is a rocker)."""


def _residual(product: NDArray[np.float64]) -> NDArray[np.float64]:
    """Translation and rotation vector of the loop product, Eq. (L2)."""
    return np.concatenate([product[:3, 3], rotation_vector(product[:3, :3])])


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a x b`` of two 3-vectors with ``np.cross``'s products and differences in its order (the same bits), without
    its handling of general shapes, which took half the time of tracing a rigid loop's motion."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def rotation_about(line: Line, angle: float) -> NDArray[np.float64]:
    r"""4x4 matrix of the rotation :math:`R(\varphi)` about ``line`` by ``angle`` (Rodrigues)."""
    rotation = Rotation.from_rotvec(angle * line.direction).as_matrix()
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = line.point - rotation @ line.point
    return matrix


@dataclass(frozen=True)
class SingleLoop:
    r"""A closed loop of ``n >= 4`` revolute joints: its axes :math:`h_0 \dots h_{n-1}` at home.

    ``scale`` (m) is the loop's size (largest distance between neighbouring axes, or their
    largest distance from the origin when all axes intersect); closure tolerances are relative
    to it.
    """

    axes: tuple[Line, ...]

    def __post_init__(self) -> None:
        axes = tuple(self.axes)
        if len(axes) < 4:
            raise ValueError(f"a single-loop linkage needs at least 4 revolute joints, got {len(axes)} axes")
        if not all(isinstance(axis, Line) for axis in axes):
            raise TypeError("SingleLoop axes must be kinematics.Line objects (Line.from_point_direction(p, l))")
        for i, axis in enumerate(axes):
            following = axes[(i + 1) % len(axes)]
            if axis.is_close(following, tol=1e-12) or axis.is_close(following.reversed(), tol=1e-12):
                raise ValueError(f"axes h_{i} and h_{(i + 1) % len(axes)} coincide: merge the two joints")
        object.__setattr__(self, "axes", axes)

    # -- construction -----------------------------------------------------------------------
    @classmethod
    def from_dh(
        cls,
        a: ArrayLike,
        alpha: ArrayLike,
        d: ArrayLike | None = None,
        theta: ArrayLike | None = None,
    ) -> SingleLoop:
        """From DH parameters (paper's convention, :mod:`kinematics.dh`) and closing joint angles.

        Raises :class:`kinematics.dh.LoopClosureError` when the chain does not close at ``theta``.
        """
        return cls(tuple(dh_axes(a, alpha, d, theta)))

    @classmethod
    def from_points_directions(cls, points: ArrayLike, directions: ArrayLike) -> SingleLoop:
        """From a point on each axis and its direction, ``(n, 3)`` each (metres)."""
        points = np.asarray(points, dtype=float)
        directions = np.asarray(directions, dtype=float)
        if points.ndim != 2 or points.shape[1] != 3 or directions.shape != points.shape:
            raise ValueError(f"points and directions must both be (n, 3), got {points.shape} and {directions.shape}")
        return cls(
            tuple(
                Line.from_point_direction(point, direction) for point, direction in zip(points, directions, strict=True)
            )
        )

    # -- geometry ---------------------------------------------------------------------------
    @property
    def n(self) -> int:
        return len(self.axes)

    @cached_property
    def scale(self) -> float:
        """Largest distance between neighbouring axes, else from the origin (m); 1 if all vanish."""
        dh = self.dh()
        size = max(float(np.max(dh.a)), float(np.max(np.abs(dh.d))))
        if size == 0.0:
            size = max(float(np.linalg.norm(axis.point)) for axis in self.axes)
        return size if size > 0.0 else 1.0

    @cached_property
    def residual_weights(self) -> NDArray[np.float64]:
        """Weights that make the closure residual dimensionless: translation over :attr:`scale`, rotation as is."""
        return np.array([1.0 / self.scale] * 3 + [1.0] * 3)

    def dh(self) -> DHParameters:
        """DH parameters of the home pose (:func:`kinematics.dh.dh_from_axes`); ``theta`` at home."""
        return dh_from_axes(list(self.axes))

    # -- poses ------------------------------------------------------------------------------
    def link_transforms(self, phi: ArrayLike) -> NDArray[np.float64]:
        r"""Displacements :math:`\sigma_0 \dots \sigma_n` of Eq. (L1) as 4x4 matrices, ``(n + 1, 4, 4)``.

        ``sigma[k]`` moves link ``k`` from home; ``sigma[n]`` is the loop product of (L2), the
        identity when ``phi`` closes the loop.
        """
        phi = self._angles(phi)
        points, directions = self._axis_arrays
        # All n rotations of (L1) in one call: the same Rodrigues matrices as rotation_about, a fraction of the time.
        rotations = Rotation.from_rotvec(phi[:, None] * directions).as_matrix()
        factors = np.zeros((self.n, 4, 4))
        factors[:, :3, :3] = rotations
        factors[:, :3, 3] = points - (rotations @ points[:, :, None])[:, :, 0]
        factors[:, 3, 3] = 1.0
        transforms = np.empty((self.n + 1, 4, 4))
        transforms[0] = np.eye(4)
        for i in range(self.n):
            transforms[i + 1] = transforms[i] @ factors[i]
        return transforms

    @cached_property
    def _axis_arrays(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Points ``l x m`` and directions ``l`` of the home axes, ``(n, 3)`` each."""
        return np.array([axis.point for axis in self.axes]), np.array([axis.direction for axis in self.axes])

    def link_poses(self, phi: ArrayLike) -> DualQuaternion:
        r"""Eq. (L1) in the paper's algebra: unit dual quaternions :math:`\sigma_0 \dots \sigma_{n-1}`."""
        phi = self._angles(phi)
        pose = DualQuaternion.identity()
        poses = [pose.coeffs]
        for i in range(self.n - 1):
            h = self.axes[i].to_dual_quaternion()
            pose = pose * (DualQuaternion.identity() * np.cos(phi[i] / 2) + h * np.sin(phi[i] / 2))
            poses.append(pose.coeffs)
        return DualQuaternion(np.array(poses))

    def current_axes(self, phi: ArrayLike) -> list[Line]:
        r"""Axes in the pose ``phi``: :math:`h_i` moved with link ``i`` (Eq. (L3))."""
        transforms = self.link_transforms(phi)
        lines = []
        for axis, transform in zip(self.axes, transforms[: self.n], strict=True):
            rotation, shift = transform[:3, :3], transform[:3, 3]
            lines.append(Line.from_point_direction(rotation @ axis.point + shift, rotation @ axis.direction))
        return lines

    # -- closure ----------------------------------------------------------------------------
    def closure_residual(self, phi: ArrayLike) -> NDArray[np.float64]:
        """Residual of Eq. (L2): translation (m) and rotation vector (rad) of the loop product, ``(6,)``."""
        return _residual(self.link_transforms(phi)[self.n])

    def jacobian(self, phi: ArrayLike) -> NDArray[np.float64]:
        r"""Closure Jacobian of Eq. (L3), ``(6, n)``: column ``i`` is :math:`(m_i, l_i)` of axis ``i`` now.

        Rows follow :meth:`closure_residual` (translation, then rotation). The translation rows
        are the exact derivative of the loop product's translation :math:`p`,
        :math:`l_i \times p + m_i`; the rotation rows :math:`l_i` are exact where the loop closes.
        """
        return self._jacobian(self.link_transforms(phi))

    def _jacobian(self, transforms: NDArray[np.float64]) -> NDArray[np.float64]:
        """Eq. (L3) from the displacements of :meth:`link_transforms`."""
        translation = transforms[self.n][:3, 3]
        jacobian = np.empty((6, self.n))
        points, directions = self._axis_arrays  # a Line's point is a cross product: formed once per loop
        for i in range(self.n):
            rotation, shift = transforms[i][:3, :3], transforms[i][:3, 3]
            direction = rotation @ directions[i]
            moment = _cross(rotation @ points[i] + shift, direction)
            jacobian[:3, i] = _cross(direction, translation) + moment
            jacobian[3:, i] = direction
        return jacobian

    def singular_values(self, phi: ArrayLike) -> NDArray[np.float64]:
        """Singular values of the closure Jacobian, lengths scaled by :attr:`scale` (dimensionless)."""
        jacobian = self.jacobian(phi)
        jacobian[:3] /= self.scale
        return np.asarray(np.linalg.svd(jacobian, compute_uv=False), dtype=np.float64)

    def mobility(self, phi: ArrayLike | None = None, rtol: float = RANK_RTOL) -> int:
        """First-order degrees of freedom ``n - rank`` at ``phi`` (default home).

        The rank counts singular values above ``rtol`` times the largest (lengths scaled by
        :attr:`scale`), so the verdict does not depend on units.
        """
        values = self.singular_values(np.zeros(self.n) if phi is None else phi)
        return self.n - int(np.sum(values > rtol * values[0]))

    def close(self, phi: ArrayLike, driver: int | None, max_iterations: int = 30) -> NDArray[np.float64]:
        """Joint angles that close the loop with joint ``driver`` held at ``phi[driver]`` (Gauss-Newton).

        With ``driver=None`` every joint is free and the minimum-norm steps end at a closing pose near
        ``phi`` (on a mobile loop's motion, or an isolated assembly, ``docs/formulation.md`` (L6)).
        Raises :class:`kinematics.dh.LoopClosureError` if the residual does not fall below
        :data:`CLOSURE_TOLERANCE` (relative to :attr:`scale`).
        """
        phi = self._angles(phi).copy()
        free = np.array([i for i in range(self.n) if i != driver])
        weights = self.residual_weights
        # With every joint free the Jacobian of a mobile loop is singular: its round-off singular values,
        # inverted, would throw the pose along the kernel, so they are cut by the rank rule of mobility.
        rcond = None if driver is not None else RANK_RTOL
        converged = False
        for _ in range(max_iterations):
            transforms = self.link_transforms(phi)  # once per iteration, for the residual and the Jacobian
            residual = weights * _residual(transforms[self.n])
            jacobian = weights[:, None] * self._jacobian(transforms)[:, free]
            step, *_ = np.linalg.lstsq(jacobian, -residual, rcond=rcond)
            phi[free] += step
            if converged:  # one more (quadratically convergent) step puts the residual at round-off
                return phi
            converged = bool(np.max(np.abs(residual)) <= CLOSURE_TOLERANCE)
        held = f"with joint {driver} at {np.degrees(phi[driver]):.6g} deg" if driver is not None else "with all free"
        raise LoopClosureError(
            f"the loop does not close {held}: residual "
            f"{np.max(np.abs(weights * self.closure_residual(phi))):.3e} after {max_iterations} Gauss-Newton "
            "iterations (the drive may have passed a dead point; take smaller steps)"
        )

    def _angles(self, phi: ArrayLike) -> NDArray[np.float64]:
        phi = np.asarray(phi, dtype=float)
        if phi.shape != (self.n,):
            raise ValueError(f"expected {self.n} joint angles, got shape {phi.shape}")
        if not np.all(np.isfinite(phi)):
            raise ValueError(f"joint angles contain NaN or infinity: {phi}")
        return phi


@dataclass(frozen=True)
class LoopMotion:
    """A loop's motion sampled at driver angles: joint rotations from home and closure quality.

    ``phi`` is ``(m, n)`` (rad, from the home pose), ``driver_angles`` ``(m,)`` (rad, joint
    ``driver``'s rotation from home), ``residual`` the largest closure residual per pose
    (relative to the loop's size), ``singular_values`` the closure Jacobian's per pose.
    """

    loop: SingleLoop
    driver: int
    driver_angles: NDArray[np.float64]
    phi: NDArray[np.float64]
    residual: NDArray[np.float64]
    singular_values: NDArray[np.float64]

    @property
    def singularity_measure(self) -> NDArray[np.float64]:
        """Smallest singular value that a 1-dof loop keeps, over the largest, per pose (0: singular)."""
        return self.singular_values[:, self.loop.n - 2] / self.singular_values[:, 0]

    def link_transforms(self) -> NDArray[np.float64]:
        """Displacements of every link at every pose, ``(m, n, 4, 4)`` (Eq. (L1))."""
        return np.array([self.loop.link_transforms(phi)[: self.loop.n] for phi in self.phi])

    def path(self, link: int, point: ArrayLike) -> NDArray[np.float64]:
        """Path ``(m, 3)`` of a point fixed to ``link``, given in world coordinates at home."""
        point = np.append(np.asarray(point, dtype=float), 1.0)
        return np.array([(self.loop.link_transforms(phi)[link] @ point)[:3] for phi in self.phi])


def trace_motion(
    loop: SingleLoop,
    driver: int = 0,
    n_poses: int = 360,
    revolution: float = 2.0 * np.pi,
    start: ArrayLike | None = None,
    fold_tolerance: float = 1e-3,
    endpoint: bool = False,
) -> LoopMotion:
    r"""The loop's motion over ``revolution`` of joint ``driver``, at ``n_poses`` equal steps (Eq. (L4)).

    ``start`` are closing joint angles to start from (default: home, all zero). With ``endpoint`` the
    last pose is at the end of ``revolution`` (as :func:`numpy.linspace`); ``revolution`` may be
    negative. See :func:`follow_driver` for the method and the errors.
    """
    if n_poses < 2:
        raise ValueError(f"n_poses must be at least 2, got {n_poses}")
    first = 0.0 if start is None else float(np.asarray(start, dtype=float)[driver])
    angles = first + np.linspace(0.0, revolution, n_poses, endpoint=endpoint)
    return follow_driver(loop, driver, angles, start, fold_tolerance=fold_tolerance)


def follow_driver(
    loop: SingleLoop,
    driver: int,
    angles: ArrayLike,
    start: ArrayLike | None = None,
    max_step: float = np.radians(2.0),
    fold_tolerance: float = 1e-3,
) -> LoopMotion:
    r"""The loop's poses with joint ``driver`` at each of ``angles`` (rad from home), in order (Eq. (L4)).

    The motion is followed continuously from ``start`` (closing joint angles, default home) through
    the angles in the given order, in steps of at most ``max_step``. Each step predicts along the
    kernel of the closure Jacobian (the tangent of the motion, scaled so that the driver advances by
    the step), then closes the loop by Gauss-Newton with the driver held (:meth:`SingleLoop.close`);
    a step that does not close is halved up to six times.

    Raises :class:`LoopFoldError` at a dead point of the driver (its share of the tangent below
    ``fold_tolerance``, or no closure within 1/64 of a step: drive another joint) and
    ``ValueError`` when the loop is not mobile at the start (first-order mobility 0).
    """
    if not 0 <= driver < loop.n:
        raise ValueError(f"driver must be a joint index 0..{loop.n - 1}, got {driver}")
    angles = np.asarray(angles, dtype=float)
    if angles.ndim != 1 or angles.size == 0 or not np.all(np.isfinite(angles)) or not max_step > 0.0:
        raise ValueError(
            f"angles must be a non-empty 1-D array of finite driver angles (rad), got shape {angles.shape}"
        )
    phi = np.zeros(loop.n) if start is None else loop.close(np.asarray(start, dtype=float), driver)
    if loop.mobility(phi) < 1:
        raise ValueError(
            "the loop is rigid: its closure Jacobian has full rank at the start, so no joint can move "
            "(check the axes, or use kinematics.rigid_mobility to see how far it is from moving)"
        )
    tangent = _tangent(loop, phi, driver, None, fold_tolerance)
    poses = []
    for target in angles:
        pieces = max(1, int(np.ceil(abs(target - phi[driver]) / max_step)))
        start_angle = phi[driver]
        for k in range(1, pieces + 1):
            phi, tangent = _advance(
                loop, phi, tangent, driver, start_angle + (target - start_angle) * k / pieces, fold_tolerance
            )
        poses.append(phi.copy())
    joint_angles = np.array(poses)
    weights = loop.residual_weights
    residual = np.array([np.max(np.abs(weights * loop.closure_residual(p))) for p in joint_angles])
    values = np.array([loop.singular_values(p) for p in joint_angles])
    return LoopMotion(loop, driver, joint_angles[:, driver], joint_angles, residual, values)


def _tangent(
    loop: SingleLoop, phi: NDArray, driver: int, previous: NDArray | None, fold_tolerance: float
) -> NDArray[np.float64]:
    """Kernel vector of the closure Jacobian, oriented like ``previous`` (or driver forward), driver share 1."""
    jacobian = loop.jacobian(phi)
    jacobian[:3] /= loop.scale
    kernel = np.linalg.svd(jacobian)[2][-1]
    if previous is not None and kernel @ previous < 0.0 or previous is None and kernel[driver] < 0.0:
        kernel = -kernel
    if abs(kernel[driver]) < fold_tolerance:
        raise LoopFoldError(
            f"joint {driver} cannot turn further at {np.degrees(phi[driver]):.4g} deg from home: the motion "
            f"folds back there (the joint's share of the motion is {abs(kernel[driver]):.2e}); drive another joint"
        )
    return kernel / kernel[driver]


def _advance(
    loop: SingleLoop, phi: NDArray, tangent: NDArray, driver: int, target: float, fold_tolerance: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """From ``phi`` to the closing pose with the driver at ``target``, halving the step if needed.

    When even 1/64 of the step does not close, the driver has reached a dead point between the last
    closed pose and the next: :class:`LoopFoldError`, naming the last angle reached.
    """
    pieces = 1
    reached, reached_tangent = phi, tangent
    while pieces <= 64:
        current, current_tangent = phi, tangent
        try:
            for k in range(1, pieces + 1):
                goal = phi[driver] + (target - phi[driver]) * k / pieces
                guess = current + (goal - current[driver]) * current_tangent
                guess[driver] = goal
                current = loop.close(guess, driver)
                current_tangent = _tangent(loop, current, driver, current_tangent, fold_tolerance)
            return current, current_tangent
        except LoopClosureError:
            if abs(current[driver] - phi[driver]) > abs(reached[driver] - phi[driver]):
                reached, reached_tangent = current, current_tangent
            pieces *= 2
    share = 1.0 / float(np.linalg.norm(reached_tangent))
    raise LoopFoldError(
        f"joint {driver} cannot turn further than {np.degrees(reached[driver]):.4g} deg from home: the loop does "
        f"not close beyond it (a dead point: the joint's share of the motion has fallen to {share:.2e}); "
        "drive another joint"
    )


def joint_rates(loop: SingleLoop, phi: ArrayLike, driver: int, fold_tolerance: float = 1e-3) -> NDArray[np.float64]:
    r"""Eq. (L9): the joint rates :math:`|d\varphi_k / d\varphi_{\mathrm{driver}}|` at the closing pose ``phi``,
    the kernel of the closure Jacobian (L3) scaled to the driver's share 1. :class:`LoopFoldError` at a dead point
    of the driver (its share of the unit kernel below ``fold_tolerance``)."""
    return np.abs(_tangent(loop, loop._angles(phi), driver, None, fold_tolerance))


@dataclass(frozen=True)
class RateProfile:
    r"""How fast the rigid loop's joints turn against its driver along a motion (Eq. (L9)).

    ``driver_angles`` (rad from home, in the order of travel), ``ratios`` the largest
    :math:`|d\varphi_k / d\varphi_{\mathrm{driver}}|` there and ``fastest`` that joint ``k``.
    """

    driver_angles: NDArray[np.float64]
    ratios: NDArray[np.float64]
    fastest: NDArray[np.int64]

    def largest(self, angle_from: float, angle_to: float) -> tuple[float, int, float]:
        """``(ratio, joint, driver angle)`` of the fastest sample among those bracketing the driver's travel from
        ``angle_from`` to ``angle_to`` (the samples just outside count too: between two samples the ratio may come
        near the larger one; past the profile's ends, its end samples)."""
        sign = 1.0 if self.driver_angles[-1] >= self.driver_angles[0] else -1.0
        travel = sign * (self.driver_angles - self.driver_angles[0])
        low, high = sorted((sign * (angle_from - self.driver_angles[0]), sign * (angle_to - self.driver_angles[0])))
        first = max(0, int(np.searchsorted(travel, low, side="right")) - 1)
        last = max(first, min(len(travel) - 1, int(np.searchsorted(travel, high, side="left"))))
        k = first + int(np.argmax(self.ratios[first : last + 1]))
        return float(self.ratios[k]), int(self.fastest[k]), float(self.driver_angles[k])


def rate_profile(
    loop: SingleLoop,
    driver: int,
    start: ArrayLike,
    turn: float,
    max_joint_step: float = np.radians(0.25),
    max_driver_step: float = np.radians(1.0),
    fold_tolerance: float = 1e-3,
) -> RateProfile:
    r"""The :class:`RateProfile` of the motion from the closing pose near ``start`` over ``turn`` (rad, signed) of
    joint ``driver``, traced as (L4) in steps that turn the fastest joint by at most ``max_joint_step`` and the
    driver by at most ``max_driver_step``, so that a sharp peak of the ratios (a near-dead point) is sampled."""
    if not (max_joint_step > 0.0 and max_driver_step > 0.0 and np.isfinite(turn)):
        raise ValueError(
            f"max_joint_step and max_driver_step must be > 0 rad and turn finite, got {max_joint_step}, "
            f"{max_driver_step}, {turn}"
        )
    phi = loop.close(np.asarray(start, dtype=float), driver)
    tangent = _tangent(loop, phi, driver, None, fold_tolerance)
    first, sign = float(phi[driver]), 1.0 if turn >= 0.0 else -1.0
    angles, ratios, fastest = [first], [float(np.abs(tangent).max())], [int(np.argmax(np.abs(tangent)))]
    while sign * (angles[-1] - first) < abs(turn) * (1.0 - 1e-12):
        step = min(max_driver_step, max_joint_step / ratios[-1])
        target = first + sign * min(abs(turn), sign * (angles[-1] - first) + step)
        phi, tangent = _advance(loop, phi, tangent, driver, target, fold_tolerance)
        angles.append(float(phi[driver]))
        ratios.append(float(np.abs(tangent).max()))
        fastest.append(int(np.argmax(np.abs(tangent))))
    return RateProfile(np.array(angles), np.array(ratios), np.array(fastest, dtype=np.int64))


def _stacked_transforms(loop: SingleLoop, phi: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    r"""Rotations ``(m, n + 1, 3, 3)`` and translations ``(m, n + 1, 3)`` of Eq. (L1) for ``m`` poses at once
    (:meth:`SingleLoop.link_transforms`, row by row)."""
    points, directions = loop._axis_arrays
    m, n = phi.shape
    rotations = Rotation.from_rotvec((phi[:, :, None] * directions[None]).reshape(-1, 3)).as_matrix()
    rotations = rotations.reshape(m, n, 3, 3)
    shifts = points[None] - (rotations @ points[None, :, :, None])[..., 0]
    rotation, translation = np.empty((m, n + 1, 3, 3)), np.empty((m, n + 1, 3))
    rotation[:, 0], translation[:, 0] = np.eye(3), 0.0
    for i in range(n):
        rotation[:, i + 1] = rotation[:, i] @ rotations[:, i]
        translation[:, i + 1] = (rotation[:, i] @ shifts[:, i, :, None])[..., 0] + translation[:, i]
    return rotation, translation


def _stacked_jacobian(loop: SingleLoop, rotation: NDArray, translation: NDArray) -> NDArray[np.float64]:
    """Eq. (L3) for ``m`` poses at once, ``(m, 6, n)`` (:meth:`SingleLoop.jacobian`, row by row)."""
    points, directions = loop._axis_arrays
    n = loop.n
    direction = (rotation[:, :n] @ directions[None, :, :, None])[..., 0]
    point = (rotation[:, :n] @ points[None, :, :, None])[..., 0] + translation[:, :n]
    moment = np.cross(point, direction)
    jacobian = np.empty((len(rotation), 6, n))
    jacobian[:, :3] = np.swapaxes(np.cross(direction, translation[:, n, None, :]) + moment, 1, 2)
    jacobian[:, 3:] = np.swapaxes(direction, 1, 2)
    return jacobian


def close_near(
    loop: SingleLoop,
    driver: int,
    seeds: ArrayLike,
    angles: ArrayLike,
    tangents: ArrayLike | None = None,
    max_iterations: int = 30,
) -> NDArray[np.float64]:
    r"""Closing joint angles ``(m, n)`` with joint ``driver`` at ``angles`` ``(m,)`` (rad from home), each found from
    the closing pose ``seeds[i]`` nearby (a sample of :func:`follow_driver`; a step of a few degrees at most), all
    at once: one predictor along the kernel of the seed's closure Jacobian, then Gauss-Newton with the driver held
    (Eq. (L4), as :meth:`SingleLoop.close`, to :data:`CLOSURE_TOLERANCE` and one step more).

    Raises :class:`kinematics.dh.LoopClosureError` when a pose does not close (a dead point between the seed and
    its angle: seeds from a closer sample are needed). ``tangents``: the seeds' :func:`motion_tangents`, when
    known (several angles from one seed)."""
    seeds = np.asarray(seeds, dtype=float)
    angles = np.asarray(angles, dtype=float)
    if seeds.ndim != 2 or seeds.shape[1] != loop.n or angles.shape != (len(seeds),):
        raise ValueError(f"expected seeds (m, {loop.n}) and angles (m,), got {seeds.shape} and {angles.shape}")
    weights = loop.residual_weights
    free = np.array([i for i in range(loop.n) if i != driver])
    tangents = motion_tangents(loop, driver, seeds) if tangents is None else np.asarray(tangents, dtype=float)
    phi = seeds + (angles - seeds[:, driver])[:, None] * tangents
    phi[:, driver] = angles
    converged = np.zeros(len(phi), dtype=bool)
    for _ in range(max_iterations):
        rotation, translation = _stacked_transforms(loop, phi)
        residual = np.concatenate(
            [translation[:, loop.n], Rotation.from_matrix(rotation[:, loop.n]).as_rotvec()], axis=1
        )
        residual *= weights
        jacobian = weights[:, None] * _stacked_jacobian(loop, rotation, translation)[:, :, free]
        # Gauss-Newton by the normal equations: with the driver held, a loop that moves keeps n - 1 independent
        # columns away from its dead points, and the step only has to converge, the residual is evaluated exactly.
        transposed = np.swapaxes(jacobian, 1, 2)
        phi[:, free] -= np.linalg.solve(transposed @ jacobian, transposed @ residual[:, :, None])[:, :, 0]
        if np.all(converged):  # one more (quadratically convergent) step puts every residual at round-off
            return phi
        converged = np.max(np.abs(residual), axis=1) <= CLOSURE_TOLERANCE
    worst = int(np.argmin(converged))
    raise LoopClosureError(
        f"the loop does not close with joint {driver} at {np.degrees(angles[worst]):.6g} deg from the pose at "
        f"{np.degrees(seeds[worst, driver]):.6g} deg after {max_iterations} Gauss-Newton iterations (a dead point "
        "between them; start from a closer pose)"
    )


def motion_tangents(loop: SingleLoop, driver: int, phi: ArrayLike) -> NDArray[np.float64]:
    """Tangents ``(m, n)`` of the motion at closing poses ``phi`` ``(m, n)``: the kernel of the closure Jacobian
    (Eq. (L3), lengths over :attr:`SingleLoop.scale`), scaled so that the driver's share is 1."""
    phi = np.atleast_2d(np.asarray(phi, dtype=float))
    jacobian = _stacked_jacobian(loop, *_stacked_transforms(loop, phi))
    jacobian[:, :3] /= loop.scale
    kernel = np.linalg.svd(jacobian)[2][:, -1]
    return kernel / kernel[:, driver : driver + 1]


def point_paths(loop: SingleLoop, phi: ArrayLike, link: int, point: ArrayLike) -> NDArray[np.float64]:
    """Positions ``(m, 3)`` of a point fixed to ``link`` (world coordinates at home) at the poses ``phi`` ``(m, n)``
    (:meth:`LoopMotion.path`, all poses at once)."""
    rotation, translation = _stacked_transforms(loop, np.atleast_2d(np.asarray(phi, dtype=float)))
    return rotation[:, link] @ np.asarray(point, dtype=float) + translation[:, link]
