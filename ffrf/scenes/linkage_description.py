r"""Any single-loop linkage of revolute joints as a scene description, nominal or as built.

:func:`linkage_description` turns a :class:`kinematics.SingleLoop` (from joint axes, a DH table or a
Rational Linkages mechanism) into the description that the one scene builder
(:mod:`ffrf.scenes.builder`) reads, the same format as scene files:

* link ``k`` (link 0 the base, carrying :math:`h_{n-1}` and :math:`h_0`; link ``k`` carrying
  :math:`h_{k-1}` and :math:`h_k`) is a parametric link (:func:`ffrf.geometry.link_geometry.build_link`)
  with a housing on each of its axes, meshed in the home pose; the base has a mounting block, clamped;
* joint ``i`` sits at one joint point on :math:`h_i`, the midpoint of the feet of the common normals
  to :math:`h_{i-1}` and :math:`h_{i+1}` (the two links' housings are stacked about it, and a link's
  arm is cranked where a DH offset :math:`d_i` is not zero);
* joint ``driver`` is driven by the paper's cosine ramp to ``omega``, the others are revolute; every
  body starts at its pose of the rigid motion at the drive's start angle (Eq. (L1), traced by
  :func:`kinematics.trace_motion`);
* as built: a :class:`BoreError` turns or moves one link's bore off the nominal axis; the link is
  meshed on its own axis, the joint's side on that link takes it, and the run starts from the
  static assembly that closes the misfit by continuation.

Joint sides: side 0 is link ``i`` and side 1 link ``i + 1``, except at the closing joint ``n - 1``,
whose side 0 is the base (as the paper's driven joint 3). A driven joint's prescribed angle is the
rotation of side 1 against side 0 (Eq. (J3)), which is :math:`\varphi_i` of Eq. (L1), or
:math:`-\varphi_{n-1}` at the closing joint.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ffrf.fe.materials import PLA, RIGID, Material
from ffrf.geometry.link_geometry import LinkDesign, arm_waypoints, trim_covering, trim_reach
from ffrf.system.drives import CosineRamp, rpm
from kinematics import Line, SingleLoop, common_normal, trace_motion
from kinematics.quaternion import matrix_to_quaternion

__all__ = [
    "BORE_ERROR_MODELS",
    "BORE_ERROR_FIELDS",
    "LINKAGE_VARIANTS",
    "TRACKED_FRACTIONS",
    "BoreError",
    "LinkageOptions",
    "bore_side",
    "drive_sign",
    "joint_points",
    "linkage_description",
    "seated_joint_points",
    "start_pose",
    "checked_tool_link",
    "with_radial_play",
]

#: Materials of the built-in linkage variants (as the paper's Bennett variants).
LINKAGE_VARIANTS: dict[str, Material] = {"rigid": RIGID, "pla": PLA}
#: How a bore error is built (:class:`LinkageOptions`): the as-built link remeshed, or a misfit on the nominal mesh.
BORE_ERROR_MODELS = ("remesh", "misfit")
#: Fractions along each moving link, from its first to its second joint point, of its tracked surface nodes.
TRACKED_FRACTIONS = (0.3, 0.5, 0.7)
#: Largest driver step (rad) when tracing the rigid motion to the start pose.
_TRACE_STEP = np.radians(2.0)


@dataclass(frozen=True)
class BoreError:
    """A bore made off its axis: joint ``joint``'s axis as link ``link`` carries it, turned by ``twist``
    (rad) about the link's common normal (which changes the link's DH twist by ``twist``), moved by
    ``offset`` (m) along that normal, away from the link's other axis (which changes its DH length), then
    tilted by ``tilt`` (rad) about the binormal (the axis crossed with the normal) through its joint point and
    moved by ``shift`` (m) along the binormal (the two errors that take the axes out of their DH relation), and
    its seat moved by ``axial`` (m) along the bore's own axis (which changes the joint's DH offset d): every
    change of a line, and where the bore sits on it. Or, with ``axis``, the bore on that line (as measured on a
    part), its joint point the nearest point of ``axis`` to the nominal one. (A turn of the bore about its own
    axis leaves the joint alone.)"""

    joint: int
    link: int
    twist: float = 0.0
    offset: float = 0.0
    axis: Line | None = None
    axial: float = 0.0
    tilt: float = 0.0
    shift: float = 0.0

    @classmethod
    def single(cls, joint: int, link: int, field: str, value: float) -> BoreError:
        """The bore error with ``value`` in one of its ``field`` (:data:`BORE_ERROR_FIELDS`), the others 0."""
        if field not in BORE_ERROR_FIELDS:
            raise ValueError(f"a bore error's field is one of {', '.join(BORE_ERROR_FIELDS)}, got {field!r}")
        values = {name: value if name == field else 0.0 for name in BORE_ERROR_FIELDS}
        return cls(
            joint,
            link,
            twist=values["twist"],
            offset=values["offset"],
            axial=values["axial"],
            tilt=values["tilt"],
            shift=values["shift"],
        )


#: The errors of a bore that :class:`BoreError` names: its turns (rad) and moves (m).
BORE_ERROR_FIELDS = ("twist", "offset", "axial", "tilt", "shift")


def _link_joints(k: int, n: int) -> tuple[int, int]:
    """The joints of link ``k``: its first axis h_{k-1} and its second axis h_k."""
    return (k - 1) % n, k


def joint_points(loop: SingleLoop) -> NDArray[np.float64]:
    """One point on each axis, ``(n, 3)``: the midpoint of the feet of the normals to its two neighbours."""
    n = loop.n
    points = np.empty((n, 3))
    for i, axis in enumerate(loop.axes):
        previous = common_normal(loop.axes[i - 1], axis).foot1
        following = common_normal(axis, loop.axes[(i + 1) % n]).foot0
        points[i] = 0.5 * (previous + following)
    return points


def seated_joint_points(loop: SingleLoop, attach_points: ArrayLike | None = None) -> NDArray[np.float64]:
    """Where each joint of the built linkage sits, ``(n, 3)``: :func:`joint_points`, or, with ``attach_points``
    ``(n, 2, 3)``, midway between the two links' attach points on its axis (the joints and the coupler point's
    sensor are placed there)."""
    return joint_points(loop) if attach_points is None else np.asarray(attach_points, dtype=float).mean(axis=1)


class _Side(NamedTuple):
    """One link's side of a joint: the bore's axis, the joint point on it, and the seat, the point from which
    the link's housing is placed (the joint point, unless the design attaches the link elsewhere on the axis)."""

    axis: Line
    point: NDArray
    seat: NDArray


