"""Joints with play (ffrf.system.clearance_joint) against closed forms: a rigid body resting on a loose pin, a pin
tilted by a moment against its bore's two rims, a bar bouncing in its bore (Hunt-Crossley's restitution), a body that
spins without touching, the limit of zero clearance (the ideal revolute joint), and forces that are the gradient of
the stored energy."""

from __future__ import annotations

import numpy as np
import pytest
from body_fixtures import rigid_bar
from pendulum_fixtures import pendulum
from scipy.optimize import brentq

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.pseudo_transient import settle
from ffrf.solvers.static_solver import static_equilibrium
from ffrf.system.clearance_joint import clearance_joint, line_contact_stiffness
from ffrf.system.forces import MarkerLoad, element_tangents
from ffrf.system.joints import GroundFrame, frame_from_axis, revolute_joint
from ffrf.system.markers import frame_marker, node_marker
from ffrf.system.multibody import MultibodySystem

RHO = 450.0
MASS = RHO * 0.2 * 0.02 * 0.01
PIN_LENGTH = 0.02
GRAVITY = np.array([0.0, 0.0, -9.81])
AXES = frame_from_axis([0.0, 1.0, 0.0])  # the pin's axis is y


def _loose_pin(point, radial, stiffness, axial=0.0, damping=0.0, marker=None):
    joint = revolute_joint(
        GroundFrame(point=point, rotation=AXES), marker or frame_marker(0, 0, point, "pin"), rotation1=AXES
    )
    return clearance_joint(joint, radial, axial, PIN_LENGTH, stiffness, damping)


def _hanging(q_rotation: float, hinge: np.ndarray) -> np.ndarray:
    """Coordinates of the rigid bar turned by ``q_rotation`` about y through ``hinge`` (the hinge stays put)."""
    q = np.zeros(7)
    q[3:7] = [np.cos(0.5 * q_rotation), 0.0, np.sin(0.5 * q_rotation), 0.0]
    q[:3] = hinge - rotation_matrix(q[3:7]) @ hinge
    return q


@pytest.mark.parametrize("axial", [0.0, 1e-4])
def test_a_bar_hanging_on_a_loose_pin_rests_on_the_clearance_plus_the_contact_compliance(axial):
    """A rigid bar hangs from a pin at the middle of its end face (the centre of mass axially between the two rims):
    the pin rests at eccentricity c + m g / (2 k) straight below the bore's centre, each rim carrying half the
    weight (measured to 1e-18 m); that tends to c at order 1 in 1/k. With axial play the pin keeps the axial
    offset it started with (no axial load), where the settling iterations leave a free direction alone."""
    body, model, _ = rigid_bar(RHO)
    hinge = model.nodes[model.nodes[:, 0] < 1e-9].mean(axis=0)
    clearance = 1e-4
    excess = []
    stiffnesses = [1e4, 1e5, 1e6, 1e7]
    for stiffness in stiffnesses:
        element = _loose_pin(hinge, clearance, stiffness, axial)
        system = MultibodySystem((body,), (), gravity=GRAVITY, forces=(element,))
        q = settle(system, _hanging(0.5 * np.pi, hinge)).q
        pin = q[:3] + rotation_matrix(q[3:7]) @ hinge
        expected = clearance + MASS * 9.81 / (2.0 * stiffness)
        np.testing.assert_allclose(pin - hinge, [0.0, 0.0, -expected], rtol=0.0, atol=1e-15)
        rims = element.contacts([q])
        np.testing.assert_allclose(
            [c.force for c in rims[:2]], 0.5 * MASS * 9.81, rtol=1e-9
        )  # Newton's tolerance: 5e-12
        assert rims[2].force == 0.0
        excess.append(-(pin - hinge)[2] - clearance)
    order = -np.polyfit(np.log(stiffnesses), np.log(excess), 1)[0]
    assert abs(order - 1.0) < 1e-6


