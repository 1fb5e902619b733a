r"""A multibody system: flexible bodies, constraints, force elements and gravity, on one coordinate vector.

The coordinates are the bodies' blocks ``[R, p, zeta]`` one after another; the multipliers
are the constraints' in order, beginning with one Euler-parameter normalisation per body. Force elements
(:mod:`ffrf.system.forces`) add to the applied forces :math:`Q`.
The system provides the pieces of the index-3 DAE (``docs/formulation.md``, Eq. (G1))

.. math:: M(q)\ddot q - Q(q, \dot q) + C_q^T\lambda = 0, \qquad g(q, t) = 0,

and their exact derivatives for Newton's method.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.body.euler_parameters import g_bar, rotation_matrix
from ffrf.body.flexible_body import FlexibleBody
from ffrf.system.constraints import (
    Constraint,
    EulerNormalization,
    constraint_hessian_term,
    constraint_velocity_derivative,
)
from ffrf.system.forces import ForceElement, assembled_forces, assembled_tangents

__all__ = ["MultibodySystem"]


@dataclass(frozen=True, eq=False)
class MultibodySystem:
    """Bodies, constraints (normalisations are added first), the gravity vector (m/s^2) and force elements."""

    bodies: tuple[FlexibleBody, ...]
    constraints: tuple[Constraint, ...] = ()
    gravity: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    forces: tuple[ForceElement, ...] = ()
    offsets: NDArray[np.int64] = field(init=False, repr=False)
    all_constraints: tuple[Constraint, ...] = field(init=False, repr=False)
    rows: NDArray[np.int64] = field(init=False, repr=False)

    def __post_init__(self):
        sizes = [b.n_coordinates for b in self.bodies]
        object.__setattr__(self, "offsets", np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64))
        names = [b.name for b in self.bodies]
        if len(set(names)) != len(names):
            raise ValueError(f"body names must be unique, got {names}")
        for kind, items in (("constraint", self.constraints), ("force element", self.forces)):
            for c in items:
                bad = [i for i in c.bodies if not 0 <= i < len(self.bodies)]
                if bad:
                    raise ValueError(
                        f"{kind} {c.name!r} refers to unknown body index {bad}; there are "
                        f"{len(self.bodies)} bodies {names}"
                    )
        normalisations = tuple(
            EulerNormalization((i,), f"{b.name}: Euler parameter norm") for i, b in enumerate(self.bodies)
        )
        constraints = normalisations + tuple(self.constraints)
        object.__setattr__(self, "all_constraints", constraints)
        object.__setattr__(
            self, "rows", np.concatenate([[0], np.cumsum([c.size for c in constraints])]).astype(np.int64)
        )
        object.__setattr__(self, "gravity", np.asarray(self.gravity, dtype=float))

    @property
    def n_coordinates(self) -> int:
        return int(self.offsets[-1])

    @property
    def n_constraints(self) -> int:
        return int(self.rows[-1])

    def block(self, i: int) -> slice:
        return slice(int(self.offsets[i]), int(self.offsets[i + 1]))

    def body_residuals(self, q, qd, qdd, t: float = 0.0) -> NDArray[np.float64]:
        """Eqs. (F8)-(F11) for all bodies: ``M qdd - Q`` (without constraint forces), ``Q`` with the force
        elements' forces at time ``t`` (Eqs. (E1)-(E5))."""
        out = np.empty(self.n_coordinates)
        for i, body in enumerate(self.bodies):
            s = self.block(i)
            out[s] = body.residual(q[s], qd[s], qdd[s], self.gravity)
        if self.forces:
            out -= assembled_forces(self.forces, self.offsets, q, qd, t)
        return out

    def _blocks(self, bodies: tuple[int, ...], q: NDArray, qd: NDArray) -> tuple[list[NDArray], list[NDArray]]:
        return [q[self.block(i)] for i in bodies], [qd[self.block(i)] for i in bodies]

    def constraint_values(self, q, t) -> NDArray[np.float64]:
        return np.concatenate([c.value([q[self.block(i)] for i in c.bodies], t) for c in self.all_constraints])

    def constraint_jacobian(self, q, t) -> NDArray[np.float64]:
        out = np.zeros((self.n_constraints, self.n_coordinates))
        for k, c in enumerate(self.all_constraints):
            rows = slice(int(self.rows[k]), int(self.rows[k + 1]))
            for i, block in zip(c.bodies, c.jacobian([q[self.block(i)] for i in c.bodies], t), strict=True):
                out[rows, self.block(i)] += block
        return out

    def constraint_hessian(self, q, multipliers, t) -> NDArray[np.float64]:
        r""":math:`\partial(C_q^T\lambda)/\partial q` (exact)."""
        out = np.zeros((self.n_coordinates, self.n_coordinates))
        for k, c in enumerate(self.all_constraints):
            lam = multipliers[int(self.rows[k]) : int(self.rows[k + 1])]
            blocks = constraint_hessian_term(c, [q[self.block(i)] for i in c.bodies], lam, t)
            for a, i in enumerate(c.bodies):
                for b, j in enumerate(c.bodies):
                    out[self.block(i), self.block(j)] += blocks[a][b]
        return out

    def constraint_acceleration_term(self, q, qd, t) -> NDArray[np.float64]:
        r""":math:`(C_q\dot q)_q\dot q` for consistent initial accelerations (scleronomic constraints)."""
        return np.concatenate(
            [
                constraint_velocity_derivative(
                    c, [q[self.block(i)] for i in c.bodies], [qd[self.block(i)] for i in c.bodies], t
                )
                for c in self.all_constraints
            ]
        )

    def residual(self, q, qd, qdd, lam, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r"""Eq. (G1): ``M qdd - Q + C_q^T lambda`` and ``g(q, t)`` (what Newton drives to zero)."""
        forces = self.body_residuals(q, qd, qdd, t) + self.constraint_jacobian(q, t).T @ lam
        return forces, self.constraint_values(q, t)

    def iteration_matrix(
        self, q, qd, qdd, lam, t: float, mass_factor: float, beta_p: float, gamma_p: float
    ) -> NDArray[np.float64]:
        r"""Eq. (FP6): ``[[c M + beta' (K_t + H) + gamma' D_t, C_q^T], [C_q, 0]]``, with ``c = 1`` for
        generalized-alpha (Eq. (G3)) and ``c = 0, beta' = 1, gamma' = 0`` for statics (Eq. (S1))."""
        jq, jqd = self.body_tangents(q, qd, qdd, t)
        upper = beta_p * (jq + self.constraint_hessian(q, lam, t))
        if gamma_p != 0.0:
            upper += gamma_p * jqd
        if mass_factor != 0.0:
            upper += mass_factor * self.mass_matrix(q)
        cq = self.constraint_jacobian(q, t)
        return np.block([[upper, cq.T], [cq, np.zeros((cq.shape[0], cq.shape[0]))]])

    def body_tangents(self, q, qd, qdd, t: float = 0.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Exact ``d(M qdd - Q)/dq`` and ``d(M qdd - Q)/dqd``: block-diagonal, plus the force elements' couplings."""
        n = self.n_coordinates
        jq, jqd = np.zeros((n, n)), np.zeros((n, n))
        for i, body in enumerate(self.bodies):
            s = self.block(i)
            jq[s, s], jqd[s, s] = body.jacobians(q[s], qd[s], qdd[s], self.gravity)
        if self.forces:
            d_q, d_qd = assembled_tangents(self.forces, self.offsets, q, qd, t)
            jq -= d_q
            jqd -= d_qd
        return jq, jqd

    def mass_matrix(self, q) -> NDArray[np.float64]:
        n = self.n_coordinates
        out = np.zeros((n, n))
        for i, body in enumerate(self.bodies):
            s = self.block(i)
            out[s, s] = body.mass_matrix(q[s])
        return out

    def energies(self, q, qd, t: float = 0.0) -> dict[str, float]:
        """Kinetic, strain and gravity potential energy (J); with force elements also ``elements``, the
        energy stored in them (Eq. (E2))."""
        kinetic = sum(b.kinetic_energy(q[self.block(i)], qd[self.block(i)]) for i, b in enumerate(self.bodies))
        strain = sum(b.strain_energy(q[self.block(i)]) for i, b in enumerate(self.bodies))
        potential = sum(b.potential_energy(q[self.block(i)], self.gravity) for i, b in enumerate(self.bodies))
        out = {"kinetic": kinetic, "strain": strain, "potential": potential}
        if self.forces:
            out["elements"] = sum(e.potential_energy(self._blocks(e.bodies, q, qd)[0], t) for e in self.forces)
        return out

    def potential_energy(self, q, t: float = 0.0) -> float:
        r"""Energy an equilibrium holds at fixed t (J): strain, gravity, the force elements' stored energy (Eq. (E2))
        and the potential :math:`-F(t)\cdot x` of every load that is conservative at fixed t (a world force that
        depends on time alone, :meth:`~ffrf.system.forces.ForceElement.load_potential`). It is the V of a snap's
        jump (Eq. (S6)) and of a forced joint configuration (Eq. (S7))."""
        zero = np.zeros_like(q)
        energies = self.energies(q, zero, t)
        loads = sum(e.load_potential(self._blocks(e.bodies, q, zero)[0], t) for e in self.forces)
        return energies["strain"] + energies["potential"] + energies.get("elements", 0.0) + loads

    def rigid_velocity(
        self,
        q: NDArray,
        body: int,
        velocity: ArrayLike = (0.0, 0.0, 0.0),
        angular_velocity: ArrayLike = (0.0, 0.0, 0.0),
        point: ArrayLike = (0.0, 0.0, 0.0),
    ) -> NDArray[np.float64]:
        r"""Velocities ``qd`` (all bodies; zero except ``body``) of a rigid motion of ``body``: its point ``point``
        (body coordinates) moving at ``velocity`` and the body turning at ``angular_velocity`` (both world).
        Eq. (R2): :math:`\dot p = \tfrac14\bar G(p)^T A(p)^T\omega` (for unit :math:`p`, :math:`\bar G\bar G^T = 4I`),
        :math:`\dot R = v - \omega\times A(p)\,\bar u`, modal velocities zero."""
        qd = np.zeros(self.n_coordinates)
        s = self.block(body)
        p = np.asarray(q[s][3:7], dtype=float)
        rotation = rotation_matrix(p)
        omega = np.asarray(angular_velocity, dtype=float)
        qd[s.start : s.start + 3] = np.asarray(velocity, dtype=float) - np.cross(
            omega, rotation @ np.asarray(point, dtype=float)
        )
        qd[s.start + 3 : s.start + 7] = 0.25 * g_bar(p).T @ (rotation.T @ omega)
        return qd

    def initial_state(
        self, positions: ArrayLike | None = None, rotations: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """Coordinates with bodies at ``positions`` (n x 3), Euler parameters ``rotations``
        (n x 4, default identity), zeta = 0."""
        q = np.zeros(self.n_coordinates)
        for i in range(len(self.bodies)):
            s = self.block(i)
            q[s.start + 3] = 1.0
            if positions is not None:
                q[s.start : s.start + 3] = np.asarray(positions, float)[i]
            if rotations is not None:
                r = np.asarray(rotations, float)[i]
                q[s.start + 3 : s.start + 7] = r / np.linalg.norm(r)
        return q
