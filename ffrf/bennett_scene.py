r"""The flexible Bennett linkage of the paper (Sect. "Simulation Setup"), built from its DH table.

Four parametric links (:mod:`ffrf.link_geometry`), meshed with gmsh and assembled with
scikit-fem, reduced with Craig-Bampton (frame interface: the first bore, or the mounting
face of the base), joined by ideal revolute joints on rigid bore markers, the base clamped
at its mounting face, and joint 3 (between link 3 and the base) driven by the paper's
cosine ramp. Link numbering and axes follow :mod:`kinematics.bennett`.

Every body's frame coincides with the world frame in the home configuration (the meshes
are built there); the simulation starts from the ideal configuration at ``start_angle``
of the driver, where link ``k`` is displaced by the motion polynomial's pose of link ``k``.
Misaligned variants (base twist 91 or 92 deg) cannot be assembled rigidly: the base's
joint-3 frame is turned from the nominal axis to its own bore axis in small steps of a
static solution (:func:`assemble`), and the assembly stresses remain in the links.

**Joint points off the bore centre.** The two housings at a joint are stacked along its axis,
so each joint point lies ``o`` = 8.5 mm from its bore's weighted centre. ``joint_offsets``
chooses where that offset lives (:func:`ffrf.markers.attach_joint_point`):

* ``"body"`` (default): in the body frame, ``p = R + A(o + x_bar + P zeta)`` (Eq. (K1) with
  the offset in the marker point). This is the paper's model: Exudyn's
  ``MarkerSuperElementRigid`` applies its offset this way, so the Exudyn twin is exactly
  equivalent (:mod:`validation.exudyn_bennett`).
* ``"marker"``: in the bore marker's frame, ``p = r_M + A exp(theta_M) o`` (a pin rigidly
  attached to the rigid bore, Eqs. (J1)-(J3)). It differs from ``"body"`` by
  ``A (exp(theta_M) - I) o``, about 3 % of the PLA coupler's sag (measured in the report of
  :mod:`validation`); Exudyn cannot express it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from kinematics import PAPER_A, PAPER_ALPHA, BennettLinkage

from .craig_bampton import CraigBamptonBasis, craig_bampton
from .drives import CosineRamp, RampedAngle, rpm
from .fe_model import FEModel
from .flexible_body import FlexibleBody
from .interfaces import InterfaceNodes, boundary_triangles, interface_from_group
from .joints import GroundFrame, MarkerJoint, driven_revolute_joint, fixed_joint, revolute_joint
from .link_geometry import LinkGeometry, bennett_axes, mesh_link, paper_link_axes
from .markers import JOINT_OFFSETS, BodyMarker, attach_joint_point, rigid_interface_marker
from .materials import PLA, RIGID, Material
from .modal_moments import modal_moments
from .static_solver import StaticDivergence, static_equilibrium
from .system import MultibodySystem

__all__ = ["VARIANTS", "LinkModel", "BennettScene", "build_bennett", "assemble", "joint_frame"]

log = logging.getLogger(__name__)

#: The paper's four simulation variants: material and base-link twist alpha_3 (deg).
VARIANTS: dict[str, tuple[Material, float]] = {
    "rigid": (RIGID, 90.0),
    "pla": (PLA, 90.0),
    "pla1": (PLA, 91.0),
    "pla2": (PLA, 92.0),
}


@dataclass(frozen=True, eq=False)
class LinkModel:
    """One link: FE model, geometry, interfaces, reduction, body and bore markers."""

    index: int
    fe: FEModel
    geometry: LinkGeometry
    interfaces: dict[str, InterfaceNodes]
    reduction: CraigBamptonBasis
    body: FlexibleBody
    markers: dict[str, BodyMarker]
    tracked_nodes: NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class BennettScene:
    """Everything a run needs; ``system`` has the variant's full misalignment."""

    variant: str
    links: tuple[LinkModel, ...]
    system: MultibodySystem
    q_start: NDArray[np.float64]
    drive: CosineRamp
    start_angle: float
    t_end: float
    linkage: BennettLinkage
    settings: dict = field(default_factory=dict)

    def with_misalignment(self, fraction: float) -> MultibodySystem:
        """The system with the base's joint-3 frame turned, and its joint point moved, by
        ``fraction`` of the misalignment (0: link 3's nominal axis, 1: the base's own bore axis)."""
        return _system(self.links, RampedAngle(self.start_angle, self.drive), self.gravity, fraction,
                       self.settings["joint_offsets"])

    def with_exact_gravity(self, exact: bool) -> "BennettScene":
        """The same scene with the exact gravity force or Exudyn's simplified one (Eq. (F10))."""
        links = tuple(replace(l, body=replace(l.body, exact_gravity=exact)) for l in self.links)
        scene = replace(self, links=links, settings=dict(self.settings, exact_gravity=exact))
        return replace(scene, system=scene.with_misalignment(1.0))

    @property
    def gravity(self) -> NDArray[np.float64]:
        return self.system.gravity

    def drive_angle(self, t: float) -> float:
        """Rotation of link 3 relative to the base about h3 (rad): start angle plus the ramp."""
        return self.start_angle + float(self.drive(t))


