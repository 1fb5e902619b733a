"""Force elements and loads (ffrf.system.forces) against closed forms: a mass on a spring, a hinged bar under a
torque and under a motor's torque-speed curve, a body hanging from a bushing, a cantilever under a tip load
(its Ritz solution), and the exact tangents against finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from body_fixtures import bar_model, rigid_bar
from pendulum_fixtures import pendulum

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.fe_model import rigid_body_modes
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.static_solver import static_equilibrium
from ffrf.system.forces import JointTorque, MarkerLoad, element_tangents, spring_damper
from ffrf.system.joints import GroundFrame, MarkerJoint, frame_from_axis, revolute_joint
from ffrf.system.markers import frame_marker, node_marker
from ffrf.system.multibody import MultibodySystem

RHO = 450.0


def _translational_spring(body, centre, stiffness, damping=0.0):
    marker = frame_marker(0, 0, centre, "centre")
    joint = MarkerJoint(
        (0,), "spring", GroundFrame(point=centre), marker, locked=(True, True, True, False, False, False)
    )
    return spring_damper(joint, stiffness, damping)


def _oscillation(zeta: float, step: float):
    """A free rigid bar held at its centre of mass by a spring-damper (Exudyn's CartesianSpringDamper), pulled
    x0 = 1 mm along x and let go, integrated with generalized-alpha at rho_inf = 1 (the trapezoidal rule)."""
    body, model, mass = rigid_bar(RHO)
    k = 18.0
    element = _translational_spring(body, model.center_of_mass, k, 2.0 * zeta * np.sqrt(k * mass))
    system = MultibodySystem((body,), (), forces=(element,))
    q0 = system.initial_state()
    q0[0] = 1e-3
    result = generalized_alpha(system, q0, np.zeros_like(q0), 0.4, step, rho_inf=1.0, output_every=10)
    assert np.max(np.abs(result.q[:, 1:3])) < 1e-12  # no force across x
    return result.time, result.q[:, 0] / 1e-3, np.sqrt(k / mass)


def test_an_undamped_mass_on_a_spring_oscillates_at_the_trapezoidal_rules_frequency():
    """The trapezoidal rule turns x'' = -w^2 x into x_n = x0 cos(W t_n) with tan(W h / 2) = w h / 2 exactly,
    so the run must follow that discrete closed form to Newton's tolerance (measured 5.2e-15 of x0)."""
    step = 1e-4
    t, x, omega = _oscillation(0.0, step)
    discrete = 2.0 / step * np.arctan(0.5 * omega * step)
    assert np.max(np.abs(x - np.cos(discrete * t))) < 1e-12


def test_a_damped_mass_on_a_spring_damper_decays_as_the_closed_form():
    """zeta = 0.1: x(t) = x0 e^(-zeta w t) (cos w_d t + zeta / sqrt(1 - zeta^2) sin w_d t), to the time
    discretisation error (measured 3.1e-6 of x0 at w h = 3.2e-3)."""
    zeta = 0.1
    t, x, omega = _oscillation(zeta, 1e-4)
    damped = omega * np.sqrt(1.0 - zeta**2)
    exact = np.exp(-zeta * omega * t) * (np.cos(damped * t) + zeta / np.sqrt(1.0 - zeta**2) * np.sin(damped * t))
    assert np.max(np.abs(x - exact)) < 1e-4


def test_a_torque_load_spins_a_hinged_bar_as_torque_over_inertia():
    """A rigid bar on a hinge about y at its end face, no gravity, a constant 1e-4 N m torque about y (world):
    phi(t) = M t^2 / (2 I), I = r^T M_FE r with r the FE rigid rotation about the hinge axis."""
    system, model, _, hinge = pendulum(n_modes=0)
    load = MarkerLoad((0,), "torque", frame_marker(0, 0, hinge), torque=[0.0, 1e-4, 0.0])
    system = MultibodySystem(system.bodies, system.constraints, gravity=np.zeros(3), forces=(load,))
    rotation = rigid_body_modes(model.nodes, hinge)[:, 4]  # about y through the hinge
    inertia = float(rotation @ model.mass @ rotation)
    result = generalized_alpha(system, system.initial_state(), np.zeros(system.n_coordinates), 0.2, 1e-3, rho_inf=1.0)
    p = result.q[:, 3:7]
    phi = 2.0 * np.arctan2(p[:, 2], p[:, 0])  # rotation about y of Euler parameters (cos, 0, sin, 0)
    # The trapezoidal rule integrates a constant acceleration exactly: only Newton's tolerance remains
    # (measured 6.7e-11 rad of 8.3e-3 rad).
    np.testing.assert_allclose(phi, 0.5 * 1e-4 / inertia * result.time**2, rtol=0.0, atol=1e-8)


def test_a_motor_with_a_torque_speed_curve_approaches_its_no_load_speed():
    """A motor tau = tau0 (1 - w / w0) on the hinge of a rigid bar (no gravity): I dw/dt = tau0 (1 - w / w0), so
    w(t) = w0 (1 - exp(-t tau0 / (I w0)))."""
    _, model, _, hinge = pendulum(n_modes=0)
    body, _, _ = rigid_bar(RHO)
    axes = frame_from_axis([0.0, 1.0, 0.0])
    hinge_joint = revolute_joint(GroundFrame(point=hinge, rotation=axes), frame_marker(0, 0, hinge), rotation1=axes)
    tau0, w0 = 2e-4, 3.0
    motor = JointTorque((0,), "motor", hinge_joint, lambda t, angle, speed: tau0 * (1.0 - speed / w0))
    system = MultibodySystem((body,), (hinge_joint,), forces=(motor,))
    rotation = rigid_body_modes(model.nodes, hinge)[:, 4]
    inertia = float(rotation @ model.mass @ rotation)
    result = generalized_alpha(system, system.initial_state(), np.zeros(system.n_coordinates), 0.5, 1e-3, rho_inf=1.0)
    p, pd = result.q[:, 3:7], result.qd[:, 3:7]
    speed = 2.0 * (p[:, 0] * pd[:, 2] - p[:, 2] * pd[:, 0])  # omega_y of a rotation about y
    exact = w0 * (1.0 - np.exp(-result.time * tau0 / (inertia * w0)))
    assert np.max(np.abs(speed - exact)) < 1e-7 * w0  # measured 2.0e-9 of w0 (time discretisation)


def test_a_body_hanging_from_a_bushing_sags_by_its_weight_over_the_stiffness():
    """A revolute joint made compliant (a bushing: the five locked directions elastic) holds a rigid bar at its
    centre of mass under gravity: the centre sinks by m g / k and the bar does not turn."""
    body, model, mass = rigid_bar(RHO)
    centre = model.center_of_mass
    axes = frame_from_axis([0.0, 1.0, 0.0])
    joint = revolute_joint(GroundFrame(point=centre, rotation=axes), frame_marker(0, 0, centre), rotation1=axes)
    k = 5e3
    bushing = spring_damper(joint, [k, k, k, 10.0, 10.0], 0.0)
    system = MultibodySystem((body,), (), gravity=np.array([0.0, 0.0, -9.81]), forces=(bushing,))
    solution = static_equilibrium(system, system.initial_state())
    np.testing.assert_allclose(solution.q[:3], [0.0, 0.0, -mass * 9.81 / k], rtol=0.0, atol=1e-13)  # measured 1e-15
    np.testing.assert_allclose(solution.q[3:7], [1.0, 0.0, 0.0, 0.0], rtol=0.0, atol=1e-12)  # measured 5e-15


def test_a_tip_load_bends_a_cantilever_as_its_ritz_solution():
    """A clamped flexible bar (8 Craig-Bampton modes) under a 1e-3 N tip load along -z: the tip displacement is
    the Ritz solution K_r zeta = Psi^T f of the same basis (the frame is clamped, so the model is linear:
    measured 2.8e-16 relative)."""
    model = bar_model(E=1e8, rho=RHO)
    clamp = np.flatnonzero(model.nodes[:, 0] < 1e-9)
    basis = craig_bampton(model, [clamp], 8)
    psi = basis.basis
    body = FlexibleBody(
        "bar", modal_moments(model.nodes, model.mass, psi), basis.reduced_stiffness, 0.0 * basis.reduced_stiffness
    )
    tip = int(np.argmin(np.linalg.norm(model.nodes - [0.2, 0.0, 0.0], axis=1)))
    clamp_joint = MarkerJoint((0,), "clamp", GroundFrame(), frame_marker(0, psi.shape[1]), locked=(True,) * 6)
    force = np.array([0.0, 0.0, -1e-3])
    load = MarkerLoad((0,), "tip", node_marker(0, model.nodes, psi, tip), force=force)
    system = MultibodySystem((body,), (clamp_joint,), forces=(load,))
    zeta = static_equilibrium(system, system.initial_state()).q[7:]
    ritz = np.linalg.solve(basis.reduced_stiffness, psi[3 * tip : 3 * tip + 3].T @ force)
    deflection = psi[3 * tip : 3 * tip + 3] @ ritz
    assert abs(deflection[2]) > 1e-6  # a real bending (1.5 um)
    np.testing.assert_allclose(psi[3 * tip : 3 * tip + 3] @ zeta, deflection, rtol=0.0, atol=1e-12 * abs(deflection[2]))


def test_element_tangents_equal_central_differences(rng):
    """Complex-step tangents of a bushing between two flexible bodies and of a follower force and torque,
    against central differences of the forces, at a random state."""
    _, model, psi, hinge = pendulum(n_modes=3)
    m = psi.shape[1]
    first = frame_marker(0, m, hinge, "a")
    second = node_marker(1, model.nodes, psi, 5, "b")
    joint = revolute_joint(first, second)
    elements = [
        spring_damper(joint, [1e3, 2e3, 3e3, 4.0, 5.0], [0.1, 0.2, 0.3, 0.01, 0.02]),
        MarkerLoad(
            (1,), "follower", second, force=lambda t: [1.0, -2.0, 0.5 * t], torque=[0.1, 0.0, -0.2], frame="marker"
        ),
    ]
    blocks = []
    for _ in range(2):
        p = rng.normal(size=4)
        blocks.append(np.concatenate([rng.normal(size=3), p / np.linalg.norm(p), 1e-3 * rng.normal(size=m)]))
    rates = [rng.normal(size=7 + m) for _ in range(2)]
    for element in elements:
        chosen = [blocks[i] for i in range(len(element.bodies))] if len(element.bodies) == 2 else [blocks[1]]
        chosen_rates = rates[: len(chosen)]
        exact_q, exact_qd = element_tangents(element, chosen, chosen_rates, 0.3)
        for a in range(len(chosen)):
            for b in range(len(chosen)):
                for k in range(chosen[b].shape[0]):
                    h = 1e-5  # central differences: O(h^2) truncation against round-off of forces up to 1e3
                    for exact, position in ((exact_q, True), (exact_qd, False)):
                        plus = [x.copy() for x in (chosen if position else chosen_rates)]
                        minus = [x.copy() for x in plus]
                        plus[b][k] += h
                        minus[b][k] -= h
                        args_plus = (plus, chosen_rates) if position else (chosen, plus)
                        args_minus = (minus, chosen_rates) if position else (chosen, minus)
                        difference = (element.forces(*args_plus, 0.3)[a] - element.forces(*args_minus, 0.3)[a]) / (
                            2 * h
                        )
                        scale = max(1.0, np.abs(exact[a][b]).max())
                        assert np.max(np.abs(exact[a][b][:, k] - difference)) < 1e-5 * scale  # measured 2e-7


def test_mass_proportional_damping_decays_a_mode_as_the_trapezoidal_rule_of_its_modal_equation():
    """Rayleigh damping D = alpha M_red (+ beta K_red, here 0) on a clamped flexible bar (no gravity), started in
    its first mode: the modal coordinate obeys x'' + alpha x' + w^2 x = 0, whose trapezoidal-rule recurrence
    (Newmark, beta = 1/4, gamma = 1/2, computed here on the scalar equation) the run must follow."""
    from scipy.linalg import eigh

    model = bar_model(E=1e8, rho=RHO)
    clamp = np.flatnonzero(model.nodes[:, 0] < 1e-9)
    basis = craig_bampton(model, [clamp], 4)
    alpha = 20.0
    damping = basis.reduced_damping(beta=0.0, alpha=alpha)
    body = FlexibleBody("bar", modal_moments(model.nodes, model.mass, basis.basis), basis.reduced_stiffness, damping)
    clamp_joint = MarkerJoint((0,), "clamp", GroundFrame(), frame_marker(0, basis.n_modes), locked=(True,) * 6)
    system = MultibodySystem((body,), (clamp_joint,))
    squares, shapes = eigh(basis.reduced_stiffness, basis.reduced_mass)
    omega, shape = np.sqrt(squares[0]), shapes[:, 0] / np.abs(shapes[:, 0]).max()
    q0 = system.initial_state()
    q0[7:] = 1e-4 * shape
    step = 2e-4
    result = generalized_alpha(system, q0, np.zeros_like(q0), 0.2, step, rho_inf=1.0)
    amplitude = result.q[:, 7:] @ (basis.reduced_mass @ shape) / (shape @ basis.reduced_mass @ shape)
    x, v = 1e-4, 0.0
    a = -(alpha * v + omega**2 * x)
    expected = [x]
    system_matrix = np.array([[1.0, 0.0, -0.25 * step**2], [0.0, 1.0, -0.5 * step], [omega**2, alpha, 1.0]])
    for _ in range(len(result.time) - 1):
        x, v, a = np.linalg.solve(system_matrix, [x + step * v + 0.25 * step**2 * a, v + 0.5 * step * a, 0.0])
        expected.append(x)
    assert np.max(np.abs(amplitude - np.array(expected))) < 1e-12 * 1e-4  # measured 3.9e-19 m


def test_a_bar_started_turning_about_its_hinge_keeps_turning_at_that_rate():
    """Initial velocities (MultibodySystem.rigid_velocity) of a rigid bar turning at 2 rad/s about its hinge (y)
    through the hinge point, no gravity: the start has the kinetic energy I w^2 / 2 (I from the FE mass matrix),
    and the bar turns at 2 rad/s, phi = 2 t, up to the integrator's second-order phase error."""
    system, model, _, hinge = pendulum(n_modes=0)
    system = MultibodySystem(system.bodies, system.constraints, gravity=np.zeros(3))
    q0 = system.initial_state()
    qd0 = system.rigid_velocity(q0, 0, angular_velocity=[0.0, 2.0, 0.0], point=hinge)
    rotation = rigid_body_modes(model.nodes, hinge)[:, 4]
    inertia = float(rotation @ model.mass @ rotation)
    assert abs(system.energies(q0, qd0)["kinetic"] / (0.5 * inertia * 4.0) - 1.0) < 1e-14  # measured 2e-16
    errors = []
    for step in (1e-3, 5e-4):
        result = generalized_alpha(system, q0, qd0, 0.5, step, rho_inf=1.0)
        p = result.q[:, 3:7]
        errors.append(np.max(np.abs(2.0 * np.arctan2(p[:, 2], p[:, 0]) - 2.0 * result.time)))
    assert errors[0] < 1e-5  # measured 7.4e-8 rad after 1 rad
    assert 3.5 < errors[0] / errors[1] < 4.5  # second order (measured 4.0)


def test_an_anisotropic_bushing_holds_the_weight_with_the_stiffness_along_its_frame_axis():
    """A bushing (revolute joint's five equations, translations in the joint frame: frame_translations) whose
    frame x axis points along world z: a rigid bar hanging at its centre of mass sinks by m g / k_x, not by
    m g / k_z as a spring in world components would."""
    from dataclasses import replace

    body, model, mass = rigid_bar(RHO)
    centre = model.center_of_mass
    axes = np.array(
        [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
    )  # columns x = world z, y = world x, z = world y
    joint = revolute_joint(GroundFrame(point=centre, rotation=axes), frame_marker(0, 0, centre), rotation1=axes)
    k_x, k_y, k_z = 2e3, 5e3, 9e3
    bushing = spring_damper(replace(joint, frame_translations=True), [k_x, k_y, k_z, 10.0, 10.0], 0.0)
    system = MultibodySystem((body,), (), gravity=np.array([0.0, 0.0, -9.81]), forces=(bushing,))
    solution = static_equilibrium(system, system.initial_state())
    np.testing.assert_allclose(solution.q[:3], [0.0, 0.0, -mass * 9.81 / k_x], rtol=0.0, atol=1e-13)


def test_a_state_dependent_drag_load_damps_a_mass_on_a_spring_as_the_closed_form():
    """A load f(t, position, velocity) = -c v on the undamped spring-mass of the tests above (zeta = 0.1 from c):
    the same decay as the damper, x(t) = x0 e^(-zeta w t) (cos w_d t + ...), to the time discretisation error."""
    body, model, mass = rigid_bar(RHO)
    k, zeta = 18.0, 0.1
    c = 2.0 * zeta * np.sqrt(k * mass)
    centre = model.center_of_mass
    drag = MarkerLoad((0,), "drag", frame_marker(0, 0, centre), force=lambda t, position, velocity: -c * velocity)
    assert not drag.complex_safe  # a user's state function: central-difference tangents
    timed = MarkerLoad((0,), "timed", frame_marker(0, 0, centre), force=lambda t, a=1.0, b=2.0: [a * t, b, 0.0])
    assert timed.complex_safe  # a time law whose extra parameters have defaults reads time only
    system = MultibodySystem((body,), (), forces=(_translational_spring(body, centre, k), drag))
    q0 = system.initial_state()
    q0[0] = 1e-3
    result = generalized_alpha(system, q0, np.zeros_like(q0), 0.4, 1e-4, rho_inf=1.0, output_every=10)
    omega = np.sqrt(k / mass)
    damped, t = omega * np.sqrt(1.0 - zeta**2), result.time
    exact = np.exp(-zeta * omega * t) * (np.cos(damped * t) + zeta / np.sqrt(1.0 - zeta**2) * np.sin(damped * t))
    assert np.max(np.abs(result.q[:, 0] / 1e-3 - exact)) < 1e-4  # the damper's own run: 3.1e-6


def test_a_dead_load_on_a_spring_holds_its_closed_form_potential_energy():
    """A rigid bar held at its centre c by a spring k, loaded there by F along x, no gravity: at the equilibrium
    x = F/k the potential energy (MultibodySystem.potential_energy) is the spring's 1/2 k x^2 plus the dead load's
    -F (c_x + x) (its marker's world point), also for a force that depends on time alone, at that time. The same
    force in the marker's axes (a follower load) or as a function of the state has no potential: only the
    spring's energy is left."""
    body, model, _ = rigid_bar(RHO)
    k, force = 18.0, 0.09
    centre = model.center_of_mass
    marker = frame_marker(0, 0, centre, "centre")
    spring = _translational_spring(body, centre, k)
    loads = {
        "world": MarkerLoad((0,), "load", marker, force=[force, 0.0, 0.0]),
        "in time": MarkerLoad((0,), "load", marker, force=lambda t: [force * t, 0.0, 0.0]),
        "marker": MarkerLoad((0,), "load", marker, force=[force, 0.0, 0.0], frame="marker"),
        "state": MarkerLoad((0,), "load", marker, force=lambda t, x, v: [force, 0.0, 0.0]),
    }
    for kind, load in loads.items():
        system = MultibodySystem((body,), (), forces=(spring, load))
        solution = static_equilibrium(system, system.initial_state(), t=1.0)
        stretch = solution.q[0]  # the frame's x, and the marker's move from the spring's ground point
        assert stretch == pytest.approx(force / k, rel=1e-9)
        dead = -force * (centre[0] + stretch) if kind in ("world", "in time") else 0.0
        assert system.potential_energy(solution.q, 1.0) == pytest.approx(0.5 * k * stretch**2 + dead, rel=1e-12)
