r"""The flexible Bennett linkage of the paper (Sect. "Simulation Setup"), built from its DH table.

The paper's linkage is one single-loop linkage among others: :func:`bennett_description` is
:func:`ffrf.scenes.linkage_description.linkage_description` of the paper's axes (four parametric links
meshed with gmsh and assembled with scikit-fem, reduced with Craig-Bampton, joined by ideal revolute
joints on rigid bore markers, the base clamped at its mounting face) with joint 3 (between link 3 and
the base) driven by the paper's cosine ramp, and the misaligned variants as a bore error of joint 3 on
the base. Link numbering and axes follow :mod:`kinematics.bennett`; :class:`BennettScene` adds the
motion polynomial, which gives the ideal coupler path in closed form.

Every body's frame coincides with the world frame in the home configuration (the meshes
are built there); the simulation starts from the ideal configuration at ``start_angle``
of the driver, where link ``k`` is displaced by the motion polynomial's pose of link ``k``.
Misaligned variants (base twist 91 or 92 deg: the base's joint-3 bore turned by 1 or 2 deg about the
base's common normal) cannot be assembled rigidly: the base's joint-3 frame is turned from the nominal
axis to its own bore axis in small steps of a static solution (:func:`ffrf.scenes.assembly.assemble`),
and the assembly stresses remain in the links.

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

from collections.abc import Callable
from dataclasses import dataclass, fields, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.fe.materials import PLA, RIGID, Material
from ffrf.output.path_distance import ExactCurve
from ffrf.scenes.assembly import assemble
from ffrf.scenes.collision_free import Stacking
from ffrf.scenes.linkage_description import BoreError, LinkageOptions, linkage_description
from ffrf.scenes.linkage_scene import LinkageScene, build_linkage
from ffrf.scenes.path_sensitivity import LoopChange
from ffrf.scenes.scene_cache import SceneCache
from ffrf.studies.spec import NamedBases
from ffrf.system.drives import rpm
from ffrf.system.markers import JOINT_OFFSETS
from ffrf.system.multibody import MultibodySystem
from kinematics import PAPER_A, PAPER_ALPHA, BennettLinkage, SingleLoop

__all__ = [
    "VARIANTS",
    "PAPER_MAX_COUPLER_DEVIATION_MM",
    "paper_max_coupler_deviation",
    "BennettScene",
    "bennett_changes",
    "bennett_description",
    "bennett_options",
    "build_bennett",
    "build_bennett_from_options",
    "STUDY_BASES",
    "COLLISION_FREE_STACKING",
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


#: Where the links' housings sit along the paper's axes so that every two links keep 1 mm (capsule proxy, along a
#: revolution from the start): :func:`ffrf.scenes.collision_free.design_stacking` of the nominal loop, driver 3,
#: 1441 poses, rounded to 0.1 mm, as it was with one capsule about each arm's whole section; today's tighter proxy
#: lets it find thinner spacers (0.5 to 2.9 mm), but this one is kept: the default scene and every figure recorded
#: on it stay as they are (``tests/test_collision_free/test_stacking.py`` checks the margin on the proxy and on the
#: meshed solids). Links 1 and 3 lie outside at both their joints (orders +1, -1, +1, -1).
COLLISION_FREE_STACKING = Stacking(
    offsets=(-27.7e-3, -32.4e-3, -38.3e-3, -26.8e-3), spacers=(3.9e-3, 10.1e-3, 6.9e-3, 4.1e-3), orders=(1, -1, 1, -1)
)


def paper_max_coupler_deviation(variant: str) -> str:
    """The paper's maximum coupler deviation of ``variant`` as its table states it, in mm
    (``"< 0.001"`` for the rigid bound, ``"0.211"`` ...); ``""`` for a variant the paper has not."""
    value = PAPER_MAX_COUPLER_DEVIATION_MM.get(variant)
    if value is None:
        return ""
    return f"< {value}" if variant == "rigid" else f"{value}"


@dataclass(frozen=True, eq=False)
class BennettScene(LinkageScene):
    """The paper's scene: a built :class:`~ffrf.scenes.linkage_scene.LinkageScene` (as built: full
    misalignment) with the variant and the ideal Bennett linkage, whose motion polynomial gives the
    ideal coupler path. ``settings`` holds the scene's settings and the arguments of :func:`build_bennett`."""

    variant: str
    linkage: BennettLinkage

    @property
    def q_start(self) -> NDArray[np.float64]:
        """Link poses of the ideal linkage at the drive's start angle, undeformed."""
        return self.q_initial

    def with_misalignment(self, fraction: float) -> MultibodySystem:
        """The system with the base's joint-3 frame turned, and its joint point moved, by
        ``fraction`` of the misalignment (0: link 3's nominal axis, 1: the base's own bore axis)."""
        return self.with_misfit(fraction)

    def ideal_coupler_points(self, drive_angles: ArrayLike) -> NDArray[np.float64]:
        """Coupler point of the ideal linkage at the given drive angles, from the motion polynomial acting on the
        scene's coupler point at home (the common normal's midpoint of the coupler's axes, unless the links attach
        elsewhere on them)."""
        angles = np.asarray(drive_angles, dtype=float)
        home = self.home_coupler_point()

        def points() -> NDArray[np.float64]:
            linkage = self.linkage
            t = linkage.parameter_from_joint(linkage.home_theta[3] - angles, joint=3)
            return linkage.coupler_pose(t).act(home)

        return self._kept(("motion polynomial", self.linkage.a, self.linkage.alpha), angles, points)

    def ideal_coupler_curve(self, n: int = 4000) -> NDArray[np.float64]:
        """``n`` points of the ideal coupler curve over one revolution from the start (motion polynomial)."""
        return self.ideal_coupler_points(self.start_angle + np.linspace(0.0, 2 * np.pi, n, endpoint=False))

    def ideal_coupler_exact(self, n: int = 720) -> ExactCurve:
        """The ideal coupler curve over one revolution from the start, ``n`` samples and the motion polynomial at
        any drive angle between them (for :func:`ffrf.output.path_distance.distance_to_curve`)."""
        linkage = self.linkage
        point = self.home_coupler_point()

        def exact(angles: NDArray[np.float64], arcs: NDArray[np.int64]) -> NDArray[np.float64]:
            t = linkage.parameter_from_joint(linkage.home_theta[3] - angles, joint=3)
            return linkage.coupler_pose(t).act(point)

        angles = self.start_angle + np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        return ExactCurve(angles, self.ideal_coupler_points(angles), 2 * np.pi, exact)


