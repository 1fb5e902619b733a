r"""The flexible Bennett linkage of the paper (Sect. "Simulation Setup"), built from its DH table.

A scene description (:func:`bennett_description`) for the one scene builder
(:mod:`ffrf.scenes.builder`): four parametric links (:mod:`ffrf.geometry.link_geometry`), meshed
with gmsh and assembled with
scikit-fem, reduced with Craig-Bampton (frame interface: the first bore, or the mounting
face of the base), joined by ideal revolute joints on rigid bore markers, the base clamped
at its mounting face, and joint 3 (between link 3 and the base) driven by the paper's
cosine ramp. Link numbering and axes follow :mod:`kinematics.bennett`.

Every body's frame coincides with the world frame in the home configuration (the meshes
are built there); the simulation starts from the ideal configuration at ``start_angle``
of the driver, where link ``k`` is displaced by the motion polynomial's pose of link ``k``.
Misaligned variants (base twist 91 or 92 deg) cannot be assembled rigidly: the base's
joint-3 frame is turned from the nominal axis to its own bore axis in small steps of a
static solution (:func:`ffrf.scenes.assembly.assemble`), and the assembly stresses remain in the links.

**Joint points off the bore centre.** The two housings at a joint are stacked along its axis,
so each joint point lies ``o`` = 8.5 mm from its bore's weighted centre. ``joint_offsets``
chooses where that offset lives (:func:`ffrf.system.markers.attach_joint_point`):

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

from dataclasses import dataclass, fields, replace

import numpy as np
from numpy.typing import NDArray

from ffrf.fe.materials import PLA, RIGID, Material
from ffrf.geometry.joint_axes import bennett_axes, common_normal_feet, paper_link_axes
from ffrf.scenes.assembly import assemble
from ffrf.scenes.builder import Scene, SceneBody, build_scene
from ffrf.system.drives import CosineRamp, rpm
from ffrf.system.markers import JOINT_OFFSETS
from ffrf.system.multibody import MultibodySystem
from kinematics import PAPER_A, PAPER_ALPHA, BennettLinkage

__all__ = [
    "VARIANTS",
    "PAPER_MAX_COUPLER_DEVIATION_MM",
    "paper_max_coupler_deviation",
    "BennettScene",
    "bennett_description",
    "build_bennett",
    "assemble",
]

#: The paper's four simulation variants: material and base-link twist alpha_3 (deg).
VARIANTS: dict[str, tuple[Material, float]] = {
    "rigid": (RIGID, 90.0),
    "pla": (PLA, 90.0),
    "pla1": (PLA, 91.0),
    "pla2": (PLA, 92.0),
}
#: The paper's maximum coupler deviations from the ideal path per variant (mm; Sect. "Results",
#: simulated, its STL links at 2 mm with 32 modes). The rigid one is a bound: "< 0.001".
PAPER_MAX_COUPLER_DEVIATION_MM: dict[str, float] = {"rigid": 0.001, "pla": 0.211, "pla1": 1.215, "pla2": 2.305}


def paper_max_coupler_deviation(variant: str) -> str:
    """The paper's maximum coupler deviation of ``variant`` as its table states it, in mm
    (``"< 0.001"`` for the rigid bound, ``"0.211"`` ...); ``""`` for a variant the paper has not."""
    value = PAPER_MAX_COUPLER_DEVIATION_MM.get(variant)
    if value is None:
        return ""
    return f"< {value}" if variant == "rigid" else f"{value}"


#: Where along each link's arm (fraction from its first to its second joint point) a surface node
#: is tracked, as the paper tracks three nodes per link.
TRACKED_FRACTIONS = (0.3, 0.5, 0.7)


@dataclass(frozen=True, eq=False)
class BennettScene(Scene):
    """The paper's scene: a built :class:`~ffrf.scenes.builder.Scene` (as built: full misalignment)
    with what the Bennett runs need besides, the variant, the drive, the run's end and the ideal
    linkage. ``settings`` holds the scene's settings and the arguments of :func:`build_bennett`."""

    variant: str
    drive: CosineRamp
    start_angle: float
    t_end: float
    linkage: BennettLinkage

    @property
    def links(self) -> tuple[SceneBody, ...]:
        return self.bodies

    @property
    def q_start(self) -> NDArray[np.float64]:
        """Link poses of the ideal linkage at the drive's start angle, undeformed."""
        return self.q_initial

    @property
    def tracked_nodes(self) -> dict[int, NDArray[np.int64]]:
        """Link index -> its three tracked surface nodes (sensors ``link{k}_node{j}``)."""
        nodes: dict[int, list[int]] = {}
        for name, (body, node) in self.sensors.items():
            if name.startswith("link") and "_node" in name:
                nodes.setdefault(body, []).append(node)
        return {k: np.array(v) for k, v in nodes.items()}

    def with_misalignment(self, fraction: float) -> MultibodySystem:
        """The system with the base's joint-3 frame turned, and its joint point moved, by
        ``fraction`` of the misalignment (0: link 3's nominal axis, 1: the base's own bore axis)."""
        return self.with_misfit(fraction)

    def with_exact_gravity(self, exact: bool) -> BennettScene:
        """The same scene with the exact gravity force or Exudyn's simplified one (Eq. (F10))."""
        bodies = tuple(replace(b, body=replace(b.body, exact_gravity=exact)) for b in self.bodies)
        scene = replace(self, bodies=bodies, settings=dict(self.settings, exact_gravity=exact))
        return replace(scene, system=scene.with_misfit(1.0))

    @property
    def gravity(self) -> NDArray[np.float64]:
        return self.system.gravity

    def drive_angle(self, t: float) -> float:
        """Rotation of link 3 relative to the base about h3 (rad): start angle plus the ramp."""
        return self.start_angle + float(self.drive(t))


