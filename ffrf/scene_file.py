"""Scenes as TOML files: run a linkage built from your own meshes without writing Python.

A scene lists bodies (a mesh file or one of the paper's parametric links), their material,
element order, number of modes and interfaces; joints between interfaces (or the ground);
an optional drive; gravity, damping, solver settings and sensors. All lengths are metres
unless a body says ``unit = "mm"`` for its mesh. Bodies sit where their meshes are: the
mesh coordinates are world coordinates at t = 0 (as in the built-in Bennett scene)::

    [scene]
    name = "hinged link"
    gravity = [0.0, 0.0, -9.81]
    beta = 0.005                      # stiffness-proportional damping
    mode = "dynamic"                  # or "quasi_static"
    t_end = 1.0
    step = 1e-3                       # dynamic time step
    rho_inf = 0.9
    outputs = 101
    joint_offsets = "body"            # joint point off its interface centre: "body" (as Exudyn) or "marker" frame

    [[bodies]]
    name = "link"
    mesh = "link.msh"                 # any meshio volume mesh; or: parametric = {link = 1, alpha3_deg = 90, h = 0.006}
    unit = "mm"                       # optional, scales the mesh to metres
    material = {E = 1.2e9, nu = 0.33, rho = 450.0}
    order = 2                         # default 2: linear tetrahedra are too stiff in bending
    modes = 4
    interfaces = [                    # the first is the body's frame interface
        {name = "bore0", group = "joint0"},
        {name = "bore1", cylinder = {point = [0.1, 0, 0], direction = [0, 0, 1], radius = 0.0095,
                                     axial_extent = [-0.01, 0.01]}},
        {name = "pad", nodes_file = "pad_nodes.txt"},   # 0-based node indices, optional 2nd column: weights
    ]

    [[joints]]
    name = "hinge"
    type = "revolute"                 # "revolute", "fixed" or "driven_revolute"
    body0 = "ground"                  # or a body name, with interface0 = "..."
    body1 = "link"
    interface1 = "bore0"
    axis = [0.0, 1.0, 0.0]            # joint axis (world, at t = 0)
    point = [0.0, 0.0, 0.0]           # joint point (world, at t = 0); default: interface1's centre
    drive = {rpm = 1.0, ramp_time = 1.0}   # driven_revolute only: the paper's cosine ramp

    [[sensors]]
    name = "tip"
    body = "link"
    point = [0.2, 0.0, 0.0]           # the mesh node nearest to this point (world, t = 0); or node = index

Every interface selector weights its nodes by the surface area of the boundary triangles they span
(``ffrf.interfaces``), unless a ``nodes_file`` gives a weight per node in a second column. The file is
checked against :mod:`ffrf.scene_schema` before anything is built: an unknown or misspelt key, a wrong
type or an impossible value is a :class:`SceneError` naming the key, where it is and the fix.
"""

from __future__ import annotations

import json
import logging
import time as wallclock
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .craig_bampton import CraigBamptonBasis, craig_bampton
from .drives import CosineRamp, RampedAngle, rpm
from .errors import SceneError
from .euler_parameters import rotation_matrix
from .fe_model import FEModel
from .flexible_body import FlexibleBody
from .generalized_alpha import generalized_alpha
from .interfaces import InterfaceNodes, interface_from_group, interface_from_nodes_file, interface_in_cylinder
from .joints import GroundFrame, MarkerJoint, driven_revolute_joint, fixed_joint, revolute_joint
from .link_geometry import bennett_axes, mesh_link, paper_link_axes
from .markers import attach_joint_point, rigid_interface_marker
from .materials import Material
from .mesh import read_mesh
from .modal_moments import modal_moments
from .output import write_csv
from .scene_schema import check_scene
from .static_solver import quasi_static, static_equilibrium
from .system import MultibodySystem

__all__ = ["SceneError", "FileScene", "load_scene", "run_scene", "simulate_scene", "start_state", "sensor_arrays"]

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class FileBody:
    name: str
    fe: FEModel
    interfaces: dict[str, InterfaceNodes]
    reduction: CraigBamptonBasis


@dataclass(frozen=True, eq=False)
class FileScene:
    """A scene read from TOML: the system, its bodies, the settings and the sensors (body, node)."""

    name: str
    bodies: tuple[FileBody, ...]
    system: MultibodySystem
    settings: dict
    sensors: dict[str, tuple[int, int]]
    driven: tuple[str, ...]


