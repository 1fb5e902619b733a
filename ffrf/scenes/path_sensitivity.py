r"""Derivatives of a linkage's quasi-static path with respect to its links' materials, bore errors and sections
(``docs/formulation.md``, Eqs. (D1)-(D2), (D5), (D7), (D9)).

At every output pose of a quasi-static run the equilibrium's response to each parameter comes from the implicit
function theorem with the tangent Newton factored there
(:func:`ffrf.solvers.equilibrium_sensitivity.equilibrium_response`): each link's relative Young's modulus and
density (exact rates: the mode basis depends on neither), and each bore's three errors of
:class:`~ffrf.scenes.linkage_description.BoreError` in the misfit model (rates of the joint's equations and reactions
by central differences of the joint the linkage builds, :data:`TWIST_STEP`, :data:`SHIFT_STEP`),
and each link's section dimensions (:data:`~ffrf.geometry.design_velocity.SECTION_PARAMETERS`: rates of the
residual by central differences of the link rebuilt on its mesh morphed along the dimension's design velocity,
:func:`~ffrf.geometry.design_velocity.design_velocity`, step :data:`MORPH_STEP` of the dimension).
The outputs are explicit, smooth functions of the equilibrium: the coupler point (the mean of the tool link's joint
points, :func:`ffrf.output.sensors.path_sensors`) and the driving torque (a multiplier). They are differentiated along
the response by central differences (Eq. (D2)): a step moving no coordinate by more than :data:`OUTPUT_STEP`, whose
truncation error (``OUTPUT_STEP**2`` relative) and round-off (about ``eps / OUTPUT_STEP`` of the output's scale)
stay near 1e-10 of the derivative, far below what a re-run's finite differences reach (about 1e-6). Each output's
own change with a parameter at fixed coordinates comes from the linkage built at +-step of it. On request, two
more outputs: the lowest squared frequency of Eq. (B1) (``stability``; its derivative with the mode held, Eq. (D7):
:func:`ffrf.solvers.stability.frequency_form`) and each link's peak von Mises stress (``stress``; closed-form
gradient in the modal coordinates, Eq. (D9): :mod:`ffrf.output.peak_stress`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import SceneError, SensitivityError
from ffrf.fe.fe_model import FEModel
from ffrf.geometry.design_velocity import SECTION_PARAMETERS, VELOCITY_STEP, design_velocity, shape_velocity
from ffrf.output.clearance import Clearance, clearance_at
from ffrf.output.loop_poses import LoopPoses
from ffrf.output.peak_stress import corner_stress, peak_stress, strain_modes, stress_norm, stress_norm_at
from ffrf.output.sensors import path_sensors
from ffrf.output.solid_distance import LinkSolid
from ffrf.output.stress_average import ball_average
from ffrf.scenes.builder import morphed_body, morphed_scene, parametric_link
from ffrf.scenes.linkage_description import (
    BoreError,
    LinkageOptions,
    bore_side,
    drive_sign,
    linkage_description,
    start_pose,
)
from ffrf.scenes.linkage_scene import LinkageScene, as_linkage, described_housings, joint_zones
from ffrf.scenes.scene_joints import joint_constraint
from ffrf.solvers.equilibrium_sensitivity import equilibrium_response, material_rates
from ffrf.solvers.stability import LowestMode, frequency_form, lowest_mode
from ffrf.system.constraints import Constraint
from ffrf.system.joints import MarkerJoint
from ffrf.system.multibody import MultibodySystem
from kinematics.pluecker import Line
from kinematics.single_loop import SingleLoop

__all__ = [
    "CLEARANCE_TIE",
    "FREQUENCY_STEP",
    "LOOP_STEP",
    "MATERIAL_STEP",
    "MORPH_STEP",
    "OUTPUT_STEP",
    "SHIFT_STEP",
    "TWIST_STEP",
    "ClearanceRates",
    "LoopChange",
    "PathSensitivity",
    "bore_sensitivity",
    "changed_linkage",
    "loop_clearance_slopes",
    "loop_sensitivity",
    "loop_velocities",
    "material_sensitivity",
    "section_sensitivity",
    "section_velocities",
    "size_change",
]

#: Largest coordinate change (m, or Euler parameter, or modal coordinate) of Eq. (D2)'s central differences.
OUTPUT_STEP = 1e-6
#: Steps of the bore errors' central differences in the joint's equations (Eq. (D1)'s right-hand side): the twist
#: (rad), and the offsets as a fraction of the loop's size (smooth in both: truncation about the step squared).
TWIST_STEP = 1e-6
SHIFT_STEP = 1e-6
#: Step of a section dimension's central differences along its morph, relative to the dimension.
MORPH_STEP = 1e-4
#: Step of a loop parameter's central differences (the changed linkage and its rigid loop), relative to its value: the
#: deviation from the ideal path is a small difference (1e-3 of the coupler point's change on the PLA Bennett), so
#: the truncation must stay far below it (the coarse PLA Bennett's derivatives by alpha0 change with the step as its
#: square: the deviation's by 8.9e-5 of it from 1e-4 to 1e-5 and 1e-6 from 1e-5 to 3e-6, the peak stresses' by 1e-5
#: from 3e-5 to 1e-5 and 1.1e-6 from 1e-5 to 3e-6).
LOOP_STEP = 3e-6
#: Samples of a pair's clearance within this of its smallest, outside its basin, hold it too (m), for the smallest
#: clearance's rates by a loop change (Eq. (CL6)): a tenth of a millimetre, below a print's resolution. Adjacent
#: links keep their clearance near a joint constant along the motion, which the links' faceted surfaces turn into
#: wiggles of microns (up to 2e-5 m over a revolution of the coarse PLA Bennett), and a loop change tilts the
#: surfaces differently at each pose.
CLEARANCE_TIE = 1e-4
#: Step of the relative Young's modulus and density (ln E, ln rho) in the outputs' own change (Eq. (D2)): the
#: matrices scale as exp(step), so central differences are off by step^2 / 6.
MATERIAL_STEP = 1e-4
#: Largest coordinate change of Eq. (D2) for the lowest squared frequency's form of Eq. (D7) (Richardson-combined
#: with twice it): the links' stiffest modes make the form's round-off about 1e-10 of the frequency, which a step of
#: OUTPUT_STEP would amplify.
FREQUENCY_STEP = 1e-4


@dataclass(frozen=True)
class PathSensitivity:
    """Per output pose (``drive_angle``, rad) the derivatives of the coupler point ``(poses, 3, k)`` (m) and of the
    driving torque ``(poses, k)`` (N m) with respect to the ``k`` ``parameters`` (a material per unit relative
    change: ``E link1`` is ``d/d ln E`` of link 1, the change per 100 % of E to first order; a bore error or a
    section dimension per unit of it, rad or m), of the links' total ``mass`` ``(k,)`` (kg), and of each joint's
    reaction force ``(poses, 3, k)`` (N, world axes; its first three multipliers), by joint name; with stability,
    the lowest squared frequency of Eq. (B1) at each pose ``squared_frequency`` ``(poses,)`` (rad^2/s^2) and its
    derivatives ``lowest_squared_frequency`` ``(poses, k)``; with stress, each link's peak von Mises stress at each
    pose ``peak_stress`` ``(poses, links)`` (Pa; NaN for a body without elements of ours), where it lies
    ``peak_stress_corner`` ``(poses, links, 2)`` (element, its corner; -1 without elements) and its derivatives
    ``peak_stress_slopes`` ``(poses, links, k)`` (Eq. (D9): those of the stress at that corner), and the p-norm of
    each link's corner stresses that a design bounds, ``stress_norm`` ``(poses, links)`` (Pa, Eq. (D10)) with its
    derivatives ``stress_norm_slopes`` ``(poses, links, k)``; for a change of the loop itself, the ideal (rigid)
    coupler point's derivatives at the same drive angles ``ideal_coupler_point`` ``(poses, 3, k)``
    (:attr:`deviation`); and the equilibria's own response ``coordinates`` ``(poses, n, k)`` (Eq. (D1): the
    derivatives of every coordinate, which any other output of the coordinates can be differentiated along,
    :func:`~ffrf.scenes.loaded_clearance.loaded_clearance`)."""

    parameters: tuple[str, ...]
    drive_angle: NDArray[np.float64]
    coupler_point: NDArray[np.float64]
    driving_torque: NDArray[np.float64]
    mass: NDArray[np.float64] | None = None
    reaction_forces: dict[str, NDArray[np.float64]] = dataclasses.field(default_factory=dict)
    squared_frequency: NDArray[np.float64] | None = None
    lowest_squared_frequency: NDArray[np.float64] | None = None
    peak_stress: NDArray[np.float64] | None = None
    peak_stress_slopes: NDArray[np.float64] | None = None
    peak_stress_corner: NDArray[np.int64] | None = None
    stress_norm: NDArray[np.float64] | None = None
    stress_norm_slopes: NDArray[np.float64] | None = None
    ideal_coupler_point: NDArray[np.float64] | None = None
    coordinates: NDArray[np.float64] | None = None

    @property
    def deviation(self) -> NDArray[np.float64]:
        """``(poses, 3, k)``: the derivatives of the coupler's deviation from the ideal path at the same drive angle:
        the coupler point's, less the ideal path's own (``ideal_coupler_point``, where a parameter moves it: the
        loop's own, :func:`loop_sensitivity`; no other parameter does)."""
        if self.ideal_coupler_point is None:
            return self.coupler_point
        return self.coupler_point - self.ideal_coupler_point

    def fold_distance(self) -> NDArray[np.float64]:
        """``(poses, k)``: the change of each parameter alone that brings the pose's lowest squared frequency of
        Eq. (B1) to zero to first order, ``mu / |d mu / dp|`` (inf where it does not move): how far the derivatives
        hold before the equilibrium folds (snaps). Needs the sensitivity computed with ``stability``."""
        if self.squared_frequency is None or self.lowest_squared_frequency is None:
            raise ValueError("these derivatives were computed without stability: pass stability=True")
        slope = np.abs(self.lowest_squared_frequency)
        with np.errstate(divide="ignore"):
            return np.where(slope > 0.0, self.squared_frequency[:, None] / slope, np.inf)


def material_sensitivity(
    scene: LinkageScene,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray,
    links: tuple[int, ...] | None = None,
    stability: bool = False,
    stress: bool = False,
    stress_radius: float | None = None,
) -> PathSensitivity:
    """The derivatives of the coupler point, driving torque and mass at the equilibria ``q`` ``(poses, n)``,
    ``multipliers`` ``(poses, m)`` at ``time`` (a quasi-static run's rows) with respect to the relative Young's
    modulus and then density of each of ``links`` (default all; module docstring). The mass is proportional to the
    density and independent of the modulus: its derivatives are 0 and the link's mass. ``stability``: the lowest
    squared frequency of Eq. (B1) too (:class:`PathSensitivity`)."""
    system = scene.system
    links = tuple(range(len(system.bodies))) if links is None else tuple(links)
    names = tuple(f"E {system.bodies[k].name}" for k in links) + tuple(f"rho {system.bodies[k].name}" for k in links)
    q = np.asarray(q, dtype=float)
    factor = np.exp(MATERIAL_STEP)
    sides = [
        (_with_material(scene, k, {field: factor}), _with_material(scene, k, {field: 1.0 / factor}), MATERIAL_STEP)
        for field in ("stiffness", "density")
        for k in links
    ]
    found = _path_derivatives(
        scene,
        time,
        q,
        multipliers,
        names,
        lambda row, t: material_rates(system, q[row], links),
        sides,
        stability,
        stress,
        stress_radius,
    )
    for values, slopes in (
        (found.peak_stress, found.peak_stress_slopes),
        (found.stress_norm, found.stress_norm_slopes),
    ):
        if values is not None and slopes is not None:
            for column, k in enumerate(links):  # at fixed strain a link's stress is proportional to its E
                slopes[:, k, column] += values[:, k]
    masses = [float(system.bodies[k].moments.mass) for k in links]
    return replace(found, mass=np.array([0.0] * len(links) + masses))


def _with_material(scene: LinkageScene, link: int, factors: dict[str, float]) -> LinkageScene:
    """``scene`` with link ``link`` of a material scaled by ``factors`` (:meth:`FlexibleBody.scaled`)."""
    bodies = list(scene.system.bodies)
    bodies[link] = bodies[link].scaled(**factors)
    return replace(scene, system=replace(scene.system, bodies=tuple(bodies)))


def bore_sensitivity(
    scene: LinkageScene,
    loop: SingleLoop,
    options: LinkageOptions,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray,
    bores: tuple[tuple[int, int], ...] | None = None,
    stability: bool = False,
    stress: bool = False,
    stress_radius: float | None = None,
    fields: tuple[str, ...] = ("twist", "offset", "axial"),
) -> PathSensitivity:
    """The derivatives of the coupler point and driving torque at a quasi-static run's equilibria (as
    :func:`material_sensitivity`) with respect to the errors ``fields`` of :class:`BoreError` (``twist`` and
    ``tilt``, rad; ``offset``, ``shift`` and ``axial``, m; default the three of the DH parameters,
    :data:`~ffrf.scenes.linkage_description.BORE_ERROR_FIELDS` for all five) of each bore ``(joint, link)`` of ``bores``
    (default every one), in the misfit model
    (the linkage ``scene`` built from ``loop`` and ``options`` with ``bore_error_model = "misfit"`` or without bore
    errors: the error only in the joint's frame and point on that link's side). The rates of the joint's equations
    and reactions (Eq. (D1)'s right-hand side) are central differences in the error of the joint built by the
    linkage's own rule (:func:`~ffrf.scenes.linkage_description.bore_side`), steps :data:`TWIST_STEP` and
    :data:`SHIFT_STEP` times the loop's size."""
    n = loop.n
    bores = tuple((j, k) for k in range(n) for j in ((k - 1) % n, k)) if bores is None else tuple(bores)
    system = scene.system
    pairs, names, sides = [], [], []
    for joint, link in bores:
        index = len(system.bodies) + _joint_index(scene, joint)  # among all constraints
        for field in fields:
            turn = field in ("twist", "tilt")
            step = TWIST_STEP if turn else SHIFT_STEP * loop.scale
            plus, minus = (_bore_joint(scene, loop, options, (joint, link), field, s) for s in (step, -step))
            pairs.append((index, plus, minus, step))
            names.append(f"{field} joint{joint} link{link}")
            sides.append((_with_joint(scene, index, plus), _with_joint(scene, index, minus), step))
    q, multipliers = np.asarray(q, dtype=float), np.asarray(multipliers, dtype=float)

    def rates(row: int, t: float) -> NDArray[np.float64]:
        out = np.zeros((system.n_coordinates + system.n_constraints, len(pairs)))
        for column, (index, plus, minus, step) in enumerate(pairs):
            out[:, column] = _joint_rate(system, index, plus, minus, step, q[row], multipliers[row], t)
        return out

    # The outputs read the joints' points: a bore error of the tool link moves the coupler point itself (the mean of
    # its joint points as built), at fixed coordinates too.
    return _path_derivatives(scene, time, q, multipliers, tuple(names), rates, sides, stability, stress, stress_radius)


def section_velocities(
    scene: LinkageScene, parameters: tuple[str, ...] = SECTION_PARAMETERS, links: tuple[int, ...] | None = None
) -> dict[tuple[int, str], NDArray[np.float64]]:
    """The design velocity (Eq. (D5), :func:`~ffrf.geometry.design_velocity.design_velocity`) of each of
    ``parameters`` on the mesh of each of ``links`` (default every parametric link), by ``(link, parameter)``."""
    bodies = scene.description["bodies"]
    links = tuple(k for k, entry in enumerate(bodies) if "parametric" in entry) if links is None else tuple(links)
    out = {}
    for k in links:
        entry = bodies[k]
        if "parametric" not in entry:
            raise SceneError(f"body {entry['name']!r} is not a parametric link: it has no section to change")
        spec = entry["parametric"]
        build = parametric_link(spec, f"body {entry['name']!r}")
        for parameter in parameters:
            mesh, velocity = design_velocity(build, float(spec.get("h", 6e-3)), parameter, entry["name"])
            if not np.array_equal(mesh.points, scene.bodies[k].mesh_model.mesh.points):
                raise SceneError(f"body {entry['name']!r}: its mesh is not the one its description builds today")
            out[k, parameter] = velocity
    return out


def section_sensitivity(
    scene: LinkageScene,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray,
    parameters: tuple[str, ...] = SECTION_PARAMETERS,
    links: tuple[int, ...] | None = None,
    step: float = MORPH_STEP,
    velocities: dict[tuple[int, str], NDArray] | None = None,
    stability: bool = False,
    stress: bool = False,
    stress_radius: float | None = None,
) -> PathSensitivity:
    """The derivatives of the coupler point, driving torque and mass at a quasi-static run's equilibria (as
    :func:`material_sensitivity`) with respect to each of ``parameters`` (fields of
    :class:`~ffrf.geometry.link_geometry.LinkDesign` that leave the bores in place, m) of each of ``links`` (default
    every parametric link), per metre. The right-hand side of Eq. (D1) and the outputs' own change are central
    differences of the linkage with that link rebuilt on its mesh moved by ``+-step`` of the dimension along its
    design velocity (Eq. (D5)); the derivative is that of the model on the morphed mesh (module docstring).
    ``velocities``: by ``(link, parameter)``, for a scene whose links are already morphed (their points moved along
    these velocities from the meshes their description builds); default :func:`section_velocities`."""
    bodies = scene.description["bodies"]
    links = tuple(k for k, entry in enumerate(bodies) if "parametric" in entry) if links is None else tuple(links)
    velocities = section_velocities(scene, parameters, links) if velocities is None else velocities
    time, q, multipliers = np.asarray(time, float), np.asarray(q, float), np.asarray(multipliers, float)
    shifted, names = [], []
    for k in links:
        points = scene.bodies[k].mesh_model.mesh.points
        design = parametric_link(bodies[k]["parametric"])["design"]
        for parameter in parameters:
            delta = step * float(getattr(design, parameter))
            velocity = velocities[k, parameter]
            morphed = tuple(
                scene.with_body(morphed_body(scene, k, points + sign * delta * velocity)) for sign in (1.0, -1.0)
            )
            shifted.append((morphed, delta))
            names.append(f"{parameter} {bodies[k]['name']}")

    sides = [(plus, minus, delta) for (plus, minus), delta in shifted]
    rates = _residual_rates(scene, q, multipliers, sides)
    sensitivity = _path_derivatives(
        scene, time, q, multipliers, tuple(names), rates, sides, stability, stress, stress_radius
    )
    return replace(sensitivity, mass=_mass_rates(sides))


@dataclass(frozen=True)
class LoopChange:
    """A design parameter of the loop itself, a DH parameter along a change that keeps the loop mobile (the Bennett
    conditions, :func:`ffrf.paper.bennett_scene.bennett_changes`): its ``name``, its nominal ``value`` (m or rad;
    the steps of the central differences are relative to it) and ``linkage(s)``, the loop and linkage options of the
    design changed by ``s`` (``s = 0``: the scene's own)."""

    name: str
    value: float
    linkage: Callable[[float], tuple[SingleLoop, LinkageOptions]]


def size_change(loop: SingleLoop, options: LinkageOptions) -> LoopChange:
    """The size of any loop as a change of its DH parameters: every length (a_i, d_i, the axes' distances from the
    origin and the housings' attach points) times ``1 + s``, the twists, joint angles and the links' section kept.
    A similar loop is as mobile as the nominal one, so this is a change of any linkage; its ideal path at a drive
    angle is the nominal one scaled about the origin (its derivative by ``s`` is the path itself)."""

    def linkage_at(s: float) -> tuple[SingleLoop, LinkageOptions]:
        if s == 0.0:
            return loop, options
        axes = tuple(Line(axis.direction, (1.0 + s) * axis.moment) for axis in loop.axes)
        attach = None if options.attach_points is None else (1.0 + s) * np.asarray(options.attach_points, dtype=float)
        return SingleLoop(axes), replace(options, attach_points=attach)

    return LoopChange("size", 1.0, linkage_at)


def loop_velocities(
    scene: LinkageScene, changes: tuple[LoopChange, ...], step: float = VELOCITY_STEP
) -> dict[tuple[int, str], NDArray[np.float64]]:
    """The velocity of every link's mesh per unit of each of ``changes`` (Eq. (D12): the link's own frame moves
    rigidly with its first housing, the rest morphs, :func:`~ffrf.geometry.design_velocity.shape_velocity`), by
    ``(link, change name)``."""
    bodies = scene.description["bodies"]
    out = {}
    for change in changes:
        nominal = _changed_design(change, 0.0)[3]
        if [b.get("parametric") for b in nominal["bodies"]] != [b.get("parametric") for b in bodies]:
            raise SceneError(
                f"change {change.name!r}: its design unchanged (s = 0) is not this scene's; make the change from the "
                "loop and options the scene was built with"
            )
        delta = step * abs(change.value)
        plus, minus = (_changed_design(change, sign * delta)[3]["bodies"] for sign in (1.0, -1.0))
        for k, entry in enumerate(bodies):
            if "parametric" not in entry:
                raise SceneError(f"body {entry['name']!r} is not a parametric link: a change of the loop remakes it")
            build = parametric_link(entry["parametric"], entry["name"])
            shifted = (parametric_link(plus[k]["parametric"]), parametric_link(minus[k]["parametric"]))
            what = f"changing {change.name} by {delta:.3g}"
            h = float(entry["parametric"].get("h", 6e-3))
            mesh, velocity = shape_velocity(build, h, shifted, delta, what, entry["name"])
            if not np.array_equal(mesh.points, scene.bodies[k].mesh_model.mesh.points):
                raise SceneError(f"body {entry['name']!r}: its mesh is not the one its description builds today")
            out[k, change.name] = velocity
    return out


def loop_sensitivity(
    scene: LinkageScene,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray,
    changes: tuple[LoopChange, ...],
    step: float = LOOP_STEP,
    velocities: dict[tuple[int, str], NDArray] | None = None,
    stability: bool = False,
    stress: bool = False,
    stress_radius: float | None = None,
) -> PathSensitivity:
    """The derivatives of the coupler point, driving torque and mass at a quasi-static run's equilibria (as
    :func:`material_sensitivity`) with respect to each of ``changes`` of the loop itself (per its unit, m or rad),
    and of the ideal (rigid) coupler point at the same drive angles (Eq. (D13), :attr:`PathSensitivity.deviation`).
    The right-hand side of Eq. (D1) and the outputs' own change are central differences of the linkage described
    at ``+-step`` of the change's value (its joints, drive and sensors) on its meshes moved along their velocities
    (:func:`loop_velocities`, default computed here); the ideal path's, of the rigid loops at the same steps."""
    velocities = loop_velocities(scene, changes) if velocities is None else velocities
    time, q, multipliers = np.asarray(time, float), np.asarray(q, float), np.asarray(multipliers, float)
    angles = np.array([scene.drive_angle(float(t)) for t in time])
    sides, ideal = [], []
    for change in changes:
        delta = step * abs(change.value)
        plus, minus = (changed_linkage(scene, change, sign * delta, velocities) for sign in (1.0, -1.0))
        sides.append((plus, minus, delta))
        ideal.append((plus.ideal_coupler_points(angles) - minus.ideal_coupler_points(angles)) / (2.0 * delta))
    names = tuple(change.name for change in changes)
    rates = _residual_rates(scene, q, multipliers, sides)
    sensitivity = _path_derivatives(scene, time, q, multipliers, names, rates, sides, stability, stress, stress_radius)
    return replace(sensitivity, mass=_mass_rates(sides), ideal_coupler_point=np.stack(ideal, axis=2))


def _changed_design(change: LoopChange, s: float) -> tuple[SingleLoop, LinkageOptions, NDArray, dict]:
    """The loop, options, start rotations and description of the design changed by ``s``."""
    loop, options = change.linkage(s)
    start = start_pose(loop, options.driver, options.start_angle, options.origin)
    return loop, options, start, linkage_description(loop, options, start)


def changed_linkage(
    scene: LinkageScene, change: LoopChange, s: float, velocities: dict[tuple[int, str], NDArray]
) -> LinkageScene:
    """The linkage of the design changed by ``s``, built on ``scene``'s meshes moved along the change's
    ``velocities``."""
    loop, options, start, description = _changed_design(change, s)
    points = [body.mesh_model.mesh.points + s * velocities[k, change.name] for k, body in enumerate(scene.bodies)]
    return as_linkage(morphed_scene(scene, description, points), loop, options, start, scene.cache)


@dataclass(frozen=True)
class ClearanceRates:
    """How each pair's smallest clearance along the revolution changes with each loop change (Eq. (CL6)), arrays
    ``(pairs, k)``: ``at_smallest`` the derivative at the pose that holds the smallest; over the poses that hold it
    within :data:`CLEARANCE_TIE` (``poses`` ``(pairs,)`` of them: samples outside the found pose's basin), the
    smallest clearance's one-sided rates: ``right`` (the change increasing: the least of their derivatives) and
    ``left`` (decreasing: the largest). Where one pose holds it, all three agree and the smallest clearance has a
    derivative."""

    at_smallest: NDArray[np.float64]
    right: NDArray[np.float64]
    left: NDArray[np.float64]
    poses: NDArray[np.int64]

    @property
    def differentiable(self) -> NDArray[np.bool_]:
        """Per pair, whether one pose holds its smallest clearance (else it has only one-sided rates)."""
        return self.poses == 1


def loop_clearance_slopes(
    scene: LinkageScene,
    found: Clearance,
    changes: tuple[LoopChange, ...],
    n_poses: int,
    step: float = LOOP_STEP,
    velocities: dict[tuple[int, str], NDArray] | None = None,
    tie: float = CLEARANCE_TIE,
) -> ClearanceRates:
    """How each pair's smallest clearance in ``found`` (``scene.clearance(n_poses)``) changes with each of
    ``changes`` of the loop (Eq. (CL6)). At each pose that holds it (the pose found and every sample of the
    revolution within ``tie`` of it outside the found pose's basin, :func:`_basin`), central differences over
    ``+-step`` of each change's value of the clearance there on the changed design: its rigid motion at the same
    drive angle, its links morphed along their ``velocities`` (:func:`loop_velocities`, default computed here) and
    its joint zones."""
    velocities = loop_velocities(scene, changes) if velocities is None else velocities
    solids, motion = scene.link_solids(), scene.rigid_revolution(n_poses)
    samples = motion.drive_angles[:-1]  # the last closes the revolution: the first again
    rows = np.repeat(found.pairs, len(samples), axis=0)
    nominal = clearance_at(solids, motion, scene.joint_zones(), rows, np.tile(samples, len(found.pairs)))
    values = nominal.reshape(len(found.pairs), len(samples))
    turn = np.angle(np.exp(1j * (samples[None, :] - found.drive_angle[:, None])))  # from the pose found, in (-pi, pi]
    nearest = np.argmin(np.abs(turn), axis=1)
    holding = np.array(
        [
            (row <= distance + tie) & ~_basin(row, i)
            for row, i, distance in zip(values, nearest, found.distance, strict=True)
        ]
    )
    pair_of = [i for i, held in enumerate(holding) for _ in range(1 + int(held.sum()))]
    angles = np.concatenate([[found.drive_angle[i], *samples[held]] for i, held in enumerate(holding)])
    pairs = found.pairs[pair_of]
    slopes = np.empty((len(angles), len(changes)))
    for column, change in enumerate(changes):
        delta = step * abs(change.value)
        plus, minus = (
            _changed_clearance(solids, change, sign * delta, velocities, pairs, angles, n_poses) for sign in (1.0, -1.0)
        )
        slopes[:, column] = (plus - minus) / (2.0 * delta)
    first = np.searchsorted(pair_of, np.arange(len(found.pairs)))  # each pair's own pose comes first
    return ClearanceRates(
        slopes[first],
        np.minimum.reduceat(slopes, first, axis=0),
        np.maximum.reduceat(slopes, first, axis=0),
        np.diff(np.append(first, len(angles))),
    )


def _basin(values: NDArray[np.float64], start: int) -> NDArray[np.bool_]:
    """The samples of a periodic sequence ``values`` in the basin of sample ``start``: from the local minimum it
    descends to, those that rise strictly on either side (a smooth minimum between samples has its neighbours in
    it; a clearance constant to microns, wiggling, has a basin of a sample or two)."""
    n = len(values)
    while min(values[(start - 1) % n], values[(start + 1) % n]) < values[start]:
        start = (start - 1) % n if values[(start - 1) % n] < values[(start + 1) % n] else (start + 1) % n
    out = np.zeros(n, dtype=bool)
    out[start] = True
    for direction in (1, -1):
        k = start
        while not out[(k + direction) % n] and values[(k + direction) % n] > values[k % n]:
            k += direction
            out[k % n] = True
    return out


def _changed_clearance(
    solids: list[LinkSolid],
    change: LoopChange,
    s: float,
    velocities: dict[tuple[int, str], NDArray],
    pairs: NDArray[np.int64],
    angles: NDArray[np.float64],
    n_poses: int,
) -> NDArray[np.float64]:
    """The clearance of each row of ``pairs`` at its drive angle in ``angles`` in the design changed by ``s``: the
    links' solids moved along the change's ``velocities``, the changed loop's motion traced as ``n_poses`` samples of
    a revolution (each pose closed from the nearest) and its joint zones; no FE model is built."""
    loop, options, start, description = _changed_design(change, s)
    moved = [
        LinkSolid(solid.vertices + s * velocities[k, change.name], solid.triangles, solid.name)
        for k, solid in enumerate(solids)
    ]
    zones = joint_zones(loop, [described_housings(entry) for entry in description["bodies"]])
    motion = LoopPoses.revolution(loop, options.driver, n_poses, start, drive_sign(options.driver, loop.n))
    return clearance_at(moved, motion, zones, pairs, angles)


def _residual_rates(
    scene: LinkageScene, q: NDArray, multipliers: NDArray, sides: list[tuple[LinkageScene, LinkageScene, float]]
) -> Callable[[int, float], NDArray[np.float64]]:
    """Eq. (D1)'s right-hand sides at row ``row`` of ``q`` and ``multipliers``: the central differences of the whole
    residual between the linkages of each of ``sides`` ``(plus, minus, step)``, at the same coordinates."""

    def rates(row: int, t: float) -> NDArray[np.float64]:
        out = np.zeros((scene.system.n_coordinates + scene.system.n_constraints, len(sides)))
        zeros = np.zeros(scene.system.n_coordinates)
        for column, (plus, minus, delta) in enumerate(sides):
            upper = np.concatenate(plus.system.residual(q[row], zeros, zeros, multipliers[row], t))
            lower = np.concatenate(minus.system.residual(q[row], zeros, zeros, multipliers[row], t))
            out[:, column] = (upper - lower) / (2.0 * delta)
        return out

    return rates


def _mass_rates(sides: list[tuple[LinkageScene, LinkageScene, float]]) -> NDArray[np.float64]:
    """The links' total mass's central differences over each of ``sides``."""
    return np.array([(_mass(plus) - _mass(minus)) / (2.0 * delta) for plus, minus, delta in sides])


def _mass(scene: LinkageScene) -> float:
    """The links' total mass (kg)."""
    return float(sum(body.moments.mass for body in scene.system.bodies))


def _bore_joint(
    scene: LinkageScene, loop: SingleLoop, options: LinkageOptions, bore: tuple[int, int], field: str, error: float
) -> Constraint:
    """Joint ``bore[0]`` of ``scene`` with bore ``(joint, link)``'s ``field`` in error by ``error``, built by the
    linkage's own rule (:func:`~ffrf.scenes.linkage_description.bore_side`)."""
    joint, link = bore
    geometry = scene.joints[_joint_index(scene, joint)]
    side = geometry.bodies.index(link)
    axis, point = bore_side(loop, options, BoreError.single(joint, link, field, error))
    axes = (axis, geometry.axes[1]) if side == 0 else (geometry.axes[0], axis)
    points = (point, geometry.points[1]) if side == 0 else (geometry.points[0], point)
    offsets = scene.settings.get("joint_offsets", "body")
    return joint_constraint(replace(geometry, axes=axes, points=points), scene.bodies, offsets, 1.0)


def _with_joint(scene: LinkageScene, index: int, joint: Constraint) -> LinkageScene:
    """``scene`` with constraint ``index`` (of the system's bodies then constraints) replaced by ``joint``."""
    constraints = list(scene.system.constraints)
    constraints[index - len(scene.system.bodies)] = joint
    return replace(scene, system=replace(scene.system, constraints=tuple(constraints)))


def _outputs(
    scene: LinkageScene, time: NDArray, q: NDArray, multipliers: NDArray, modes: list[LowestMode] | None = None
) -> dict:
    """The differentiated outputs at the rows ``(time, q, multipliers)``: the coupler point ``(rows, 3)``, the
    driving torque and, with ``modes`` (one per row, of the nominal equilibria), the lowest squared frequency's form
    of Eq. (D7) ``(rows,)``, whose change is the frequency's."""
    sensors = path_sensors(scene, time, q, multipliers)
    out = {"coupler_point": sensors["coupler_point"], "driving_torque": sensors["driving_torque"]}
    if modes is not None:
        out["lowest_squared_frequency"] = np.array(
            [
                frequency_form(scene.system, row, lam, float(t), mode)
                for t, row, lam, mode in zip(time, q, multipliers, modes, strict=True)
            ]
        )
    return out


def _joint_index(scene: LinkageScene, joint: int) -> int:
    """The index of joint ``joint`` of the loop among the scene's joints (named ``joint{j}``, the driven one with
    ``(drive)`` added)."""
    found = [i for i, g in enumerate(scene.joints) if g.name.split(" ")[0] == f"joint{joint}"]
    if len(found) != 1:
        raise ValueError(
            f"the linkage has no joint named joint{joint}: its joints are {[g.name for g in scene.joints]}"
        )
    return found[0]


def _joint_rate(
    system: MultibodySystem,
    index: int,
    plus: Constraint,
    minus: Constraint,
    step: float,
    q: NDArray,
    lam: NDArray,
    t: float,
) -> NDArray[np.float64]:
    """Eq. (D1)'s right-hand side for a parameter of constraint ``index`` (of ``all_constraints``), whose joint built
    at the parameter's +-``step`` is ``plus``, ``minus``: the change of its equations and of their reactions
    ``C_q^T lambda`` on the bodies it joins, by central differences."""
    n = system.n_coordinates
    rows = slice(int(system.rows[index]), int(system.rows[index + 1]))
    blocks = [q[system.block(i)] for i in plus.bodies]
    out = np.zeros(n + system.n_constraints)
    out[n + rows.start : n + rows.stop] = (plus.value(blocks, t) - minus.value(blocks, t)) / (2.0 * step)
    for i, upper, lower in zip(plus.bodies, plus.jacobian(blocks, t), minus.jacobian(blocks, t), strict=True):
        out[system.block(i)] += (upper - lower).T @ lam[rows] / (2.0 * step)
    return out


def _path_derivatives(
    scene: LinkageScene,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray,
    names: tuple[str, ...],
    rates: Callable[[int, float], NDArray],
    sides: list[tuple[LinkageScene, LinkageScene, float]],
    stability: bool = False,
    stress: bool = False,
    stress_radius: float | None = None,
) -> PathSensitivity:
    """Eq. (D1) at every pose with ``rates(row, t)``'s right-hand sides, then Eq. (D2) for the outputs: along the
    response, plus, per parameter, the outputs' own change at fixed coordinates, central differences of the linkage
    built at +-step of it (``sides``: ``(plus, minus, step)``). With ``stability`` the lowest squared frequency of
    Eq. (B1) too, refused (:class:`SensitivityError`) at a pose where it is not positive. With ``stress`` each link's
    peak stress and its norm too (Eqs. (D9), (D10)); with a ``stress_radius`` (m) of the strain averaged over balls of
    that radius (Eq. (D14)) instead of the corner strains."""
    if scene.loose_joints:  # contact switches make the path non-smooth; Eq. (D1) assumes a smooth one
        raise SensitivityError(
            f"path sensitivities of a linkage with joints with play ({', '.join(j.name for j in scene.loose_joints)}) "
            "are not available yet; compute them on the linkage with ideal joints (no clearance)"
        )
    system = scene.system
    time, q, multipliers = np.asarray(time, float), np.asarray(q, float), np.asarray(multipliers, float)
    poses, k = len(time), len(names)
    modes = (
        [lowest_mode(system, row, lam, float(t)) for t, row, lam in zip(time, q, multipliers, strict=True)]
        if stability
        else None
    )
    frequencies = None if modes is None else np.array([mode.mu for mode in modes])
    if frequencies is not None and np.any(frequencies <= 0.0):
        _refuse_unstable(scene, time, frequencies)
    dq, dlam = np.empty((poses, k, q.shape[1])), np.empty((poses, k, multipliers.shape[1]))
    for row, t in enumerate(time):
        response_q, response_lam = equilibrium_response(
            system, q[row], multipliers[row], float(t), rates(row, float(t))
        )
        dq[row], dlam[row] = response_q.T, response_lam.T
    # Eq. (D2): each (pose, parameter) pair stepped along its response, all in one evaluation per side
    derivatives = _along_response(scene, time, q, multipliers, dq, dlam, OUTPUT_STEP)
    if modes is not None:  # Richardson's rule on steps h and 2h: truncation h^4
        fine, coarse = (
            _along_response(scene, time, q, multipliers, dq, dlam, factor * FREQUENCY_STEP, modes)
            for factor in (1.0, 2.0)
        )
        name = "lowest_squared_frequency"
        derivatives[name] = (4.0 * fine[name] - coarse[name]) / 3.0
    for column, (plus, minus, step) in enumerate(sides):
        upper, lower = (_outputs(side, time, q, multipliers, modes) for side in (plus, minus))
        for name, values in derivatives.items():
            values[:, column] += (upper[name] - lower[name]) / (2.0 * step)
    stresses = _stress_derivatives(scene, q, dq, sides, stress_radius) if stress else None
    angles = np.array([scene.drive_angle(float(t)) for t in time])
    # a joint's reaction force is its first three multipliers (Eq. (J2)): its derivative is the response's, exactly
    reactions = {
        joint.name: np.transpose(dlam[:, :, int(system.rows[c]) : int(system.rows[c]) + 3], (0, 2, 1))
        for c, joint in enumerate(system.all_constraints)
        if isinstance(joint, MarkerJoint)
    }
    return PathSensitivity(
        names,
        angles,
        np.transpose(derivatives["coupler_point"], (0, 2, 1)),
        derivatives["driving_torque"],
        reaction_forces=reactions,
        squared_frequency=frequencies,
        lowest_squared_frequency=derivatives.get("lowest_squared_frequency"),
        coordinates=np.transpose(dq, (0, 2, 1)),
        **({} if stresses is None else stresses),
    )


def _stress_derivatives(
    scene: LinkageScene,
    q: NDArray,
    dq: NDArray,
    sides: list[tuple[LinkageScene, LinkageScene, float]],
    radius: float | None = None,
) -> dict[str, NDArray]:
    """Each link's peak von Mises stress at every pose ``(poses, links)``, its element and corner, and its
    derivatives ``(poses, links, k)`` (Eq. (D9)); the p-norm of its corner stresses and its derivatives likewise
    (Eq. (D10)); as :class:`PathSensitivity`'s fields. Along the response ``dq`` ``(poses, k, n)`` exactly, by the
    gradients in the link's modal coordinates; plus, for a parameter whose linkage at +-step has that link rebuilt (a
    section), the stress at the peak's corner (and the norm) of the rebuilt link at the same coordinates, by central
    differences. A material's own share (the stress is proportional to E at fixed strain) is the caller's
    (:func:`material_sensitivity`). With a ``radius`` (m), of the strains averaged over balls of that radius around
    each vertex (Eq. (D14)): the 'element' is then the ball's centre (its row of the averaging), the corner 0, and a
    rebuilt link is averaged with the nominal one's balls (the same elements, their moved volumes)."""
    system = scene.system
    poses, k = dq.shape[:2]
    links = len(scene.bodies)
    out = {
        "peak_stress": np.full((poses, links), np.nan),
        "peak_stress_slopes": np.full((poses, links, k), np.nan),
        "peak_stress_corner": np.full((poses, links, 2), -1, dtype=np.int64),
        "stress_norm": np.full((poses, links), np.nan),
        "stress_norm_slopes": np.full((poses, links, k), np.nan),
    }
    for link, body in enumerate(scene.bodies):
        if not isinstance(body.fe, FEModel):
            continue
        average = None if radius is None else ball_average(body.fe, radius)
        modes = strain_modes(body.fe, body.reduction.basis, average)
        block = system.block(link)
        material = body.fe.material
        for row in range(poses):
            zeta = q[row, block][7:]
            response = dq[row, :, block.start + 7 : block.stop]
            peak = peak_stress(modes, zeta, material.E, material.nu)
            norm = stress_norm(modes, zeta, material.E, material.nu)
            out["peak_stress"][row, link], out["peak_stress_corner"][row, link] = (
                peak.value,
                (peak.element, peak.corner),
            )
            out["stress_norm"][row, link] = norm.value
            out["peak_stress_slopes"][row, link] = response @ peak.gradient
            out["stress_norm_slopes"][row, link] = response @ norm.gradient
            for column, (plus, minus, step) in enumerate(sides):
                rebuilt = [side.bodies[link] for side in (plus, minus)]
                if all(other is body for other in rebuilt):
                    continue
                at = [
                    corner_stress(other.mesh_model, other.reduction.basis, zeta, peak.element, peak.corner, average)
                    for other in rebuilt
                ]
                out["peak_stress_slopes"][row, link, column] += (at[0] - at[1]) / (2.0 * step)
                norms = [
                    stress_norm_at(other.mesh_model, other.reduction.basis, zeta, average=average) for other in rebuilt
                ]
                out["stress_norm_slopes"][row, link, column] += (norms[0] - norms[1]) / (2.0 * step)
    return out


def _along_response(
    scene: LinkageScene,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray,
    dq: NDArray,
    dlam: NDArray,
    largest: float,
    modes: list[LowestMode] | None = None,
) -> dict[str, NDArray[np.float64]]:
    """Eq. (D2): the outputs' central differences along each response ``(dq, dlam)`` ``(poses, k, .)``, a step
    moving no coordinate by more than ``largest``; each output ``(poses, k, ...)``."""
    poses, k = dq.shape[:2]
    step = largest / np.maximum(np.abs(dq).max(axis=2), np.finfo(float).tiny)  # (poses, k)
    times = np.repeat(time, k)
    sides = []
    for sign in (1.0, -1.0):
        shifted_q = (q[:, None, :] + sign * step[..., None] * dq).reshape(poses * k, -1)
        shifted_lam = (multipliers[:, None, :] + sign * step[..., None] * dlam).reshape(poses * k, -1)
        repeated = None if modes is None else [mode for mode in modes for _ in range(k)]
        sides.append(_outputs(scene, times, shifted_q, shifted_lam, repeated))
    out = {}
    for name in sides[0]:
        difference = (sides[0][name] - sides[1][name]).reshape(poses, k, *sides[0][name].shape[1:])
        out[name] = difference / (2.0 * step).reshape(poses, k, *([1] * (difference.ndim - 2)))
    return out


def _refuse_unstable(scene: LinkageScene, time: NDArray, frequencies: NDArray) -> None:
    """:class:`SensitivityError` for the first pose whose lowest squared frequency of Eq. (B1) is not positive."""
    row = int(np.flatnonzero(frequencies <= 0.0)[0])
    angle = np.degrees(scene.drive_angle(float(time[row])))
    raise SensitivityError(
        f"the equilibrium at drive angle {angle:.4g} deg (t = {time[row]:g} s) is not stable (lowest squared "
        f"frequency of Eq. (B1) {frequencies[row]:.3g} rad^2/s^2): a print does not rest there, and its derivatives "
        "are those of a fold or of a path it has left; take the poses on either side"
    )
