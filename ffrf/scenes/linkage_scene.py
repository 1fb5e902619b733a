r"""A built single-loop linkage: the scene, its drive and the ideal (rigid) motion it is compared with.

:func:`build_linkage` builds :func:`ffrf.scenes.linkage_description.linkage_description` with the one
scene builder and keeps what a linkage run needs besides the system: the loop (:class:`kinematics.SingleLoop`,
the nominal design), the driven joint and its drive, the start, the run's end and the tool link. The ideal
coupler point at a drive angle is the tool link's point moved by the rigid loop's motion at that angle
(Eq. (L1), followed by :func:`kinematics.follow_driver`); for the paper's Bennett linkage
(:class:`ffrf.paper.bennett_scene.BennettScene`) it comes from the motion polynomial instead, which is
the same curve (``tests/test_kinematics/test_single_loop.py``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import SceneError
from ffrf.fe.interfaces import boundary_triangles
from ffrf.geometry.joint_axes import Axis, common_normal_feet
from ffrf.geometry.link_geometry import LinkDesign, housing_centers
from ffrf.output.clearance import Clearance, signed_clearance
from ffrf.output.clearance_sensitivity import clearance_slopes
from ffrf.output.loop_poses import LoopPoses
from ffrf.output.path_distance import ExactCurve
from ffrf.output.solid_distance import JointZone, LinkSolid
from ffrf.scenes.builder import Scene, SceneBody, build_scene, parametric_link
from ffrf.scenes.linkage_description import (
    BoreError,
    LinkageOptions,
    checked_tool_link,
    drive_sign,
    joint_points,
    linkage_description,
    seated_joint_points,
    start_pose,
)
from ffrf.scenes.scene_cache import PROCESS_CACHE, SceneCache, content_key
from ffrf.system.drives import CosineRamp
from kinematics import (
    LoopFoldError,
    SingleLoop,
    close_near,
    follow_driver,
    motion_tangents,
    point_paths,
    trace_motion,
)

__all__ = ["Housings", "LinkageScene", "as_linkage", "build_linkage", "described_housings", "joint_zones"]


@dataclass(frozen=True, eq=False)
class LinkageScene(Scene):
    """A built linkage (as built: every bore error in place) with its nominal ``loop``, the ``driver``
    joint, its ``drive`` (ramp from ``start_angle``, rad, the driven joint's prescribed angle), the
    rigid loop's joint rotations ``start_phi`` at the start, the run's end ``t_end``, the ``tool_link`` and
    ``coupler_home``, the coupler point at home: the mean of where the tool link's two joints sit
    (:func:`~ffrf.scenes.linkage_description.seated_joint_points`, as the run's ``coupler_point`` sensor);
    ``cache``: where its ideal (rigid) coupler path is kept by content
    (:class:`~ffrf.scenes.scene_cache.SceneCache`, the one it was built with)."""

    loop: SingleLoop
    driver: int
    drive: CosineRamp
    start_angle: float
    start_phi: NDArray[np.float64]
    t_end: float
    tool_link: int
    coupler_home: NDArray[np.float64]
    cache: SceneCache

    @property
    def links(self) -> tuple[SceneBody, ...]:
        return self.bodies

    @property
    def gravity(self) -> NDArray[np.float64]:
        return self.system.gravity

    @cached_property
    def link_length(self) -> float:
        """Largest distance between the two joint points of one link (m)."""
        points = joint_points(self.loop)
        return float(max(np.linalg.norm(points[k] - points[k - 1]) for k in range(self.loop.n)))

    @property
    def tracked_nodes(self) -> dict[int, NDArray[np.int64]]:
        """Link index -> its tracked surface nodes (sensors ``link{k}_node{j}``)."""
        nodes: dict[int, list[int]] = {}
        for name, (body, node) in self.sensors.items():
            if name.startswith("link") and "_node" in name:
                nodes.setdefault(body, []).append(node)
        return {k: np.array(v) for k, v in nodes.items()}

    def drive_angle(self, t: float) -> float:
        """The driven joint's prescribed angle (rad): start angle plus the ramp."""
        return self.start_angle + float(self.drive(t))

    def home_coupler_point(self) -> NDArray[np.float64]:
        """The coupler point at home (``coupler_home``, a copy): where the run's ``coupler_point`` sensor starts."""
        return np.array(self.coupler_home)

    def ideal_coupler_points(self, drive_angles: ArrayLike) -> NDArray[np.float64]:
        """The coupler point of the rigid nominal loop with the driven joint at ``drive_angles`` (in order)."""
        angles = np.asarray(drive_angles, dtype=float)
        return self._kept("ideal coupler points", angles, lambda: self._rigid_coupler_points(angles))

    def _rigid_coupler_points(self, angles: NDArray[np.float64]) -> NDArray[np.float64]:
        phi = drive_sign(self.driver, self.loop.n) * angles
        motion = follow_driver(self.loop, self.driver, phi, start=self.start_phi)
        return motion.path(self.tool_link, self.home_coupler_point())

    def _kept(self, what: Any, argument: Any, compute: Callable[[], NDArray[np.float64]]) -> NDArray[np.float64]:
        """``compute()`` (a copy), computed once per ``what``, ``argument`` and this linkage's nominal loop, driver,
        start, tool link and coupler point: every variant of a study has the same ideal path."""
        key = content_key(
            what, _loop_content(self.loop), self.driver, self.start_phi, self.tool_link, self.coupler_home, argument
        )
        return np.array(self.cache.rigid_motions.get_or_compute(key, compute))

    def clearance(self, n_poses: int = 72, margin: float = 1e-3) -> Clearance:
        """Signed clearance of every pair of links along one revolution of the rigid nominal motion from the start,
        sampled at ``n_poses`` poses and bounded between them, against ``margin`` (m)
        (:func:`ffrf.output.clearance.signed_clearance`, ``docs/formulation.md`` Eqs. (CL1)-(CL4))."""
        return signed_clearance(self.link_solids(), self.rigid_revolution(n_poses), self.joint_zones(), margin)

    def link_solids(self) -> list[LinkSolid]:
        """Every link's solid at home: its mesh's points and boundary triangles (normals out)."""
        return [
            LinkSolid(body.mesh_model.mesh.points, boundary_triangles(body.mesh_model.mesh, outward=True), body.name)
            for body in self.bodies
        ]

    def rigid_revolution(self, n_poses: int) -> LoopPoses:
        """One revolution of the rigid nominal loop's drive from the start, ``n_poses`` equal steps (the clearance
        check's samples)."""
        sign = drive_sign(self.driver, self.loop.n)  # turn the way the drive turns
        return LoopPoses.revolution(self.loop, self.driver, n_poses, self.start_phi, sign)

    def clearance_slopes(
        self,
        found: Clearance,
        velocities: dict[tuple[int, str], NDArray],
        parameters: tuple[str, ...],
        steps: ArrayLike,
        n_poses: int = 72,
    ) -> NDArray[np.float64]:
        """The derivatives ``(pairs, k)`` of each pair's smallest clearance in ``found`` (:meth:`clearance`) by
        ``parameters``, whose velocities at each link's mesh points are ``velocities[link, parameter]`` ``(m, 3)``
        (a link without one does not move), central differences over ``steps`` (m) along them (Eq. (CL5)): at the
        pose that holds the smallest, for the rigid motion does not depend on the links' shape; ``n_poses``: those of
        :meth:`clearance`'s samples, from which each pose is closed."""
        solids, zones = self.link_solids(), self.joint_zones()
        transforms, _ = self.rigid_revolution(n_poses).poses(found.drive_angle)  # (pairs, links, 4, 4)
        fields = [
            np.stack([velocities.get((k, p), np.zeros_like(solid.vertices)) for p in parameters], axis=-1)
            for k, solid in enumerate(solids)
        ]
        out = np.empty((len(found.pairs), len(parameters)))
        for row, (a, b) in enumerate(found.pairs):
            relative = np.linalg.solve(transforms[row, a], transforms[row, b])
            zone = zones.get((int(a), int(b)))
            out[row] = clearance_slopes(solids[a], solids[b], relative, fields[a], fields[b], steps, zone)[1]
        return out

    def joint_zones(self) -> dict[tuple[int, int], JointZone]:
        """The zone of each joint (Eq. (CL3)), keyed by the two links that share it (:func:`joint_zones`), the
        housings of each link from its geometry, else from its description's parametric table (a changed design's
        morphed link, :func:`~ffrf.scenes.builder.morphed_scene`)."""
        housings = []
        for body, entry in zip(self.bodies, self.description["bodies"], strict=True):
            geometry = body.geometry
            if geometry is None:
                housings.append(described_housings(entry))
            else:
                centres = dict(zip(geometry.interface_names, geometry.housing_centers, strict=True))
                housings.append((centres, geometry.design))
        return joint_zones(self.loop, housings)

    def ideal_coupler_curve(self, n: int = 720) -> NDArray[np.float64]:
        """``n`` points of the ideal coupler curve over one revolution of the driver from the start."""

        def curve() -> NDArray[np.float64]:
            sign = drive_sign(self.driver, self.loop.n)
            motion = trace_motion(self.loop, self.driver, n_poses=n, revolution=sign * 2 * np.pi, start=self.start_phi)
            return motion.path(self.tool_link, self.home_coupler_point())

        return self._kept("ideal coupler curve", n, curve)

    def ideal_coupler_exact(self, n: int = 720) -> ExactCurve:
        """The ideal coupler curve over one revolution of the driver from the start, exactly: ``n`` samples at equal
        drive angles (with the rigid loop's joint angles there, kept as :meth:`ideal_coupler_curve`) and, between
        them, the rigid loop closed at any drive angle from the sample before it (:func:`kinematics.close_near`),
        for :func:`ffrf.output.path_distance.distance_to_curve`."""
        sign = drive_sign(self.driver, self.loop.n)
        home = self.home_coupler_point()

        def samples() -> NDArray[np.float64]:
            motion = trace_motion(self.loop, self.driver, n_poses=n, revolution=sign * 2 * np.pi, start=self.start_phi)
            tangents = motion_tangents(self.loop, self.driver, motion.phi)
            return np.column_stack(
                [sign * motion.driver_angles, motion.phi, tangents, motion.path(self.tool_link, home)]
            )

        table = self._kept("ideal coupler samples", n, samples)
        joints = self.loop.n
        phi, tangents = table[:, 1 : 1 + joints], table[:, 1 + joints : 1 + 2 * joints]

        def exact(angles: NDArray[np.float64], arcs: NDArray[np.int64]) -> NDArray[np.float64]:
            closed = close_near(self.loop, self.driver, phi[arcs], sign * angles, tangents[arcs])
            return point_paths(self.loop, closed, self.tool_link, home)

        return ExactCurve(table[:, 0], table[:, 1 + 2 * joints :], 2 * np.pi, exact)


def _plain(error: BoreError) -> dict:
    """A bore error as plain data for the metadata (SI units)."""
    axis = (
        None if error.axis is None else {"point": error.axis.point.tolist(), "direction": error.axis.direction.tolist()}
    )
    return {
        "joint": error.joint,
        "link": error.link,
        "twist": error.twist,
        "offset": error.offset,
        "axial": error.axial,
        "axis": axis,
    }


def _check_drive_range(loop: SingleLoop, options: LinkageOptions, start_phi: NDArray, turn: float, where: str) -> None:
    """Refuse a run whose drive turns the driven joint beyond a dead point of the rigid loop (the ideal motion
    the run is compared with ends there; a flexible model would only be strained past it)."""
    sign = drive_sign(options.driver, loop.n)
    poses = int(np.ceil(abs(turn) / np.radians(2.0))) + 1
    try:
        trace_motion(loop, options.driver, n_poses=poses, revolution=sign * turn, start=start_phi, endpoint=True)
    except LoopFoldError as error:
        raise SceneError(
            f"{where}: the run turns joint {options.driver} by {np.degrees(turn):.4g} deg from the start, but "
            f"the rigid loop stops before: {error}, or shorten the run (revolutions)"
        ) from error


def _loop_content(loop: SingleLoop) -> list:
    """What the rigid loop's motion depends on: its axes' Pluecker coordinates (for :func:`content_key`)."""
    return [(axis.direction, axis.moment) for axis in loop.axes]


def _cached_start(loop: SingleLoop, options: LinkageOptions, cache: SceneCache) -> NDArray[np.float64]:
    """:func:`~ffrf.scenes.linkage_description.start_pose` of the options, once per loop, driver, angle and origin."""
    origin = None if options.origin is None else np.asarray(options.origin, dtype=float)
    key = content_key("start pose", _loop_content(loop), options.driver, options.start_angle, origin)
    start = cache.rigid_motions.get_or_compute(
        key, lambda: start_pose(loop, options.driver, options.start_angle, options.origin)
    )
    return np.array(start)


def _cached_range_check(
    loop: SingleLoop, options: LinkageOptions, start_phi: NDArray, turn: float, where: str, cache: SceneCache
) -> None:
    """:func:`_check_drive_range`, passed once per loop, driver, start and turn (a refused range is not kept)."""

    def check() -> bool:
        _check_drive_range(loop, options, start_phi, turn, where)
        return True

    cache.rigid_motions.get_or_compute(
        content_key("drive range", _loop_content(loop), options.driver, start_phi, turn), check
    )


def build_linkage(
    loop: SingleLoop,
    options: LinkageOptions | None = None,
    where: str | None = None,
    cache: SceneCache | None = None,
) -> LinkageScene:
    """Build :func:`~ffrf.scenes.linkage_description.linkage_description` of ``loop`` with the one scene builder.
    A drive that turns its joint beyond a dead point of the rigid loop is refused (:class:`ffrf.errors.SceneError`);
    ``where`` (default the linkage's name) starts every error message; ``cache``: the content-keyed
    :class:`~ffrf.scenes.scene_cache.SceneCache` of the rigid loop's start and range and of what
    :func:`~ffrf.scenes.builder.build_scene` builds (default the process's own)."""
    options = LinkageOptions() if options is None else options
    where = options.name if where is None else where
    cache = PROCESS_CACHE if cache is None else cache
    checked_tool_link(loop, options)
    start_phi = _cached_start(loop, options, cache)
    description = linkage_description(loop, options, start_phi)
    t_end = float(description["scene"]["t_end"])
    turn = float(CosineRamp(options.omega, options.ramp_time)(t_end))
    _cached_range_check(loop, options, start_phi, turn, where, cache)
    return as_linkage(build_scene(description, where=where, cache=cache), loop, options, start_phi, cache)


#: A link's housing centres by its interfaces' names and its design (:func:`joint_zones`).
Housings = tuple[dict[str, NDArray[np.float64]], LinkDesign]


def described_housings(entry: dict) -> Housings | None:
    """The housings of a body described by a ``parametric`` table (``None`` for a body from a mesh file): its
    housing centres where :func:`~ffrf.geometry.link_geometry.build_link` puts them."""
    if "parametric" not in entry:
        return None
    link = parametric_link(entry["parametric"], entry["name"])
    axes = (Axis.of(link["axis_a"]), Axis.of(link["axis_b"]))
    points = common_normal_feet(*axes) if link["joint_points"] is None else link["joint_points"]
    centres = housing_centers(points, axes, link["design"])
    return dict(zip(link["names"], centres, strict=True)), link["design"]


def joint_zones(loop: SingleLoop, housings: Sequence[Housings | None]) -> dict[tuple[int, int], JointZone]:
    """The zone of each joint of ``loop`` (Eq. (CL3)), keyed by the two links that share it: about the nominal
    axis, around both links' housings there; ``housings[k]``: link ``k``'s (``None``, a link from a mesh file: the
    default design's housings stacked about the joint point, the offset rule of
    :mod:`ffrf.geometry.link_geometry`)."""
    n = loop.n
    points = joint_points(loop)
    zones = {}
    for joint, axis in enumerate(loop.axes):
        links = (joint, (joint + 1) % n)
        centres, design = [], LinkDesign()
        for link, side in zip(links, (1, -1), strict=True):  # h_joint: the near link's second axis, far's first
            own = housings[link]
            if own is None:
                centres.append(points[joint] - side * design.housing_offset * axis.direction)
            else:
                design = own[1]
                centres.append(own[0][f"joint{joint}"])
        zones[min(links), max(links)] = JointZone.around_housings(
            points[joint],
            axis.direction,
            centres,
            design.housing_length,
            design.housing_outer_radius,
            design.axial_gap,
        )
    return zones


def as_linkage(
    scene: Scene, loop: SingleLoop, options: LinkageOptions, start_phi: NDArray, cache: SceneCache
) -> LinkageScene:
    """The built ``scene`` of :func:`~ffrf.scenes.linkage_description.linkage_description` of ``loop`` and
    ``options`` from the rigid loop's joint rotations ``start_phi``, as a :class:`LinkageScene` keeping its ideal
    path in ``cache``."""
    tool = checked_tool_link(loop, options)
    angle = next(j.angle for j in scene.joints if j.angle is not None)  # the drive the system runs with
    settings = dict(
        scene.settings,
        driver=options.driver,
        h=options.h,
        order=options.order,
        n_modes=options.n_modes,
        omega=options.omega,
        ramp_time=options.ramp_time,
        revolutions=options.revolutions,
        material=options.material.name,
        bore_errors=[_plain(e) for e in options.bore_errors],
        bore_error_model=options.bore_error_model,
    )
    built = {f.name: getattr(scene, f.name) for f in fields(Scene)}
    return LinkageScene(
        **dict(built, settings=settings),
        loop=loop,
        driver=options.driver,
        drive=angle.ramp,
        start_angle=angle.start,
        start_phi=start_phi,
        t_end=float(scene.description["scene"]["t_end"]),
        tool_link=tool,
        coupler_home=seated_joint_points(loop, options.attach_points)[[tool - 1, tool]].mean(axis=0),
        cache=cache,
    )