def test_a_pin_under_a_moment_tilts_against_the_two_rims_as_the_closed_form():
    """A rigid bar held at its centre of mass by a loose pin (no gravity, no axial play) under a moment M about x:
    the pin tilts by theta against opposite rims, M = k L cos(theta) (L/2 sin(theta) - c); as k grows theta tends
    to the rigid tilt asin(2 c / L)."""
    body, model, _ = rigid_bar(RHO)
    centre = model.center_of_mass
    clearance, moment = 1e-4, 2e-3
    tilts = []
    for stiffness in [1e5, 1e6, 1e7]:
        element = _loose_pin(centre, clearance, stiffness)
        load = MarkerLoad((0,), "moment", frame_marker(0, 0, centre), torque=[moment, 0.0, 0.0])
        system = MultibodySystem((body,), (), forces=(element, load))
        q = settle(system, system.initial_state()).q
        rotation = rotation_matrix(q[3:7])
        theta = np.arctan2(rotation[2, 1], rotation[1, 1])  # the pin axis y turned about x
        closed = stiffness * PIN_LENGTH * np.cos(theta) * (0.5 * PIN_LENGTH * np.sin(theta) - clearance)
        assert abs(closed - moment) < 1e-10 * moment
        np.testing.assert_allclose(q[:3] + rotation @ centre, centre, rtol=0.0, atol=1e-15)  # centred
        tilts.append(theta)
    rigid = np.arcsin(2.0 * clearance / PIN_LENGTH)
    assert 0.0 < tilts[2] - rigid < tilts[1] - rigid < tilts[0] - rigid


def _bounce(step: float, stiffness: float, damping: float, v0: float):
    """A rigid bar on a pin at its centre of mass, no gravity, thrown at v0 along -z from the bore's centre with
    rho_inf = 1 (the trapezoidal rule, no numerical damping): it crosses the clearance, hits both rims at once and
    rebounds. Returns the run and the system."""
    body, model, _ = rigid_bar(RHO)
    element = _loose_pin(model.center_of_mass, 1e-4, stiffness, damping=damping)
    system = MultibodySystem((body,), (), forces=(element,))
    q0 = system.initial_state()
    qd0 = system.rigid_velocity(q0, 0, velocity=[0.0, 0.0, -v0])
    return generalized_alpha(system, q0, qd0, 0.014, step, rho_inf=1.0), system, element


def test_a_bar_bouncing_in_its_bore_rebounds_as_hunt_and_crossleys_law_predicts():
    """Two rims, each f = k d + chi d d', on a mass m: m u du = -2 d (k + chi u) dd, so the exit speed u1 solves
    F(u1) = F(u0) with F(u) = u / chi - k / chi^2 ln(k + chi u) (no closed form for u1, but an exact equation, solved
    here by bisection). The run's rebound converges to it as the step shrinks (measured 8.9e-4, 3.4e-4, 7.5e-5 of
    v0 at 100, 50, 25 us; the contact starts and ends inside steps) and the energy the dampers took is the kinetic
    energy lost (the balance closes to the same order)."""
    stiffness, chi, v0 = 1e4, 1e5, 0.01

    def f(u):
        return u / chi - stiffness / chi**2 * np.log(stiffness + chi * u)

    exit_speed = brentq(lambda u: f(u) - f(v0), -stiffness / chi * (1.0 - 1e-12), 0.0)
    assert 0.9 < -exit_speed / v0 < 0.95  # a real loss (6 %)
    errors, balances = [], []
    for step in [1e-4, 2.5e-5]:
        run, system, element = _bounce(step, stiffness, chi, v0)
        assert np.max(np.abs(run.q[:, [0, 1, 4, 5, 6]])) < 1e-15  # no force across z, no turn
        errors.append(abs(run.qd[-1, 2] + exit_speed) / v0)
        dissipation = [element.dissipation_rate([q], [qd]) for q, qd in zip(run.q, run.qd, strict=True)]
        assert min(dissipation) >= 0.0
        lost = 0.5 * MASS * (v0**2 - run.qd[-1, 2] ** 2)
        taken = np.trapezoid(dissipation, run.time)
        balances.append(abs(taken - lost) / (0.5 * MASS * v0**2))
    assert errors[1] < 1e-4 and errors[1] < 0.25 * errors[0]
    assert balances[1] < 2e-4


