"""The one scene builder (``ffrf.scenes.builder``): start poses, as-built joints closed by the
assembly continuation, parametric links on two axes, and the paper's Bennett scenes as plain scene descriptions.

Truth is independent of the builder: a rotated start pose with rotated gravity must give the rotated
motion (the equations are frame-invariant), and a body held by one fixed joint whose two sides
disagree must end up rigidly moved onto the ground's frame and point, without strain energy."""

import json

import numpy as np
from scene_fixtures import PENDULUM, write_bar
from scipy.spatial.transform import Rotation

from ffrf import load
from ffrf.paper.bennett_scene import VARIANTS, bennett_description
from ffrf.scenes.assembly import assemble
from ffrf.scenes.builder import build_scene
from ffrf.scenes.scene_file import load_scene, sensor_arrays
from ffrf.scenes.scene_schema import check_scene
from ffrf.system.joints import frame_from_axis


def _pendulum_tip(tmp_path, name: str, text: str):
    (tmp_path / name).write_text(text)
    scene = load_scene(tmp_path / name)
    run = load(scene).run()
    assert run.multipliers is not None  # a dynamic run keeps its multipliers
    return scene, sensor_arrays(scene, run.q, run.multipliers)["tip"]


def test_a_rotated_start_pose_with_rotated_gravity_gives_the_rotated_motion(tmp_path):
    write_bar(tmp_path)
    scene, tip = _pendulum_tip(tmp_path, "plain.toml", PENDULUM)
    hinge = scene.bodies[0].markers["hinge"].point  # the joint point (mesh coordinates)
    turn = Rotation.from_rotvec([0.0, 0.7, 0.0])  # about the hinge axis y, through the hinge point
    rotation = turn.as_matrix()
    euler = np.roll(turn.as_quat(), 1).tolist()  # scalar first
    position = hinge - rotation @ hinge
    gravity = rotation @ np.array([0.0, 0.0, -9.81])
    posed = PENDULUM.replace("gravity = [0.0, 0.0, -9.81]", f"gravity = {gravity.tolist()}").replace(
        "modes = 3\n",
        f"modes = 3\npose = {{position = {position.tolist()}, euler_parameters = {euler}}}\n",
    )
    _, tip_posed = _pendulum_tip(tmp_path, "posed.toml", posed)
    expected = hinge + (tip - hinge) @ rotation.T
    swing = np.abs(tip - tip[0]).max()
    assert swing > 0.01  # the pendulum does swing
    np.testing.assert_allclose(tip_posed, expected, rtol=0, atol=5e-12)  # measured 4.4e-14 m


FIXED_WITH_MISFIT = """
[scene]
gravity = [0.0, 0.0, 0.0]
[[bodies]]
name = "bar"
mesh = "bar.vtu"
unit = "mm"
material = {E = 1e8, nu = 0.3, rho = 450.0}
order = 1
modes = 3
interfaces = [{name = "hinge", nodes_file = "hinge.txt"}]
[[joints]]
name = "mount"
type = "fixed"
body0 = "ground"
body1 = "bar"
interface1 = "hinge"
axis0 = AXIS0
point0 = POINT0
axis1 = [0.0, 1.0, 0.0]
point1 = POINT1
[[sensors]]
name = "tip"
body = "bar"
point = [0.2, 0.0, 0.0]
"""


def test_a_fixed_joint_with_misfit_moves_the_body_rigidly_onto_the_ground_frame(tmp_path):
    """Side 0 (ground) is tilted by 3 deg and shifted by 2 mm against side 1 (the bar's bore): one
    joint, so the assembly is a rigid motion, by the rotation that takes the bar's joint frame onto
    the ground's, without strain."""
    write_bar(tmp_path)
    axis0 = Rotation.from_rotvec(np.radians(3.0) * np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)).apply([0.0, 1.0, 0.0])
    origin = "[0.0, 0.0, 0.0]"
    aligned = FIXED_WITH_MISFIT.replace("AXIS0", "[0.0, 1.0, 0.0]").replace("POINT0", origin)
    hinge = load_scene_text(tmp_path, aligned.replace("POINT1", origin)).bodies[0].markers["hinge"].point
    point0 = hinge + np.array([0.0, 0.0, 2e-3])
    text = FIXED_WITH_MISFIT.replace("AXIS0", str(axis0.tolist())).replace("POINT0", str(point0.tolist()))
    scene = load_scene_text(tmp_path, text.replace("POINT1", str(hinge.tolist())))
    assert abs(scene.misfit_degrees - 3.0) < 1e-12
    solution = assemble(scene)
    q = solution.q
    # The rotation Q with Q J1 = J0 for the two joint frames of the builder's convention.
    frame1 = frame_from_axis([0.0, 1.0, 0.0])
    frame0 = frame_from_axis(axis0, frame1[:, 0])
    rotation = frame0 @ frame1.T
    tip_mesh = scene.bodies[0].fe.nodes[scene.sensors["tip"][1]]
    expected = point0 + rotation @ (tip_mesh - hinge)
    tip = sensor_arrays(scene, q[None], solution.multipliers[None])["tip"][0]
    np.testing.assert_allclose(tip, expected, rtol=0, atol=2e-12)  # measured 1.4e-14 m
    assert scene.system.energies(q, np.zeros_like(q))["strain"] < 1e-14
    assert np.abs(scene.system.constraint_values(q, 0.0)).max() < 1e-12