def _erroneous_side(side: _Side, other: Line, error: BoreError) -> _Side:
    """``side`` (carried with ``other`` by one link) turned about their common normal and moved along it, or
    put on the measured ``error.axis``; then moved by ``error.axial`` along its axis."""
    if error.axis is not None:
        shift = error.axial * error.axis.direction
        return _Side(error.axis, error.axis.project(side.point) + shift, error.axis.project(side.seat) + shift)
    normal = common_normal(other, side.axis)
    direction = normal.unit
    if direction is None:
        raise ValueError(f"bore error on joint {error.joint} of link {error.link}: the link's two axes coincide")
    rotation = Rotation.from_rotvec(error.twist * direction).as_matrix()
    foot = normal.foot1
    axis = rotation @ side.axis.direction
    point, seat = (foot + rotation @ (x - foot) + error.offset * direction for x in (side.point, side.seat))
    if error.tilt or error.shift:
        binormal = np.cross(axis, direction)
        binormal /= np.linalg.norm(binormal)
        tilt = Rotation.from_rotvec(error.tilt * binormal).as_matrix()
        axis = tilt @ axis
        seat = point + tilt @ (seat - point) + error.shift * binormal
        point = point + error.shift * binormal
    point, seat = point + error.axial * axis, seat + error.axial * axis
    return _Side(Line.from_point_direction(point, axis), point, seat)


def _seats(loop: SingleLoop, attach: NDArray | None, design: LinkDesign) -> NDArray[np.float64] | None:
    """Seats ``(n, 2, 3)`` of the links at each joint (link i, link i+1) for housings centred on ``attach``."""
    if attach is None:
        return None
    attach = np.asarray(attach, dtype=float)
    if attach.shape != (loop.n, 2, 3):
        raise ValueError(f"attach_points must be (n, 2, 3) = ({loop.n}, 2, 3), got {attach.shape}")
    offset = design.housing_offset
    seats = np.empty_like(attach)
    for i, axis in enumerate(loop.axes):
        # Link i carries h_i as its second axis (housing at seat - s l), link i+1 as its first (seat + s l).
        seats[i, 0] = attach[i, 0] + offset * axis.direction
        seats[i, 1] = attach[i, 1] - offset * axis.direction
    return seats


