r"""The single-body scenes of the Exudyn cross-checks, solver neutral: a :class:`SingleBodyScene` is one
:class:`validation.reduced_body.ReducedBody` with gravity, Rayleigh damping, its initial state, an
optional revolute joint to ground at the frame interface (:class:`Hinge`) and force elements and loads
(:mod:`validation.single_body_forces`).

Scene 1, :func:`pendulum_scene`: the bar hinged at bore 0, released from horizontal at rest.
Scene 2, :func:`free_body_scene`: the bar spinning freely, no gravity, elastically pre-deformed.
:mod:`validation.exudyn_ffrf` runs them in Exudyn and in our solver.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from .force_specs import ForceSpec
from .reduced_body import ReducedBody, static_deflection, tip_node

__all__ = ["Hinge", "SingleBodyScene", "pendulum_scene", "free_body_scene"]


@dataclass(frozen=True)
class Hinge:
    """Revolute joint to ground at the frame-interface centre, about the world ``axis``."""

    axis: tuple[float, float, float] = (0.0, 1.0, 0.0)

    def __post_init__(self):
        if not np.linalg.norm(np.asarray(self.axis, dtype=float)) > 0:
            raise ValueError(f"hinge axis must be non-zero, got {self.axis!r}")

    def frame(self) -> NDArray[np.float64]:
        """The joint frame (columns x, y, z; z the unit ``axis``), as every joint of ours builds it
        (:func:`ffrf.system.joints.frame_from_axis`); x and y are the normals of our
        ``GroundPerpendicular``."""
        from ffrf.system.joints import frame_from_axis

        return frame_from_axis(self.axis)


@dataclass(frozen=True, eq=False)
class SingleBodyScene:
    """One body, its initial state, loads and an optional hinge; all in SI units.

    ``euler0`` is the initial (= Exudyn reference) rotation of the frame as unit Euler
    parameters; a hinged scene needs the identity. ``omega_bar`` is the body-frame angular
    velocity, ``velocity`` the initial velocity of the body point ``velocity_point`` (body
    coordinates; default the frame origin). Damping is Rayleigh's D = alpha M_red + beta K_red.
    """

    body: ReducedBody
    tracked_nodes: tuple[int, ...]
    gravity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    beta: float = 0.0  # stiffness-proportional damping (s)
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    omega_bar: tuple[float, float, float] = (0.0, 0.0, 0.0)
    euler0: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    zeta0: NDArray[np.float64] | None = None
    hinge: Hinge | None = None
    t_end: float = 1.0
    step: float = 1e-3
    rho_inf: float = 0.8
    alpha: float = 0.0  # mass-proportional damping (1/s)
    velocity_point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    forces: tuple[ForceSpec, ...] = ()

    def __post_init__(self):
        p = np.asarray(self.euler0, dtype=float)
        if p.shape != (4,) or abs(np.linalg.norm(p) - 1.0) > 1e-12:
            raise ValueError(f"euler0 must be 4 unit Euler parameters, got {self.euler0!r}")
        if self.hinge is not None and np.abs(p - np.array([1.0, 0.0, 0.0, 0.0])).max() > 0:
            raise ValueError("a hinged scene starts from the identity rotation (euler0 = (1, 0, 0, 0))")

    def rotation0(self) -> NDArray[np.float64]:
        """Initial rotation matrix A(euler0) (body to world)."""
        from ffrf.body.euler_parameters import rotation_matrix

        return rotation_matrix(np.asarray(self.euler0, dtype=float))

    def initial_zeta(self) -> NDArray[np.float64]:
        if self.zeta0 is None:
            return np.zeros(self.body.n_modes)
        zeta0 = np.asarray(self.zeta0, dtype=float)
        if zeta0.shape != (self.body.n_modes,):
            raise ValueError(f"zeta0 has shape {zeta0.shape}, expected ({self.body.n_modes},)")
        return zeta0

    @property
    def n_steps(self) -> int:
        n = int(round(self.t_end / self.step))
        if n < 1 or abs(n * self.step - self.t_end) > 1e-9 * self.t_end:
            raise ValueError(f"t_end={self.t_end} is not a whole number of steps h={self.step}")
        return n

    def with_step(self, step: float) -> SingleBodyScene:
        return replace(self, step=step)


def pendulum_scene(
    body: ReducedBody,
    step: float = 1e-3,
    t_end: float = 1.0,
    beta: float = 0.0,
    rho_inf: float = 0.8,
    axis: tuple[float, float, float] = (0.0, 1.0, 0.0),
) -> SingleBodyScene:
    """Scene 1: hinged at bore 0 about ``axis``, released from horizontal at rest, g = -9.81 e_z."""
    corner = int(np.argmax(body.nodes @ np.array([1.0, 1e-3, 1e-6])))  # an outer tip corner
    return SingleBodyScene(
        body,
        (tip_node(body), corner),
        gravity=(0.0, 0.0, -9.81),
        beta=beta,
        hinge=Hinge(axis),
        t_end=t_end,
        step=step,
        rho_inf=rho_inf,
    )


def free_body_scene(
    body: ReducedBody,
    step: float = 1e-3,
    t_end: float = 0.2,
    rho_inf: float = 0.8,
    tip_force: tuple[float, float, float] = (0.0, 1e-2, 1e-2),
    tilted: bool = False,
) -> SingleBodyScene:
    """Scene 2: no gravity, no constraints, omega_bar = (1, 2, 30) rad/s, v = (0.1, 0, 0) m/s.

    The elastic excitation zeta0 is the static deflection under a small ``tip_force`` (10 mN:
    zeta0 ~ 1e-5, tip deflection ~ 1.5 um for the default bar). A smooth shape is needed:
    zeta0 = 1e-6 (1, -1, ...) excites the stiffest modes (up to 16 kHz, omega h ~ 100; about
    1e-4 m at up to 1e6 m/s^2) and Newton diverges in the first step at h = 1e-3 in *both*
    solvers (ours: NewtonDivergence after 12 iterations, full or modified Newton; Exudyn:
    "Newton has been stopped"); it runs at h = 1e-4. So does 100x the default tip force.
    ``tilted=True`` starts from a rotation of 40 deg about (1, 2, 3)/sqrt(14), so that body and
    world angular velocities differ (this checks the angular-velocity frame convention).
    """
    euler0 = (1.0, 0.0, 0.0, 0.0)
    if tilted:
        half, axis = np.radians(40.0) / 2.0, np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
        p = np.r_[np.cos(half), np.sin(half) * axis]
        euler0 = (float(p[0]), float(p[1]), float(p[2]), float(p[3]))
    corner = int(np.argmax(body.nodes @ np.array([1.0, 1e-3, 1e-6])))
    return SingleBodyScene(
        body,
        (tip_node(body), corner),
        velocity=(0.1, 0.0, 0.0),
        omega_bar=(1.0, 2.0, 30.0),
        zeta0=static_deflection(body, tip_force),
        euler0=euler0,
        t_end=t_end,
        step=step,
        rho_inf=rho_inf,
    )
