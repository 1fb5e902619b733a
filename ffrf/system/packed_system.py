r"""The fast path: a :class:`~ffrf.system.multibody.MultibodySystem` packed into plain arrays once, evaluated by
whole-system numba kernels (:mod:`ffrf.system.system_kernels`) instead of Python loops over bodies and
constraints.

:func:`pack_system` supports plain :class:`~ffrf.body.flexible_body.FlexibleBody` bodies and the
constraints the Bennett scene uses: :class:`~ffrf.system.constraints.EulerNormalization` and
:class:`~ffrf.system.joints.MarkerJoint` (any ``locked`` subset, optional prescribed angle, ground or
body marker 0). Force elements (springs, loads, joints with play) are added to the kernels' residual and iteration
matrix by their own Python methods (:func:`~ffrf.system.forces.assembled_forces`); the fused Newton loops
(``static_iterations``, ``alpha_iterations``) take only systems without them. Anything else, including
*subclasses* of these (which may override ``value`` or ``jacobian``), returns ``None``, and :func:`newton_model`
falls back to the reference implementation, the ``MultibodySystem`` itself, with a debug log line. Both provide the same
Newton pieces, ``residual`` (Eq. (G1)) and ``iteration_matrix`` (Eq. (FP6)), and agree to
round-off (``tests/test_ffrf_body/test_packed_system.py``).

A prescribed angle :math:`\varphi(t)` stays a Python callable; it is evaluated once per time
value (the last one is cached) and passed to the kernels.
"""

from __future__ import annotations

import logging
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ffrf.body.flexible_body import FlexibleBody
from ffrf.system.constraints import EulerNormalization
from ffrf.system.forces import ForceElement, assembled_forces, assembled_tangents
from ffrf.system.joints import GroundFrame, MarkerJoint
from ffrf.system.markers import BodyMarker
from ffrf.system.multibody import MultibodySystem
from ffrf.system.system_kernels import (
    EULER,
    MARKER_JOINT,
    system_body_tangents,
    system_hessian,
    system_iteration_matrix,
    system_jacobian,
    system_mass_matrix,
    system_residual,
)

__all__ = ["PackedSystem", "contiguous", "pack_system", "newton_model"]

log = logging.getLogger(__name__)

# (bodies, joints, q, qd, qdd, lambda, gravity, phi): see PackedSystem._kernel_arguments
_KernelArguments = tuple[
    tuple,
    tuple,
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
]