def _trims(attach: NDArray | None, design: LinkDesign) -> NDArray[np.float64] | None:
    """Per joint the trimming's reach beyond both housings there ``(n,)``, m: enough to cover the other link's
    housing (:func:`~ffrf.geometry.link_geometry.trim_covering`); a scene names it only where it exceeds the
    default."""
    return (
        None
        if attach is None
        else np.array([trim_covering(float(np.linalg.norm(a[1] - a[0])), design) for a in attach])
    )


def _link_axes(
    loop: SingleLoop, points: NDArray, errors: tuple[BoreError, ...], seats: NDArray | None = None
) -> list[list[_Side]]:
    """Per link its two sides as built."""
    n = loop.n
    links = []
    for k in range(n):
        first, second = _link_joints(k, n)
        sides = [
            _Side(loop.axes[first], points[first], points[first] if seats is None else seats[first, 1]),
            _Side(loop.axes[second], points[second], points[second] if seats is None else seats[second, 0]),
        ]
        for error in errors:
            if error.link != k:
                continue
            if error.joint not in (first, second):
                raise ValueError(
                    f"bore error on joint {error.joint} of link {k}: link {k} carries joints {first} and {second}"
                )
            side = 0 if error.joint == first else 1
            sides[side] = _erroneous_side(sides[side], sides[1 - side].axis, error)
        links.append(sides)
    return links


def bore_side(loop: SingleLoop, options: LinkageOptions, error: BoreError) -> tuple[NDArray, NDArray]:
    """The axis direction and joint point of link ``error.link``'s side of joint ``error.joint`` as built with
    ``options``' bore errors and ``error`` (after them): what that side of the joint takes in the linkage's
    description (the misfit model's joint, :func:`linkage_description`)."""
    attach = None if options.attach_points is None else np.asarray(options.attach_points, dtype=float)
    points = seated_joint_points(loop, attach)
    links = _link_axes(loop, points, (*options.bore_errors, error), _seats(loop, attach, options.design))
    side = links[error.link][0 if error.joint == _link_joints(error.link, loop.n)[0] else 1]
    return np.array(side.axis.direction), np.array(side.point)


def _along(course: NDArray, fraction: float) -> NDArray[np.float64]:
    """The point ``fraction`` of the way along the polyline ``course`` (by length)."""
    lengths = np.linalg.norm(np.diff(course, axis=0), axis=1)
    target = fraction * float(lengths.sum())
    k = int(np.searchsorted(np.cumsum(lengths), target))
    k = min(k, len(lengths) - 1)
    before = float(np.sum(lengths[:k]))
    return course[k] + (target - before) / lengths[k] * (course[k + 1] - course[k])


def drive_sign(joint: int, n: int) -> float:
    """+1 when joint ``joint``'s prescribed angle is its rotation phi of Eq. (L1), -1 at the closing joint."""
    return -1.0 if joint == n - 1 else 1.0


def start_pose(loop: SingleLoop, driver: int, angle: float, origin: ArrayLike | None = None) -> NDArray[np.float64]:
    """Joint rotations of the rigid loop with the driver at ``angle`` (rad from home, Eq. (L4)), traced
    from ``origin`` (closing joint rotations; default home, which must then be a regular pose)."""
    phi = np.zeros(loop.n) if origin is None else loop.close(np.asarray(origin, dtype=float), driver)
    turn = angle - phi[driver]
    if turn == 0.0:
        return phi
    poses = int(np.ceil(abs(turn) / _TRACE_STEP)) + 1
    return trace_motion(loop, driver, n_poses=poses, revolution=turn, start=phi, endpoint=True).phi[-1]


def _joint_name(joint: int, driver: int) -> str:
    """The scene's name of joint ``joint``: the driven one says so."""
    return f"joint{joint} (drive)" if joint == driver else f"joint{joint}"


def _vector(x) -> list[float]:
    return [float(v) for v in x]


