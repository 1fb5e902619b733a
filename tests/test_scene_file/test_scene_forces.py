"""Force elements in scene files (``[[forces]]``, ffrf.scenes.scene_forces) against closed forms: a bar hanging from
a spring-damper sags by its weight over the stiffness, a tip load ramped by a table bends a cantilever as the Ritz
solution of its basis, and a motor spins a hinged bar towards its no-load speed."""

from __future__ import annotations

import numpy as np
import pytest
from scene_fixtures import PENDULUM, write_bar

from ffrf import load
from ffrf.errors import SceneError
from ffrf.fe.fe_model import rigid_body_modes
from ffrf.output.sensors import scene_sensors
from ffrf.scenes.scene_file import load_scene

SPRING = """
[[forces]]
name = "support"
type = "spring_damper"
elastic = "fixed"
body0 = "ground"
body1 = "bar"
interface1 = "hinge"
axis = [0.0, 1.0, 0.0]
stiffness = [5e3, 5e3, 5e3, 20.0, 20.0, 20.0]
"""


def _scene(tmp_path, text: str):
    """The scene ``text`` on the bar of ``scene_fixtures``, with a second interface ``tip`` (the x = 0.2 m face)."""
    model = write_bar(tmp_path)
    np.savetxt(tmp_path / "tip.txt", np.flatnonzero(model.nodes[:, 0] > 0.2 - 1e-9), fmt="%d")
    (tmp_path / "scene.toml").write_text(text)
    return load_scene(tmp_path / "scene.toml")


def _with_tip(text: str) -> str:
    """``text`` with the bar's tip face as a second interface, ``tip``."""
    return text.replace(
        'interfaces = [{name = "hinge", nodes_file = "hinge.txt"}]',
        'interfaces = [{name = "hinge", nodes_file = "hinge.txt"}, {name = "tip", nodes_file = "tip.txt"}]',
    )


def test_a_bar_hanging_from_a_spring_damper_sinks_by_its_weight_over_the_stiffness(tmp_path):
    """The pendulum's hinge replaced by a 'fixed' spring-damper (translations 5e3 N/m, rotations 20 N m) under
    gravity, statically: the spring alone carries the weight, so the hinge interface sinks by m g / k exactly
    (the translation equations are the world components of p1 - p0), whatever the bar's rotation."""
    text = PENDULUM.replace('mode = "dynamic"', 'mode = "quasi_static"').replace("outputs = 101", "outputs = 2")
    text = text[: text.index("[[joints]]")] + SPRING
    scene = _scene(tmp_path, text)
    run = load(scene).run()
    mass = scene.bodies[0].fe.total_mass
    hinge = scene.bodies[0].markers["hinge"]
    sag = hinge.position(run.q[-1]) - hinge.position(scene.q_initial)
    np.testing.assert_allclose(sag, [0.0, 0.0, -mass * 9.81 / 5e3], rtol=0.0, atol=1e-12 * mass * 9.81 / 5e3)


def test_a_ramped_tip_load_bends_a_cantilever_as_the_ritz_solution_of_its_basis(tmp_path):
    """The bar clamped at its hinge face (a fixed joint), no gravity, a 1e-3 N load along -z on its tip face
    ramped by a table to full at 0.05 s: at the end, the generalized coordinates solve K_r zeta = P^T f with P
    the tip interface's averaged modes (the clamped frame makes the model linear)."""
    text = PENDULUM.replace('mode = "dynamic"', 'mode = "quasi_static"').replace("outputs = 101", "outputs = 3")
    text = text.replace("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, 0.0, 0.0]").replace(
        'type = "revolute"', 'type = "fixed"'
    )
    text = _with_tip(text)
    text += """
[[forces]]
name = "payload"
type = "load"
body = "bar"
interface = "tip"
force = [0.0, 0.0, -1e-3]
table = {time = [0.0, 0.05], scale = [0.0, 1.0]}
"""
    scene = _scene(tmp_path, text)
    run = load(scene).run()
    body = scene.bodies[0]
    tip = body.markers["tip"]
    ritz = np.linalg.solve(body.reduction.reduced_stiffness, tip.position_modes.T @ np.array([0.0, 0.0, -1e-3]))
    assert np.linalg.norm(ritz) > 0.0
    np.testing.assert_allclose(run.q[-1, 7:], ritz, rtol=0.0, atol=1e-12 * np.abs(ritz).max())
    np.testing.assert_allclose(run.q[1, 7:], ritz, rtol=0.0, atol=1e-12 * np.abs(ritz).max())  # t = 0.05 s, full


