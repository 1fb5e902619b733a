r"""Applied forces: spring-dampers and bushings between markers, loads on markers, torque drives.

An element adds generalized forces :math:`Q_e(q, \dot q, t)` to the bodies' applied forces of Eq. (G1)
(``docs/formulation.md``, Sect. "Force elements and loads", Eqs. (E1)-(E5)):

* :class:`SpringDamperJoint`: a joint (:class:`~ffrf.system.joints.MarkerJoint`) made compliant, its
  equations :math:`g` held by :math:`f = K(g - g_0) + D\,C_q\dot q` instead of multipliers,
  :math:`Q = -C_q^Tf` (E1), with the potential :math:`\tfrac12 (g - g_0)^TK(g - g_0)` (E2). A joint locking
  three translations gives Exudyn's ``CartesianSpringDamper`` (world components of :math:`p_1 - p_0`); a
  revolute joint, a bushing (the five locked directions compliant); all six, a rigid-body spring-damper for
  small relative rotations.
* :class:`MarkerLoad`: a force and a torque on a marker, constant or functions of time, in the world or the
  marker frame: :math:`Q = G_p^TF + G_\omega^TM` (E3), with the marker's position and angular velocity
  Jacobians (E4).
* :class:`JointTorque`: a torque about a joint's z axis between its two markers, a function of time, the
  relative angle and the relative angular speed (a motor's torque-speed curve) (E5).
* :class:`AxialSpringDamper`: a spring-damper along the line between two marker points (E6), Exudyn's
  ``SpringDamper``; geometrically nonlinear (a truss of them can snap through).

Tangents :math:`\partial Q/\partial q` and :math:`\partial Q/\partial\dot q` for the iteration matrix are
exact (complex-step differentiation) for elements whose functions are analytic (``complex_safe``); a
user's function (a load's time law, a torque curve) is differentiated by central differences.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.system.joints import GroundFrame, MarkerJoint, joint_side
from ffrf.system.markers import BodyMarker

__all__ = [
    "AxialSpringDamper",
    "ForceElement",
    "JointTorque",
    "MarkerLoad",
    "SpringDamperJoint",
    "assembled_forces",
    "assembled_tangents",
    "element_tangents",
    "marker_jacobians",
    "spring_damper",
    "tangent_rates",
]

Vector = Callable[[float], ArrayLike]
StateVector = Callable[[float, NDArray, NDArray], ArrayLike]


@dataclass(frozen=True, eq=False)
class ForceElement:
    """Base: ``bodies`` whose coordinates the element reads and loads; ``complex_safe``: its forces are analytic
    in ``q`` and ``qd`` (exact complex-step tangents), else central differences."""

    bodies: tuple[int, ...]
    name: str

    @property
    def complex_safe(self) -> bool:
        return True

    @property
    def reads_velocities(self) -> bool:
        """Whether the forces depend on ``qd`` (else their ``qd`` tangent is zero and not differentiated)."""
        return True

    @property
    def conservative(self) -> bool:
        """Whether the forces are minus the gradient of :meth:`potential_energy` (a spring without damper): their work
        over any motion is then the decrease of that energy, exactly."""
        return False

    @property
    def separates(self) -> bool:
        """Whether the element can let go of what it holds (a contact with play): a quasi-static path may then jump
        where a load through it reverses."""
        return False

    def forces(self, blocks: list[NDArray], velocities: list[NDArray], t: float) -> list[NDArray]:
        """Generalized forces ``Q`` on each body of ``bodies`` (added to the applied forces of Eq. (G1))."""
        raise NotImplementedError  # pragma: no cover - abstract

    def tangents(
        self, blocks: list[NDArray], velocities: list[NDArray], t: float
    ) -> tuple[list[list[NDArray]], list[list[NDArray]]]:
        r""":math:`\partial Q/\partial q` and :math:`\partial Q/\partial\dot q` as blocks ``[i][j]``; by default
        :func:`element_tangents` (complex steps of :meth:`forces`), an element with analytic ones overrides it."""
        return element_tangents(self, blocks, velocities, t)

    def potential_energy(self, blocks: list[NDArray], t: float) -> float:
        """Energy stored in the element (J); zero for loads and drives."""
        return 0.0

    def load_potential(self, blocks: list[NDArray], t: float) -> float:
        """Potential of the element's load at fixed ``t`` (J), whose decrease is the load's work in a motion at that
        ``t`` (a snap's jump, Eq. (S6)); zero for elements whose load has none (springs store theirs in
        :meth:`potential_energy`; drives, follower and state-dependent loads are not conservative)."""
        return 0.0


def marker_jacobians(marker: BodyMarker | GroundFrame, q: NDArray | None) -> tuple[NDArray, NDArray, Any, Any]:
    r"""Point, axes (columns) and Eq. (E4)'s Jacobians :math:`G_p = \partial r/\partial q` and
    :math:`G_\omega` (:math:`\omega = G_\omega\dot q`, world) of a marker; ``None`` Jacobians on the ground."""
    point, axes, d_point, d_axes = joint_side(marker, q, np.eye(3), np.zeros(3))
    if d_point is None:
        return point, axes, None, None
    # omega = 1/2 sum_k a_k x da_k/dt for the orthonormal axes a_k (Eq. (E4))
    omega = 0.5 * sum(np.cross(axes[:, k], d_axes[k], axisa=0, axisb=0, axisc=0) for k in range(3))
    return point, axes, d_point, omega


def tangent_rates(q: NDArray, qd: NDArray) -> NDArray:
    r"""``qd`` with :math:`\dot p` projected onto the tangent of :math:`p\cdot p = 1`, :math:`\dot p - p\,(p\cdot\dot
    p)/(p\cdot p)` (Eq. (E1)): index-3 integration keeps :math:`p\cdot p = 1` but not :math:`p\cdot\dot p = 0`, and
    a damper must not feel that drift (Exudyn's markers leave it out too). Analytic, so complex-safe."""
    out = qd.astype(np.result_type(q, qd))
    p = q[3:7]
    out[3:7] = qd[3:7] - p * ((p @ qd[3:7]) / (p @ p))
    return out


def _takes_state(value: object) -> bool:
    """Whether a load's function reads the state, ``f(t, position, velocity)``, rather than time alone."""
    if not callable(value):
        return False
    required = [
        p
        for p in inspect.signature(value).parameters.values()
        if p.default is p.empty and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
    ]
    return len(required) == 3


def _vector(value: ArrayLike | Vector | StateVector | None, t: float, point=None, velocity=None) -> NDArray:
    if value is None:
        return np.zeros(3)
    if not callable(value):
        return np.asarray(value, dtype=float)
    return np.asarray(value(t, point, velocity) if _takes_state(value) else value(t))  # type: ignore[call-arg]


@dataclass(frozen=True, eq=False)
class SpringDamperJoint(ForceElement):
    r"""Eqs. (E1)-(E2): the equations of ``joint`` held by stiffness ``stiffness`` and damping ``damping``
    (``(size,)`` diagonals or ``(size, size)`` matrices in the units of the joint's equations: N/m and N s/m for
    translations, N m for the rotation equations z0.y1, z0.x1, x0.y1, which are (phi_x, -phi_y, -phi_z) to first
    order) about ``offset`` :math:`g_0`. Translations are world components when the joint locks all three, unless
    its ``frame_translations`` (then, as for a subset, components in joint frame 0: an anisotropic bushing)."""

    joint: MarkerJoint
    stiffness: NDArray[np.float64]
    damping: NDArray[np.float64]
    offset: NDArray[np.float64]

    @property
    def reads_velocities(self) -> bool:
        return bool(np.any(self.damping))

    @property
    def conservative(self) -> bool:
        return not self.reads_velocities

    def _force(self, blocks: list[NDArray], velocities: list[NDArray], t: float):
        rows = self.joint.jacobian(blocks, t)
        rate = sum(r @ tangent_rates(b, v) for r, b, v in zip(rows, blocks, velocities, strict=True))
        return rows, self.stiffness @ (self.joint.value(blocks, t) - self.offset) + self.damping @ rate

    def forces(self, blocks, velocities, t):
        rows, force = self._force(blocks, velocities, t)
        return [-(r.T @ force) for r in rows]

    def potential_energy(self, blocks, t):
        stretch = self.joint.value(blocks, t) - self.offset
        return float(0.5 * stretch @ self.stiffness @ stretch)

    def joint_force(self, blocks: list[NDArray], velocities: list[NDArray], t: float) -> NDArray[np.float64]:
        """The element's force :math:`f` in the units of the joint's equations (the reaction a rigid joint's
        multipliers would carry)."""
        return np.real(self._force(blocks, velocities, t)[1])


@dataclass(frozen=True, eq=False)
class AxialSpringDamper(ForceElement):
    r"""Eq. (E6): a spring-damper along the line between two marker points (Exudyn's ``SpringDamper``):
    :math:`f = k(L - L_0) + c\,\dot L` with :math:`L = |p_1 - p_0|`, pulling the points together when stretched;
    stored energy :math:`\tfrac12 k (L - L_0)^2`. ``marker0`` may be the ground."""

    marker0: BodyMarker | GroundFrame
    marker1: BodyMarker
    stiffness: float
    damping: float
    length: float

    @property
    def reads_velocities(self) -> bool:
        return self.damping != 0.0

    @property
    def conservative(self) -> bool:
        return not self.reads_velocities

    def _sides(self, blocks: list[NDArray], velocities: list[NDArray]):
        q0 = None if isinstance(self.marker0, GroundFrame) else blocks[0]
        p0, _, g0, _ = marker_jacobians(self.marker0, q0)
        p1, _, g1, _ = marker_jacobians(self.marker1, blocks[-1])
        gap = p1 - p0
        rate = g1 @ tangent_rates(blocks[-1], velocities[-1])
        if g0 is not None:
            rate = rate - g0 @ tangent_rates(blocks[0], velocities[0])
        return g0, g1, gap, rate

    def forces(self, blocks, velocities, t):
        g0, g1, gap, rate = self._sides(blocks, velocities)
        length = np.sqrt(gap @ gap)
        unit = gap / length
        pull = (self.stiffness * (length - self.length) + self.damping * (unit @ rate)) * unit
        out = [-(g1.T @ pull)]
        return out if g0 is None else [g0.T @ pull] + out

    def potential_energy(self, blocks, t):
        gap = self._sides(blocks, [np.zeros_like(b) for b in blocks])[2]
        return float(0.5 * self.stiffness * (np.sqrt(gap @ gap) - self.length) ** 2)


def spring_damper(
    joint: MarkerJoint, stiffness: ArrayLike, damping: ArrayLike = 0.0, offset: ArrayLike | None = None
) -> SpringDamperJoint:
    """``joint``'s equations held elastically (Eqs. (E1)-(E2)); scalars and diagonals are spread to matrices."""
    if joint.angle is not None:
        raise ValueError(
            f"spring-damper {joint.name!r}: its joint has a prescribed angle; a spring-damper holds a passive joint's "
            "equations (drive it with a separate driven joint or a JointTorque)"
        )
    n = joint.size

    def matrix(value: ArrayLike, what: str) -> NDArray[np.float64]:
        value = np.asarray(value, dtype=float)
        if value.ndim == 0:
            value = np.full(n, float(value))
        if value.ndim == 1:
            value = np.diag(value)
        if value.shape != (n, n) or not np.all(np.isfinite(value)):
            raise ValueError(
                f"spring-damper {joint.name!r}: {what} must be a number, {n} diagonal values or a {n} x {n} matrix "
                f"(the joint has {n} equations), got shape {value.shape}"
            )
        if not np.allclose(value, value.T, rtol=0.0, atol=1e-12 * max(float(np.abs(value).max()), 1e-300)):
            raise ValueError(f"spring-damper {joint.name!r}: the {what} matrix must be symmetric")
        return value

    g0 = np.zeros(n) if offset is None else np.asarray(offset, dtype=float)
    if g0.shape != (n,):
        raise ValueError(f"spring-damper {joint.name!r}: offset needs {n} values, got shape {g0.shape}")
    return SpringDamperJoint(
        joint.bodies, joint.name, joint, matrix(stiffness, "stiffness"), matrix(damping, "damping"), g0
    )


@dataclass(frozen=True, eq=False)
class MarkerLoad(ForceElement):
    r"""Eq. (E3): force ``force`` (N) and torque ``torque`` (N m) on ``marker``, each a constant vector, a
    function of time ``f(t)`` or of the state ``f(t, position, velocity)`` (the marker point's world position and
    velocity: a payload's drag, a contact), in world axes or, with ``frame="marker"``, in the marker's axes."""

    marker: BodyMarker
    force: ArrayLike | Vector | StateVector | None = None
    torque: ArrayLike | Vector | StateVector | None = None
    frame: str = "world"

    def __post_init__(self):
        if self.frame not in ("world", "marker"):
            raise ValueError(f"load {self.name!r}: frame must be 'world' or 'marker', got {self.frame!r}")

    @property
    def complex_safe(self) -> bool:
        return not (_takes_state(self.force) or _takes_state(self.torque))

    def load_potential(self, blocks, t):
        r""":math:`-F(t)\cdot x` (x the marker point) for a world force that is constant or a function of time alone: at
        fixed t it is a dead load, whose work in any motion is the fall of this potential. A force in the marker's
        axes turns with it and one that reads the state is not conservative, and a torque's work depends on the
        path of the rotation: they have none (0)."""
        if self.force is None or self.frame != "world" or _takes_state(self.force):
            return 0.0
        point = joint_side(self.marker, blocks[0], np.eye(3), np.zeros(3))[0]
        return -float(np.real(_vector(self.force, t) @ point))

    def forces(self, blocks, velocities, t):
        point, axes, g_point, g_omega = marker_jacobians(self.marker, blocks[0])
        velocity = g_point @ tangent_rates(blocks[0], velocities[0])
        force, torque = _vector(self.force, t, point, velocity), _vector(self.torque, t, point, velocity)
        if self.frame == "marker":
            force, torque = axes @ force, axes @ torque
        return [g_point.T @ force + g_omega.T @ torque]


@dataclass(frozen=True, eq=False)
class JointTorque(ForceElement):
    r"""Eq. (E5): torque :math:`\tau(t, \varphi, \dot\varphi)` (N m) about the z axis of ``joint``'s frame on
    marker 0, acting on marker 1 (and its reaction on marker 0), with :math:`\varphi` the relative angle about
    that axis (from the joint's reference pose) and :math:`\dot\varphi` the relative angular speed."""

    joint: MarkerJoint
    torque: Callable[[float, float, float], float]

    @property
    def complex_safe(self) -> bool:
        return False

    def forces(self, blocks, velocities, t):
        j = self.joint
        ground = isinstance(j.marker0, GroundFrame)
        q0, v0 = (None, None) if ground else (blocks[0], velocities[0])
        q1, v1 = blocks[-1], velocities[-1]
        _, axes0, _, g_omega0 = marker_jacobians(j.marker0, q0)
        _, axes1, _, g_omega1 = marker_jacobians(j.marker1, q1)
        frame0, frame1 = axes0 @ j.rotation0, axes1 @ j.rotation1
        axis = frame0[:, 2]
        angle = float(np.arctan2(frame0[:, 1] @ frame1[:, 0], frame0[:, 0] @ frame1[:, 0]))
        speed = axis @ (g_omega1 @ v1 - (0.0 if ground else g_omega0 @ v0))
        moment = float(self.torque(t, angle, float(speed))) * axis
        out = [g_omega1.T @ moment]
        return out if ground else [-(g_omega0.T @ moment)] + out


COMPLEX_STEP = 1e-30


def _shifted(blocks: list[NDArray], j: int, k: int, step: complex | float) -> list[NDArray]:
    out = [b.astype(np.result_type(b, step)) for b in blocks]
    out[j][k] += step
    return out


def element_tangents(
    element: ForceElement, blocks: list[NDArray], velocities: list[NDArray], t: float
) -> tuple[list[list[NDArray]], list[list[NDArray]]]:
    r""":math:`\partial Q/\partial q` and :math:`\partial Q/\partial\dot q` as blocks ``[i][j]`` (body i rows,
    body j columns): complex step (exact) for a ``complex_safe`` element, else central differences."""
    sizes = [b.shape[0] for b in blocks]
    d_q = [[np.zeros((sizes[i], sizes[j])) for j in range(len(blocks))] for i in range(len(blocks))]
    d_qd = [[np.zeros((sizes[i], sizes[j])) for j in range(len(blocks))] for i in range(len(blocks))]
    for target, position in ((d_q, True), (d_qd, False))[: 2 if element.reads_velocities else 1]:
        for j, block in enumerate(blocks if position else velocities):
            for k in range(block.shape[0]):
                if element.complex_safe:
                    if position:
                        columns = element.forces(_shifted(blocks, j, k, 1j * COMPLEX_STEP), velocities, t)
                    else:
                        columns = element.forces(blocks, _shifted(velocities, j, k, 1j * COMPLEX_STEP), t)
                    for i in range(len(blocks)):
                        target[i][j][:, k] = np.imag(columns[i]) / COMPLEX_STEP
                    continue
                h = 1e-7 * max(1.0, abs(float(block[k])))
                if position:
                    plus = element.forces(_shifted(blocks, j, k, h), velocities, t)
                    minus = element.forces(_shifted(blocks, j, k, -h), velocities, t)
                else:
                    plus = element.forces(blocks, _shifted(velocities, j, k, h), t)
                    minus = element.forces(blocks, _shifted(velocities, j, k, -h), t)
                for i in range(len(blocks)):
                    target[i][j][:, k] = (plus[i] - minus[i]) / (2.0 * h)
    return d_q, d_qd


def _element_blocks(element: ForceElement, offsets: NDArray, q: NDArray, qd: NDArray):
    spans = [slice(int(offsets[i]), int(offsets[i + 1])) for i in element.bodies]
    return spans, [q[s] for s in spans], [qd[s] for s in spans]


def assembled_forces(
    elements: tuple[ForceElement, ...], offsets: NDArray, q: NDArray, qd: NDArray, t: float
) -> NDArray[np.float64]:
    """The force elements' generalized forces ``Q`` (Eqs. (E1)-(E5), (P3)) on the whole coordinate vector, the
    bodies' blocks starting at ``offsets``."""
    out = np.zeros(q.shape[0], dtype=np.result_type(q, qd))
    # a diverging Newton iterate overflows here; the solvers test the residual for finiteness and say so in one line
    with np.errstate(over="ignore", invalid="ignore"):
        for element in elements:
            spans, blocks, rates = _element_blocks(element, offsets, q, qd)
            for span, force in zip(spans, element.forces(blocks, rates, t), strict=True):
                out[span] += force
    return out


def assembled_tangents(
    elements: tuple[ForceElement, ...], offsets: NDArray, q: NDArray, qd: NDArray, t: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``dQ/dq`` and ``dQ/dqd`` of :func:`assembled_forces` (n x n), from each element's
    :meth:`ForceElement.tangents`."""
    n = q.shape[0]
    d_q, d_qd = np.zeros((n, n)), np.zeros((n, n))
    with np.errstate(over="ignore", invalid="ignore"):  # as in assembled_forces: the solvers judge finiteness
        for element in elements:
            spans, blocks, rates = _element_blocks(element, offsets, q, qd)
            by_q, by_qd = element.tangents(blocks, rates, t)
            for a, row in enumerate(spans):
                for b, column in enumerate(spans):
                    d_q[row, column] += by_q[a][b]
                    d_qd[row, column] += by_qd[a][b]
    return d_q, d_qd