def test_a_spinning_body_on_a_centred_pin_never_touches_its_bore():
    """A rigid bar spinning about the pin's axis through its centre of mass, no gravity: no contact force ever,
    so the spin stays as it started and the centre moves only by the integrator's error of the rotation."""
    body, model, _ = rigid_bar(RHO)
    element = _loose_pin(model.center_of_mass, 1e-4, 1e6, axial=1e-4, damping=1e3)
    system = MultibodySystem((body,), (), forces=(element,))
    q0 = system.initial_state()
    qd0 = system.rigid_velocity(q0, 0, angular_velocity=[0.0, 20.0, 0.0], point=model.center_of_mass)
    run = generalized_alpha(system, q0, qd0, 0.3, 1e-3, rho_inf=1.0)
    for q, qd in zip(run.q, run.qd, strict=True):
        assert all(c.force == 0.0 for c in element.contacts([q], [qd]))
        centre = q[:3] + rotation_matrix(q[3:7]) @ model.center_of_mass
        # the trapezoidal rule's error of the rotation (10 um after 6 rad) stays inside the 0.1 mm clearance
        assert np.max(np.abs(centre - model.center_of_mass)) < 3e-5
    p, pd = run.q[:, 3:7], run.qd[:, 3:7]
    spin = 2.0 * (p[:, 0] * pd[:, 2] - p[:, 2] * pd[:, 0])
    np.testing.assert_allclose(spin, 20.0, rtol=1e-9)  # Newton's tolerance


def test_with_zero_clearance_a_stiffening_pin_tends_to_the_ideal_revolute_joint():
    """A flexible bar (3 Craig-Bampton modes) hangs from a hinge at its end face, pushed sideways at its tip: with
    the ideal revolute joint and with a pin of zero clearance (a bushing) of growing stiffness. The bushing's
    equilibrium differs by its compliance, so the difference falls as 1 / k (order measured within 2 %)."""
    ideal_system, model, psi, hinge = pendulum(n_modes=3)
    tip = int(np.argmin(np.linalg.norm(model.nodes - [0.2, 0.0, 0.0], axis=1)))
    push = MarkerLoad((0,), "push", node_marker(0, model.nodes, psi, tip), force=[0.02, 0.0, 0.0])
    q0 = np.concatenate([_hanging(0.5 * np.pi, hinge), np.zeros(psi.shape[1])])
    ideal = static_equilibrium(
        MultibodySystem(ideal_system.bodies, ideal_system.constraints, gravity=GRAVITY, forces=(push,)), q0
    ).q
    assert abs(ideal[7]) > 1e-7  # the bar bends
    marker = frame_marker(0, psi.shape[1], hinge, "pin")
    differences = []
    stiffnesses = [1e5, 1e6, 1e7]
    for stiffness in stiffnesses:
        element = _loose_pin(hinge, 0.0, stiffness, marker=marker)
        system = MultibodySystem(ideal_system.bodies, (), gravity=GRAVITY, forces=(element, push))
        q = static_equilibrium(system, ideal).q
        differences.append(np.max(np.abs(q - ideal)))
    order = -np.polyfit(np.log(stiffnesses), np.log(differences), 1)[0]
    assert abs(order - 1.0) < 0.02