def test_a_motor_spins_a_hinged_bar_towards_its_no_load_speed(tmp_path):
    """A motor tau = tau0 (1 - w / w0) on the pendulum's hinge, no gravity, the bar made stiff (E = 1e13 Pa):
    I dw/dt = tau with I from the FE mass matrix, so the hinge turns by phi(t) = w0 t - w0 T (1 - exp(-t / T)),
    T = I w0 / tau0 (measured 1.2e-6 of phi: the time step and the bar's vibration, which the step torque starts)."""
    text = PENDULUM.replace("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, 0.0, 0.0]").replace(
        "t_end = 0.1", "t_end = 0.3"
    )
    text = text.replace("E = 1e8", "E = 1e13")
    text += """
[[forces]]
name = "motor"
type = "motor"
body0 = "ground"
body1 = "bar"
interface1 = "hinge"
axis = [0.0, 1.0, 0.0]
stall_torque = 2e-4
no_load_speed = 3.0
"""
    scene = _scene(tmp_path, text)
    run = load(scene).run()
    angle = scene_sensors(scene, run.time, run.q, run.multipliers, run.qd)["hinge_angle"]
    fe = scene.bodies[0].fe
    rotation = rigid_body_modes(fe.nodes, scene.bodies[0].markers["hinge"].point)[:, 4]
    constant = float(rotation @ fe.mass @ rotation) * 3.0 / 2e-4
    exact = 3.0 * run.time - 3.0 * constant * (1.0 - np.exp(-run.time / constant))
    assert exact[-1] > 0.01
    assert np.max(np.abs(angle - exact)) < 1e-4 * exact[-1]


def test_a_body_started_turning_in_a_scene_file_keeps_turning(tmp_path):
    """``velocity = {linear, angular}`` of the pendulum's bar, the frame origin's velocity chosen so that the hinge
    point stays (v = -w x h): with no gravity, the stiff bar turns at w = 2 rad/s about its hinge, phi = 2 t (to
    the integrator's phase error, measured 1.1e-8 rad after 0.2 rad)."""
    hinge = np.array([0.0, 0.01, 0.005])  # centre of the bar's x = 0 face, where its frame interface is
    linear = -np.cross([0.0, 2.0, 0.0], hinge)
    text = PENDULUM.replace("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, 0.0, 0.0]").replace("E = 1e8", "E = 1e13")
    text = text.replace(
        "modes = 3\n",
        f"modes = 3\nvelocity = {{linear = [{linear[0]}, {linear[1]}, {linear[2]}], angular = [0, 2, 0]}}\n",
    )
    scene = _scene(tmp_path, text)
    np.testing.assert_allclose(scene.bodies[0].markers["hinge"].point, hinge, atol=1e-15)
    run = load(scene).run()
    angle = scene_sensors(scene, run.time, run.q, run.multipliers, run.qd)["hinge_angle"]
    assert np.max(np.abs(angle - 2.0 * run.time)) < 1e-6


def test_the_energy_balance_of_a_driven_bar_pulling_a_spring_damper_closes(tmp_path):
    """The pendulum driven at its hinge (60 rpm, 0.05 s ramp) with its tip tied to the ground by a spring-damper
    (20 N/m, 0.05 N s/m) and gravity: the drive's work plus the element's work (springs return what they store,
    dampers take) equals the change of kinetic, gravity and strain energy plus the bar's damping."""
    text = PENDULUM.replace('type = "revolute"', 'type = "driven_revolute"\ndrive = {rpm = 60.0, ramp_time = 0.05}')
    text = (
        text.replace("t_end = 0.1", "t_end = 0.2")
        .replace("step = 1e-3", "step = 2e-4")
        .replace("outputs = 101", "outputs = 201")
    )
    text = text.replace('mode = "dynamic"', 'mode = "dynamic"\nbeta = 1e-4')
    text = _with_tip(text)
    text += """
[[forces]]
name = "tie"
type = "spring_damper"
body0 = "ground"
body1 = "bar"
interface1 = "tip"
stiffness = [20.0]
damping = [0.05]
"""
    scene = _scene(tmp_path, text)
    run = load(scene).run()
    sensors = scene_sensors(scene, run.time, run.q, run.multipliers, run.qd)
    elements = sensors["energy_elements_work"]
    drive = sensors["energy_drive_work"]
    assert np.max(np.abs(elements)) > 0.1 * np.max(np.abs(drive))  # the spring-damper matters
    residual = np.max(np.abs(sensors["energy_balance_residual"])) / np.max(np.abs(drive))
    assert residual < 1e-4  # measured 6.6e-7 of the drive work (without the element work: over 0.1)