def load_scene_text(tmp_path, text: str):
    (tmp_path / "scene.toml").write_text(text)
    return load_scene(tmp_path / "scene.toml")


def test_bennett_scenes_are_plain_scene_descriptions():
    """Every Bennett variant is data in the scene-file format (JSON round trip unchanged, accepted
    by the scene schema), with the base's h3 misaligned by alpha_3 - 90 deg against link 3's."""
    for variant, (_, alpha3) in VARIANTS.items():
        description = bennett_description(variant)
        assert json.loads(json.dumps(description)) == description
        check_scene(description, variant)
        drive = [j for j in description["joints"] if j["type"] == "driven_revolute"]
        assert len(drive) == 1
        a, b = (np.array(drive[0][f"axis{s}"]) for s in "01")
        angle = np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b))
        assert abs(angle - abs(alpha3 - 90.0)) < 1e-9


def test_a_bennett_description_builds_like_a_file(tmp_path):
    """The builder takes the Bennett description as it takes a file (coarse links): closed at the
    start pose up to the base's misalignment, which the assembly closes."""
    description = bennett_description("pla1", h=0.012, n_modes=2)
    scene = build_scene(description, where="pla1 coarse")
    assert np.abs(scene.with_misfit(0.0).constraint_values(scene.q_initial, 0.0)).max() < 1e-12
    assert np.abs(scene.system.constraint_values(scene.q_initial, 0.0)).max() > 1e-4  # 1 deg misfit
    q = assemble(scene).q
    assert np.abs(scene.system.constraint_values(q, 0.0)).max() < 1e-10
    assert scene.system.energies(q, np.zeros_like(q))["strain"] > 0.0  # the misfit stays in the links


def test_a_run_with_misfit_writes_its_assembly_and_every_sensor(tmp_path):
    """``python -m ffrf run`` on the fixed joint with misfit: the assembly is a rigid motion, so the
    assembly report shows no strain and no reaction (no gravity), and the results hold the joint's
    sensors and the coordinates."""
    from ffrf.cli import main

    write_bar(tmp_path)
    axis0 = Rotation.from_rotvec(np.radians(2.0) * np.array([1.0, 0.0, 0.0])).apply([0.0, 1.0, 0.0])
    text = FIXED_WITH_MISFIT.replace("AXIS0", str(axis0.tolist())).replace("POINT0", "[0.0, 0.0, 0.001]")
    text = text.replace("POINT1", "[0.0, 0.0, 0.0]").replace("[scene]\n", "[scene]\nt_end = 0.01\nstep = 1e-3\n")
    (tmp_path / "misfit.toml").write_text(text)
    assert main(["run", str(tmp_path / "misfit.toml"), "--out", str(tmp_path / "out")]) == 0
    metadata = json.loads((tmp_path / "out" / "metadata.json").read_text())
    assert (tmp_path / "out" / "assembly.vtu").is_file()
    assert metadata["assembly"]["strain_energy_j"] < 1e-14
    data = np.load(tmp_path / "out" / "results.npz")
    assert data["q"].shape == (len(data["time"]), metadata["n_coordinates"])
    assert np.abs(data["mount_reaction"]).max() < 1e-9  # measured 9e-11 N (Newton tolerance)
    assert data["constraint_residual"].max() < 5e-12  # measured 4.9e-14
    np.testing.assert_allclose(data["mount_point1"], data["mount_point0"], rtol=0, atol=1e-12)


def _axes_link(first, second, names, joint_points=None) -> dict:
    axes = []
    for k, (axis, name) in enumerate(zip((first, second), names, strict=True)):
        entry = {"name": name, "point": axis.point.tolist(), "direction": axis.direction.tolist()}
        if joint_points is not None:
            entry["joint_point"] = [float(v) for v in joint_points[k]]
        axes.append(entry)
    return {
        "name": "link",
        "parametric": {"axes": axes, "h": 0.012},
        "material": {"E": 1.2e9, "nu": 0.33, "rho": 450.0},
        "order": 1,
        "modes": 2,
        "interfaces": [{"name": n, "group": n} for n in names],
    }