def _mesh(entry: dict, base: Path, where: str):
    if "mesh" in entry:
        path = base / entry["mesh"]
        if not path.is_file():
            raise SceneError(f"{where}: mesh file {path} not found; give a path relative to the scene file")
        return read_mesh(path, unit=entry.get("unit"))
    spec = entry["parametric"]
    first, second, names = paper_link_axes(spec["link"], bennett_axes(float(spec.get("alpha3_deg", 90.0))))
    mesh, _ = mesh_link(first, second, h=float(spec.get("h", 6e-3)), names=names, mount=spec["link"] == 0,
                        name=entry["name"])
    return mesh


def _interface(fe: FEModel, spec: dict, base: Path) -> InterfaceNodes:
    name = spec["name"]
    if "group" in spec:
        return interface_from_group(fe, name, spec["group"])
    if "cylinder" in spec:
        c = spec["cylinder"]
        return interface_in_cylinder(fe, name, c["point"], c["direction"], float(c["radius"]),
                                     tuple(c["axial_extent"]), float(c.get("tolerance", 1e-4)))
    return interface_from_nodes_file(fe, name, base / spec["nodes_file"])


def _body(entry: dict, base: Path, beta: float, exact_gravity: bool) -> tuple[FileBody, FlexibleBody]:
    name = entry["name"]
    m = entry["material"]
    material = Material(float(m["E"]), float(m["nu"]), float(m["rho"]), name=f"{name} material")
    fe = FEModel.from_tet_mesh(_mesh(entry, base, f"body {name!r}"), material, entry.get("order", 2))
    interfaces = {}
    for spec in entry["interfaces"]:
        interface = _interface(fe, spec, base)
        interfaces[interface.name] = interface
    reduction = craig_bampton(fe, list(interfaces.values()), int(entry.get("modes", 4)))
    body = FlexibleBody(name, modal_moments(fe.nodes, fe.mass, reduction.basis), reduction.reduced_stiffness,
                        beta * reduction.reduced_stiffness, exact_gravity)
    return FileBody(name, fe, interfaces, reduction), body


def _joint_frame(axis) -> NDArray:
    from .bennett_scene import joint_frame

    return joint_frame(np.asarray(axis, dtype=float))


def _joint(spec: dict, index: dict[str, int], bodies: list[FileBody], joint_offsets: str) -> MarkerJoint:
    name = spec.get("name", "joint")
    kind = spec.get("type", "revolute")

    def marker(side: str):  # the scene schema has checked the body and interface names
        body_name = spec[f"body{side}"]
        if body_name == "ground":
            return None
        body = bodies[index[body_name]]
        interface_name = spec[f"interface{side}"]
        itf = body.interfaces[interface_name]
        return rigid_interface_marker(index[body_name], body.fe.nodes, body.reduction.basis, itf.nodes, itf.weights,
                                      name=f"{body_name}:{interface_name}")

    m0, m1 = marker("0"), marker("1")
    if m1 is None:
        m0, m1 = m1, m0
    frame = _joint_frame(spec.get("axis", [0.0, 0.0, 1.0]))
    point = np.asarray(spec.get("point", m1.point), dtype=float)
    if m0 is None:
        side0, offset0 = GroundFrame(point, np.eye(3)), np.zeros(3)
    else:
        side0, offset0 = attach_joint_point(m0, point, joint_offsets)
    m1, offset1 = attach_joint_point(m1, point, joint_offsets)
    if kind == "revolute":
        return revolute_joint(side0, m1, frame, frame, offset0, offset1, name=name)
    if kind == "fixed":
        return fixed_joint(side0, m1, frame, frame, offset0, offset1, name=name)
    d = spec["drive"]  # driven_revolute, the only other type the schema admits
    ramp = CosineRamp(rpm(float(d["rpm"])), float(d.get("ramp_time", 1.0)))
    start = np.radians(float(d.get("start_angle_deg", 0.0)))
    return driven_revolute_joint(side0, m1, RampedAngle(start, ramp), frame, frame, offset0, offset1, name=name)