def test_a_hinged_bar_held_up_by_an_axial_spring_settles_where_the_moments_balance(tmp_path):
    """The stiff pendulum (E = 1e13 Pa) held near horizontal by a spring (Eq. (E6)) from its tip to a ground point
    0.1 m above the tip, unloaded at the start: statically the bar turns down by the angle where gravity's moment
    about the hinge equals the spring's (a one-degree-of-freedom closed form, solved here by bisection)."""
    from scipy.optimize import brentq

    text = PENDULUM.replace('mode = "dynamic"', 'mode = "quasi_static"').replace("outputs = 101", "outputs = 2")
    text = _with_tip(text.replace("E = 1e8", "E = 1e13"))
    k, rise = 2.0, 0.1
    text += f"""
[[forces]]
name = "tie"
type = "spring"
body0 = "ground"
point0 = [0.2, 0.01, {0.005 + rise}]
body1 = "bar"
interface1 = "tip"
stiffness = [{k}]
"""
    scene = _scene(tmp_path, text)
    body = scene.bodies[0]
    hinge, tip = body.markers["hinge"].point, body.markers["tip"].point
    np.testing.assert_allclose(tip - hinge, [0.2, 0.0, 0.0], atol=1e-15)
    arm = (body.fe.center_of_mass - hinge)[0]
    weight = body.fe.total_mass * 9.81

    def moment(angle: float) -> float:  # about +y through the hinge; the bar turned down by angle
        end = np.array([0.2 * np.cos(angle), 0.0, -0.2 * np.sin(angle)])
        pull = np.array([0.2, 0.0, rise]) - end
        length = np.linalg.norm(pull)
        force = k * (length - rise) * pull / length
        return weight * arm * np.cos(angle) + (end[2] * force[0] - end[0] * force[2])

    expected = brentq(moment, 0.0, 1.0, xtol=1e-15)
    run = load(scene).run()
    p = run.q[-1, 3:7]
    angle = 2.0 * np.arctan2(p[2], p[0])
    assert expected > 0.05  # the spring holds the bar well above hanging
    assert abs(angle - expected) < 1e-7  # measured 1.5e-9 rad (the stiff bar still bends a little)


def test_modal_start_velocities_carry_the_kinetic_energy_of_the_reduced_mass(tmp_path):
    """``velocity = {modal = [...]}`` of the clamped bar: the start's kinetic energy is v^T M_red v / 2 (the frame
    does not move); a list of the wrong length is refused with the number of modes."""
    text = PENDULUM.replace('type = "revolute"', 'type = "fixed"').replace(
        "modes = 3\n", "modes = 3\nvelocity = {modal = [0.3, -0.2, 0.1]}\n"
    )
    scene = _scene(tmp_path, text)
    rates = np.array([0.3, -0.2, 0.1])
    body = scene.bodies[0]
    assert body.reduction.n_modes == 3
    kinetic = scene.system.energies(scene.q_initial, scene.qd_initial)["kinetic"]
    assert abs(kinetic / (0.5 * rates @ body.reduction.reduced_mass @ rates) - 1.0) < 1e-12
    wrong = _scene(tmp_path, text.replace("[0.3, -0.2, 0.1]", "[0.3, -0.2]"))
    with pytest.raises(SceneError, match=r"velocity.modal needs one rate per mode \(3\), got 2"):
        wrong.qd_initial  # noqa: B018 - the property raises