def _bore_errors(variant: str) -> tuple[BoreError, ...]:
    """The variant's misalignment: joint 3's bore on the base turned by alpha_3 - 90 deg."""
    _, alpha3 = VARIANTS[variant]
    return (BoreError(joint=3, link=0, twist=np.radians(alpha3 - 90.0)),) if alpha3 != 90.0 else ()


def bennett_options(
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
    collision_free: bool = True,
) -> LinkageOptions:
    """The paper's scene ``variant`` (``rigid``, ``pla``, ``pla1``, ``pla2``) as linkage options: joint 3
    driven (side 0 the base, side 1 link 3), the coupler link 2, the base's h3 misaligned by alpha_3 - 90 deg.

    ``h``: maximum tetrahedron edge (m; paper 2 mm); ``order``: 1 (linear, the paper's) or 2
    (quadratic) tetrahedra; ``n_modes``: fixed-interface modes per link (paper 32). The defaults
    are the cheapest discretisation that puts the coupler path within 0.01 mm of the converged one
    (the rule and its measurements: ``docs/speed_vs_error.md``); ``start_angle``: link 3's
    rotation about h3 from the folded home pose at t = 0 (the folded pose itself has overlapping
    arms); ``revolutions`` after the ramp; ``joint_offsets``: ``"body"`` (paper, Exudyn) or
    ``"marker"`` (module docstring); ``collision_free``: the links' housings placed along the axes by
    :data:`COLLISION_FREE_STACKING` (every two links 1 mm apart along the revolution; the default), or, when False,
    centred on the joint points (links that pass through each other, as every release before the clearance check).
    """
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r}; choose one of {sorted(VARIANTS)}")
    if joint_offsets not in JOINT_OFFSETS:
        raise ValueError(f"joint_offsets must be one of {JOINT_OFFSETS}, got {joint_offsets!r}")
    return LinkageOptions(
        material=VARIANTS[variant][0],
        name=f"Bennett {variant}",
        driver=3,
        start_angle=-start_angle,  # the drive turns link 3 against the base: phi_3 = -angle (Eq. (L1))
        h=h,
        order=order,
        n_modes=n_modes,
        beta=beta,
        omega=omega,
        ramp_time=ramp_time,
        revolutions=revolutions,
        gravity=(float(gravity[0]), float(gravity[1]), float(gravity[2])),
        bore_errors=_bore_errors(variant),
        tool_link=2,
        exact_gravity=exact_gravity,
        joint_offsets=joint_offsets,
        attach_points=COLLISION_FREE_STACKING.attach_points(_paper_loop()) if collision_free else None,
    )


