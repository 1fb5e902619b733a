r"""The force elements and loads of the single-body scenes
(:class:`validation.single_body_scenes.SingleBodyScene`) as plain, solver-neutral data: what each element is, in
the units and axes both solvers read. Their translations into our elements and Exudyn's items are
:mod:`validation.single_body_forces`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["BushingSpring", "CartesianSpring", "ForceSpec", "HingeTorque", "INTERFACES", "InterfaceLoad"]

Vector3 = tuple[float, float, float]
Vector6 = tuple[float, float, float, float, float, float]
INTERFACES = ("frame", "tip")


def _check_interface(interface: str) -> None:
    if interface not in INTERFACES:
        raise ValueError(f"interface must be one of {INTERFACES}, got {interface!r}")


@dataclass(frozen=True)
class CartesianSpring:
    """Spring-damper from the ground point ``anchor`` (world) to the weighted centre of ``interface``:
    f = k o (p1 - p0 - offset) + d o (v1 - v0) per world axis (N/m, N s/m, m), -f on the body."""

    anchor: Vector3
    stiffness: Vector3
    damping: Vector3 = (0.0, 0.0, 0.0)
    offset: Vector3 = (0.0, 0.0, 0.0)
    interface: str = "tip"

    def __post_init__(self):
        _check_interface(self.interface)


@dataclass(frozen=True)
class InterfaceLoad:
    """A force (``kind="force"``, N) or a torque (``"torque"``, N m) on ``interface``: ``vector`` times ``law(t)``
    (constant without a law), in world axes or, with ``frame="marker"``, in the interface marker's axes."""

    kind: str
    vector: Vector3
    interface: str = "tip"
    law: Callable[[float], float] | None = None
    frame: str = "world"

    def __post_init__(self):
        _check_interface(self.interface)
        if self.kind not in ("force", "torque"):
            raise ValueError(f"load kind must be 'force' or 'torque', got {self.kind!r}")
        if self.frame not in ("world", "marker"):
            raise ValueError(f"load frame must be 'world' or 'marker', got {self.frame!r}")


@dataclass(frozen=True)
class BushingSpring:
    """Six-axis spring-damper from a ground frame (the frame interface's initial pose) to the frame interface:
    diagonal ``stiffness`` and ``damping`` (translations x, y, z of the ground frame in N/m, N s/m, then rotations
    about x, y, z in N m/rad, N m s/rad) and a translational ``offset`` (m, ground axes)."""

    stiffness: Vector6
    damping: Vector6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    offset: Vector3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class HingeTorque:
    """Torque on the body about the hinge axis (needs ``SingleBodyScene.hinge``), positive about the axis:
    tau = torque - stiffness (phi - offset) - damping phi_dot (a motor curve with ``stiffness = 0``)."""

    torque: float = 0.0
    stiffness: float = 0.0
    damping: float = 0.0
    offset: float = 0.0

    def law(self, t: float, angle: float, speed: float) -> float:
        return self.torque - self.stiffness * (angle - self.offset) - self.damping * speed


ForceSpec = CartesianSpring | InterfaceLoad | BushingSpring | HingeTorque