@dataclass(frozen=True)
class LinkageOptions:
    """How a loop becomes a flexible linkage and how it runs (SI units, angles in rad).

    ``driver``: the driven joint; ``start_angle``: its rotation from home (phi of Eq. (L1)) where the run
    starts, reached along the rigid motion from ``origin`` (closing joint rotations; default home: give a
    regular pose where home is singular, as for a loop folded flat); ``h``, ``order``, ``n_modes``: the
    links' tetrahedron edge (m), element order and fixed-interface modes; ``beta``: stiffness-proportional
    damping; ``omega``, ``ramp_time``, ``revolutions``: the cosine ramp to ``omega`` (rad/s) and the turns
    after it; ``bore_errors``: the as-built misfits; ``tool_link``: the link whose joint points' mean is
    the sensor ``coupler_point`` (default ``n // 2``, the coupler of a 4R); ``mode``, ``outputs``: of a
    scene-file run; ``exact_gravity``, ``joint_offsets``: the scene-file settings of the same names;
    ``attach_points`` ``(n, 2, 3)``: where on each joint's axis links i and i+1 attach (housings centred there,
    e.g. a Rational Linkages design, :func:`kinematics.rational_mechanism.attach_points`; default: both
    stacked about :func:`joint_points`); the joint point is then their midpoint. ``bore_error_model``: how a
    bore error is built, ``"remesh"`` (the link meshed on its erroneous bore, the as-built part) or ``"misfit"``
    (the nominal meshes, the error only in the joint's frame and point on that link's side: a joint-frame misfit
    closed by the assembly, the cheap model of studies, :data:`BORE_ERROR_MODELS`). ``design``: the parametric
    links' dimensions (arm section, housings; :class:`~ffrf.geometry.link_geometry.LinkDesign`). ``joint_play``: a
    scene file's ``clearance`` table (mm) for every passive joint (:mod:`ffrf.system.clearance_joint`), ``None``: ideal
    joints.
    """

    material: Material = PLA
    name: str = "linkage"
    driver: int = 0
    start_angle: float = 0.0
    origin: ArrayLike | None = None
    h: float = 6e-3
    order: int = 2
    n_modes: int = 4
    beta: float = 0.005
    omega: float = rpm(1.0)
    ramp_time: float = 1.0
    revolutions: float = 1.0
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    bore_errors: tuple[BoreError, ...] = ()
    tool_link: int | None = None
    mode: str = "quasi_static"
    outputs: int = 241
    exact_gravity: bool = True
    joint_offsets: str = "body"
    attach_points: ArrayLike | None = None
    bore_error_model: str = "remesh"
    design: LinkDesign = LinkDesign()
    joint_play: dict | None = None


def checked_tool_link(loop: SingleLoop, options: LinkageOptions) -> int:
    """The tool link of ``options`` (default ``n // 2``), after checking it and the driver against the loop."""
    n = loop.n
    if not 0 <= options.driver < n:
        raise ValueError(f"driver must be a joint index 0..{n - 1}, got {options.driver}")
    tool = n // 2 if options.tool_link is None else options.tool_link
    if not 0 < tool < n:
        raise ValueError(f"tool_link must be a moving link 1..{n - 1}, got {tool}")
    return tool


def with_radial_play(options: LinkageOptions, radial_mm: float) -> LinkageOptions:
    """``options`` with ``radial_mm`` of radial play in every passive joint (the rest of its ``joint_play`` kept;
    pins as long as the housings unless it says otherwise); ideal joints at zero."""
    if radial_mm == 0.0:
        return replace(options, joint_play=None)
    play = {"pin_length_mm": 1e3 * options.design.housing_length, **(options.joint_play or {})}
    return replace(options, joint_play=play | {"radial_mm": float(radial_mm)})


