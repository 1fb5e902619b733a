r"""Other assemblies of a loop's links near its motion: isolated (rigid) solutions of the closure.

The closure (L2) of an ``n``-joint loop is six equations :math:`F(\varphi) = 0` in ``n`` joint
angles. For a mobile loop its real solutions are the traced motion curve, possibly other curves
(branches through a bifurcation, a second assembly mode), and isolated points: assemblies of the
same links that cannot move, where the closure Jacobian :math:`J = \partial F/\partial\varphi`
(L3) has full rank ``n`` (``docs/formulation.md``, (L6)). Printed 6R prototypes snap to such
points when they lie near the motion (paper, Discussion).

They are found by Levenberg-Marquardt on (L2) from seeded random perturbations of the curve's
poses, polished by Gauss-Newton to round-off (:meth:`SingleLoop.close` with every joint free),
de-duplicated modulo :math:`2\pi` and classified by the rank of :math:`J` and by their joint-space
distance to the traced curve (L7). Rational Linkages has no tool for this: its
``singularity_check`` is a symbolic test of the motion curve itself, and its kinematics evaluate
the motion polynomial, which holds only the curve.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from .dh import LoopClosureError, wrap_angle
from .single_loop import RANK_RTOL, LoopMotion, SingleLoop, _tangent

__all__ = ["Assembly", "NearbyAssemblies", "nearby_assemblies", "solve_closure"]

#: Verdicts of (L7) off the traced motion: isolated (rigid), or a point of another mobile branch.
KINDS = ("isolated", "branch")


@dataclass(frozen=True)
class Assembly:
    """One closing pose off (or on) the traced motion and its relation to the motion (L7).

    ``phi``: joint angles (rad from home, in ``(-pi, pi]``); ``kind``: one of :data:`KINDS`;
    ``rank``: rank of the closure Jacobian; ``smallest_singular``: its smallest singular value over
    the largest (lengths over the loop's size); ``nearest``: the closing pose of the motion nearest in
    joint space, ``driver_angle`` its driver angle (rad); ``distance_max`` / ``distance_rms``: largest
    and RMS joint-angle difference to it (rad); ``gap_translation`` (m) / ``gap_rotation`` (rad): the
    largest closure residual on the straight joint-space path from ``nearest`` to ``phi`` (L8);
    ``curve_singular``: the motion's singularity measure at ``nearest``; ``hits``: starts that ended here.
    """

    phi: NDArray[np.float64]
    kind: str
    rank: int
    smallest_singular: float
    nearest: NDArray[np.float64]
    driver_angle: float
    distance_max: float
    distance_rms: float
    gap_translation: float
    gap_rotation: float
    curve_singular: float
    hits: int

    def as_dict(self) -> dict[str, object]:
        """JSON-ready fields (angles in rad, lengths in m)."""
        return {
            "kind": self.kind,
            "phi_rad": self.phi.tolist(),
            "rank": self.rank,
            "smallest_singular_value": self.smallest_singular,
            "nearest_motion_phi_rad": self.nearest.tolist(),
            "driver_angle_rad": self.driver_angle,
            "distance_max_rad": self.distance_max,
            "distance_rms_rad": self.distance_rms,
            "gap_translation_m": self.gap_translation,
            "gap_rotation_rad": self.gap_rotation,
            "curve_singularity_measure": self.curve_singular,
            "hits": self.hits,
        }


@dataclass(frozen=True)
class NearbyAssemblies:
    """Every distinct closing pose off the motion found from ``starts`` perturbed poses, nearest first.

    ``converged``: starts that closed the loop; ``on_motion``: of those, the ones that ended on the
    traced motion; ``seed``, ``spread`` (rad): the perturbation (:func:`nearby_assemblies`).
    """

    assemblies: tuple[Assembly, ...]
    starts: int
    converged: int
    on_motion: int
    seed: int
    spread: float

    def of_kind(self, kind: str) -> tuple[Assembly, ...]:
        """The assemblies classified ``kind`` (one of :data:`KINDS`)."""
        if kind not in KINDS:
            raise ValueError(f"unknown kind {kind!r}; choose one of {', '.join(KINDS)}")
        return tuple(a for a in self.assemblies if a.kind == kind)

    @property
    def isolated(self) -> tuple[Assembly, ...]:
        return self.of_kind("isolated")


def _rotation_vector_jacobian(loop: SingleLoop, phi: NDArray[np.float64]) -> NDArray[np.float64]:
    r"""Weighted derivative of :meth:`SingleLoop.closure_residual`, exact also where the loop is open.

    (L3)'s rotation rows are the spatial angular velocities :math:`l_i`; the rotation vector
    :math:`\theta` of the loop product moves with :math:`J_l^{-1}(\theta)\, l_i` (inverse left
    Jacobian of SO(3)), which is the identity only at closure. Levenberg-Marquardt starts far from
    closure, where the difference decides whether it converges.
    """
    transforms = loop.link_transforms(phi)
    jacobian = loop._jacobian(transforms)
    residual = loop.closure_residual(phi)
    theta = residual[3:]
    angle = float(np.linalg.norm(theta))
    if angle > 1e-8:
        cross = np.array([[0.0, -theta[2], theta[1]], [theta[2], 0.0, -theta[0]], [-theta[1], theta[0], 0.0]])
        factor = 1.0 / angle**2 - (1.0 + np.cos(angle)) / (2.0 * angle * np.sin(angle))
        jacobian[3:] = (np.eye(3) - 0.5 * cross + factor * cross @ cross) @ jacobian[3:]
    return loop.residual_weights[:, None] * jacobian


def solve_closure(loop: SingleLoop, start: ArrayLike) -> NDArray[np.float64] | None:
    """A closing pose from ``start``: Levenberg-Marquardt, then Gauss-Newton to round-off; None if none."""
    weights = loop.residual_weights
    fit = least_squares(
        lambda phi: weights * loop.closure_residual(phi),
        start,
        jac=lambda phi: _rotation_vector_jacobian(loop, phi),
        method="lm",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=200,
    )
    if not np.all(np.isfinite(fit.x)) or np.max(np.abs(fit.fun)) > 1e-6:
        return None  # a local minimum of the misfit, not a closure
    try:
        return wrap_angle(loop.close(fit.x, driver=None))
    except LoopClosureError:
        return None


def _on_motion(motion: LoopMotion, phi: NDArray[np.float64], tolerance: float) -> bool:
    """Whether the motion's pose at ``phi``'s driver angle is ``phi`` (RMS below ``tolerance``, rad).

    One Gauss-Newton closure from the trace interpolated at that angle: the driver of a traced
    revolution passes each angle once, so the motion has one pose there.
    """
    angles, driver = motion.driver_angles, motion.driver
    angle = angles[0] + np.mod(phi[driver] - angles[0], 2.0 * np.pi)
    k = min(int(np.searchsorted(angles, angle, side="right")) - 1, angles.size - 1)
    following = motion.phi[(k + 1) % angles.size]
    step = wrap_angle(following - motion.phi[k])
    share = (angle - angles[k]) / step[driver] if step[driver] != 0.0 else 0.0
    guess = motion.phi[k] + share * step
    guess[driver] = phi[driver]
    try:
        pose = motion.loop.close(guess, driver)
    except LoopClosureError:
        return False
    return bool(np.sqrt(np.mean(wrap_angle(phi - pose) ** 2)) < tolerance)


def _nearest_on_motion(motion: LoopMotion, phi: NDArray[np.float64]) -> tuple[NDArray[np.float64], int]:
    r"""Closing pose :math:`c(\theta)` of ``motion`` nearest to ``phi`` in joint space, and the nearest traced pose.

    The traced poses (one revolution of the driver) are joined by straight segments, the last back to
    the first; the nearest point of that polyline, closed at its driver angle, starts Gauss-Newton on
    the distance along the motion's tangent :math:`\tau = dc/d\theta` (driver share 1, (L4)):
    :math:`\theta \leftarrow \theta + \tau\cdot(\varphi - c)/|\tau|^2`. The polyline alone is off the
    curve by its sagitta (1e-5 rad at 0.5 deg steps), too coarse to tell a motion pose from a branch.
    """
    loop, driver, poses = motion.loop, motion.driver, motion.phi
    steps = wrap_angle(np.roll(poses, -1, axis=0) - poses)
    offsets = wrap_angle(phi - poses)  # phi relative to each traced pose, the short way round
    lengths = np.einsum("ij,ij->i", steps, steps)
    s = np.clip(np.einsum("ij,ij->i", offsets, steps) / np.where(lengths > 0.0, lengths, 1.0), 0.0, 1.0)
    k = int(np.argmin(np.linalg.norm(offsets - s[:, None] * steps, axis=1)))
    nearest = loop.close(poses[k] + s[k] * steps[k], driver)
    tangent = None
    for _ in range(30):
        tangent = _tangent(loop, nearest, driver, tangent, fold_tolerance=0.0)
        shift = float(wrap_angle(phi - nearest) @ tangent / (tangent @ tangent))
        nearest = loop.close(nearest + shift * tangent, driver)
        if abs(shift) < 1e-13:
            break
    return wrap_angle(nearest), k


def _gap(loop: SingleLoop, start: NDArray, end: NDArray, samples: int = 32) -> tuple[float, float]:
    """Largest translation (m) and rotation (rad) residual of (L2) on the straight path ``start`` -> ``end`` (L8)."""
    step = wrap_angle(end - start)
    residuals = np.array([loop.closure_residual(start + s * step) for s in np.linspace(0.0, 1.0, samples + 1)])
    translation, rotation = np.linalg.norm(residuals[:, :3], axis=1), np.linalg.norm(residuals[:, 3:], axis=1)
    return float(np.max(translation)), float(np.max(rotation))


def nearby_assemblies(
    motion: LoopMotion,
    starts: int = 200,
    spread: float = 1.0,
    seed: int = 0,
    motion_tolerance: float = 1e-6,
    duplicate_tolerance: float = 1e-7,
) -> NearbyAssemblies:
    r"""Closing poses of ``motion.loop`` off its traced ``motion``, from perturbed poses of it, classified (L6), (L7).

    ``motion`` is one revolution of a driver that turns fully (:func:`kinematics.trace_motion`). Each
    start is a traced pose (chosen uniformly, seeded by ``seed``) plus independent normal perturbations
    of every joint angle with standard deviation ``spread`` (rad) times a uniform factor in (0, 1], so
    small and large perturbations are both tried. A closing pose whose RMS joint-space distance to the
    motion is below ``motion_tolerance`` (rad) and whose Jacobian is rank-deficient is counted as
    ``on_motion``; the others, one per ``duplicate_tolerance`` (rad, modulo :math:`2\pi`), are
    ``isolated`` (Jacobian of rank ``n``: :data:`kinematics.single_loop.RANK_RTOL`) or ``branch``.
    """
    loop, angles = motion.loop, motion.driver_angles
    if starts < 1 or not (np.isfinite(spread) and spread > 0.0):
        raise ValueError(f"need starts >= 1 and a positive finite spread (rad), got {starts} and {spread}")
    span = float(np.degrees(angles[-1] - angles[0]))
    if angles.size < 8 or np.any(np.diff(angles) <= 0.0) or span < 360.0 * (1.0 - 1.5 / angles.size):
        raise ValueError(
            f"motion must be one revolution of joint {motion.driver} in increasing angle, at 8 poses or more "
            f"(trace_motion(loop, driver, n_poses)); got {angles.size} poses over {span:.4g} deg"
        )
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, motion.phi.shape[0], size=starts)
    sizes = spread * (1.0 - rng.random(starts))
    perturbations = rng.standard_normal((starts, loop.n)) * sizes[:, None]
    assemblies: list[Assembly] = []
    converged = on_motion = 0
    for pick, perturbation in zip(picks, perturbations, strict=True):
        phi = solve_closure(loop, motion.phi[pick] + perturbation)
        if phi is None:
            continue
        converged += 1
        known = [j for j, a in enumerate(assemblies) if np.max(np.abs(wrap_angle(phi - a.phi))) < duplicate_tolerance]
        if known:
            assemblies[known[0]] = replace(assemblies[known[0]], hits=assemblies[known[0]].hits + 1)
            continue
        values = loop.singular_values(phi)
        rank = int(np.sum(values > RANK_RTOL * values[0]))
        if rank < loop.n and _on_motion(motion, phi, motion_tolerance):
            on_motion += 1
            continue
        nearest, k = _nearest_on_motion(motion, phi)
        difference = wrap_angle(phi - nearest)
        rms = float(np.sqrt(np.mean(difference**2)))
        if rank < loop.n and rms < motion_tolerance:
            on_motion += 1
            continue
        gap = _gap(loop, nearest, phi)
        assemblies.append(
            Assembly(
                phi=phi,
                kind="isolated" if rank == loop.n else "branch",
                rank=rank,
                smallest_singular=float(values[-1] / values[0]),
                nearest=nearest,
                driver_angle=float(nearest[motion.driver]),
                distance_max=float(np.max(np.abs(difference))),
                distance_rms=rms,
                gap_translation=gap[0],
                gap_rotation=gap[1],
                curve_singular=float(motion.singularity_measure[k]),
                hits=1,
            )
        )
    assemblies.sort(key=lambda a: a.distance_rms)
    return NearbyAssemblies(tuple(assemblies), starts, converged, on_motion, seed, spread)