def _paper_loop() -> SingleLoop:
    return SingleLoop(BennettLinkage(PAPER_A, PAPER_ALPHA).axes)


def bennett_description(variant: str = "pla", **options) -> dict:
    """The paper's scene ``variant`` as a scene description (the format of scene files): four parametric
    links, the base clamped at its mounting face, revolute joints 0..2 and joint 3 driven by the cosine
    ramp, each joint side on its own link's axis, link poses of the ideal linkage at the start, three
    tracked nodes per moving link and the coupler point. ``options``: those of :func:`bennett_options`."""
    return linkage_description(_paper_loop(), bennett_options(variant, **options))


def build_bennett(variant: str = "pla", **options) -> BennettScene:
    """Build the paper's scene ``variant`` with the one scene builder; ``options``: those of
    :func:`bennett_options` (discretisation, drive, start, gravity, joint offsets)."""
    return build_bennett_from_options(bennett_options(variant, **options), variant)


def build_bennett_from_options(
    options: LinkageOptions, variant: str = "pla", cache: SceneCache | None = None
) -> BennettScene:
    """The paper's loop built with any linkage ``options`` (e.g. :func:`bennett_options` of ``variant`` with other
    bore errors or material, as a study varies them), compared with the motion polynomial; ``cache``: the
    content-keyed :class:`~ffrf.scenes.scene_cache.SceneCache` (:func:`ffrf.scenes.linkage_scene.build_linkage`)."""
    scene = build_linkage(_paper_loop(), options, cache=cache)
    settings = dict(
        scene.settings,
        variant=variant,
        beta=options.beta,
        start_angle=-options.start_angle,
        gravity=list(options.gravity),
        exact_gravity=options.exact_gravity,
        alpha3_deg=VARIANTS[variant][1],
        joint_offsets=options.joint_offsets,
    )
    built = {f.name: getattr(scene, f.name) for f in fields(LinkageScene)}
    return BennettScene(**dict(built, settings=settings), variant=variant, linkage=BennettLinkage(PAPER_A, PAPER_ALPHA))


def bennett_changes(
    options: LinkageOptions, stacking: Stacking | None = COLLISION_FREE_STACKING, linkage: BennettLinkage | None = None
) -> tuple[LoopChange, ...]:
    """The free DH parameters of the Bennett ``linkage`` (default the paper's; :data:`kinematics.BENNETT_PARAMETERS`:
    a0, alpha0, alpha1, the others kept by the Bennett conditions) as changes of the linkage built from it with
    ``options`` (:func:`ffrf.scenes.path_sensitivity.loop_sensitivity`): the housings stacked on the changed axes by
    ``stacking`` as :func:`bennett_options` stacks them (``None``: centred on the joint points)."""
    nominal = BennettLinkage(PAPER_A, PAPER_ALPHA) if linkage is None else linkage
    free = nominal.free

    def changed(name: str) -> Callable[[float], tuple[SingleLoop, LinkageOptions]]:
        def linkage_at(s: float) -> tuple[SingleLoop, LinkageOptions]:
            moved = nominal if s == 0.0 else BennettLinkage.from_free(**(free | {name: free[name] + s}))
            loop = SingleLoop(moved.axes)
            return loop, replace(options, attach_points=None if stacking is None else stacking.attach_points(loop))

        return linkage_at

    return tuple(LoopChange(name, value, changed(name)) for name, value in free.items())


#: The paper's variants as a study's named bases: ``[base] bennett = "pla"`` (:mod:`ffrf.studies.spec`).
STUDY_BASES = NamedBases("bennett", tuple(VARIANTS), 4, bennett_options, build_bennett_from_options)
