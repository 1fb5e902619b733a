"""What a scene file may say: every table, key, type and admissible value, checked before anything is built.

The schema is plain data (one :class:`Key` per key) so the documentation, the checks and the error
messages cannot drift apart. :func:`check_scene` walks a parsed TOML document and raises
:class:`~ffrf.errors.SceneError` with one line that names the key, where it is, what is wrong and
what to write instead; a misspelt key (``gravty``, ``rpmm``) is an error with a suggestion, never
ignored. Checks that need the built model (a selection that finds no node, a sensor point far from
its body) stay with the builder in :mod:`ffrf.scenes.scene_file`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from ffrf.errors import SceneError
from ffrf.geometry.link_geometry import LINK_DESIGN_FIELDS
from ffrf.scenes.limits import MAX_OUTPUTS, MAX_TIME_STEPS, steps_problem
from ffrf.scenes.scene_forces import ELASTIC, FORCE_TYPES, check_force
from ffrf.scenes.scene_matrices import MATRIX_FILES, MATRIX_FORMATS, is_abaqus_input
from ffrf.scenes.schema_keys import (
    Key,
    between,
    check_table,
    label,
    non_negative,
    nonzero,
    nonzero_vector,
    one_of,
    ordered_pair,
    positive,
    unique,
    unit_quaternion,
)
from ffrf.solvers.stability import check_judged_at_equilibria
from ffrf.system.markers import JOINT_OFFSETS

__all__ = [
    "Key",
    "MATERIAL",
    "MAX_OUTPUTS",
    "MAX_TIME_STEPS",
    "REDUCTIONS",
    "SCHEMA",
    "SETTINGS",
    "check_scene",
    "check_table",
]

JOINT_TYPES = ("revolute", "fixed", "driven_revolute")
PARAMETRIC_H_RANGE = (5e-4, 0.05)  # m: finer meshes of a whole link do not fit in memory
MESH_UNITS = ("m", "mm")
MODES = ("dynamic", "quasi_static")
#: Mode bases of a body: Craig-Bampton (interface and fixed-interface modes) or free-free eigenmodes.
REDUCTIONS = ("craig_bampton", "free_free")
#: Body keys that describe a mesh (and its material), not a body from matrices.
MESH_KEYS = ("material", "order", "unit", "h")


MATERIAL = {
    "name": Key("string"),
    "E": Key("number", True, positive),
    "nu": Key("number", True, between(-1.0, 0.5, closed=False)),
    "rho": Key("number", True, positive),
    "strength": Key("number", False, positive),
}
LINK_AXIS = {
    "name": Key("string", True),
    "point": Key("vector3", True),
    "direction": Key("vector3", True, nonzero_vector),
    "joint_point": Key("vector3"),
    "trim": Key("number", False, positive),  # the trimming's reach beyond this housing's end faces (m)
}
#: The parametric link's dimensions (m), :class:`ffrf.geometry.link_geometry.LinkDesign`; the rest keep defaults.
LINK_DESIGN = {name: Key("number", False, positive) for name in LINK_DESIGN_FIELDS}
PARAMETRIC = {
    "design": Key("table", keys=LINK_DESIGN),
    "axes": Key("tables", True, keys=LINK_AXIS),
    "mount": Key("boolean"),
    "h": Key("number", False, between(*PARAMETRIC_H_RANGE, closed=True)),
}
CYLINDER = {
    "point": Key("vector3", True),
    "direction": Key("vector3", True, nonzero_vector),
    "radius": Key("number", True, positive),
    "axial_extent": Key("pair", True, ordered_pair),
    "tolerance": Key("number", False, positive),
}
AROUND_AXIS = {
    "point": Key("vector3", True),
    "direction": Key("vector3", True, nonzero_vector),
    "tolerance": Key("number", False, positive),
}
PLANE = {
    "point": Key("vector3", True),
    "normal": Key("vector3", True, nonzero_vector),
    "tolerance": Key("number", False, positive),
}
INTERFACE = {
    "name": Key("string", True),
    "axis": Key("table", keys=AROUND_AXIS),
    "group": Key("string"),
    "cylinder": Key("table", keys=CYLINDER),
    "plane": Key("table", keys=PLANE),
    "nodes_file": Key("string"),
    "weights": Key("string", False, one_of(("area", "equal"))),
}
SELECTORS = ("group", "cylinder", "axis", "plane", "nodes_file")
POINT_MASS = {
    "node": Key("integer", False, non_negative),
    "point": Key("vector3"),
    "tolerance": Key("number", False, positive),
    "mass": Key("number", True, non_negative),
}
MATRICES = {
    "format": Key("string", True, one_of(MATRIX_FORMATS)),
    "file": Key("string"),
    "nodes": Key("string"),
    "instance": Key("string"),
    "mass": Key("string"),
    "stiffness": Key("string"),
    "scale_stiffness": Key("number", False, positive),
    "point_masses": Key("tables", keys=POINT_MASS),
}
POSE = {
    "position": Key("vector3"),
    "euler_parameters": Key("vector4", False, unit_quaternion),
}
VELOCITY = {
    "linear": Key("vector3"),
    "angular": Key("vector3"),
    "modal": Key("numbers"),
}
BODY = {
    "name": Key("string", True),
    "mesh": Key("string"),
    "unit": Key("string", False, one_of(MESH_UNITS)),
    "h": Key("number", False, between(*PARAMETRIC_H_RANGE, closed=True)),
    "parametric": Key("table", keys=PARAMETRIC),
    "matrices": Key("table", keys=MATRICES),
    "material": Key("table", keys=MATERIAL),
    "order": Key("integer", False, one_of((1, 2))),
    "reduction": Key("string", False, one_of(REDUCTIONS)),
    "modes": Key("integer", False, non_negative),
    "interfaces": Key("tables", True, keys=INTERFACE),
    "pose": Key("table", keys=POSE),
    "velocity": Key("table", keys=VELOCITY),
}
DRIVE = {
    "rpm": Key("number", False, nonzero),
    "omega": Key("number", False, nonzero),
    "ramp_time": Key("number", False, positive),
    "start_angle": Key("number", False, between(-2.0 * math.pi, 2.0 * math.pi, closed=True)),
    "start_angle_deg": Key("number", False, between(-360.0, 360.0, closed=True)),
}
#: A revolute joint's play (``docs/formulation.md``, Eqs. (P1)-(P5)): millimetres at the file's edge.
CLEARANCE = {
    "radial_mm": Key("number", True, non_negative),
    "axial_mm": Key("number", False, non_negative),
    "pin_length_mm": Key("number", True, positive),
    "stiffness": Key("number", False, positive),
    "damping": Key("number", False, non_negative),
}
JOINT = {
    "name": Key("string"),
    "type": Key("string", False, one_of(JOINT_TYPES)),
    "body0": Key("string", True),
    "body1": Key("string", True),
    "interface0": Key("string"),
    "interface1": Key("string"),
    "axis": Key("vector3", False, nonzero_vector),
    "point": Key("vector3"),
    "axis0": Key("vector3", False, nonzero_vector),
    "point0": Key("vector3"),
    "axis1": Key("vector3", False, nonzero_vector),
    "point1": Key("vector3"),
    "drive": Key("table", keys=DRIVE),
    "clearance": Key("table", keys=CLEARANCE),
}
LOAD_TABLE = {
    "time": Key("numbers", True),
    "scale": Key("numbers", True),
}
FORCE = {
    "name": Key("string", True),
    "type": Key("string", True, one_of(FORCE_TYPES)),
    "body0": Key("string"),
    "body1": Key("string"),
    **{key: JOINT[key] for key in ("interface0", "interface1", "axis", "point", "axis0", "point0", "axis1", "point1")},
    "elastic": Key("string", False, one_of(tuple(ELASTIC))),
    "stiffness": Key("numbers"),
    "damping": Key("numbers"),
    "offset": Key("numbers"),
    "body": Key("string"),
    "interface": Key("string"),
    "force": Key("vector3"),
    "torque": Key("vector3"),
    "frame": Key("string", False, one_of(("world", "marker"))),
    "table": Key("table", keys=LOAD_TABLE),
    "stall_torque": Key("number"),
    "length": Key("number", False, positive),
    "no_load_speed": Key("number", False, positive),
}
SENSOR = {
    "name": Key("string", True),
    "body": Key("string", True),
    "point": Key("vector3"),
    "node": Key("integer", False, non_negative),
    "surface": Key("boolean"),
    "joints": Key("strings"),
}
SETTINGS = {
    "name": Key("string"),
    "gravity": Key("vector3"),
    "beta": Key("number", False, non_negative),
    "alpha": Key("number", False, non_negative),
    "mode": Key("string", False, one_of(MODES)),
    "t_end": Key("number", False, positive),
    "step": Key("number", False, positive),
    "rho_inf": Key("number", False, between(0.0, 1.0, closed=True)),
    "outputs": Key("integer", False, between(2, MAX_OUTPUTS, closed=True)),
    "joint_offsets": Key("string", False, one_of(JOINT_OFFSETS)),
    "exact_gravity": Key("boolean"),
    "static_start": Key("boolean"),
    "stability": Key("boolean"),
    "max_steps": Key("number", False, positive),
    "clearance": Key("table", keys=CLEARANCE),
}
#: The whole document: ``[scene]``, ``[[bodies]]``, ``[[joints]]``, ``[[sensors]]``.
SCHEMA = {
    "scene": Key("table", keys=SETTINGS),
    "bodies": Key("tables", True, keys=BODY),
    "joints": Key("tables", keys=JOINT),
    "sensors": Key("tables", keys=SENSOR),
    "forces": Key("tables", keys=FORCE),
}


def _check_body(body: dict, where: str) -> None:
    sources = [key for key in ("mesh", "parametric", "matrices") if key in body]
    if len(sources) != 1:
        raise SceneError(
            f'{where}: give exactly one of mesh = "file", parametric = {{axes = ...}} or matrices = {{format = ...}}, '
            f"got {sources or 'none'}"
        )
    if body.get("reduction") == "free_free" and body.get("modes", 4) < 1:
        raise SceneError(
            f'{where}: reduction = "free_free" keeps modes >= 1 flexible free-free modes, got 0 (a body without '
            'them is rigid); give modes >= 1, or reduction = "craig_bampton" for interface modes only'
        )
    if "matrices" in body:
        _check_matrices_body(body, where)
        return
    if "material" not in body:
        raise SceneError(f"{where}: missing required key 'material' (a table {{E, nu, rho}} for the mesh)")
    spec = body.get("parametric")
    if spec is not None and len(spec["axes"]) != 2:
        raise SceneError(f"{where}, parametric: a link has exactly two axes, got {len(spec['axes'])}")
    if "h" in body and not str(body.get("mesh", "")).lower().endswith(".stl"):
        raise SceneError(
            f"{where}: 'h' sizes the tetrahedra that fill an STL surface (mesh = \"part.stl\"); a volume mesh keeps "
            "its elements and a parametric link takes parametric = {h = ...}"
        )
    if "unit" in body and "mesh" not in body:
        raise SceneError(f"{where}: 'unit' scales a mesh file; a parametric link is in metres, remove 'unit'")
    _check_interfaces(body, SELECTORS, where)


def _check_interfaces(body: dict, selectors: tuple[str, ...], where: str) -> None:
    """At least one interface, unique names, each selected by exactly one of ``selectors``."""
    if not body["interfaces"]:
        raise SceneError(f"{where}: list at least one interface (the first is the body's frame)")
    unique(body["interfaces"], "interfaces", where)
    for k, interface in enumerate(body["interfaces"]):
        given = [key for key in SELECTORS if key in interface]
        if len(given) != 1 or given[0] not in selectors:
            why = "; a body from matrices has no named groups or surface mesh of ours" if "matrices" in body else ""
            raise SceneError(
                f"{where}, interfaces[{k}]{label(interface)}: select it by exactly one of {', '.join(selectors[:-1])} "
                f"or {selectors[-1]}, got {given or 'none'}{why}"
            )


def _check_matrices_body(body: dict, where: str) -> None:
    """A body from matrices: no mesh keys, the files its format reads, interfaces on nodes."""
    spec, place = body["matrices"], f"{where}, matrices"
    mesh_keys = [key for key in MESH_KEYS if key in body]
    if mesh_keys:
        raise SceneError(
            f"{where}: {mesh_keys} describe a mesh; a body from matrices takes its mass and stiffness from its "
            "files (SI units), remove them"
        )
    wanted = MATRIX_FILES[spec["format"]]
    missing = [key for key in wanted if key not in spec]
    extra = [key for key in ("file", "nodes", "mass", "stiffness") if key in spec and key not in wanted]
    if missing or extra:
        raise SceneError(
            f"{place}: format = {spec['format']!r} reads {' = ..., '.join(wanted)} = ... "
            f"({'missing ' + str(missing) if missing else 'not ' + str(extra)})"
        )
    if "instance" in spec and not is_abaqus_input(spec.get("nodes", "")):
        raise SceneError(f"{place}: 'instance' names a *Part or *Instance of an Abaqus .inp given as nodes = ...")
    for k, point_mass in enumerate(spec.get("point_masses", [])):
        if ("node" in point_mass) == ("point" in point_mass):
            raise SceneError(f"{place}, point_masses[{k}]: give exactly one of node = index or point = [x, y, z] (m)")
    _check_interfaces(body, ("cylinder", "plane", "nodes_file"), where)


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
    if "clearance" in joint and kind != "revolute":
        raise SceneError(
            f"{where}: only a passive revolute joint can have clearance, this one is {kind!r}; drive a loose joint "
            "through a separate driven joint, or remove 'clearance'"
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
    """A dynamic run's step no longer than the run, and at most ``max_steps`` (:data:`MAX_TIME_STEPS`) of them."""
    t_end, step = settings.get("t_end", 1.0), settings.get("step", 1e-3)
    if settings.get("mode", "dynamic") != "dynamic":
        return
    if step > t_end:
        raise SceneError(f"{where}: step = {step!r} s is longer than the run, t_end = {t_end!r} s; give step <= t_end")
    problem = steps_problem(t_end / step, settings.get("max_steps"), "max_steps = N in [scene]", " (t_end / step)")
    if problem is not None:
        raise SceneError(f"{where}: {problem}")


