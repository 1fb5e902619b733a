"""Force elements of a scene description (``[[forces]]``): spring-dampers and bushings, loads, motors.

Each entry becomes one element of :mod:`ffrf.system.forces` (``docs/formulation.md``, Eqs. (E1)-(E5))::

    [[forces]]
    name = "support"
    type = "spring_damper"            # a joint's equations held elastically (E1)
    elastic = "translations"          # "translations" (Exudyn's CartesianSpringDamper, world axes),
                                      # "revolute" (a bushing: five directions in the joint's frame, the turn
                                      # about axis free) or "fixed" (all six, in the joint's frame)
    body0 = "ground"                  # the sides as a joint's: body0/body1, interface0/interface1, axis, point
    body1 = "bar"                     # (or axis0/point0, axis1/point1 as built)
    interface1 = "end"
    stiffness = [2e8, 2e8, 2e8]       # one value, or one per equation (N/m; N m for the rotation equations)
    damping = [2e6, 2e6, 2e6]         # N s/m (N m s)
    offset = [0.0, 0.0, 0.0]          # the equations' values at which the element is unloaded

    [[forces]]
    name = "tie"
    type = "spring"                   # along the line between two interfaces' centres (E6), geometrically nonlinear
    body0 = "ground"                  # a ground end needs point0 = [x, y, z]
    point0 = [0.0, 0.0, -0.2]
    body1 = "bar"
    interface1 = "tip"
    stiffness = [100.0]               # N/m
    damping = [0.1]                   # N s/m
    length = 0.15                     # m, unloaded length (default: the start distance)

    [[forces]]
    name = "payload"
    type = "load"                     # force and torque on an interface's marker (E3)
    body = "bar"
    interface = "tip"
    force = [0.0, 0.0, -1.0]          # N
    torque = [0.0, 0.0, 0.0]          # N m
    frame = "world"                   # or "marker": the vectors turn with the interface
    table = {time = [0.0, 1.0], scale = [0.0, 1.0]}   # optional: both vectors times this (linear in time)

    [[forces]]
    name = "motor"
    type = "motor"                    # torque about the joint axis, from body0's side to body1's (E5)
    body0 = "ground"
    body1 = "bar"
    interface1 = "hinge"
    axis = [0.0, 1.0, 0.0]
    stall_torque = 0.02               # N m: tau = stall_torque (1 - speed / no_load_speed)
    no_load_speed = 10.0              # rad/s
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from functools import partial

import numpy as np

from ffrf.errors import SceneError
from ffrf.scenes.scene_joints import HasMarkers, joint_constraint, joint_geometry
from ffrf.system.forces import AxialSpringDamper, ForceElement, JointTorque, MarkerLoad, spring_damper
from ffrf.system.joints import GroundFrame
from ffrf.system.markers import BodyMarker

__all__ = ["ELASTIC", "FORCE_TYPES", "build_forces", "check_force"]

FORCE_TYPES = ("spring_damper", "spring", "load", "motor")
#: Which of a joint's equations a spring-damper holds, as the joint's locked directions.
ELASTIC = {
    "translations": (True, True, True, False, False, False),
    "revolute": (True, True, True, True, True, False),
    "fixed": (True,) * 6,
}
#: The keys each type takes (the schema, :mod:`ffrf.scenes.scene_schema`, knows their kinds).
_SIDES = {"body0", "body1", "interface0", "interface1", "axis", "point", "axis0", "point0", "axis1", "point1"}
_KEYS = {
    "spring_damper": _SIDES | {"elastic", "stiffness", "damping", "offset"},
    "load": {"body", "interface", "force", "torque", "frame", "table"},
    "motor": _SIDES | {"stall_torque", "no_load_speed"},
    "spring": {"body0", "body1", "interface0", "interface1", "point0", "stiffness", "damping", "length"},
}


def check_force(spec: dict, where: str) -> None:
    """Raise :class:`SceneError` for keys a force entry of its type does not take or misses (before building)."""
    kind = spec["type"]
    stray = sorted(set(spec) - _KEYS[kind] - {"name", "type"})
    if stray:
        raise SceneError(f"{where}: a {kind} takes no {stray}; its keys are {sorted(_KEYS[kind])}")
    if kind != "load" and ("body0" not in spec or "body1" not in spec):
        raise SceneError(f"{where}: a {kind} connects body0 and body1 (either may be 'ground'), as a joint does")
    if kind == "load" and ("force" not in spec and "torque" not in spec):
        raise SceneError(f"{where}: a load needs force = [fx, fy, fz] (N), torque = [mx, my, mz] (N m) or both")
    if kind == "spring" and (len(spec.get("stiffness", [])) != 1 or len(spec.get("damping", [0.0])) != 1):
        raise SceneError(
            f"{where}: a spring (along the line between two interfaces) needs stiffness = [k] (N/m), optionally "
            "damping = [c] (N s/m) and length (m; default the start distance)"
        )
    if kind == "spring" and "ground" in (spec.get("body0"), spec.get("body1")) and "point0" not in spec:
        raise SceneError(f"{where}: a spring to the ground needs point0 = [x, y, z], its end on the ground (m)")
    if kind == "spring_damper" and "stiffness" not in spec:
        raise SceneError(f"{where}: a spring_damper needs stiffness = [...] (one value, or one per equation)")
    if kind == "motor" and ("stall_torque" not in spec or "no_load_speed" not in spec):
        raise SceneError(f"{where}: a motor needs stall_torque (N m) and no_load_speed (rad/s)")


def _per_equation(values: list[float] | None, n: int, what: str, where: str) -> np.ndarray:
    if values is None:
        return np.zeros(n)
    if len(values) not in (1, n):
        raise SceneError(f"{where}: {what} needs one value or {n} (one per elastic equation), got {len(values)}")
    return np.full(n, float(values[0])) if len(values) == 1 else np.asarray(values, dtype=float)


def _time_law(table: dict | None, where: str) -> Callable[[float], float]:
    if table is None:
        return lambda t: 1.0
    times, scale = np.asarray(table["time"], dtype=float), np.asarray(table["scale"], dtype=float)
    if times.shape != scale.shape or np.any(np.diff(times) <= 0.0):
        raise SceneError(f"{where}, table: time must increase and match scale one to one, got {times} and {scale}")
    return lambda t: float(np.interp(t, times, scale))


def _scaled(law: Callable[[float], float], vector: np.ndarray, t: float) -> np.ndarray:
    return law(t) * vector


def _motor(stall: float, no_load_speed: float, t: float, angle: float, speed: float) -> float:
    """A DC motor's linear torque-speed curve (Eq. (E5))."""
    return stall * (1.0 - speed / no_load_speed)


