"""Any single-loop linkage as a scene (ffrf.scenes.linkage_scene) against independent truth.

- the paper's Bennett scenes, nominal and misaligned: the paper's axes and its motion polynomial's poses;
- Rational Linkages' motion polynomial of its collision-free 6R, which a flexible model with stiff
  links must follow when nothing loads it.
"""

from __future__ import annotations

import numpy as np
import pytest

from ffrf.fe.materials import RIGID
from ffrf.output.sensors import scene_sensors
from ffrf.paper.axes import bennett_axes, paper_link_axes
from ffrf.paper.bennett_scene import VARIANTS, bennett_description
from ffrf.scenes.assembly import start_state
from ffrf.scenes.builder import build_scene
from ffrf.scenes.linkage_description import BoreError, LinkageOptions, drive_sign, joint_points, linkage_description
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.solvers.static_solver import quasi_static
from kinematics import BennettLinkage, SingleLoop
from kinematics.dual_quaternion import DualQuaternion
from kinematics.rational_mechanism import load_model, loop_from_mechanism, tool_link


def _numbers(value):
    """Every number in a nested description, in order (strings and names left out)."""
    if isinstance(value, dict):
        return [x for key in sorted(value) for x in _numbers(value[key])]
    if isinstance(value, list | tuple):
        return [x for item in value for x in _numbers(item)]
    if isinstance(value, bool | str) or value is None:
        return []
    return [float(value)]


@pytest.mark.parametrize("variant", ["pla", "pla1", "pla2"])
def test_bennett_descriptions_carry_the_papers_axes_and_the_motion_polynomials_poses(variant):
    """The paper's Bennett scenes are generic linkage descriptions; checked against the paper's own axes
    h0..h3 (kinematics.bennett, with the base's h3 of alpha_3 = 91, 92 deg: ffrf.geometry.joint_axes) and the
    link poses of the motion polynomial at the start (link 3 turned by 90 deg about h3)."""
    _, alpha3 = VARIANTS[variant]
    description = bennett_description(variant)
    for k, body in enumerate(description["bodies"]):
        first, second, names = paper_link_axes(k, bennett_axes(alpha3 if k == 0 else 90.0))
        axes = body["parametric"]["axes"]
        assert [a["name"] for a in axes] == list(names)
        for given, paper in zip(axes, (first, second), strict=True):
            assert np.max(np.abs(np.array(given["direction"]) - paper.direction)) < 1e-15
            offset = np.array(given["point"]) - paper.point
            assert np.linalg.norm(offset - (offset @ paper.direction) * paper.direction) < 1e-15
    linkage = BennettLinkage.paper()
    t = linkage.parameter_from_joint(linkage.home_theta[3] - np.radians(90.0), joint=3)
    for body, pose in zip(description["bodies"], linkage.link_poses(t), strict=True):
        unit = pose.normalized()
        assert np.max(np.abs(np.array(body["pose"]["position"]) - unit.translation_vector())) < 1e-14
        assert np.max(np.abs(np.array(body["pose"]["euler_parameters"]) - unit.primal)) < 1e-14


def test_bore_error_changes_the_dh_parameters_it_names():
    """A twist error of joint 1 on link 1 changes that link's DH twist alpha_0 by the error, an offset its length."""
    loop = loop_from_mechanism(load_model("collisions_free_6r"), scale=0.1)
    error = BoreError(joint=1, link=1, twist=np.radians(0.5), offset=2e-4)
    link1 = linkage_description(loop, LinkageOptions(bore_errors=(error,)))["bodies"][1]["parametric"]["axes"]
    built = SingleLoop.from_points_directions(
        [a["point"] for a in link1] + [p.point for p in loop.axes[2:]],
        [a["direction"] for a in link1] + [p.direction for p in loop.axes[2:]],
    ).dh()
    nominal = loop.dh()
    assert abs(built.alpha[0] - nominal.alpha[0] - np.radians(0.5)) < 1e-12
    assert abs(built.a[0] - nominal.a[0] - 2e-4) < 1e-12
    with pytest.raises(ValueError, match="link 1 carries joints 0 and 1"):
        linkage_description(loop, LinkageOptions(bore_errors=(BoreError(joint=3, link=1, twist=0.01),)))


def test_joint_points_lie_on_their_axes_between_the_feet_of_the_normals():
    loop = loop_from_mechanism(load_model("collisions_free_6r"), scale=0.1)
    points = joint_points(loop)
    for axis, point in zip(loop.axes, points, strict=True):
        assert axis.distance_to_point(point) < 1e-15


