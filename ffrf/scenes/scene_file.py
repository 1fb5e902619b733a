"""Scenes as TOML files: run a linkage built from your own meshes without writing Python (``python -m ffrf run``,
or :func:`ffrf.load` ``(path).run()`` in Python: :mod:`ffrf.model`).

A file with a ``[linkage]`` table instead describes a whole single-loop linkage by its DH table, joint
axes or a Rational Linkages model (:mod:`ffrf.scenes.linkage_file`); the rest of this docstring is about
scenes of bodies and joints.

A scene lists bodies (a mesh file or a parametric link on two axes), their material,
element order, number of modes and interfaces; joints between interfaces (or the ground);
an optional drive; gravity, damping, solver settings and sensors. All lengths are metres
unless a body says ``unit = "mm"`` for its mesh. Joint axes and points, interfaces and sensor points
are given where the meshes are (mesh coordinates); bodies start there unless a ``pose`` moves
them. The file is a scene description for the one builder, :mod:`ffrf.scenes.builder`, which also
builds the descriptions code generates (:func:`ffrf.scenes.linkage_description.linkage_description`)::

    [scene]
    name = "hinged link"
    gravity = [0.0, 0.0, -9.81]
    beta = 0.005                      # Rayleigh damping alpha M + beta K of the modal coordinates (s)
    alpha = 0.0                       # (1/s)
    mode = "dynamic"                  # or "quasi_static"
    t_end = 1.0
    step = 1e-3                       # dynamic time step (<= t_end)
    # max_steps = 2e7                 # lifts the limit of 1e7 steps (t_end / step; ffrf.scenes.limits)
    rho_inf = 0.9
    outputs = 101                     # quasi_static: solved from the path, whose own steps (3 deg of the fastest
                                      # drive, or t_end / 40) the outputs do not change (Eq. (S10))
    joint_offsets = "body"            # joint point off its interface centre: "body" (as Exudyn) or "marker" frame
    stability = false                 # quasi_static only: Eq. (B1) at every output, and the run goes on past folds
                                      # of the equilibrium path (Eq. (S6)), each snap in the metadata

    [[bodies]]
    name = "link"
    mesh = "link.msh"                 # any meshio volume mesh, or a closed STL surface filled with tetrahedra of
                                      # edge h = 0.006 (m; a scan or CAD export); or a parametric link
                                      # on any two skew axes (housings at the joint points,
                                      # default the feet of their common normal; cranked arm otherwise):
                                      # parametric = {axes = [{name = "a", point = [...], direction = [...],
                                      #   joint_point = [...], trim = 0.1}, {name = "b", ...}], h = 0.006,
                                      #   mount = false,  (trim: how far beyond the housing's end faces the
                                      #   arm is cut away near the axis, default 2 x (arm section + mount))
                                      #   design = {arm_width = 0.016, arm_thickness = 0.012}}  (m, LinkDesign)
    unit = "mm"                       # optional, scales the mesh to metres
    material = {E = 1.2e9, nu = 0.33, rho = 450.0}   # optional strength = 53e6 (Pa): the assembly is checked
    order = 2                         # default 2: linear tetrahedra are too stiff in bending
    modes = 4
    reduction = "craig_bampton"       # default; or "free_free": modes = the lowest elastic free-free modes (>= 1),
                                      # eqs. (FF-1)-(FF-3); interfaces then only place markers (mean of their nodes)
    pose = {position = [0, 0, 0], euler_parameters = [1, 0, 0, 0]}   # optional start pose of the body frame
    velocity = {linear = [0, 0, 0], angular = [0, 0, 0]}   # optional start velocity of the frame (world, m/s, rad/s);
                                      # modal = [...]: one rate per mode
    interfaces = [                    # the first is the body's frame interface
        {name = "bore0", group = "joint0"},
        {name = "bore1", cylinder = {point = [0.1, 0, 0], direction = [0, 0, 1], radius = 0.0095,
                                     axial_extent = [-0.01, 0.01]}},
        {name = "pad", nodes_file = "pad_nodes.txt"},   # 0-based node indices, optional 2nd column: weights
        {name = "bore2", axis = {point = [0.2, 0, 0], direction = [0, 0, 1]}},  # the bore nearest the axis
        {name = "end", plane = {point = [0.3, 0, 0], normal = [1, 0, 0]}},     # the nodes within tolerance = 1e-5
    ]                                                                           # (m) of a plane (a face)
    # Any interface may say weights = "equal" (all its nodes alike, as Exudyn's 1/n) instead of area weights.

    [[joints]]
    name = "hinge"
    type = "revolute"                 # "revolute", "fixed" or "driven_revolute"
    body0 = "ground"                  # or a body name, with interface0 = "..."
    body1 = "link"
    interface1 = "bore0"
    axis = [0.0, 1.0, 0.0]            # joint axis (world, at t = 0)
    point = [0.0, 0.0, 0.0]           # joint point (world, at t = 0); default: interface1's centre
    drive = {rpm = 1.0, ramp_time = 1.0}   # driven_revolute only: the paper's cosine ramp (or omega = rad/s);
                                      # start_angle_deg = 0 (or start_angle, rad)
    # As built: axis0/point0 (body0's side) and axis1/point1 (body1's side) instead of axis/point;
    # the run starts from a static assembly that closes the misfit (ffrf.scenes.builder).
    clearance = {radial_mm = 0.1, axial_mm = 0.2, pin_length_mm = 12.0}
                                      # optional, passive revolute only: a pin (body1's side) loose in a bore
                                      # (body0's), Eqs. (P1)-(P6); stiffness = N/m per contact (default from the
                                      # materials) and damping = N s/m^2 (Hunt-Crossley) optional; the same table
                                      # in [scene] gives every passive revolute joint that play

    [[sensors]]
    name = "tip"
    body = "link"
    point = [0.2, 0.0, 0.0]           # the mesh node nearest to this point (mesh coordinates); or node = index,
                                      # or joints = ["hinge", ...]: the mean of these joints' points on this body
    surface = true                    # optional: the nearest node on the body's surface

A body given by the mass and stiffness matrices another FE program assembled (SI units, 3 DOFs per node in
the order of the nodes) says ``matrices = {...}`` instead of ``mesh``/``parametric`` and has no ``material``,
``order`` or ``unit`` (:mod:`ffrf.scenes.scene_matrices`)::

    [[bodies]]
    name = "block"
    modes = 5
    interfaces = [{name = "face", plane = {point = [0, 0, 0], normal = [-1, 0, 0]}}]   # cylinder, plane or nodes_file
    [bodies.matrices]                 # the matrices table of this body (or matrices = {...} on one line)
    format = "abaqus"                 # *MATRIX OUTPUT, STIFFNESS, MASS, FORMAT=COORDINATE files (.gz, .xz read)
    nodes = "block.inp"               # nodes and elements of a *Part or *Instance of an Abaqus input file ...
    instance = "block-1"
    mass = "block_MASS1.mtx"
    stiffness = "block_STIF1.mtx"
    scale_stiffness = 1.0             # optional: K times this (Exudyn's ScaleStiffnessMatrix)
    point_masses = [{node = 9, mass = 0.1}, {point = [4, 0, 0], mass = 0.1}]   # optional (kg; AddNodeMass)
    # format = "matrix_market": mass and stiffness as Matrix Market files; nodes = "nodes.txt" (also with
    #   "abaqus"): one node "x y z" per line, row k is node k (DOFs 3k, 3k + 1, 3k + 2), no elements
    # format = "npz", file = "block.npz": nodes, M, K and optional elements in one file (ffrf.fe.matrix_import.NPZ_KEYS)

Its interfaces are weighted by the surface area of the elements they span (Exudyn's rule: corner nodes), or
need ``weights = "equal"`` or a weight column in their ``nodes_file`` when the matrices come without elements.
Such a body has no stresses of ours: the assembly reports its strain energy and reactions, ``assembly.vtu``
leaves it out, and a ``surface = true`` sensor on it needs elements.

Force elements (spring-dampers and bushings on a joint's equations, loads on interfaces, motors) are
``[[forces]]`` tables, documented in :mod:`ffrf.scenes.scene_forces`.

Every interface selector weights its nodes by the surface area of the boundary triangles they span
(``ffrf.fe.interfaces``), unless a ``nodes_file`` gives a weight per node in a second column or the interface
says ``weights = "equal"``. The file is
checked against :mod:`ffrf.scenes.scene_schema` before anything is built: an unknown or misspelt key, a wrong
type or an impossible value is a :class:`SceneError` naming the key, where it is and the fix.

A run (``python -m ffrf run SCENE.toml --out DIR``) writes ``results.npz`` with the output times, every
sensor of :func:`ffrf.output.sensors.scene_sensors` (the listed node sensors; per joint its angle, the
joint point of each side, the reaction on side 1 in joint frame 0 and a driven joint's torque;
energies, the constraint residual and, with one driven joint, the energy balance) and the coordinates
``q``; the sensors again as ``results.csv``; ``metadata.json``; and, when the run starts from a static
assembly, the assembled state with its stresses as ``assembly.vtu`` (per body in the metadata under
``assembly``: largest von Mises stress and where, strain energy, joint reactions). With ``stability = true`` the
three smallest squared frequencies of Eq. (B1) at every output are the sensor ``stability_squared_frequencies`` and
the metadata's ``stability`` sums them up, with each snap the run went through under ``snaps``
(:func:`ffrf.solvers.snap_through.snap_summary`: the fold's time, the energy released, the bodies the critical
mode moves).
"""

