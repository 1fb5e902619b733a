"""Joints between markers: exact Jacobians, equivalence with the ground hinge, and a driven bar
whose driving torque is known in closed form."""

import numpy as np
import pytest
from body_fixtures import bar_model, random_state
from pendulum_fixtures import pendulum, tip_position

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.system.joints import GroundFrame, MarkerJoint, driven_revolute_joint, exp_so3_tangent, revolute_joint
from ffrf.system.markers import exp_so3, frame_marker, rigid_interface_marker
from ffrf.system.multibody import MultibodySystem


def test_exponential_map_tangent(rng):
    theta, delta = rng.normal(size=3), rng.normal(size=3)
    h = 1e-6
    numeric = (exp_so3(theta + h * delta) - exp_so3(theta - h * delta)) / (2 * h)
    t = exp_so3_tangent(theta) @ delta
    skew = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
    np.testing.assert_allclose(numeric, exp_so3(theta) @ skew, atol=1e-9)


@pytest.mark.parametrize("locked", [(True,) * 5 + (False,), (True,) * 6, (False, True, True, True, False, True)])
def test_joint_jacobian_against_finite_differences(rng, locked):
    model = bar_model()
    n = model.nodes.shape[0]
    basis = rng.normal(size=(3 * n, 3)) * 0.1
    ends = [np.flatnonzero(model.nodes[:, 0] < 1e-9), np.flatnonzero(model.nodes[:, 0] > 0.2 - 1e-9)]
    m0 = rigid_interface_marker(0, model.nodes, basis, ends[1], name="a")
    m1 = rigid_interface_marker(1, model.nodes, basis, ends[0], name="b")
    rot0 = exp_so3(rng.normal(size=3))
    joint = MarkerJoint(
        (0, 1),
        "j",
        m0,
        m1,
        rot0,
        exp_so3(rng.normal(size=3)),
        rng.normal(size=3) * 0.01,
        rng.normal(size=3) * 0.01,
        locked,
        (lambda t: 0.3 * t) if locked[5] else None,
    )
    blocks = [np.r_[random_state(rng, 3)[:3]] for _ in range(2)]
    exact = joint.jacobian(blocks, 0.7)
    h = 1e-6
    for b in range(2):
        numeric = []
        for k in range(blocks[b].size):
            plus = [x.copy() for x in blocks]
            minus = [x.copy() for x in blocks]
            plus[b][k] += h
            minus[b][k] -= h
            numeric.append((joint.value(plus, 0.7) - joint.value(minus, 0.7)) / (2 * h))
        np.testing.assert_allclose(exact[b], np.array(numeric).T, atol=1e-7)


def test_marker_revolute_to_ground_equals_ground_hinge():
    reference, model, psi, hinge = pendulum(n_modes=3)
    body = reference.bodies[0]
    marker = frame_marker(0, body.n_modes, hinge, name="hinge")
    # Joint z-axis along world y: columns x, y, z of the joint frame.
    axes = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]]).T
    joint = revolute_joint(GroundFrame(hinge, np.eye(3)), marker, rotation0=axes, rotation1=axes)
    system = MultibodySystem((body,), (joint,), gravity=reference.gravity)
    q0 = system.initial_state()
    ours = generalized_alpha(system, q0, np.zeros_like(q0), 0.1, 1e-3, rho_inf=0.8)
    theirs = generalized_alpha(reference, q0, np.zeros_like(q0), 0.1, 1e-3, rho_inf=0.8)
    np.testing.assert_allclose(tip_position(ours.q[-1], model, psi), tip_position(theirs.q[-1], model, psi), atol=1e-12)


def test_driven_bar_needs_the_analytic_torque():
    """A rigid bar turned about the horizontal y-axis through its end by phi(t) = 0.5 t^3 (from rest).
    About +y, gravity (-z) pulls with +m g (L/2) cos(phi), so the drive must supply
    tau = I phi'' - m g (L/2) cos(phi), with the exact consistent-mass inertia I = m (L^2/3 + t^2/12)."""
    model = bar_model(E=1e8, rho=450.0)
    nodes = model.nodes
    hinge = nodes[np.flatnonzero(nodes[:, 0] < 1e-9)].mean(axis=0)
    body = FlexibleBody(
        "bar", modal_moments(nodes, model.mass, np.zeros((3 * nodes.shape[0], 0))), np.zeros((0, 0)), np.zeros((0, 0))
    )
    axes = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]]).T  # joint z = world y
    drive = driven_revolute_joint(
        GroundFrame(hinge, np.eye(3)), frame_marker(0, 0, hinge), lambda t: 0.5 * t**3, rotation0=axes, rotation1=axes
    )
    system = MultibodySystem((body,), (drive,), gravity=np.array([0.0, 0.0, -9.81]))
    q0 = system.initial_state()
    result = generalized_alpha(system, q0, np.zeros_like(q0), 1.0, 1e-3, rho_inf=0.8)
    # Rotation about +y by phi turns the bar's x-axis towards -z (downwards): angle from A e_x.
    angle = np.array([np.arctan2(-rotation_matrix(q[3:7])[2, 0], rotation_matrix(q[3:7])[0, 0]) for q in result.q])
    np.testing.assert_allclose(angle, 0.5 * result.time**3, atol=1e-10)
    length, thickness, mass = 0.2, 0.01, 450.0 * 0.2 * 0.02 * 0.01
    inertia = mass * (length**2 / 3 + thickness**2 / 12)
    phi, phi_dd = 0.5 * result.time**3, 3.0 * result.time
    torque = inertia * phi_dd - mass * 9.81 * length / 2 * np.cos(phi)
    # g = x0'.y1 = sin(phi - psi) for a body turned by psi, dg/dpsi = -1 at the solution: the torque
    # -lambda dg/dpsi applied to the body about the joint z-axis equals the multiplier.
    np.testing.assert_allclose(result.multipliers[:, -1], torque, atol=1e-4 * np.abs(torque).max())
