"""What a scene file may say: every table, key, type and admissible value, checked before anything is built.

The schema is plain data (one :class:`Key` per key) so the documentation, the checks and the error
messages cannot drift apart. :func:`check_scene` walks a parsed TOML document and raises
:class:`~ffrf.errors.SceneError` with one line that names the key, where it is, what is wrong and
what to write instead; a misspelt key (``gravty``, ``rpmm``) is an error with a suggestion, never
ignored. Checks that need the built model (a selection that finds no node, a sensor point far from
its body) stay with the builder in :mod:`ffrf.scenes.scene_file`.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from ffrf.errors import SceneError
from ffrf.system.markers import JOINT_OFFSETS

__all__ = ["Key", "MATERIAL", "SCHEMA", "SETTINGS", "check_scene", "check_table"]

JOINT_TYPES = ("revolute", "fixed", "driven_revolute")
#: Runs beyond these sizes are typing mistakes, not studies: they would not finish (or not fit in memory).
MAX_TIME_STEPS = 10_000_000
MAX_OUTPUTS = 1_000_000
PARAMETRIC_H_RANGE = (5e-4, 0.05)  # m: finer meshes of a whole link do not fit in memory
MESH_UNITS = ("m", "mm")
MODES = ("dynamic", "quasi_static")


@dataclass(frozen=True)
class Key:
    """One key: its kind (``number``, ``integer``, ``string``, ``boolean``, ``vector3``, ``vector4``,
    ``pair``, ``numbers``, ``strings``, ``table`` or ``tables``), whether it is required, a check of its
    value returning the problem (or ``None``), and, for ``table``/``tables``, the keys inside."""

    kind: str
    required: bool = False
    check: Callable[[object], str | None] | None = None
    keys: Mapping[str, Key] | None = None


def _positive(value) -> str | None:
    return None if value > 0 else f"must be > 0, got {value!r}"


def _non_negative(value) -> str | None:
    return None if value >= 0 else f"must be >= 0, got {value!r}"


def _between(low: float, high: float, closed: bool) -> Callable[[object], str | None]:
    def check(value) -> str | None:
        inside = low <= value <= high if closed else low < value < high
        bounds = f"[{low:g}, {high:g}]" if closed else f"({low:g}, {high:g})"
        return None if inside else f"must lie in {bounds}, got {value!r}"

    return check


def _one_of(choices: tuple) -> Callable[[object], str | None]:
    return lambda value: None if value in choices else f"must be one of {list(choices)}, got {value!r}"


def _at_least(bound: int) -> Callable[[Any], str | None]:
    return lambda value: None if value >= bound else f"must be >= {bound}, got {value!r}"


def _nonzero_vector(value) -> str | None:
    return None if math.hypot(*value) > 0.0 else "has zero length; give a direction such as [0.0, 0.0, 1.0]"


def _ordered_pair(value) -> str | None:
    return None if value[0] <= value[1] else f"is reversed ({value!r}); give [t_min, t_max]"


def _nonzero(value) -> str | None:
    return None if value != 0 else "must not be 0 (a drive that never turns); remove the drive or give a speed"


def _unit_quaternion(value) -> str | None:
    norm = math.sqrt(sum(v * v for v in value))
    return (
        None if abs(norm - 1.0) < 1e-9 else f"must have unit length (Euler parameters e0, e1, e2, e3), norm {norm:.6g}"
    )


MATERIAL = {
    "name": Key("string"),
    "E": Key("number", True, _positive),
    "nu": Key("number", True, _between(-1.0, 0.5, closed=False)),
    "rho": Key("number", True, _positive),
}
LINK_AXIS = {
    "name": Key("string", True),
    "point": Key("vector3", True),
    "direction": Key("vector3", True, _nonzero_vector),
    "joint_point": Key("vector3"),
}
PARAMETRIC = {
    "link": Key("integer", False, _one_of((0, 1, 2, 3))),
    "alpha3_deg": Key("number"),
    "axes": Key("tables", keys=LINK_AXIS),
    "mount": Key("boolean"),
    "h": Key("number", False, _between(*PARAMETRIC_H_RANGE, closed=True)),
}
CYLINDER = {
    "point": Key("vector3", True),
    "direction": Key("vector3", True, _nonzero_vector),
    "radius": Key("number", True, _positive),
    "axial_extent": Key("pair", True, _ordered_pair),
    "tolerance": Key("number", False, _positive),
}
AROUND_AXIS = {
    "point": Key("vector3", True),
    "direction": Key("vector3", True, _nonzero_vector),
    "tolerance": Key("number", False, _positive),
}
INTERFACE = {
    "name": Key("string", True),
    "axis": Key("table", keys=AROUND_AXIS),
    "group": Key("string"),
    "cylinder": Key("table", keys=CYLINDER),
    "nodes_file": Key("string"),
}
POSE = {
    "position": Key("vector3"),
    "euler_parameters": Key("vector4", False, _unit_quaternion),
}
BODY = {
    "name": Key("string", True),
    "mesh": Key("string"),
    "unit": Key("string", False, _one_of(MESH_UNITS)),
    "h": Key("number", False, _between(*PARAMETRIC_H_RANGE, closed=True)),
    "parametric": Key("table", keys=PARAMETRIC),
    "material": Key("table", True, keys=MATERIAL),
    "order": Key("integer", False, _one_of((1, 2))),
    "modes": Key("integer", False, _non_negative),
    "interfaces": Key("tables", True, keys=INTERFACE),
    "pose": Key("table", keys=POSE),
}
DRIVE = {
    "rpm": Key("number", False, _nonzero),
    "omega": Key("number", False, _nonzero),
    "ramp_time": Key("number", False, _positive),
    "start_angle": Key("number"),
    "start_angle_deg": Key("number"),
}
JOINT = {
    "name": Key("string"),
    "type": Key("string", False, _one_of(JOINT_TYPES)),
    "body0": Key("string", True),
    "body1": Key("string", True),
    "interface0": Key("string"),
    "interface1": Key("string"),
    "axis": Key("vector3", False, _nonzero_vector),
    "point": Key("vector3"),
    "axis0": Key("vector3", False, _nonzero_vector),
    "point0": Key("vector3"),
    "axis1": Key("vector3", False, _nonzero_vector),
    "point1": Key("vector3"),
    "drive": Key("table", keys=DRIVE),
}
SENSOR = {
    "name": Key("string", True),
    "body": Key("string", True),
    "point": Key("vector3"),
    "node": Key("integer", False, _non_negative),
    "surface": Key("boolean"),
    "joints": Key("strings"),
}
SETTINGS = {
    "name": Key("string"),
    "gravity": Key("vector3"),
    "beta": Key("number", False, _non_negative),
    "mode": Key("string", False, _one_of(MODES)),
    "t_end": Key("number", False, _positive),
    "step": Key("number", False, _positive),
    "rho_inf": Key("number", False, _between(0.0, 1.0, closed=True)),
    "outputs": Key("integer", False, _between(2, MAX_OUTPUTS, closed=True)),
    "joint_offsets": Key("string", False, _one_of(JOINT_OFFSETS)),
    "exact_gravity": Key("boolean"),
    "static_start": Key("boolean"),
}
#: The whole document: ``[scene]``, ``[[bodies]]``, ``[[joints]]``, ``[[sensors]]``.
SCHEMA = {
    "scene": Key("table", keys=SETTINGS),
    "bodies": Key("tables", True, keys=BODY),
    "joints": Key("tables", keys=JOINT),
    "sensors": Key("tables", keys=SENSOR),
}

_KIND_NAMES = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "boolean": "true or false",
    "vector3": "a list of 3 numbers",
    "vector4": "a list of 4 numbers",
    "pair": "a list of 2 numbers",
    "table": "a table {...}",
    "tables": "a list of tables ([[...]] or [{...}, ...])",
    "strings": "a list of strings",
    "numbers": "a list of numbers",
}


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _type_problem(kind: str, value) -> str | None:
    """Why ``value`` is not of ``kind`` (None if it is); nan and inf are not numbers of a scene."""
    if kind in ("number", "integer"):
        if not _is_number(value) or (kind == "integer" and not isinstance(value, int)):
            return f"must be {_KIND_NAMES[kind]}, got {value!r}"
        return None if math.isfinite(value) else f"must be finite, got {value!r}"
    if kind in ("vector3", "vector4", "pair"):
        size = {"vector3": 3, "vector4": 4, "pair": 2}[kind]
        if not isinstance(value, list) or len(value) != size or not all(_is_number(v) for v in value):
            return f"must be {_KIND_NAMES[kind]}, got {value!r}"
        return None if all(math.isfinite(v) for v in value) else f"must be finite, got {value!r}"
    if kind == "numbers":
        if not isinstance(value, list) or not value or not all(_is_number(v) for v in value):
            return f"must be {_KIND_NAMES[kind]} (at least one), got {value!r}"
        return None if all(math.isfinite(v) for v in value) else f"must be finite, got {value!r}"
    if kind == "strings":
        ok = isinstance(value, list) and value and all(isinstance(v, str) for v in value)
        return None if ok else f"must be {_KIND_NAMES[kind]} (at least one), got {value!r}"
    expected = {"string": str, "boolean": bool, "table": dict}.get(kind)
    if expected is not None:
        return None if isinstance(value, expected) else f"must be {_KIND_NAMES[kind]}, got {value!r}"
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        return f"must be {_KIND_NAMES[kind]}, got {value!r}"
    return None


def check_table(table: dict, keys: Mapping[str, Key], where: str) -> None:
    """Raise :class:`SceneError` for the first key of ``table`` (and of the tables inside) that ``keys`` refuses."""
    for name in table:
        if name not in keys:
            close = difflib.get_close_matches(name, keys, n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise SceneError(f"{where}: unknown key {name!r}; {hint}valid keys are {sorted(keys)}")
    for name, key in keys.items():
        if name not in table:
            if key.required:
                raise SceneError(f"{where}: missing required key {name!r} ({_KIND_NAMES[key.kind]})")
            continue
        value = table[name]
        problem = _type_problem(key.kind, value)
        if problem is None and key.check is not None:
            problem = key.check(value)
        if problem is not None:
            raise SceneError(f"{where}: {name!r} {problem}")
        if key.kind == "table":
            check_table(value, key.keys or {}, f"{where}, {name}")
        elif key.kind == "tables":
            for k, entry in enumerate(value):
                check_table(entry, key.keys or {}, f"{where}, {name}[{k}]{_label(entry)}")


def _label(entry: dict) -> str:
    name = entry.get("name")
    return f" {name!r}" if isinstance(name, str) else ""


def _unique(entries: list[dict], what: str, where: str) -> None:
    seen: set[str | None] = set()
    for entry in entries:
        name = entry.get("name")
        if name in seen:
            raise SceneError(f"{where}: two {what} are named {name!r}; give each a unique name")
        seen.add(name)


def _check_body(body: dict, where: str) -> None:
    sources = [key for key in ("mesh", "parametric") if key in body]
    if len(sources) != 1:
        raise SceneError(
            f'{where}: give exactly one of mesh = "file" or parametric = {{link = ...}}, got {sources or "neither"}'
        )
    spec = body.get("parametric")
    if spec is not None and ("link" in spec) == ("axes" in spec):
        raise SceneError(
            f"{where}, parametric: give exactly one of link = 0..3 (the paper's link) or axes = [{{name, point, "
            "direction}, {...}] (any two skew axes)"
        )
    if spec is not None and "axes" in spec and len(spec["axes"]) != 2:
        raise SceneError(f"{where}, parametric: a link has exactly two axes, got {len(spec['axes'])}")
    if spec is not None and "axes" in spec and "alpha3_deg" in spec:
        raise SceneError(f"{where}, parametric: alpha3_deg belongs to the paper's links (link = ...), not to axes")
    if "h" in body and not str(body.get("mesh", "")).lower().endswith(".stl"):
        raise SceneError(
            f"{where}: 'h' sizes the tetrahedra that fill an STL surface (mesh = \"part.stl\"); a volume mesh keeps "
            "its elements and a parametric link takes parametric = {h = ...}"
        )
    if "unit" in body and "mesh" not in body:
        raise SceneError(f"{where}: 'unit' scales a mesh file; a parametric link is in metres, remove 'unit'")
    if not body["interfaces"]:
        raise SceneError(f"{where}: list at least one interface (the first is the body's frame)")
    _unique(body["interfaces"], "interfaces", where)
    for k, interface in enumerate(body["interfaces"]):
        selectors = [key for key in ("group", "cylinder", "axis", "nodes_file") if key in interface]
        if len(selectors) != 1:
            raise SceneError(
                f"{where}, interfaces[{k}]{_label(interface)}: select it by exactly one of group, "
                f"cylinder, axis or nodes_file, got {selectors or 'none'}"
            )


def _check_joint(joint: dict, interfaces: Mapping[str, set[str]], where: str) -> None:
    kind = joint.get("type", "revolute")
    if kind == "driven_revolute" and "drive" not in joint:
        raise SceneError(f"{where}: a driven_revolute needs drive = {{rpm = ..., ramp_time = ...}}")
    if kind != "driven_revolute" and "drive" in joint:
        raise SceneError(f"{where}: a {kind} joint has no drive; use type = \"driven_revolute\" or remove 'drive'")
    if "drive" in joint and ("rpm" in joint["drive"]) == ("omega" in joint["drive"]):
        raise SceneError(f"{where}, drive: give exactly one of rpm = ... (rev/min) or omega = ... (rad/s)")
    if "drive" in joint and "start_angle" in joint["drive"] and "start_angle_deg" in joint["drive"]:
        raise SceneError(f"{where}, drive: give start_angle (rad) or start_angle_deg, not both")
    for side in ("0", "1"):
        if f"axis{side}" in joint and "axis" in joint or f"point{side}" in joint and "point" in joint:
            raise SceneError(
                f"{where}: give either axis/point (both sides) or axis{side}/point{side} (side {side}), not both"
            )
    sides = [joint["body0"], joint["body1"]]
    if sides == ["ground", "ground"]:
        raise SceneError(f"{where}: at least one side must be a body, both are 'ground'")
    for index, body in enumerate(sides):
        if body == "ground":
            continue
        if body not in interfaces:
            raise SceneError(f"{where}: unknown body {body!r} in body{index}; bodies are {sorted(interfaces)}")
        interface = joint.get(f"interface{index}")
        if interface is None:
            raise SceneError(
                f"{where}: missing required key 'interface{index}' (an interface of body {body!r}: "
                f"{sorted(interfaces[body])})"
            )
        if interface not in interfaces[body]:
            raise SceneError(
                f"{where}: body {body!r} has no interface {interface!r}; it has {sorted(interfaces[body])}"
            )


def _check_run_size(settings: dict, where: str) -> None:
    steps = settings.get("t_end", 1.0) / settings.get("step", 1e-3)
    if settings.get("mode", "dynamic") == "dynamic" and steps > MAX_TIME_STEPS:
        raise SceneError(
            f"{where}: t_end / step = {steps:.3g} time steps (more than {MAX_TIME_STEPS:.0e}); check "
            "the units (seconds) or split the run"
        )


def check_scene(document: dict, where: str = "scene") -> None:
    """Raise :class:`SceneError` for the first thing in a parsed scene file that is not allowed."""
    check_table(document, SCHEMA, where)
    _check_run_size(document.get("scene", {}), f"{where}, scene")
    bodies, joints, sensors = document["bodies"], document.get("joints", []), document.get("sensors", [])
    if not bodies:
        raise SceneError(f"{where}: no [[bodies]]; a scene needs at least one body")
    _unique(bodies, "bodies", where)
    _unique(joints, "joints", where)
    _unique(sensors, "sensors", where)
    for k, body in enumerate(bodies):
        _check_body(body, f"{where}, bodies[{k}]{_label(body)}")
    interfaces = {body["name"]: {i["name"] for i in body["interfaces"]} for body in bodies}
    if "ground" in interfaces:
        raise SceneError(f"{where}: a body is named 'ground', which names the world in joints; rename the body")
    for k, joint in enumerate(joints):
        _check_joint(joint, interfaces, f"{where}, joints[{k}]{_label(joint)}")
    for k, sensor in enumerate(sensors):
        label = f"{where}, sensors[{k}]{_label(sensor)}"
        if sensor["body"] not in interfaces:
            raise SceneError(f"{label}: unknown body {sensor['body']!r}; bodies are {sorted(interfaces)}")
        if sum(key in sensor for key in ("point", "node", "joints")) != 1:
            raise SceneError(
                f"{label}: give exactly one of point = [x, y, z] (m), node = index or joints = [names] (the mean "
                "of their joint points on this body)"
            )
        for name in sensor.get("joints", []):
            sides = next((j for j in joints if j.get("name", "joint") == name), None)
            if sides is None:
                raise SceneError(f"{label}: unknown joint {name!r}; joints are {[j.get('name') for j in joints]}")
            if sensor["body"] not in (sides["body0"], sides["body1"]):
                raise SceneError(f"{label}: joint {name!r} does not hold body {sensor['body']!r}")