def test_a_cranked_link_puts_its_housings_at_the_given_joint_points():
    """DH offsets d != 0: the joint point on each axis is given, 15 mm from the common normal's foot;
    each bore (interface) centre lies on its axis, the housing offset s from its joint point."""
    from ffrf.geometry.joint_axes import common_normal_feet
    from ffrf.geometry.link_geometry import LinkDesign
    from ffrf.paper.axes import paper_link_axes

    first, second, names = paper_link_axes(2)
    feet = common_normal_feet(first, second)
    points = np.array([feet[0] - 0.015 * first.direction, feet[1] + 0.015 * second.direction])
    body = build_scene({"bodies": [_axes_link(first, second, names, points)]}).bodies[0]
    s = LinkDesign().housing_offset
    np.testing.assert_allclose(body.geometry.joint_points, points, rtol=0, atol=1e-15)
    for k, (axis, name, sign) in enumerate(zip((first, second), names, (1.0, -1.0), strict=True)):
        centre = body.markers[name].point
        # the bore's area-weighted centre: its faceting at h = 12 mm moves it by 1.4e-5 m (measured)
        np.testing.assert_allclose(centre, points[k] + sign * s * axis.direction, rtol=0, atol=1e-4)


def test_a_joint_point_sensor_of_a_hinge_stays_on_the_ground(tmp_path):
    """A sensor on the hinge's joint point (the pendulum's side) moves with the bar but must stay at
    the ground's hinge point while the bar swings: the constraint, seen by the sensor."""
    write_bar(tmp_path)
    text = PENDULUM + '\n[[sensors]]\nname = "pin"\nbody = "bar"\njoints = ["hinge"]\n'
    (tmp_path / "pin.toml").write_text(text)
    scene = load_scene(tmp_path / "pin.toml")
    run = load(scene).run()
    from ffrf.output.sensors import scene_sensors

    sensors = scene_sensors(scene, run.time, run.q, run.multipliers, run.qd)
    hinge = scene.bodies[0].markers["hinge"].point
    assert np.abs(sensors["tip"] - sensors["tip"][0]).max() > 0.01  # the bar swings
    np.testing.assert_allclose(
        sensors["pin"], np.broadcast_to(hinge, sensors["pin"].shape), rtol=0, atol=2e-15
    )  # measured 1.9e-17 m


def test_a_bore_found_from_its_axis_is_the_meshed_bore():
    """``axis = {point, direction}`` finds the same bore as the mesher's named group: same nodes, same
    area weights (the selection is independent: radii and extents of the boundary vertices)."""
    from ffrf.paper.axes import bennett_axes, paper_link_axes

    first, second, names = paper_link_axes(1, bennett_axes(90.0))
    by_group = _axes_link(first, second, names)
    by_axis = dict(
        by_group,
        interfaces=[
            {"name": names[0], "group": names[0]},
            {"name": names[1], "axis": {"point": second.point.tolist(), "direction": second.direction.tolist()}},
        ],
    )
    named = build_scene({"bodies": [by_group]}).bodies[0].interfaces[names[1]]
    found = build_scene({"bodies": [by_axis]}).bodies[0].interfaces[names[1]]
    np.testing.assert_array_equal(np.sort(found.nodes), np.sort(named.nodes))
    order_found, order_named = np.argsort(found.nodes), np.argsort(named.nodes)
    np.testing.assert_allclose(found.weights[order_found], named.weights[order_named], rtol=1e-12, atol=0)


def test_an_stl_surface_in_millimetres_is_filled_and_its_bores_found_from_the_axes(tmp_path):
    """A scanned or exported part: the paper's link 1 as a bare STL surface in mm (no groups). The scene fills it
    with tetrahedra (mesh = "link1.stl", h) and finds each bore from its joint axis alone: the volume and the
    bore areas equal those of the mesh the surface came from (the same triangles; measured 0 and 1.1e-16)."""
    import meshio

    from ffrf.fe.interfaces import boundary_triangles
    from ffrf.geometry.link_geometry import mesh_link
    from ffrf.paper.axes import bennett_axes, paper_link_axes

    first, second, names = paper_link_axes(1, bennett_axes(90.0))
    source, _ = mesh_link(first, second, h=0.012, names=names)
    surface = boundary_triangles(source)
    meshio.write(tmp_path / "link1.stl", meshio.Mesh(1e3 * source.points, [("triangle", surface)]), file_format="stl")
    axes = [{"name": n, "axis": {"point": a.point.tolist(), "direction": a.direction.tolist()}} for a, n in
            zip((first, second), names, strict=True)]  # fmt: skip
    body = {"name": "scan", "mesh": "link1.stl", "unit": "mm", "h": 0.012, "material": {"E": 1.2e9, "nu": 0.33,
            "rho": 450.0}, "order": 1, "modes": 2, "interfaces": axes}  # fmt: skip
    scene = build_scene({"bodies": [body]}, tmp_path, "scan")
    built = scene.bodies[0]
    assert abs(built.fe.mesh.volume - source.volume) < 1e-12 * source.volume
    reference = build_scene({"bodies": [_axes_link(first, second, names)]}).bodies[0]
    for name in names:
        assert (
            abs(built.interfaces[name].area - reference.interfaces[name].area) < 1e-6 * reference.interfaces[name].area
        )