def _spring(spec: dict, bodies: Sequence[HasMarkers], index: dict[str, int]) -> AxialSpringDamper:
    """Eq. (E6) between two interfaces' marker points, or an interface and ``point0`` on the ground."""
    markers = [
        bodies[index[spec[f"body{k}"]]].markers[spec[f"interface{k}"]] for k in "01" if spec[f"body{k}"] != "ground"
    ]
    end1 = markers[-1]
    end0: BodyMarker | GroundFrame = (
        markers[0] if len(markers) == 2 else GroundFrame(point=np.asarray(spec["point0"], dtype=float))
    )
    start = float(np.linalg.norm(end1.point - end0.point))
    stiffness, damping = float(spec["stiffness"][0]), float(spec.get("damping", [0.0])[0])
    return AxialSpringDamper(
        tuple(m.body for m in markers), spec["name"], end0, end1, stiffness, damping, float(spec.get("length", start))
    )


def _joint(spec: dict, bodies: Sequence[HasMarkers], index: dict[str, int], offsets: str, kind: str):
    sides = {key: spec[key] for key in _SIDES if key in spec}
    return joint_constraint(
        joint_geometry(dict(sides, name=spec["name"], type=kind), index, bodies), bodies, offsets, 1.0
    )


def build_forces(
    specs: list[dict], bodies: Sequence[HasMarkers], index: dict[str, int], joint_offsets: str, where: str
) -> tuple[ForceElement, ...]:
    """The elements of ``[[forces]]`` (module docstring) on the built ``bodies`` (``index``: name -> body)."""
    elements: list[ForceElement] = []
    for k, spec in enumerate(specs):
        place = f"{where}, forces[{k}] {spec['name']!r}"
        kind = spec["type"]
        if kind == "spring_damper":
            elastic = spec.get("elastic", "translations")
            joint = _joint(spec, bodies, index, joint_offsets, "fixed" if elastic == "fixed" else "revolute")
            # a bushing's translational stiffness turns with its frame; a Cartesian one stays in world axes
            joint = replace(joint, locked=ELASTIC[elastic], frame_translations=elastic != "translations")
            n = joint.size
            stiffness = _per_equation(spec["stiffness"], n, "stiffness", place)
            damping = _per_equation(spec.get("damping"), n, "damping", place)
            elements.append(
                spring_damper(joint, stiffness, damping, _per_equation(spec.get("offset"), n, "offset", place))
            )
        elif kind == "spring":
            elements.append(_spring(spec, bodies, index))
        elif kind == "load":
            body = bodies[index[spec["body"]]]
            law = _time_law(spec.get("table"), place)
            force, torque = (np.asarray(spec.get(key, [0.0, 0.0, 0.0]), dtype=float) for key in ("force", "torque"))
            marker = body.markers[spec["interface"]]
            elements.append(
                MarkerLoad(
                    (marker.body,),
                    spec["name"],
                    marker,
                    force=partial(_scaled, law, force),
                    torque=partial(_scaled, law, torque),
                    frame=spec.get("frame", "world"),
                )
            )
        else:
            joint = _joint(spec, bodies, index, joint_offsets, "revolute")
            stall, free = float(spec["stall_torque"]), float(spec["no_load_speed"])
            elements.append(JointTorque(joint.bodies, spec["name"], joint, partial(_motor, stall, free)))
    return tuple(elements)