def load_scene(path: str | Path) -> FileScene:
    """Read and build a TOML scene (see the module docstring)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as error:
        raise SceneError(f"{path}: cannot read the scene ({error})") from error
    check_scene(data, path.name)
    settings = dict(data.get("scene", {}))
    beta = float(settings.get("beta", 0.0))
    built = [_body(entry, path.parent, beta, settings.get("exact_gravity", True)) for entry in data["bodies"]]
    bodies = [b for b, _ in built]
    index = {b.name: k for k, b in enumerate(bodies)}
    joint_offsets = settings.get("joint_offsets", "body")
    joints = [_joint(spec, index, bodies, joint_offsets) for spec in data.get("joints", [])]
    system = MultibodySystem(tuple(body for _, body in built), tuple(joints),
                             gravity=np.asarray(settings.get("gravity", [0.0, 0.0, -9.81]), dtype=float))
    sensors = {spec["name"]: (index[spec["body"]], _sensor_node(spec, bodies[index[spec["body"]]].fe))
               for spec in data.get("sensors", [])}
    driven = tuple(j.name for j in joints if j.angle is not None)
    return FileScene(settings.get("name", path.stem), tuple(bodies), system, settings, sensors, driven)


#: A sensor point farther than this fraction of its body's bounding-box diagonal from every node is a mistake.
SENSOR_REACH = 0.1


def _sensor_node(spec: dict, fe: FEModel) -> int:
    """The node a sensor reads: given, or the node nearest to its point (which must lie on the body)."""
    if "node" in spec:
        if spec["node"] >= len(fe.nodes):
            raise SceneError(f"sensor {spec['name']!r}: node {spec['node']} does not exist; body {spec['body']!r} "
                             f"has nodes 0 to {len(fe.nodes) - 1}")
        return spec["node"]
    distances = np.linalg.norm(fe.nodes - np.asarray(spec["point"], dtype=float), axis=1)
    size = float(np.linalg.norm(np.ptp(fe.nodes, axis=0)))
    if distances.min() > SENSOR_REACH * size:
        raise SceneError(f"sensor {spec['name']!r}: point {spec['point']} is {distances.min():.4g} m from the nearest "
                         f"node of body {spec['body']!r} (body size {size:.4g} m); give a point on the body, in "
                         "metres and world coordinates at t = 0")
    return int(np.argmin(distances))


def start_state(scene: FileScene) -> NDArray[np.float64]:
    """The state the run starts from: the meshes' configuration, statically equilibrated unless
    ``static_start = false`` (default: static start for quasi-static runs only)."""
    s = scene.settings
    q0 = scene.system.initial_state()
    if s.get("static_start", s.get("mode", "dynamic") != "dynamic"):
        q0 = static_equilibrium(scene.system, q0).q
    return q0


def sensor_arrays(scene: FileScene, q: NDArray, multipliers: NDArray) -> dict[str, NDArray]:
    """Sensor positions (rows = q's rows) and the multiplier of each driven joint's angle
    equation, ``<joint>_torque`` (N m, applied to the joint's side 1)."""
    arrays = {}
    for name, (body, node) in scene.sensors.items():
        block = scene.system.block(body)
        psi = scene.bodies[body].reduction.basis[3 * node:3 * node + 3]
        local = scene.bodies[body].fe.nodes[node]
        arrays[name] = np.array([row[block][:3] + rotation_matrix(row[block][3:7]) @ (local + psi @ row[block][7:])
                                 for row in q])
    rows = scene.system.rows
    for k, constraint in enumerate(scene.system.all_constraints):
        if constraint.name in scene.driven:
            arrays[f"{constraint.name}_torque"] = multipliers[:, int(rows[k + 1]) - 1]
    return arrays


def simulate_scene(scene: FileScene, q0: NDArray | None = None, progress=None) -> tuple[NDArray, NDArray, NDArray]:
    """The scene's dynamic or quasi-static run from ``q0`` (default :func:`start_state`):
    output times, coordinates and multipliers (rows = times)."""
    s = scene.settings
    t_end = float(s.get("t_end", 1.0))
    outputs = int(s.get("outputs", 101))
    mode = s.get("mode", "dynamic")
    q0 = start_state(scene) if q0 is None else q0
    if mode == "quasi_static":
        times = np.linspace(0.0, t_end, outputs)
        solution = quasi_static(scene.system, q0, times, progress=progress)
        return times, solution.q, solution.multipliers
    if mode == "dynamic":
        step = float(s.get("step", 1e-3))
        every = max(1, int(round(t_end / step / max(outputs - 1, 1))))
        result = generalized_alpha(scene.system, q0, np.zeros_like(q0), t_end, step,
                                   rho_inf=float(s.get("rho_inf", 0.9)), output_every=every, progress=progress)
        return result.time, result.q, result.multipliers
    raise SceneError(f"scene mode {mode!r}: use 'dynamic' or 'quasi_static'")


def run_scene(scene: FileScene, directory: str | Path, progress=None) -> dict:
    """Static start, then the dynamic or quasi-static run; writes ``results.npz``, ``results.csv`` and
    ``metadata.json``."""
    started = wallclock.perf_counter()
    time, q, lam = simulate_scene(scene, progress=progress)
    arrays = {"time": time, **sensor_arrays(scene, q, lam)}
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    np.savez(directory / "results.npz", **arrays)
    write_csv(directory / "results.csv", arrays)
    metadata = dict(scene=scene.name, settings=scene.settings, bodies=[b.name for b in scene.bodies],
                    modes=[b.reduction.n_modes for b in scene.bodies], wall_time_s=wallclock.perf_counter() - started)
    (directory / "metadata.json").write_text(json.dumps(metadata, indent=2, default=str))
    return metadata
