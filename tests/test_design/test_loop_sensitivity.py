"""Exact derivatives by the loop's own DH parameters (Eqs. (D1), (D12), (D13), issue #35), on the PLA Bennett along
its family (a0, alpha0, alpha1 with the Bennett conditions kept) and on a 6R by its size (and by its sections): the
morph against rigid motion and the CAD's volumes, the ideal path's derivative against closed forms (the motion
polynomial; a scaled path), the path's derivatives against re-solved linkages on the morphed meshes and on remeshed
links, and the smallest clearance's rates against the clearance check re-run on changed linkages."""

import tomllib
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from ffrf.errors import SceneError
from ffrf.fe.materials import PLA
from ffrf.geometry.link_geometry import build_link
from ffrf.geometry.meshing import gmsh_session
from ffrf.mesh.tet_mesh import TetMesh
from ffrf.output.peak_stress import corner_stress
from ffrf.output.sensors import path_sensors
from ffrf.paper.bennett_scene import bennett_changes, bennett_options, build_bennett_from_options
from ffrf.scenes.builder import morphed_body, parametric_link
from ffrf.scenes.linkage_description import linkage_description, seated_joint_points
from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import LinkageScene, build_linkage, described_housings, joint_zones
from ffrf.scenes.path_sensitivity import (
    LoopChange,
    _basin,
    changed_linkage,
    loop_clearance_slopes,
    loop_sensitivity,
    loop_velocities,
    section_sensitivity,
    section_velocities,
    size_change,
)
from ffrf.solvers.stability import equilibrium_stability
from ffrf.solvers.static_solver import static_equilibrium
from kinematics import BennettLinkage

ROWS = [1, 3, 4]
EXAMPLES = Path(__file__).parents[2] / "examples"


def _options(h: float = 8e-3, order: int = 1, n_modes: int = 2):
    return replace(bennett_options("pla", h=h, order=order, n_modes=n_modes), material=PLA)