def joint_frame(z: NDArray, reference_x: NDArray | None = None) -> NDArray[np.float64]:
    """Orthonormal frame (columns x, y, z) with the given z; x is ``reference_x`` made normal to z."""
    z = np.asarray(z, float) / np.linalg.norm(z)
    x = np.array([1.0, 0.0, 0.0]) if reference_x is None else np.asarray(reference_x, float)
    x = x - (x @ z) * z
    if np.linalg.norm(x) < 1e-8:
        x = np.array([0.0, 1.0, 0.0]) - z[1] * z
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _build_link(k: int, axes, material: Material, h: float, order: int, n_modes: int, beta: float,
                exact_gravity: bool) -> LinkModel:
    first, second, names = paper_link_axes(k, axes)
    mesh, geometry = mesh_link(first, second, h=h, names=names, mount=(k == 0), name=f"link{k}")
    fe = FEModel.from_tet_mesh(mesh, material, order)
    order_of_interfaces = (["mount"] if k == 0 else []) + list(names)
    interfaces = {name: interface_from_group(fe, name) for name in order_of_interfaces}
    reduction = craig_bampton(fe, [interfaces[n] for n in order_of_interfaces], n_modes)
    basis = reduction.basis
    body = FlexibleBody(f"link{k}", modal_moments(fe.nodes, fe.mass, basis), reduction.reduced_stiffness,
                        beta * reduction.reduced_stiffness, exact_gravity)
    markers = {name: rigid_interface_marker(k, fe.nodes, basis, itf.nodes, itf.weights, name=f"link{k}:{name}")
               for name, itf in interfaces.items()}
    # Three surface nodes along the arm, as the paper tracks three nodes per link.
    a, b = geometry.joint_points
    candidates = np.unique(boundary_triangles(mesh))
    targets = [a + f * (b - a) for f in (0.3, 0.5, 0.7)]
    tracked = np.array([candidates[np.argmin(np.linalg.norm(fe.nodes[candidates] - p, axis=1))] for p in targets])
    log.info("link %d: %d nodes, %d modes (%s)", k, fe.nodes.shape[0], reduction.n_modes, reduction.summary())
    return LinkModel(k, fe, geometry, interfaces, reduction, body, markers, tracked)


def _joint_point(link: LinkModel, name: str) -> NDArray[np.float64]:
    index = list(link.geometry.interface_names).index(name)
    return link.geometry.joint_points[index]


def _axis(link: LinkModel, name: str) -> NDArray[np.float64]:
    index = list(link.geometry.interface_names).index(name)
    return link.geometry.axes[index].direction