@pytest.mark.parametrize(("radial", "axial", "grounded"), [(1e-3, 2e-3, False), (0.0, 0.0, False), (1e-3, 2e-3, True)])
def test_contact_forces_are_the_gradient_of_the_stored_energy_and_their_tangent_is_exact(rng, radial, axial, grounded):
    """At a state where both rims and the axial stop are in touch (between two flexible bodies or a body and the
    ground, with play or bilateral): the spring forces are minus the central differences of the energy
    1/2 k delta^2 (an independent check of Eq. (P4)'s gradients); the analytic tangent (Eq. (P7)) is symmetric and
    equals the complex-step tangent of the forces to round-off and their central differences."""
    _, model, psi, hinge = pendulum(n_modes=3)
    m = psi.shape[1]
    bore = GroundFrame(point=hinge) if grounded else frame_marker(0, m, hinge, "bore")
    pin = node_marker(0 if grounded else 1, model.nodes, psi, 5, "pin")
    element = clearance_joint(revolute_joint(bore, pin), radial, axial, PIN_LENGTH, 1e4, 0.0)
    blocks = []
    for _ in range(1 if grounded else 2):
        p = np.array([1.0, 0.0, 0.0, 0.0]) + 0.01 * rng.normal(size=4)
        blocks.append(np.concatenate([1e-3 * rng.normal(size=3), p / np.linalg.norm(p), 1e-4 * rng.normal(size=m)]))
    # the pin 1.58 mm off the bore's axis (clearance 1 mm) and 1.5 mm along it (half the play 1 mm)
    turn = np.eye(3) if grounded else rotation_matrix(blocks[0][3:7])
    bore_point = hinge if grounded else blocks[0][:3] + turn @ hinge
    pin_point = rotation_matrix(blocks[-1][3:7]) @ (model.nodes[5] + psi[15:18] @ blocks[-1][7:])
    blocks[-1][:3] = bore_point - pin_point + turn @ [1.5e-3, 0.5e-3, 1.5e-3]
    touching = element.contacts(blocks)
    assert all(c.penetration > 0.0 for c in touching), touching
    rates = [np.zeros_like(b) for b in blocks]
    forces = element.forces(blocks, rates, 0.0)
    d_q, d_qd = element.tangents(blocks, rates, 0.0)
    stepped, _ = element_tangents(element, blocks, rates, 0.0)
    full = np.block(d_q)
    np.testing.assert_allclose(full, np.block(stepped), rtol=0.0, atol=1e-12 * np.abs(full).max())
    assert not np.any(np.block(d_qd))
    h = 1e-7
    for b in range(len(blocks)):
        for k in range(blocks[b].shape[0]):
            plus = [x.copy() for x in blocks]
            minus = [x.copy() for x in blocks]
            plus[b][k] += h
            minus[b][k] -= h
            energy_slope = (element.potential_energy(plus, 0.0) - element.potential_energy(minus, 0.0)) / (2 * h)
            assert abs(forces[b][k] + energy_slope) < 1e-6 * np.abs(forces[b]).max()
            slope = [
                (fp - fm) / (2 * h)
                for fp, fm in zip(element.forces(plus, rates, 0.0), element.forces(minus, rates, 0.0), strict=True)
            ]
            for a in range(len(blocks)):
                assert np.max(np.abs(d_q[a][b][:, k] - slope[a])) < 1e-5 * np.abs(d_q[a][b]).max()
    np.testing.assert_allclose(full, full.T, rtol=0.0, atol=1e-10 * np.abs(full).max())


def test_bad_clearances_are_refused_in_one_line():
    joint = revolute_joint(GroundFrame(rotation=AXES), frame_marker(0, 0, np.zeros(3)), rotation1=AXES)
    with pytest.raises(ValueError, match="clearances and damping must be >= 0"):
        clearance_joint(joint, -1e-4, 0.0, PIN_LENGTH, 1e6)
    with pytest.raises(ValueError, match="pin length and stiffness"):
        clearance_joint(joint, 1e-4, 0.0, 0.0, 1e6)
    with pytest.raises(ValueError, match="E > 0"):
        line_contact_stiffness(3.5e9, 0.6, 3.5e9, 0.35, PIN_LENGTH)
    # two equal materials: E* = E / (2 (1 - nu^2))
    assert line_contact_stiffness(3.5e9, 0.35, 3.5e9, 0.35, 0.012) == pytest.approx(3.5e9 / (2 * (1 - 0.35**2)) * 0.006)