@dataclass(frozen=True, eq=False)
class PackedSystem:
    """A system as plain arrays (layout in :mod:`ffrf.system.system_kernels`), with the methods of
    :class:`~ffrf.system.multibody.MultibodySystem` that Newton needs, evaluated in single kernel calls."""

    n_coordinates: int
    n_constraints: int
    gravity: NDArray[np.float64]
    bodies: tuple
    joints: tuple
    angles: tuple[Callable[[float], float] | None, ...]
    forces: tuple[ForceElement, ...] = ()
    offsets: NDArray[np.int64] = field(default_factory=lambda: np.zeros(1, dtype=np.int64))
    source: Callable[[], MultibodySystem | None] = field(default=lambda: None, repr=False)
    _last_angles: list = field(default_factory=lambda: [None, None], repr=False)

    def phi(self, t: float) -> NDArray[np.float64]:
        """Each constraint's prescribed angle at ``t`` (0 without one)."""
        if self._last_angles[0] != t:
            values = np.array([0.0 if a is None else float(a(t)) for a in self.angles])
            self._last_angles[:] = [t, values]
        return self._last_angles[1]

    def _kernel_arguments(self, q, qd, qdd, lam, t: float) -> _KernelArguments:
        """The arguments every system kernel starts with: packed bodies and joints, the state as
        contiguous arrays, gravity and the prescribed angles at ``t`` (a fixed-length tuple: type
        checkers match a star-unpacked tuple against the kernel's parameters)."""
        return (
            self.bodies,
            self.joints,
            contiguous(q),
            contiguous(qd),
            contiguous(qdd),
            contiguous(lam),
            self.gravity,
            self.phi(t),
        )

    def residual(self, q, qd, qdd, lam, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Eq. (G1): ``M qdd - Q + C_q^T lambda`` and ``g(q, t)``."""
        forces, gap = system_residual(*self._kernel_arguments(q, qd, qdd, lam, t))
        if self.forces:
            forces -= assembled_forces(self.forces, self.offsets, contiguous(q), contiguous(qd), t)
        return forces, gap

    def iteration_matrix(
        self, q, qd, qdd, lam, t: float, mass_factor: float, beta_p: float, gamma_p: float
    ) -> NDArray[np.float64]:
        """Eq. (FP6): ``[[c M + beta' (K_t + H) + gamma' D_t, C_q^T], [C_q, 0]]``."""
        out = system_iteration_matrix(
            *self._kernel_arguments(q, qd, qdd, lam, t), float(mass_factor), float(beta_p), float(gamma_p)
        )
        if self.forces:
            n = self.n_coordinates
            d_q, d_qd = assembled_tangents(self.forces, self.offsets, contiguous(q), contiguous(qd), t)
            out[:n, :n] -= beta_p * d_q + gamma_p * d_qd
        return out

    def body_residuals(self, q, qd, qdd, t: float = 0.0) -> NDArray[np.float64]:
        """Eqs. (F8)-(F11) for all bodies: ``M qdd - Q``, ``Q`` with the force elements' forces at ``t``."""
        return self.residual(q, qd, qdd, np.zeros(self.n_constraints), t)[0]

    def body_tangents(self, q, qd, qdd, t: float = 0.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        jq, jqd = system_body_tangents(self.bodies, contiguous(q), contiguous(qd), contiguous(qdd), self.gravity)
        if self.forces:
            d_q, d_qd = assembled_tangents(self.forces, self.offsets, contiguous(q), contiguous(qd), t)
            jq, jqd = jq - d_q, jqd - d_qd
        return jq, jqd

    def mass_matrix(self, q) -> NDArray[np.float64]:
        return system_mass_matrix(self.bodies, contiguous(q))

    def constraint_values(self, q, t: float) -> NDArray[np.float64]:
        zeros = np.zeros(self.n_coordinates)
        return self.residual(q, zeros, zeros, np.zeros(self.n_constraints), t)[1]

    def constraint_jacobian(self, q, t: float) -> NDArray[np.float64]:
        return system_jacobian(self.bodies, self.joints, contiguous(q), self.phi(t))

    def constraint_hessian(self, q, multipliers, t: float) -> NDArray[np.float64]:
        r""":math:`\partial(C_q^T\lambda)/\partial q`, analytic (Eq. (FP4))."""
        return system_hessian(self.bodies, self.joints, contiguous(q), contiguous(multipliers), self.phi(t))


def contiguous(x) -> NDArray[np.float64]:
    """``x`` as a C-contiguous float64 array, the layout the numba kernels are compiled for."""
    return np.ascontiguousarray(x, dtype=np.float64)


def _ragged(arrays, dtype=np.float64) -> tuple[NDArray, NDArray[np.int64]]:
    """Arrays of different sizes as one flat buffer and start indices (``flat[starts[i]:starts[i + 1]]``)."""
    sizes = [np.size(a) for a in arrays]
    starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    flat = np.concatenate([np.ravel(a) for a in arrays] + [np.zeros(0)]).astype(dtype)
    return flat, starts


def _pack_bodies(bodies: tuple[FlexibleBody, ...], offsets: NDArray) -> tuple:
    """``(offsets, mass, exact_gravity, real, starts)``
    (module docstring of :mod:`ffrf.system.system_kernels`)."""
    columns = [_ragged([body._packed[k] for body in bodies]) for k in range(8)]
    real = tuple(flat for flat, _ in columns)
    starts = np.array([st for _, st in columns], dtype=np.int64)
    return (
        np.asarray(offsets, dtype=np.int64),
        np.array([b.moments.mass for b in bodies], dtype=float),
        np.array([b.exact_gravity for b in bodies], dtype=np.bool_),
        real,
        starts,
    )


def _side_arrays(marker, rotation, offset) -> tuple:
    """(body, point, rotation, offset, P, Theta) of one joint side; a ground side is composed here."""
    if isinstance(marker, GroundFrame):
        return (
            -1,
            marker.point + marker.rotation @ offset,
            marker.rotation @ rotation,
            np.zeros(3),
            np.zeros((3, 0)),
            np.zeros((3, 0)),
        )
    return (marker.body, marker.point, rotation, offset, marker.position_modes, marker.rotation_modes)


_PLACEHOLDER_SIDE = (-1, np.zeros(3), np.eye(3), np.zeros(3), np.zeros((3, 0)), np.zeros((3, 0)))


def _unsupported(system: MultibodySystem) -> str | None:
    """Why the fast path cannot take ``system`` (``None`` when it can)."""
    for body in system.bodies:
        if type(body) is not FlexibleBody:
            return f"body {body.name!r} is a {type(body).__name__}"
    for c in system.all_constraints:
        if type(c) is EulerNormalization:
            continue
        if type(c) is not MarkerJoint:
            return f"constraint {c.name!r} is a {type(c).__name__}"
        if c.frame_translations:
            return f"joint {c.name!r} takes its translations in its frame"
        if type(c.marker1) is not BodyMarker or type(c.marker0) not in (BodyMarker, GroundFrame):
            return f"joint {c.name!r} has a marker of type {type(c.marker0).__name__}/{type(c.marker1).__name__}"
    return None


def _pack_side(sides: list[tuple]) -> tuple:
    """``(point (J, 3), rotation (J, 3, 3), offset (J, 3), P flat, Theta flat, starts)`` of one side of all joints."""
    modes, starts = _ragged([s[4] for s in sides])
    rotation_modes, _ = _ragged([s[5] for s in sides])
    return (
        np.array([s[1] for s in sides], dtype=float).reshape(-1, 3),
        np.array([s[2] for s in sides], dtype=float).reshape(-1, 3, 3),
        np.array([s[3] for s in sides], dtype=float).reshape(-1, 3),
        modes,
        rotation_modes,
        starts,
    )


def _pack_joints(system: MultibodySystem) -> tuple[tuple, tuple]:
    kinds: list[int] = []
    sides: list[tuple] = []
    locked: list[tuple[int, ...]] = []
    angles: list[Callable[[float], float] | None] = []
    for c in system.all_constraints:
        if type(c) is EulerNormalization:
            kinds.append(EULER)
            sides.append((_PLACEHOLDER_SIDE, (c.bodies[0],) + _PLACEHOLDER_SIDE[1:]))
            locked.append((0,) * 6)
            angles.append(None)
        elif type(c) is MarkerJoint:
            kinds.append(MARKER_JOINT)
            sides.append(
                (_side_arrays(c.marker0, c.rotation0, c.offset0), _side_arrays(c.marker1, c.rotation1, c.offset1))
            )
            locked.append(tuple(int(bool(x)) for x in c.locked))
            angles.append(c.angle)
        else:  # _unsupported(system) turns such a system away before packing
            raise TypeError(f"constraint {c.name!r} is a {type(c).__name__}: the packed system takes none")
    joints = (
        np.array(kinds, dtype=np.int64),
        np.array([s[0][0] for s in sides], dtype=np.int64),
        np.array([s[1][0] for s in sides], dtype=np.int64),
        np.asarray(system.rows, dtype=np.int64),
        np.array(locked, dtype=np.int64).reshape(-1, 6),
        _pack_side([s[0] for s in sides]),
        _pack_side([s[1] for s in sides]),
    )
    return joints, tuple(angles)


_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def pack_system(system: MultibodySystem) -> PackedSystem | None:
    """The packed form of ``system`` (cached per system object), or ``None`` when it has bodies or
    constraints the fast path does not know (the reason is logged at debug level)."""
    if system in _CACHE:
        return _CACHE[system]
    reason = _unsupported(system)
    if reason is not None:
        log.debug("fast path not used (%s); using the reference Python path", reason)
        packed = None
    else:
        joints, angles = _pack_joints(system)
        packed = PackedSystem(
            system.n_coordinates,
            system.n_constraints,
            np.asarray(system.gravity, float),
            _pack_bodies(system.bodies, system.offsets),
            joints,
            angles,
            tuple(system.forces),
            system.offsets,
            weakref.ref(system),  # not the system itself: the cache's value would keep its key alive
        )
    _CACHE[system] = packed
    return packed


def newton_model(system: MultibodySystem, fast_path: bool = True) -> PackedSystem | MultibodySystem:
    """What Newton evaluates: the packed system when ``fast_path`` and supported, else ``system`` itself
    (both have ``residual`` and ``iteration_matrix``)."""
    packed = pack_system(system) if fast_path else None
    return system if packed is None else packed