@pytest.fixture(scope="module")
def bennett():
    """The coarse PLA Bennett, a quasi-static stretch of its revolution, its loop changes and their morphs."""
    options = _options()
    scene = build_bennett_from_options(options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    changes = bennett_changes(options)
    velocities = loop_velocities(scene, changes)
    exact = loop_sensitivity(
        scene, result.time, result.q, result.multipliers, changes, velocities=velocities, stability=True, stress=True
    )
    return scene, result, changes, velocities, exact


def _rigid_fit(points: np.ndarray, velocity: np.ndarray) -> tuple[float, tuple[np.ndarray, np.ndarray]]:
    """The largest departure of ``velocity`` ``(k, 3)`` at ``points`` from the rigid velocity field ``w x p + v``
    closest to it (least squares), and that field's ``(w, v)``."""
    skew = np.zeros((len(points), 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = points[:, 2], -points[:, 1], points[:, 0]
    skew -= np.transpose(skew, (0, 2, 1))  # w x p = -[p]x w, [p]x the cross-product matrix of p
    matrix = np.concatenate([skew, np.broadcast_to(np.eye(3), skew.shape)], axis=2).reshape(-1, 6)
    solution, *_ = np.linalg.lstsq(matrix, velocity.ravel(), rcond=None)
    return float(np.abs(matrix @ solution - velocity.ravel()).max()), (solution[:3], solution[3:])


def test_a_link_the_change_only_carries_along_moves_rigidly_and_a_bore_with_its_housing(bennett):
    """alpha1 (= alpha3) is the twist of links 0 and 2 only: link 1 (on h0 and h1, which it does not move) stays where
    it is, link 3 keeps its shape and is carried along, so its velocity is a rigid motion's (to 1e-9 of it: the closed
    form of a rigid body's velocity field); on links 0 and 2, which change shape, each bore's nodes still move
    rigidly (the joints' interfaces)."""
    scene, _, changes, velocities, _ = bennett
    change = next(c for c in changes if c.name == "alpha1")
    assert np.abs(velocities[1, change.name]).max() == 0.0
    velocity = velocities[3, change.name]
    assert np.abs(velocity).max() > 1e-3
    assert _rigid_fit(scene.bodies[3].mesh_model.mesh.points, velocity)[0] < 1e-9 * np.abs(velocity).max()
    for k in (0, 2):
        velocity = velocities[k, change.name]
        points = scene.bodies[k].mesh_model.mesh.points
        assert _rigid_fit(points, velocity)[0] > 1e-3 * np.abs(velocity).max()  # its shape changes
        for interface in scene.bodies[k].interfaces.values():
            nodes = interface.nodes
            assert _rigid_fit(points[nodes], velocity[nodes])[0] < 1e-9 * np.abs(velocity).max()


@pytest.mark.parametrize("name", ["a0", "alpha0", "alpha1"])
def test_every_bore_follows_its_axis_in_the_changed_loop(bennett, name):
    """Each bore's nodes turn and move with the bore's axis and housing centre of the changed loop's description
    (central differences at +-1e-6 of the parameter, kinematics' DH chain and the stacking rule): the rate of the
    axis' direction and of the housing centre on it, within 1e-6 of the link's largest velocity (or of 1 m per unit
    of the parameter where the link stays)."""
    scene, _, changes, velocities, _ = bennett
    change = next(c for c in changes if c.name == name)
    delta = 1e-6 * abs(change.value)
    described = [linkage_description(*change.linkage(s))["bodies"] for s in (delta, -delta)]
    for k, body in enumerate(scene.bodies):
        points, velocity = body.mesh_model.mesh.points, velocities[k, name]
        offset = parametric_link(scene.description["bodies"][k]["parametric"])["design"].housing_offset
        for side, interface in enumerate(body.interfaces[f"joint{j}"] for j in ((k - 1) % 4, k)):
            _, (spin, shift) = _rigid_fit(points[interface.nodes], velocity[interface.nodes])
            axes = [parametric_link(d[k]["parametric"])[("axis_a", "axis_b")[side]] for d in described]
            joint_points = [np.asarray(parametric_link(d[k]["parametric"])["joint_points"][side]) for d in described]
            directions = [np.asarray(a[1]) / np.linalg.norm(a[1]) for a in axes]
            sign = 1.0 if side == 0 else -1.0
            centres = [p + sign * offset * d for p, d in zip(joint_points, directions, strict=True)]
            nominal = parametric_link(scene.description["bodies"][k]["parametric"])
            direction = np.asarray(nominal[("axis_a", "axis_b")[side]][1], dtype=float)
            direction /= np.linalg.norm(direction)
            centre = np.asarray(nominal["joint_points"][side]) + sign * offset * direction
            expected = np.concatenate([(directions[0] - directions[1]), (centres[0] - centres[1])]) / (2 * delta)
            ours = np.concatenate([np.cross(spin, direction), np.cross(spin, centre) + shift])
            np.testing.assert_allclose(ours, expected, rtol=0, atol=1e-6 * max(np.abs(velocity).max(), 1.0))


def _cad_volume(build: dict) -> float:
    with gmsh_session("volume") as gmsh:
        build_link(gmsh, **build)
        return sum(gmsh.model.occ.getMass(3, tag) for _, tag in gmsh.model.getEntities(3))


def test_the_morph_changes_a_links_volume_as_the_cad_solid_of_the_changed_loop(bennett):
    """Link 1 carries a0 (its arm's length): the volume of its mesh morphed along the velocity changes as
    OpenCASCADE's exact volume of the link built on the changed loop's axes, to the faceting of the housings'
    cylinders (measured 1.5e-5)."""
    scene, _, changes, velocities, _ = bennett
    name = "a0"
    change = next(c for c in changes if c.name == name)
    mesh = scene.bodies[1].mesh_model.mesh
    step = 1e-7
    morphed = [TetMesh(mesh.points + s * step * velocities[1, name], mesh.tets).volume for s in (1.0, -1.0)]
    ours = (morphed[0] - morphed[1]) / (2 * step)
    delta = 1e-6 * abs(change.value)
    cad = []
    for s in (delta, -delta):
        loop, options = change.linkage(s)
        cad.append(_cad_volume(parametric_link(linkage_description(loop, options)["bodies"][1]["parametric"])))
    exact = (cad[0] - cad[1]) / (2 * delta)
    assert exact > 1e-4  # m^3 per m: the arm lengthens
    assert abs(ours / exact - 1) < 1e-3


def test_the_ideal_paths_derivative_is_the_motion_polynomials(bennett):
    """The ideal coupler point's derivative by each free DH parameter at the run's drive angles against central
    differences of the closed-form motion polynomial of the Bennett linkages at +-1e-6 of it (kinematics'
    :class:`BennettLinkage`, acting on the changed linkage's coupler point at home), within 1e-6 of the largest."""
    scene, result, changes, _, exact = bennett
    assert exact.ideal_coupler_point is not None
    angles = np.array([scene.drive_angle(float(t)) for t in result.time])
    nominal = BennettLinkage.paper()
    for column, change in enumerate(changes):
        delta = 1e-6 * abs(change.value)
        sides = []
        for s in (delta, -delta):
            linkage = BennettLinkage.from_free(**(nominal.free | {change.name: nominal.free[change.name] + s}))
            loop, options = change.linkage(s)
            home = seated_joint_points(loop, options.attach_points)[[1, 2]].mean(axis=0)  # the coupler's joints
            t = linkage.parameter_from_joint(linkage.home_theta[3] - angles, joint=3)
            sides.append(linkage.coupler_pose(t).act(home))
        theirs = (sides[0] - sides[1]) / (2 * delta)
        ours = exact.ideal_coupler_point[:, :, column]
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-6 * np.abs(theirs).max())


@pytest.mark.parametrize("name", ["a0", "alpha0", "alpha1"])
def test_the_path_derivatives_agree_with_re_solved_linkages_on_the_morphed_meshes(bennett, name):
    """The derivatives of the coupler point, its deviation from the ideal path, the driving torque, the lowest
    squared frequency of Eq. (B1) and every link's peak stress by each free DH parameter against central differences
    (Richardson's rule over +-3e-4 and +-6e-4 of the parameter) of equilibria re-solved by Newton for the linkage of
    the changed loop on its meshes moved along their velocities: the same model, differentiated the long way. The
    coupler point and torque within 1e-6 of the largest derivative (measured 3e-11 to 9e-7), the deviation, a
    difference 1e-3 of the coupler point's change, within 1e-5 of its own (measured 3e-8 to 1.4e-6), the frequency
    within 1e-5 (its eigenvalue's round-off over the steps)."""
    scene, result, changes, velocities, exact = bennett
    column = [c.name for c in changes].index(name)
    change = changes[column]
    step = 3e-4 * abs(change.value)
    angles = np.array([scene.drive_angle(float(t)) for t in result.time[ROWS]])

    def outputs(s: float) -> dict:
        moved = changed_linkage(scene, change, s, velocities)
        solved = []
        for r in ROWS:
            first = static_equilibrium(moved.system, result.q[r], t=float(result.time[r]), tolerance=1e-13)
            solved.append(static_equilibrium(moved.system, first.q, t=float(result.time[r]), tolerance=1e-15))
        q = np.array([x.q for x in solved])
        out = path_sensors(moved, result.time[ROWS], q, np.array([x.multipliers for x in solved]))
        out["deviation"] = out["coupler_point"] - moved.ideal_coupler_points(angles)
        out["mu"] = np.array(
            [
                equilibrium_stability(moved.system, x.q, x.multipliers, float(result.time[r]), 1).squared_frequencies[0]
                for x, r in zip(solved, ROWS, strict=True)
            ]
        )
        out["peaks"] = np.array(
            [
                [
                    corner_stress(body.mesh_model, body.reduction.basis, x.q[moved.system.block(k)][7:], *corner)
                    for k, (body, corner) in enumerate(zip(moved.bodies, exact.peak_stress_corner[r], strict=True))
                ]
                for x, r in zip(solved, ROWS, strict=True)
            ]
        )
        return out

    near, far = ((outputs(s * step), outputs(-s * step)) for s in (1.0, 2.0))
    assert exact.lowest_squared_frequency is not None and exact.peak_stress_slopes is not None
    for key, ours, tolerance in (
        ("coupler_point", exact.coupler_point[ROWS, :, column], 1e-6),
        ("deviation", exact.deviation[ROWS, :, column], 1e-5),
        ("driving_torque", exact.driving_torque[ROWS, column], 1e-6),
        ("mu", exact.lowest_squared_frequency[ROWS, column], 1e-5),
        ("peaks", exact.peak_stress_slopes[ROWS, :, column], 1e-6),
    ):
        central = [
            (np.asarray(plus[key]) - np.asarray(minus[key])) / (2 * s * step)
            for s, (plus, minus) in ((1, near), (2, far))
        ]
        theirs = (4 * central[0] - central[1]) / 3
        print(name, key, np.abs(np.asarray(ours) - theirs).max() / np.abs(theirs).max())
        assert np.abs(theirs).max() > 0.0
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=tolerance * np.abs(theirs).max())


def test_a_changed_links_joint_zones_come_from_its_description_as_from_its_geometry(bennett):
    """A changed design's links are morphed meshes without CAD geometry: their joint zones come from the
    description's parametric tables, placed as the link builder places the housings; on the nominal design they are
    the zones from the built geometry, bit for bit."""
    scene = bennett[0]
    described = joint_zones(scene.loop, [described_housings(entry) for entry in scene.description["bodies"]])
    built = scene.joint_zones()
    assert described.keys() == built.keys()
    for key, zone in built.items():
        other = described[key]
        assert np.array_equal(zone.point, other.point) and np.array_equal(zone.direction, other.direction)
        assert (zone.radius, zone.lower, zone.upper) == (other.radius, other.lower, other.upper)


def test_the_basin_of_a_sampled_minimum_is_its_valley_and_a_flat_sequence_has_none():
    """The poses that hold a smallest besides the one found are the samples outside its basin: a smooth valley's
    samples all belong to it (the neighbours of a minimum between samples too), on a periodic sequence and from a
    start beside the minimum (a bisection's pose lands next to a sample); equal neighbours stop it (a constant
    clearance wiggling by microns holds its smallest at many poses)."""
    valley = np.cos(np.linspace(0.0, 2 * np.pi, 12, endpoint=False))  # one smooth minimum, at sample 6
    assert _basin(valley, 6).all() and _basin(valley, 5).all()
    shifted = np.roll(valley, 6)  # the minimum at sample 0: the valley wraps around
    assert _basin(shifted, 11).all()
    flat = np.array([1.0, 1.0, 1.0 + 1e-9, 1.0, 1.0])
    np.testing.assert_array_equal(_basin(flat, 0), [True, False, False, False, False])
    two = np.array([0.0, 1.0, 2.0, 1.0, 0.0, 1.0, 2.0, 1.0]) + np.array([0, 0, 0, 0, 1e-3, 0, 0, 0])
    np.testing.assert_array_equal(_basin(two, 1), [True, True, True, False, False, False, True, True])


def test_the_smallest_clearances_rates_agree_with_the_whole_check_re_run_on_changed_linkages(bennett):
    """Eq. (CL6): each pair's smallest clearance along the revolution (24 poses and the bisections of Eq. (CL4))
    against the whole check re-run on the changed linkages (their own motion, joint zones and morphed links, the
    smallest found again anywhere) at +-1e-4 of each parameter. The crossing pairs (0-2, 1-3) have one pose that
    holds the smallest: their derivative agrees with the central difference to 1e-6 of the column's largest
    (measured 3e-10, 5e-7, 4e-9). Adjacent links keep their clearance near the joint along the whole motion (to
    microns: the faceted surfaces), and a loop change tilts the surfaces differently at each pose, so their smallest
    clearance has one-sided rates only (Danskin's theorem over the poses that hold it): the forward difference is at
    least the right rate, the backward one at most the left rate (to 1e-4 of the largest: the truncation; measured
    at least 7e-9 inside), and the central difference lies between them."""
    scene, _, changes, velocities, _ = bennett
    found = scene.clearance(n_poses=24)
    assert np.all(found.distance > 0.0)  # apart: a pose holds each pair's smallest
    rates = loop_clearance_slopes(scene, found, changes, 24, velocities=velocities)
    crossing = np.array([list(pair) in ([0, 2], [1, 3]) for pair in found.pairs.tolist()])
    np.testing.assert_array_equal(rates.differentiable, crossing)
    assert np.all(rates.right[~crossing] < rates.left[~crossing])  # a kink, not a derivative
    for j, change in enumerate(changes):
        delta = 1e-4 * abs(change.value)
        plus, minus = (changed_linkage(scene, change, sign * delta, velocities).clearance(24) for sign in (1.0, -1.0))
        central = (plus.distance - minus.distance) / (2.0 * delta)
        forward, backward = (plus.distance - found.distance) / delta, (found.distance - minus.distance) / delta
        largest = np.abs(rates.at_smallest[:, j]).max()
        right, left, tolerance = rates.right[~crossing, j], rates.left[~crossing, j], 1e-4 * largest
        error = np.abs(rates.at_smallest[crossing, j] - central[crossing]).max() / largest
        inside = np.minimum(forward[~crossing] - right, left - backward[~crossing]).min() / largest
        print(change.name, "crossing pairs' error", error, "adjacent pairs' one-sided differences inside by", inside)
        np.testing.assert_allclose(rates.at_smallest[crossing, j], central[crossing], rtol=0, atol=1e-6 * largest)
        assert np.all(forward[~crossing] >= right - tolerance) and np.all(backward[~crossing] <= left + tolerance)
        assert np.all((central[~crossing] >= right - tolerance) & (central[~crossing] <= left + tolerance))


def test_a_change_that_is_not_the_scenes_design_is_refused(bennett):
    scene, _, changes, _, _ = bennett
    other = _options(h=10e-3)
    wrong = LoopChange("a0", changes[0].value, lambda s: (changes[0].linkage(s)[0], other))
    with pytest.raises(SceneError, match="is not this scene's"):
        loop_velocities(scene, (wrong,))


@pytest.fixture(scope="module")
def six_r():
    """Rational Linkages' collisions_free_6r (coarse, linear links, two modes) and a quasi-static stretch of its
    revolution."""
    document = tomllib.loads((EXAMPLES / "collisions_free_6r.toml").read_text())
    document["linkage"].update(h=8e-3, order=1, modes=2)
    loop, options, _ = linkage_options(document)
    scene = build_linkage(loop, options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    return loop, options, scene, result


def _re_solved(linkage: LinkageScene, result, angles: np.ndarray | None = None) -> dict:
    """The path sensors of ``linkage`` at ``result``'s rows :data:`ROWS`, each equilibrium re-solved by Newton from
    ``result``'s, and with ``angles`` (the drive angles of those rows) the deviation from its own ideal path."""
    solved = []
    for r in ROWS:
        first = static_equilibrium(linkage.system, result.q[r], t=float(result.time[r]), tolerance=1e-13)
        solved.append(static_equilibrium(linkage.system, first.q, t=float(result.time[r]), tolerance=1e-15))
    out = path_sensors(
        linkage, result.time[ROWS], np.array([x.q for x in solved]), np.array([x.multipliers for x in solved])
    )
    if angles is None:
        return out
    return out | {"deviation": out["coupler_point"] - linkage.ideal_coupler_points(angles)}


def _richardson(outputs: Callable[[float], dict], step: float, key: str) -> np.ndarray:
    """Richardson's rule on the central differences of ``outputs(s)[key]`` over +-step and +-2 step."""
    central = [(outputs(s * step)[key] - outputs(-s * step)[key]) / (2 * s * step) for s in (1.0, 2.0)]
    return (4 * central[0] - central[1]) / 3


def test_a_6r_s_section_derivatives_agree_with_re_solved_linkages_on_the_morphed_mesh(six_r):
    """Eq. (D5) on the 6R: the coupler point's and the driving torque's derivatives by a moving link's arm
    thickness and housing radius against equilibria re-solved for the linkage with that link on its mesh morphed by
    +-1e-3 and +-2e-3 of the dimension (Richardson), within 1e-6 of the largest derivative (measured 4e-11 to 6e-9)."""
    _, _, scene, result = six_r
    link = 3
    parameters = ("arm_thickness", "housing_outer_radius")
    velocities = section_velocities(scene, parameters, (link,))
    exact = section_sensitivity(
        scene, result.time, result.q, result.multipliers, parameters, (link,), velocities=velocities
    )
    design = parametric_link(scene.description["bodies"][link]["parametric"])["design"]
    points = scene.bodies[link].mesh_model.mesh.points
    for column, parameter in enumerate(parameters):
        velocity = velocities[link, parameter]

        def outputs(change: float, velocity: np.ndarray = velocity) -> dict:
            return _re_solved(scene.with_body(morphed_body(scene, link, points + change * velocity)), result)

        step = 1e-3 * getattr(design, parameter)
        for key, ours in (
            ("coupler_point", exact.coupler_point[ROWS, :, column]),
            ("driving_torque", exact.driving_torque[ROWS, column]),
        ):
            theirs = _richardson(outputs, step, key)
            print(parameter, key, np.abs(ours - theirs).max() / np.abs(theirs).max())
            assert np.abs(theirs).max() > 0.0
            np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-6 * np.abs(theirs).max())


def test_a_6r_grown_as_a_whole_moves_its_path_as_re_solved_linkages_and_its_ideal_path_scales(six_r):
    """Any loop's size (every length times 1 + s, the section kept: :func:`size_change`) on Rational Linkages'
    collisions_free_6r (coarse, linear links), a quasi-static stretch of its revolution: the ideal path's derivative
    is the ideal path itself (a similar loop, scaled about the origin: closed form, measured 1.2e-10), and against
    equilibria re-solved for the changed linkage on the morphed meshes (Richardson over +-3e-4, +-6e-4) the coupler
    point and torque agree within 1e-6 of the largest (measured 7e-10, 4e-10), the deviation within 1e-5 of its own
    (measured 5e-8). Its six links morph with faces on one plane (a housing's end face cut by the arm, a sliver) and
    nodes just beyond a cylinder face's parameter box, which the face matching must tell apart."""
    loop, options, scene, result = six_r
    change = size_change(loop, options)
    velocities = loop_velocities(scene, (change,))
    exact = loop_sensitivity(scene, result.time, result.q, result.multipliers, (change,), velocities=velocities)
    angles = np.array([scene.drive_angle(float(t)) for t in result.time])
    ideal = scene.ideal_coupler_points(angles)
    np.testing.assert_allclose(exact.ideal_coupler_point[:, :, 0], ideal, rtol=0, atol=1e-8 * np.abs(ideal).max())

    runs: dict[float, dict] = {}

    def outputs(s: float) -> dict:
        if s not in runs:
            runs[s] = _re_solved(changed_linkage(scene, change, s, velocities), result, angles[ROWS])
        return runs[s]

    for key, ours, tolerance in (
        ("coupler_point", exact.coupler_point[ROWS, :, 0], 1e-6),
        ("deviation", exact.deviation[ROWS, :, 0], 1e-5),
        ("driving_torque", exact.driving_torque[ROWS, 0], 1e-6),
    ):
        theirs = _richardson(outputs, 3e-4, key)
        print(key, np.abs(ours - theirs).max() / np.abs(theirs).max())
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=tolerance * np.abs(theirs).max())