def linkage_description(
    loop: SingleLoop, options: LinkageOptions | None = None, start_phi: ArrayLike | None = None
) -> dict:
    """The loop as a scene description (module docstring), built as ``options`` say; ``start_phi``: the rigid
    loop's joint rotations at the start, when the caller has them (default :func:`start_pose` of ``options``)."""
    o = LinkageOptions() if options is None else options
    n = loop.n
    tool = checked_tool_link(loop, o)
    attach = None if o.attach_points is None else np.asarray(o.attach_points, dtype=float)
    points = seated_joint_points(loop, attach)
    if o.bore_error_model not in BORE_ERROR_MODELS:
        raise ValueError(f"bore_error_model must be one of {BORE_ERROR_MODELS}, got {o.bore_error_model!r}")
    seats = _seats(loop, attach, o.design)
    trims = _trims(attach, o.design)
    links = _link_axes(loop, points, tuple(o.bore_errors), seats)
    # The bodies are meshed on the built bores, or, for the misfit model, on the nominal ones; joints take `links`.
    meshed = links if o.bore_error_model == "remesh" else _link_axes(loop, points, (), seats)
    design = {} if o.design == LinkDesign() else asdict(o.design)  # a default design stays out of the scene
    phi = start_pose(loop, o.driver, o.start_angle, o.origin) if start_phi is None else np.asarray(start_phi)
    transforms = loop.link_transforms(phi)
    bodies, sensors = [], []
    for k, sides in enumerate(meshed):
        first, second = _link_joints(k, n)
        axes = [
            {
                "name": f"joint{j}",
                "point": _vector(line.point),
                "direction": _vector(line.direction),
                "joint_point": _vector(seat),
            }
            | ({} if trims is None or trims[j] <= trim_reach(o.design) else {"trim": float(trims[j])})
            for j, (line, _, seat) in zip((first, second), sides, strict=True)
        ]
        interfaces = (["mount"] if k == 0 else []) + [f"joint{first}", f"joint{second}"]
        bodies.append(
            {
                "name": f"link{k}",
                "parametric": {"axes": axes, "h": o.h, "mount": k == 0} | ({"design": design} if design else {}),
                "material": {"E": o.material.E, "nu": o.material.nu, "rho": o.material.rho, "name": o.material.name}
                | ({} if o.material.strength is None else {"strength": o.material.strength}),
                "order": o.order,
                "modes": o.n_modes,
                "interfaces": [{"name": i, "group": i} for i in interfaces],
                "pose": {
                    "position": _vector(transforms[k][:3, 3]),
                    "euler_parameters": _vector(matrix_to_quaternion(transforms[k][:3, :3])),
                },
            }
        )
        if k > 0:
            course = arm_waypoints([sides[0].seat, sides[1].seat], [sides[0].axis, sides[1].axis], o.design)
            sensors += [
                {"name": f"link{k}_node{j}", "body": f"link{k}", "point": _vector(_along(course, f)), "surface": True}
                for j, f in enumerate(TRACKED_FRACTIONS)
            ]
    joints: list[dict] = [
        {"name": "clamp", "type": "fixed", "body0": "ground", "body1": "link0", "interface1": "mount"}
    ]
    for i in range(n):
        near, far = i, (i + 1) % n  # h_i is the near link's second axis and the far link's first
        near_side = {"body": f"link{near}", "axis": links[near][1].axis.direction, "point": links[near][1].point}
        far_side = {"body": f"link{far}", "axis": links[far][0].axis.direction, "point": links[far][0].point}
        side0, side1 = (far_side, near_side) if i == n - 1 else (near_side, far_side)
        joint = {
            "name": _joint_name(i, o.driver),
            "type": "driven_revolute" if i == o.driver else "revolute",
            "body0": side0["body"],
            "interface0": f"joint{i}",
            "axis0": _vector(side0["axis"]),
            "point0": _vector(side0["point"]),
            "body1": side1["body"],
            "interface1": f"joint{i}",
            "axis1": _vector(side1["axis"]),
            "point1": _vector(side1["point"]),
        }
        if i == o.driver:
            joint["drive"] = {
                "omega": float(o.omega),
                "ramp_time": float(o.ramp_time),
                "start_angle": float(drive_sign(i, n) * phi[i]),
            }
        joints.append(joint)
    ramp = CosineRamp(o.omega, o.ramp_time)
    t_end = ramp.time_for_angle(float(ramp.angle(o.ramp_time)) + 2.0 * np.pi * o.revolutions)
    sensors.append(
        {
            "name": "coupler_point",
            "body": f"link{tool}",
            "joints": [_joint_name(j, o.driver) for j in _link_joints(tool, n)],
        }
    )
    settings = {
        "name": o.name,
        "gravity": _vector(o.gravity),
        "beta": float(o.beta),
        "static_start": True,
        "exact_gravity": bool(o.exact_gravity),
        "joint_offsets": o.joint_offsets,
        "mode": o.mode,
        "t_end": float(t_end),
        "outputs": int(o.outputs),
    } | ({} if o.joint_play is None else {"clearance": dict(o.joint_play)})
    return {"scene": settings, "bodies": bodies, "joints": joints, "sensors": sensors}