def _system(links, drive_angle, gravity, misalignment: float, joint_offsets: str) -> MultibodySystem:
    base = links[0]
    mount = base.markers["mount"]
    constraints: list = [fixed_joint(GroundFrame(mount.point.copy(), np.eye(3)), mount, name="clamp")]
    for i in range(4):
        name = f"joint{i}"
        near, far = links[i], links[(i + 1) % 4]  # h_i is near's second axis and far's first axis
        marker_near, marker_far = near.markers[name], far.markers[name]
        point_far = _joint_point(far, name)
        z_far = _axis(far, name)
        frame_far = joint_frame(z_far)
        z_near = _axis(near, name)
        point_near = _joint_point(near, name)
        if i == 3:
            # Continuation moves the base's joint point, as it turns its frame (below), from link
            # 3's nominal point to the point on the base's own (misaligned) bore axis.
            point_far = point_near + misalignment * (point_far - point_near)
        marker_near, offset_near = attach_joint_point(marker_near, point_near, joint_offsets)
        marker_far, offset_far = attach_joint_point(marker_far, point_far, joint_offsets)
        if i != 3:
            frame_near = joint_frame(z_near, frame_far[:, 0])
            constraints.append(revolute_joint(marker_near, marker_far, frame_near, frame_far, offset_near, offset_far,
                                              name=name))
        else:
            # Joint 3: marker 0 on the base (link 0, far side), marker 1 on link 3 (near side).
            # The base's own axis may be misaligned; continuation turns its frame from the
            # nominal axis (link 3's) to the base's bore axis.
            nominal = joint_frame(z_near)
            own = joint_frame(z_far, nominal[:, 0])
            frame_base = _interpolate_frames(nominal, own, misalignment)
            constraints.append(driven_revolute_joint(marker_far, marker_near, drive_angle, frame_base, nominal,
                                                     offset_far, offset_near, name="joint3 (drive)"))
    return MultibodySystem(tuple(l.body for l in links), tuple(constraints), gravity=gravity)


def _interpolate_frames(start: NDArray, end: NDArray, fraction: float) -> NDArray:
    """Rotate ``start`` towards ``end`` by ``fraction`` of the relative rotation (geodesic)."""
    from scipy.spatial.transform import Rotation

    relative = Rotation.from_matrix(end @ start.T).as_rotvec()
    return Rotation.from_rotvec(fraction * relative).as_matrix() @ start


def _start_state(system: MultibodySystem, linkage: BennettLinkage, start_angle: float) -> NDArray:
    """Link poses of the ideal linkage with link 3 turned by ``start_angle`` about h3 from home."""
    # Link 3 turns about h3 by -psi_3 when the DH angle of joint 3 grows by psi_3 (kinematics.bennett).
    t = linkage.parameter_from_joint(linkage.home_theta[3] - start_angle, joint=3)
    poses = linkage.link_poses(t)
    q = system.initial_state()
    for k, pose in enumerate(poses):
        block = system.block(k)
        unit = pose.normalized()
        q[block.start:block.start + 3] = unit.translation_vector()
        q[block.start + 3:block.start + 7] = unit.primal
    return q