@pytest.mark.slow
def test_the_path_derivatives_agree_with_remeshed_linkages_to_the_discretisation():
    """a0 (the loop's size: a1 follows), quadratic links at h = 8 mm: central differences of linkages built on the
    changed loop and remeshed at +-0.5 % of a0 agree with ours to 1 % of the largest for the coupler point, the
    driving torque and the mass (measured 0.002 %, 0.025 %, 0.82 %). Not the deviation: its change
    (1.7 um per mm of a0) is below what remeshing changes in it."""
    options = _options(8e-3, 2, 4)
    scene = build_bennett_from_options(options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end, sensors="path")
    change = bennett_changes(options)[0]
    exact = loop_sensitivity(scene, result.time, result.q, result.multipliers, (change,))
    assert exact.mass is not None
    delta = 5e-3 * change.value

    def remeshed(s: float) -> tuple[dict, float]:
        built = build_linkage(*change.linkage(s))
        solved = [static_equilibrium(built.system, result.q[r], t=float(result.time[r])) for r in ROWS]
        q, lam = np.array([x.q for x in solved]), np.array([x.multipliers for x in solved])
        return path_sensors(built, result.time[ROWS], q, lam), sum(b.moments.mass for b in built.system.bodies)

    (plus, mass_plus), (minus, mass_minus) = remeshed(delta), remeshed(-delta)
    for key, ours in (
        ("coupler_point", exact.coupler_point[ROWS, :, 0]),
        ("driving_torque", exact.driving_torque[ROWS, 0]),
    ):
        theirs = (plus[key] - minus[key]) / (2 * delta)
        print(key, np.abs(ours - theirs).max() / np.abs(theirs).max())
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-2 * np.abs(theirs).max())
    print("mass", (mass_plus - mass_minus) / (2 * delta) / exact.mass[0] - 1)
    assert abs((mass_plus - mass_minus) / (2 * delta) / exact.mass[0] - 1) < 1e-2