def check_scene(document: dict, where: str = "scene") -> None:
    """Raise :class:`SceneError` for the first thing in a parsed scene file that is not allowed."""
    check_table(document, SCHEMA, where)
    _check_run_size(document.get("scene", {}), f"{where}, scene")
    settings = document.get("scene", {})
    stability, mode = settings.get("stability", False), settings.get("mode", "dynamic")
    check_judged_at_equilibria(mode, stability, 'set mode = "quasi_static"', f"{where}, scene")
    bodies, joints, sensors = document["bodies"], document.get("joints", []), document.get("sensors", [])
    if not bodies:
        raise SceneError(f"{where}: no [[bodies]]; a scene needs at least one body")
    unique(bodies, "bodies", where)
    unique(joints, "joints", where)
    unique(sensors, "sensors", where)
    for k, body in enumerate(bodies):
        _check_body(body, f"{where}, bodies[{k}]{label(body)}")
    interfaces = {body["name"]: {i["name"] for i in body["interfaces"]} for body in bodies}
    if "ground" in interfaces:
        raise SceneError(f"{where}: a body is named 'ground', which names the world in joints; rename the body")
    for k, joint in enumerate(joints):
        _check_joint(joint, interfaces, f"{where}, joints[{k}]{label(joint)}")
    forces = document.get("forces", [])
    unique(forces, "forces", where)
    for k, force in enumerate(forces):
        place = f"{where}, forces[{k}]{label(force)}"
        check_force(force, place)
        if force["type"] != "load" and "body0" in force and "body1" in force:
            _check_joint(force, interfaces, place)
        elif force["type"] == "load" and "body" in force:
            body, interface = force["body"], force.get("interface")
            if body not in interfaces:
                raise SceneError(f"{place}: unknown body {body!r}; bodies are {sorted(interfaces)}")
            if interface not in interfaces[body]:
                raise SceneError(
                    f"{place}: body {body!r} has no interface {interface!r}; it has {sorted(interfaces[body])}"
                )
    for k, sensor in enumerate(sensors):
        place = f"{where}, sensors[{k}]{label(sensor)}"
        if sensor["body"] not in interfaces:
            raise SceneError(f"{place}: unknown body {sensor['body']!r}; bodies are {sorted(interfaces)}")
        if sum(key in sensor for key in ("point", "node", "joints")) != 1:
            raise SceneError(
                f"{place}: give exactly one of point = [x, y, z] (m), node = index or joints = [names] (the mean "
                "of their joint points on this body)"
            )
        for name in sensor.get("joints", []):
            sides = next((j for j in joints if j.get("name", "joint") == name), None)
            if sides is None:
                raise SceneError(f"{place}: unknown joint {name!r}; joints are {[j.get('name') for j in joints]}")
            if sensor["body"] not in (sides["body0"], sides["body1"]):
                raise SceneError(f"{place}: joint {name!r} does not hold body {sensor['body']!r}")