def _stiff_6r_against_rational_linkages(name: str, gravity: float, outputs: int) -> tuple[float, float]:
    """Largest distance (m) over ramp and one revolution between the coupler point (mean of link 3's joint points)
    of the model ``name`` at 1/10 scale with E = 1e15 Pa links and the point moved by C(t) of Rational Linkages,
    at the t of its own joint-angle map for the drive angle, and largest difference (rad) of the joint-angle
    sensors from the angles of C(t)'s factors (Eq. (L5)); from a regular start (plane_fold_6r is flat at home)."""
    from kinematics import wrap_angle
    from kinematics.rational_mechanism import factor_joint_angles, regular_start

    mechanism = load_model(name)
    loop = loop_from_mechanism(mechanism, scale=0.1)
    origin = regular_start(mechanism, loop)
    options = LinkageOptions(
        material=RIGID,
        h=12e-3,
        order=1,
        n_modes=2,
        gravity=(0.0, 0.0, gravity),
        start_angle=float(origin[0]),
        origin=origin,
    )
    scene = build_scene(linkage_description(loop, options), where=name)
    times = np.linspace(0.0, float(scene.settings["t_end"]), outputs)
    solution = quasi_static(scene.system, start_state(scene), times)
    sensors = scene_sensors(scene, times, solution.q, solution.multipliers)
    angles = np.column_stack([sensors[j.name + "_angle"] for j in scene.joints if j.name != "clamp"])
    drive = next(j.angle for j in scene.joints if j.angle is not None)
    tool = tool_link(mechanism)
    points = joint_points(loop)
    home_point = 0.5 * (points[tool - 1] + points[tool])
    first = mechanism.factorizations[0]
    signs = np.array([drive_sign(i, loop.n) for i in range(loop.n)])  # the closing joint's angle is -phi
    worst_point = worst_angle = 0.0
    for t, ours, joint_angles in zip(times, sensors["coupler_point"], angles, strict=True):
        phi0 = drive_sign(0, loop.n) * (drive.start + drive.ramp(t))
        parameter = first.joint_angle_to_t_param(float(np.mod(-phi0, 2.0 * np.pi)))  # Rational Linkages' map
        pose = DualQuaternion(np.asarray(mechanism.evaluate(parameter), dtype=float)).normalized()
        worst_point = max(worst_point, float(np.linalg.norm(ours - pose.act(home_point / 0.1) * 0.1)))
        expected = signs * factor_joint_angles(mechanism, parameter)
        worst_angle = max(worst_angle, float(np.max(np.abs(wrap_angle(joint_angles - expected)))))
    return worst_point, worst_angle


@pytest.mark.parametrize("name", ["collisions_free_6r", "plane_fold_6r"])
def test_stiff_6r_follows_the_motion_polynomial_of_rational_linkages(name):
    """Unloaded, the stiff model follows C(t) over a whole revolution, through plane_fold_6r's two flat-folded poses
    (measured 1.0e-14 m and 1.5e-14 m; with gravity the links' 1e-10 strain gives collisions_free_6r 3.3e-9 m),
    and its joint angles are those of C(t)'s factors (measured 1.2e-13 and 8.8e-14 rad)."""
    point, angle = _stiff_6r_against_rational_linkages(name, gravity=0.0, outputs=25)
    assert point < 1e-12 and angle < 1e-11


def test_stiff_plane_fold_6r_under_gravity_keeps_its_branch_through_the_flat_folds():
    """Under gravity, other equilibrium branches pass close to the motion at the flat-folded poses (first-order
    mobility 3 there: gravity acts on two freedoms that only the second order resists, measured 4.9e-5 m off C(t)
    at the fold). With 1.5 deg between outputs, Newton from the predicted state converged to one of them (0.18 m
    off C(t)) until steps whose correction exceeds half the predicted step were halved (Eq. (S4))."""
    assert _stiff_6r_against_rational_linkages("plane_fold_6r", gravity=-9.81, outputs=241)[0] < 1e-3


def test_a_planar_four_bar_from_parallel_axes_follows_its_closed_form():
    """Parallel axes (a planar loop, no unique common normal) build links at the joint points; the stiff,
    unloaded crank-rocker's coupler point (mean of the coupler's joints) is where the circles about the crank pin
    and the rocker's pivot meet (closed form), over a revolution of the crank (measured 8.0e-12 m)."""
    ground, crank, coupler, rocker = 0.4, 0.1, 0.35, 0.3
    start = np.radians(60.0)
    b0 = crank * np.array([np.cos(start), np.sin(start)])
    pivot = np.array([ground, 0.0])

    def coupler_rocker_joint(b: np.ndarray) -> np.ndarray:
        distance = float(np.linalg.norm(pivot - b))
        along = (coupler**2 - rocker**2 + distance**2) / (2 * distance)
        unit = (pivot - b) / distance
        return b + along * unit + np.sqrt(coupler**2 - along**2) * np.array([-unit[1], unit[0]])

    joints = np.array([[0.0, 0.0], b0, coupler_rocker_joint(b0), pivot])
    loop = SingleLoop.from_points_directions(np.column_stack([joints, np.zeros(4)]), np.tile([0.0, 0.0, 1.0], (4, 1)))
    scene = build_linkage(loop, LinkageOptions(material=RIGID, h=12e-3, order=1, n_modes=2, gravity=(0.0, 0.0, 0.0)))
    times = np.linspace(0.0, scene.t_end, 25)
    solution = quasi_static(scene.system, start_state(scene), times)
    ours = scene_sensors(scene, times, solution.q, solution.multipliers)["coupler_point"]
    z = joint_points(loop)[1:3, 2].mean()
    worst = 0.0
    for t, point in zip(times, ours, strict=True):
        b = crank * np.array([np.cos(start + scene.drive(t)), np.sin(start + scene.drive(t))])
        worst = max(worst, float(np.linalg.norm(point - np.append(0.5 * (b + coupler_rocker_joint(b)), z))))
    assert worst < 1e-9


