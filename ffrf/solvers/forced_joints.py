r"""The energy of a forced joint configuration and its gradient (``docs/formulation.md``, Eqs. (S7), (S8)).

Every named joint's relative rotation about its axis is prescribed (Eq. (J3): its z rotation locked, the angle
a function of t), ``angle_i = s_i phi_i`` with a sign ``s_i`` per joint. The static equilibrium (S1) under those
angles holds the potential energy

.. math:: V(\varphi) = \text{strain} + \text{gravity} + \dots \quad \text{(S7)},

and since :math:`V_q + C_q^T\lambda = 0` and :math:`g(q(\varphi), \varphi) = 0`, its gradient is the multipliers
of the angle equations, :math:`\partial V/\partial\varphi_i = s_i\lambda_i` (S8): the torque a drive would apply
at joint i (:func:`ffrf.system.reactions.driving_torques`). Each equilibrium is reached from the nearest one
already solved, the angles moving along the straight line between the two (t from 0 to 1, quasi-static steps
of at most ``max_step`` rad of any joint, halved where Newton needs it), so that a string of poses is followed
continuously.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.solvers.static_solver import StaticSolution, quasi_static
from ffrf.system.joints import MarkerJoint
from ffrf.system.multibody import MultibodySystem
from ffrf.system.reactions import driving_torques, joint_poses, relative_angle
from kinematics.dh import wrap_angle

__all__ = ["ForcedEnergy", "LinearAngle", "joint_angles", "prescribed_joints"]


@dataclass(frozen=True)
class LinearAngle:
    """The prescribed angle ``start + t (end - start)`` (rad) of Eq. (J3)."""

    start: float
    end: float

    def __call__(self, t: float) -> float:
        return self.start + t * (self.end - self.start)


def prescribed_joints(
    system: MultibodySystem,
    names: tuple[str, ...],
    start: ArrayLike,
    end: ArrayLike,
    free: tuple[str, ...] = (),
) -> MultibodySystem:
    """``system`` with the joints ``names`` (revolute or driven :class:`~ffrf.system.joints.MarkerJoint`) turned from
    the angles ``start`` at t = 0 to ``end`` at t = 1 (rad, Eq. (J3)): all six relative motions locked, as
    :func:`~ffrf.system.joints.driven_revolute_joint` does; the joints ``free`` turn freely (revolute)."""
    first, last = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    laws = {name: LinearAngle(float(a), float(b)) for name, a, b in zip(names, first, last, strict=True)}
    constraints = []
    for c in system.constraints:
        if c.name in laws or c.name in free:
            if not isinstance(c, MarkerJoint) or c.locked[:5] != (True,) * 5:
                raise ValueError(f"joint {c.name!r} is not a revolute joint: its angle cannot be prescribed")
            held = c.name in laws
            c = replace(c, locked=(True,) * 5 + (held,), angle=laws[c.name] if held else None)
        constraints.append(c)
    missing = (set(laws) | set(free)) - {c.name for c in system.constraints}
    if missing:
        raise ValueError(f"no joints named {sorted(missing)}; the system has {[c.name for c in system.constraints]}")
    return replace(system, constraints=tuple(constraints))


def joint_angles(
    system: MultibodySystem, names: tuple[str, ...], signs: ArrayLike, q: NDArray, reference: ArrayLike
) -> NDArray[np.float64]:
    """phi of the joints ``names`` at ``q``: each one's relative rotation (
    :func:`~ffrf.system.reactions.relative_angle`) times its sign, the value nearest ``reference`` modulo 2 pi."""
    joints = {c.name: c for c in system.constraints if isinstance(c, MarkerJoint)}
    angles = [
        relative_angle(joint_poses(joints[name], [q[system.block(i)] for i in joints[name].bodies])) for name in names
    ]
    reference = np.asarray(reference, dtype=float)
    return reference + wrap_angle(np.asarray(signs, dtype=float) * np.array(angles) - reference)


class ForcedEnergy:
    r""":math:`V(\varphi)` of Eq. (S7) and its gradient (S8) for the joints ``names`` of ``system``, angle_i =
    ``signs[i] * phi[i]``; callable as ``energy(phi) -> (V, dV/dphi)``.

    ``phi0``, ``q0``: a first known equilibrium, the coordinates of ``system`` that hold the joints at ``phi0``
    (e.g. an assembled state and its joints' measured angles, :func:`joint_angles`). t is the parameter of the way
    from one equilibrium to the next, so the named joints must be the system's only time laws (a linkage's drive
    is one of them; other prescribed joints are refused, loads that depend on time are the caller's care).
    ``max_step``: the largest turn of one joint (rad) between two equilibria on the way to a new one;
    ``tolerance``: Newton's (:func:`~ffrf.solvers.static_solver.quasi_static`); ``memory``: the equilibria kept to
    start from (the first and the newest). ``evaluations`` counts the equilibria solved.
    """

    def __init__(
        self,
        system: MultibodySystem,
        names: tuple[str, ...],
        signs: ArrayLike,
        phi0: ArrayLike,
        q0: NDArray,
        max_step: float = math.radians(3.0),
        tolerance: float = 1e-10,
        memory: int = 256,
    ):
        self.system, self.names = system, tuple(names)
        others = [c.name for c in system.constraints if getattr(c, "angle", None) is not None and c.name not in names]
        if others:
            raise ValueError(f"joints {others} have prescribed angles of their own: name them to prescribe them too")
        self.signs = np.asarray(signs, dtype=float)
        self.max_step, self.tolerance = float(max_step), float(tolerance)
        phi0 = np.asarray(phi0, dtype=float)
        self.memory = int(memory)
        held = prescribed_joints(system, self.names, self.signs * phi0, self.signs * phi0)
        known = quasi_static(held, q0, np.array([1.0]), tolerance)
        self.forced = held  # the constraints' layout of every forced system: where the multipliers are
        self._phi: list[NDArray] = [phi0]
        self._states: list[StaticSolution] = [StaticSolution(known.q[0], known.multipliers[0], known.iterations)]
        self.evaluations = 1

    def _nearest(self, phi: NDArray) -> int:
        distances = [float(np.max(np.abs(wrap_angle(phi - known)))) for known in self._phi]
        return int(np.argmin(distances))

    def solve(self, phi: ArrayLike) -> StaticSolution:
        """The equilibrium with the joints at ``phi`` (multipliers ordered as :attr:`forced`'s constraints), from
        the nearest equilibrium solved before."""
        phi = np.asarray(phi, dtype=float)
        k = self._nearest(phi)
        turn = wrap_angle(phi - self._phi[k])
        if not np.any(turn):
            return self._states[k]
        start = self.signs * self._phi[k]
        forced = prescribed_joints(self.system, self.names, start, start + self.signs * turn)
        step = self.max_step / float(np.max(np.abs(turn)))
        path = quasi_static(forced, self._states[k].q, np.array([0.0, 1.0]), self.tolerance, max_step=min(step, 1.0))
        state = StaticSolution(path.q[-1], path.multipliers[-1], path.iterations)
        self._remember(self._phi[k] + turn, state)
        return state

    def _remember(self, phi: NDArray, state: StaticSolution) -> None:
        self.evaluations += 1
        self._phi.append(phi)
        self._states.append(state)
        if len(self._phi) > self.memory:
            del self._phi[1], self._states[1]

    def relax(self, phi: ArrayLike, held: tuple[str, ...]) -> NDArray[np.float64]:
        """The joint angles where the joints not ``held`` settle (no torque on them, so V is least over their
        angles) with the ``held`` ones at ``phi``'s values, from the nearest equilibrium solved before. The
        equilibrium is remembered with every joint at its angles."""
        phi = np.asarray(phi, dtype=float)
        k = self._nearest(phi)
        turn = wrap_angle(phi - self._phi[k])
        which = np.array([name in held for name in self.names])
        start, names = self.signs * self._phi[k], np.array(self.names)
        free = prescribed_joints(
            self.system, tuple(names[which]), start[which], (start + self.signs * turn)[which], tuple(names[~which])
        )
        step = min(1.0, self.max_step / max(float(np.max(np.abs(turn[which]), initial=0.0)), 1e-300))
        q = quasi_static(free, self._states[k].q, np.array([0.0, 1.0]), self.tolerance, max_step=step).q[-1]
        relaxed = joint_angles(self.system, self.names, self.signs, q, phi)
        held_there = prescribed_joints(self.system, self.names, self.signs * relaxed, self.signs * relaxed)
        state = quasi_static(held_there, q, np.array([1.0]), self.tolerance)
        self._remember(relaxed, StaticSolution(state.q[0], state.multipliers[0], state.iterations))
        return relaxed

    def __call__(self, phi: ArrayLike) -> tuple[float, NDArray[np.float64]]:
        """``(V, dV/dphi)`` at ``phi``: Eqs. (S7), (S8)."""
        state = self.solve(phi)
        torques = driving_torques(self.forced, state.multipliers)
        gradient = self.signs * np.array([torques[name] for name in self.names])
        return self.forced.potential_energy(state.q, 1.0), gradient