def test_a_bar_swinging_on_a_loose_pin_has_the_two_freedoms_of_a_pin_rolling_in_its_bore():
    """Eq. (B1) with play: the rigid bar hanging on a frictionless loose pin (axial play zero) has, in the plane of
    the swing, two slow freedoms: the pin's centre rolling on the circle of radius r = c + m g / (2 k) about the
    bore's axis (angle phi) and the bar turning about the pin (theta). With l the pin-to-centre-of-mass distance and
    I the bar's inertia about its centre of mass, T = m/2 (r phi' + l theta')^2 + I/2 theta'^2 and
    V = m g (r phi^2 + l theta^2) / 2: the monitoring's lowest squared frequency and one of its next are that
    pencil's (to 1e-9), the lowest below the ideal hinge's m g l / (I + m l^2)."""
    from scipy.linalg import eigh

    from ffrf.solvers.stability import equilibrium_stability

    body, model, mass = rigid_bar(RHO)
    hinge = model.nodes[model.nodes[:, 0] < 1e-9].mean(axis=0)
    clearance, stiffness = 1e-4, 1e6
    element = _loose_pin(hinge, clearance, stiffness)
    system = MultibodySystem((body,), (), gravity=GRAVITY, forces=(element,))
    solution = settle(system, _hanging(0.5 * np.pi, hinge))
    found = equilibrium_stability(system, solution.q, solution.multipliers, count=4)
    radius, arm = clearance + mass * 9.81 / (2.0 * stiffness), 0.1
    inertia = mass * (0.2**2 + 0.01**2) / 12.0  # about y through the centre of mass (0.2 m along x, 0.01 m along z)
    kinetic = mass * np.array([[radius**2, radius * arm], [radius * arm, arm**2]]) + np.diag([0.0, inertia])
    potential = mass * 9.81 * np.diag([radius, arm])
    expected = eigh(potential, kinetic, eigvals_only=True)
    assert found.squared_frequencies[0] == pytest.approx(expected[0], rel=1e-9)
    # the second in-plane mode (the pin rolling against the swing) is among the slow ones; below it the pin yaws in
    # its bore, its two rims rolling opposite ways
    assert np.min(np.abs(found.squared_frequencies / expected[1] - 1.0)) < 1e-9
    assert expected[0] < mass * 9.81 * arm / (inertia + mass * arm**2)


def test_a_quasi_static_path_jumps_across_the_bore_where_the_load_through_the_pin_reverses():
    """A rigid bar held at its centre of mass by a loose pin (no gravity) under a force along x that falls
    linearly through zero at t = 0.55 s: the pin rests against the +x side at c + F / (2k), floats where F vanishes
    (no equilibrium path continues: Newton's tangent is singular there) and the path jumps, by settling (Eq. (P6)),
    to the -x side, where it rests at c + |F| / (2k) again (to Newton's tolerance at every output). The path
    records the jump."""
    from ffrf.solvers.static_solver import quasi_static

    body, model, _ = rigid_bar(RHO)
    centre = model.center_of_mass
    clearance, stiffness, force = 1e-4, 1e5, 0.2
    element = _loose_pin(centre, clearance, stiffness)

    def pull(t):
        return [force * (1.0 - t / 0.55), 0.0, 0.0]

    load = MarkerLoad((0,), "pull", frame_marker(0, 0, centre), force=pull)
    system = MultibodySystem((body,), (), forces=(element, load))
    start = settle(system, system.initial_state()).q
    times = np.linspace(0.0, 1.0, 11)
    path = quasi_static(system, start, times, max_step=0.05)
    for t, q in zip(times, path.q, strict=True):
        pin = q[:3] + rotation_matrix(q[3:7]) @ centre - centre
        f = pull(t)[0]
        expected = [np.sign(f) * (clearance + abs(f) / (2.0 * stiffness)), 0.0, 0.0]
        # Newton's tolerance on increments, 1e-10 m (measured 6e-12 m along the bore, where a pin resting on it is
        # held only by its load over the clearance: 2e3 N/m against the contact's 1e5)
        np.testing.assert_allclose(pin, expected, rtol=0.0, atol=1e-10)
    # the path records its jump (the energy books are kept apart across it): once, where the load passes zero,
    # from the +x side of the bore to the -x side within one path step
    (jump,) = path.jumps
    assert jump.t_from <= 0.55 < jump.t_to <= jump.t_from + 0.05
    assert jump.q_from[0] > 0.9 * clearance and jump.q_to[0] < -0.9 * clearance