def test_links_on_intersecting_axes_leave_their_housings_radially():
    """plane_fold_6r has all DH lengths a = 0 (intersecting axes, offsets d only): a straight arm would run along
    the axes through the neighbours' housings, so it leaves each housing by a radial stub. Every link meshes as
    one solid, and the tracked points lie on it (the builder refuses points farther than 10 % of the body)."""
    from kinematics.rational_mechanism import regular_start

    mechanism = load_model("plane_fold_6r")
    loop = loop_from_mechanism(mechanism, scale=0.1)
    assert np.max(loop.dh().a) < 1e-12
    origin = regular_start(mechanism, loop)
    description = linkage_description(
        loop, LinkageOptions(h=12e-3, order=1, n_modes=2, start_angle=float(origin[0]), origin=origin)
    )
    scene = build_scene(description, where="plane_fold_6r")
    assert len(scene.bodies) == 6 and len(scene.sensors) == 15
    assert np.abs(scene.system.constraint_values(scene.q_initial, 0.0)).max() < 1e-12  # assembled at the start


def test_rational_linkages_design_points_attach_each_link_where_its_own_link_api_says():
    """attach_points against Rational Linkages' MotionFactorization.link: link k of the first factorisation runs
    between the points our links k attach at on joints k-1 and k; every point lies on its joint's axis."""
    from kinematics.rational_mechanism import attach_points

    mechanism = load_model("collisions_free_6r")
    loop = loop_from_mechanism(mechanism, scale=1.0)
    attach = attach_points(mechanism)
    first = mechanism.factorizations[0]
    for k in (1, 2):
        _, start, end = first.link(k)
        np.testing.assert_allclose(attach[k - 1, 1], np.asarray(start.normalized_euclidean(), dtype=float), atol=1e-15)
        np.testing.assert_allclose(attach[k, 0], np.asarray(end.normalized_euclidean(), dtype=float), atol=1e-15)
    for axis, pair in zip(loop.axes, attach, strict=True):
        assert np.max(axis.distance_to_point(pair)) < 1e-12


@pytest.mark.slow  # 64 s: a comparison of two designs, not a check of ours
def test_the_models_own_design_keeps_more_links_apart_than_ours():
    """collisions_free_6r at 1/4 scale: with the links attached at the design's connection points, fewer pairs of
    links come closer than 1 mm along the motion (signed clearance, ffrf.output.clearance) than with the housings
    stacked at our joint points."""
    from kinematics.rational_mechanism import attach_points, regular_start

    mechanism = load_model("collisions_free_6r")
    loop = loop_from_mechanism(mechanism, scale=0.25)
    start = regular_start(mechanism, loop)
    common = dict(h=12e-3, order=1, n_modes=2, start_angle=float(start[0]), origin=start, tool_link=3)
    ours = build_linkage(loop, LinkageOptions(**common)).clearance()
    design = build_linkage(loop, LinkageOptions(**common, attach_points=attach_points(mechanism, 0.25))).clearance()
    assert np.sum(design.distance < 1e-3) < np.sum(ours.distance < 1e-3)


def test_a_stiff_goldberg_5r_follows_its_rigid_motion():
    """Goldberg's 5R (tests/kinematics_reference.py; its rigid motion equals the two Bennett linkages' closed form,
    tests/test_kinematics/test_goldberg_5r.py) as a flexible linkage with E = 1e15 Pa links and no load: the coupler
    point follows the rigid motion over ramp and revolution (measured 6.6e-15 m), and every joint closes."""
    from kinematics_reference import goldberg_5r

    from ffrf import load

    goldberg = goldberg_5r(0.1, np.radians(75.0), np.radians(45.0), np.radians(100.0), theta0=0.7)
    loop = SingleLoop.from_points_directions(goldberg.points, goldberg.directions)
    options = LinkageOptions(material=RIGID, h=12e-3, order=1, n_modes=2, gravity=(0.0, 0.0, 0.0))
    summary = load(build_linkage(loop, options)).run(mode="quasi_static", outputs=25).summary()
    assert summary["max_coupler_deviation_m"] < 1e-12 and summary["max_constraint_residual"] < 1e-10