def build_bennett(
    variant: str = "pla",
    h: float = 6e-3,
    order: int = 2,
    n_modes: int = 4,
    beta: float = 0.005,
    omega: float = rpm(1.0),
    ramp_time: float = 1.0,
    start_angle: float = np.radians(90.0),
    revolutions: float = 1.0,
    gravity=(0.0, 0.0, -9.81),
    exact_gravity: bool = True,
    joint_offsets: str = "body",
) -> BennettScene:
    """Build the paper's scene ``variant`` (``rigid``, ``pla``, ``pla1``, ``pla2``).

    ``h``: maximum tetrahedron edge (m; paper 2 mm); ``order``: 1 (linear, the paper's) or 2
    (quadratic) tetrahedra; ``n_modes``: fixed-interface modes per link (paper 32). The defaults
    are the cheapest discretisation that puts the coupler path within 0.01 mm of the converged one
    (measured 1.6 um; the rule and its measurements: ``docs/speed_vs_error.md``); ``start_angle``: link 3's rotation about h3 from the folded home pose
    at t = 0 (the folded pose itself has overlapping arms); ``revolutions`` after the ramp;
    ``joint_offsets``: ``"body"`` (paper, Exudyn) or ``"marker"`` (module docstring).
    """
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r}; choose one of {sorted(VARIANTS)}")
    if joint_offsets not in JOINT_OFFSETS:
        raise ValueError(f"joint_offsets must be one of {JOINT_OFFSETS}, got {joint_offsets!r}")
    material, alpha3 = VARIANTS[variant]
    # Only the base is misaligned: it carries its own (closing) h3; link 3 keeps the nominal h3.
    axes, nominal = bennett_axes(alpha3), bennett_axes(90.0)
    links = tuple(_build_link(k, nominal if k == 3 else axes, material, h, order, n_modes, beta, exact_gravity)
                  for k in range(4))
    drive = CosineRamp(omega, ramp_time)
    linkage = BennettLinkage(PAPER_A, PAPER_ALPHA)
    gravity = np.asarray(gravity, dtype=float)
    settings = dict(variant=variant, h=h, order=order, n_modes=n_modes, beta=beta, omega=omega, ramp_time=ramp_time,
                    start_angle=start_angle, revolutions=revolutions, gravity=gravity.tolist(),
                    exact_gravity=exact_gravity, alpha3_deg=alpha3, material=material.name,
                    joint_offsets=joint_offsets)

    system = _system(links, RampedAngle(start_angle, drive), gravity, 1.0, joint_offsets)
    q_start = _start_state(system, linkage, start_angle)
    t_end = drive.time_for_angle(float(drive.angle(ramp_time)) + 2.0 * np.pi * revolutions)
    return BennettScene(variant, links, system, q_start, drive, start_angle, t_end, linkage, settings)


def assemble(scene: BennettScene, steps: int | None = None, t: float = 0.0,
             convert: Callable[[MultibodySystem], MultibodySystem] | None = None):
    """Static assembly at time ``t``: gravity, then the misalignment in ``steps`` increments
    (default: 1 for aligned variants, 4 per degree otherwise). ``convert`` maps each
    intermediate system (e.g. to other joint conventions). Returns the static solution."""
    misaligned = abs(scene.settings["alpha3_deg"] - 90.0) > 1e-12
    steps = (max(1, int(np.ceil(4 * abs(scene.settings["alpha3_deg"] - 90.0)))) if misaligned else 1) \
        if steps is None else steps
    convert = (lambda system: system) if convert is None else convert
    q = scene.q_start
    k = 0
    try:
        solution = static_equilibrium(convert(scene.with_misalignment(0.0)), q, t=t, load_steps=2)
        for k in range(1, steps + 1):
            solution = static_equilibrium(convert(scene.with_misalignment(k / steps)), solution.q, t=t)
    except StaticDivergence as error:
        # Name the scene and the continuation step: the solver's own message knows neither.
        alpha3 = scene.settings["alpha3_deg"]
        gap = float(np.abs(scene.system.constraint_values(scene.q_start, t)).max())
        raise StaticDivergence(
            f"static assembly of the Bennett scene (alpha_3 = {alpha3:g} deg, {abs(alpha3 - 90.0):g} deg from a closing "
            f"loop) failed at continuation step {k}/{steps} (gravity and the joint gap of {gap:.3g} at the start "
            f"pose): {error}. The links must absorb this misfit elastically from the ideal start pose; check alpha_3 "
            "(the paper's prototypes: 90 to 92 deg) or, for a large misfit, give Newton more iterations") from error
    return solution