def _vector(x) -> list[float]:
    return [float(v) for v in x]


def _start_poses(linkage: BennettLinkage, start_angle: float) -> list[dict]:
    """Link poses of the ideal linkage with link 3 turned by ``start_angle`` about h3 from home."""
    # Link 3 turns about h3 by -psi_3 when the DH angle of joint 3 grows by psi_3 (kinematics.bennett).
    t = linkage.parameter_from_joint(linkage.home_theta[3] - start_angle, joint=3)
    poses = []
    for pose in linkage.link_poses(t):
        unit = pose.normalized()
        poses.append({"position": _vector(unit.translation_vector()), "euler_parameters": _vector(unit.primal)})
    return poses


def bennett_description(
    variant: str = "pla",
    h: float = 6e-3,
    order: int = 2,
    n_modes: int = 4,
    beta: float = 0.005,
    omega: float = rpm(1.0),
    ramp_time: float = 1.0,
    start_angle: float = np.radians(90.0),
    gravity=(0.0, 0.0, -9.81),
    exact_gravity: bool = True,
    joint_offsets: str = "body",
) -> dict:
    """The paper's scene ``variant`` as a scene description (the format of scene files): four
    parametric links, the base clamped at its mounting face, revolute joints 0..2 and joint 3 driven
    by the cosine ramp, each joint side on its own link's axis (the base's h3 misaligned by
    alpha_3 - 90 deg), link poses of the ideal linkage at ``start_angle``, three tracked nodes per
    moving link."""
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r}; choose one of {sorted(VARIANTS)}")
    if joint_offsets not in JOINT_OFFSETS:
        raise ValueError(f"joint_offsets must be one of {JOINT_OFFSETS}, got {joint_offsets!r}")
    material, alpha3 = VARIANTS[variant]
    # Only the base is misaligned: it carries its own (closing) h3; link 3 keeps the nominal h3.
    link_axes = [paper_link_axes(k, bennett_axes(90.0 if k == 3 else alpha3)) for k in range(4)]
    feet = [common_normal_feet(first, second) for first, second, _ in link_axes]
    poses = _start_poses(BennettLinkage(PAPER_A, PAPER_ALPHA), start_angle)
    bodies, sensors = [], []
    for k, (_, _, names) in enumerate(link_axes):
        interfaces = (["mount"] if k == 0 else []) + list(names)
        bodies.append(
            {
                "name": f"link{k}",
                "parametric": {"link": k, "alpha3_deg": 90.0 if k == 3 else alpha3, "h": h},
                "material": {"E": material.E, "nu": material.nu, "rho": material.rho, "name": material.name},
                "order": order,
                "modes": n_modes,
                "interfaces": [{"name": n, "group": n} for n in interfaces],
                "pose": poses[k],
            }
        )
        if k > 0:
            a, b = feet[k]
            sensors += [
                {"name": f"link{k}_node{j}", "body": f"link{k}", "point": _vector(a + f * (b - a)), "surface": True}
                for j, f in enumerate(TRACKED_FRACTIONS)
            ]
    joints: list[dict] = [
        {"name": "clamp", "type": "fixed", "body0": "ground", "body1": "link0", "interface1": "mount"}
    ]
    for i in range(4):
        near, far = i, (i + 1) % 4  # h_i is near's second axis and far's first axis
        near_side = {"body": f"link{near}", "axis": link_axes[near][1].direction, "point": feet[near][1]}
        far_side = {"body": f"link{far}", "axis": link_axes[far][0].direction, "point": feet[far][0]}
        # Joint 3: side 0 is the base (link 0, far side, its own possibly misaligned bore), side 1
        # link 3 (near side, nominal); joints 0..2: side 0 near, side 1 far.
        side0, side1 = (far_side, near_side) if i == 3 else (near_side, far_side)
        joint = {
            "name": "joint3 (drive)" if i == 3 else f"joint{i}",
            "type": "driven_revolute" if i == 3 else "revolute",
            "body0": side0["body"],
            "interface0": f"joint{i}",
            "axis0": _vector(side0["axis"]),
            "point0": _vector(side0["point"]),
            "body1": side1["body"],
            "interface1": f"joint{i}",
            "axis1": _vector(side1["axis"]),
            "point1": _vector(side1["point"]),
        }
        if i == 3:
            joint["drive"] = {
                "omega": float(omega),
                "ramp_time": float(ramp_time),
                "start_angle": float(start_angle),
            }
        joints.append(joint)
    settings = {
        "name": f"Bennett {variant}",
        "gravity": _vector(gravity),
        "beta": float(beta),
        "exact_gravity": bool(exact_gravity),
        "joint_offsets": joint_offsets,
        "static_start": True,
    }
    # The paper's coupler point: the mean of link 2's two joint points.
    sensors.append({"name": "coupler_point", "body": "link2", "joints": ["joint1", "joint2"]})
    return {"scene": settings, "bodies": bodies, "joints": joints, "sensors": sensors}


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
    """Build the paper's scene ``variant`` (``rigid``, ``pla``, ``pla1``, ``pla2``) from
    :func:`bennett_description` with the one scene builder.

    ``h``: maximum tetrahedron edge (m; paper 2 mm); ``order``: 1 (linear, the paper's) or 2
    (quadratic) tetrahedra; ``n_modes``: fixed-interface modes per link (paper 32). The defaults
    are the cheapest discretisation that puts the coupler path within 0.01 mm of the converged one
    (the rule and its measurements: ``docs/speed_vs_error.md``); ``start_angle``: link 3's
    rotation about h3 from the folded home pose at t = 0 (the folded pose itself has overlapping
    arms); ``revolutions`` after the ramp; ``joint_offsets``: ``"body"`` (paper, Exudyn) or
    ``"marker"`` (module docstring).
    """
    description = bennett_description(
        variant, h, order, n_modes, beta, omega, ramp_time, start_angle, gravity, exact_gravity, joint_offsets
    )
    scene = build_scene(description, where=f"Bennett {variant}")
    angle = next(j.angle for j in scene.joints if j.angle is not None)  # the drive the system runs with
    drive = angle.ramp
    material, alpha3 = VARIANTS[variant]
    settings = dict(
        scene.settings,
        variant=variant,
        h=h,
        order=order,
        n_modes=n_modes,
        beta=beta,
        omega=omega,
        ramp_time=ramp_time,
        start_angle=start_angle,
        revolutions=revolutions,
        gravity=list(description["scene"]["gravity"]),
        exact_gravity=exact_gravity,
        alpha3_deg=alpha3,
        material=material.name,
        joint_offsets=joint_offsets,
    )
    t_end = drive.time_for_angle(float(drive.angle(ramp_time)) + 2.0 * np.pi * revolutions)
    built = {f.name: getattr(scene, f.name) for f in fields(Scene)}
    return BennettScene(
        **dict(built, settings=settings),
        variant=variant,
        drive=drive,
        start_angle=start_angle,
        t_end=t_end,
        linkage=BennettLinkage(PAPER_A, PAPER_ALPHA),
    )