from __future__ import annotations

import logging
import time as wallclock
import tomllib
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import Interrupted, NewtonDivergence, SceneError, StaticDivergence
from ffrf.output.assembly_stress import scene_assembly_stress
from ffrf.output.result import Result
from ffrf.output.sensors import node_sensors, scene_sensors
from ffrf.output.verification import verify_scene_run
from ffrf.scenes.assembly import assemble, quasi_static_path_step, start_state, starts_static
from ffrf.scenes.builder import Scene, build_scene
from ffrf.scenes.linkage_file import load_linkage
from ffrf.solvers.simulate import Run, simulate
from ffrf.solvers.snap_through import run_critical_pose, snap_summary
from ffrf.solvers.stability import CriticalPose, stability_along, stability_summary

__all__ = ["SceneError", "load_scene", "run_scene", "start_state", "sensor_arrays"]

log = logging.getLogger(__name__)


def load_scene(path: str | Path) -> Scene:
    """Read and build a TOML scene (see the module docstring)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))  # a BOM (Windows editors) is no TOML
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise SceneError(f"{path}: cannot read the scene ({error})") from error
    if "linkage" in data:  # a linkage file: the links, joints and sensors are generated
        linkage = load_linkage(data, path.parent, path.name)
        return linkage if "name" in data["linkage"] else _renamed(linkage, path.stem)
    scene = build_scene(data, path.parent, path.name)
    return scene if "name" in scene.settings else _renamed(scene, path.stem)


def _renamed(scene: Scene, name: str) -> Scene:
    from dataclasses import replace

    return replace(scene, name=name)


def sensor_arrays(scene: Scene, q: NDArray, multipliers: NDArray) -> dict[str, NDArray]:
    """The scene's node sensors (rows = q's rows) and each driven joint's torque, ``<joint>_torque``
    (N m, applied to the joint's side 1): the quantities its Exudyn twin also measures."""
    arrays = node_sensors(scene, q)
    rows = scene.system.rows
    for k, constraint in enumerate(scene.system.all_constraints):
        if constraint.name in scene.driven:
            arrays[f"{constraint.name}_torque"] = multipliers[:, int(rows[k + 1]) - 1]
    return arrays


def run_scene(scene: Scene, progress: Callable[[float, float], None] | None = None) -> Result:
    """The run of the module docstring, as :class:`~ffrf.output.result.Result` (``kind="scene"``): static assembly
    when the scene starts static (:func:`ffrf.scenes.assembly.starts_static`; its stress state in the metadata under
    ``assembly``), then the dynamic or quasi-static run (:func:`ffrf.solvers.simulate.simulate`; with ``stability`` a
    quasi-static run goes on past folds of its equilibrium path), the sensors, the stability monitor and the run's
    checks of itself. A quasi-static path is followed on its own steps
    (:func:`ffrf.scenes.assembly.quasi_static_path_step`, Eq. (S10)) and the outputs are solved from it: they do not
    change the equilibria or where the path stops or snaps. A run that stops raises the solver's error with
    ``partial``, the Result up to its last output (its metadata's ``stopped`` says where and why), when it reached
    one. Users call it through the facade, :func:`ffrf.load` ``(scene).run()``."""
    started = wallclock.perf_counter()
    metadata = dict(
        scene=scene.name,
        settings=scene.settings,
        bodies=[b.name for b in scene.bodies],
        modes=[b.reduction.n_modes for b in scene.bodies],
        n_coordinates=scene.system.n_coordinates,
    )
    q0, stress = scene.q_initial.copy(), None
    if starts_static(scene):
        assembly = assemble(scene)
        q0 = assembly.q
        stress = scene_assembly_stress(scene, assembly.q, assembly.multipliers)
        metadata["assembly"] = stress.as_dict()
    s = scene.settings
    mode, t_end = s.get("mode", "dynamic"), float(s.get("t_end", 1.0))
    try:
        run = simulate(
            scene.system,
            q0,
            mode,
            t_end,
            int(s.get("outputs", 101)),
            step=float(s.get("step", 1e-3)),
            rho_inf=float(s.get("rho_inf", 0.9)),
            progress=progress,
            qd0=scene.qd_initial,
            through_snaps=bool(s.get("stability", False)),
            static_path_step=quasi_static_path_step(scene, t_end) if mode == "quasi_static" else None,
            static_path_breaks=_table_corners(scene),
        )
        stopped = None
    except (StaticDivergence, NewtonDivergence, Interrupted) as error:  # hand over what was computed, then say so
        if error.partial is None or len(error.partial.time) == 0:
            error.partial = None
            raise
        run, stopped = error.partial, error
    sensors = scene_sensors(scene, run.time, run.q, run.multipliers, run.qd, run.jumps)
    critical = None
    if s.get("stability", False):
        metadata["stability"], critical = _monitor_stability(scene, run, sensors)
    metadata["verification"] = verify_scene_run(scene, sensors, metadata).as_dict()
    metadata["wall_time_s"] = wallclock.perf_counter() - started
    result = Result(run.time, sensors, run.q, metadata, stress, critical, None, run.qd, run.multipliers, "scene", scene)
    if stopped is not None:
        reason = "interrupted" if isinstance(stopped, Interrupted) else str(stopped)
        metadata["stopped"] = {"time_s": float(run.time[-1]), "reason": reason, "message": str(stopped)}
        stopped.partial = result
        raise stopped
    return result


def _table_corners(scene: Scene) -> tuple[float, ...]:
    """The times of the load tables' points: kinks of the loads' time laws (linear between them), where the
    quasi-static path's predictor starts again (``docs/formulation.md``, (S10))."""
    tables = [force["table"] for force in scene.description.get("forces", []) if "table" in force]
    return tuple(sorted({float(t) for table in tables for t in table["time"]}))


def _monitor_stability(scene: Scene, run: Run, sensors: dict) -> tuple[dict, CriticalPose]:
    """Eq. (B1) at every output (the sensor ``stability_squared_frequencies``), the snaps the run went through, and
    the critical pose: its summary (``stability.json`` and ``stability_critical.vtu`` when the Result is saved)."""
    judged = stability_along(scene.system, run.time, run.q, run.multipliers, count=3)
    values = np.array([s.squared_frequencies for s in judged])
    sensors["stability_squared_frequencies"] = values
    summary = stability_summary(values, run.time, "time_s")
    summary["snaps"] = [snap_summary(scene.system, snap) for snap in run.snaps]
    critical = run_critical_pose(scene.system, run.time, run.q, run.multipliers, values, run.snaps)
    summary["critical"] = critical.summary(scene.system)
    return summary, critical
