"""The variational midpoint integrator (docs/formulation.md, Eqs. (V1)-(V6)).

Independent truths: momenta summed node by node with the full FE mass matrix (not our modal
moments), the exact conservation laws of an undamped free system, complex-step derivatives of
the kinetic energy, second-order convergence, and generalized-alpha on the same pendulum."""

import numpy as np
import pytest
from body_fixtures import free_bar, nodal_velocities, random_state, tumbling_start
from pendulum_fixtures import pendulum, tip_position

from ffrf.body.euler_parameters import g_bar, rotation_matrix
from ffrf.body.flexible_body import kinetic_energy_of
from ffrf.errors import NewtonDivergence
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.variational_midpoint import variational_midpoint
from ffrf.system.joints import revolute_joint
from ffrf.system.markers import rigid_interface_marker
from ffrf.system.multibody import MultibodySystem


def _momenta(model, psi, q, qd):
    """Linear and angular momentum (about the origin) of one body, node by node with the full mass matrix."""
    velocities = nodal_velocities(model.nodes, psi, qd[:3], q[3:7], q[7:], qd[3:7], qd[7:])
    positions = q[:3] + (model.nodes + (psi @ q[7:]).reshape(-1, 3)) @ rotation_matrix(q[3:7]).T
    forces = (model.mass @ velocities).reshape(-1, 3)
    return forces.sum(axis=0), np.cross(positions, forces).sum(axis=0)


def _system_momenta(system, model, psi, result):
    rows = []
    for q, qd in zip(result.q, result.qd, strict=True):
        parts = [_momenta(model, psi, q[system.block(i)], qd[system.block(i)]) for i in range(len(system.bodies))]
        rows.append(np.concatenate([sum(p[0] for p in parts), sum(p[1] for p in parts)]))
    return np.array(rows)


def _relative_drift(rows):
    """Largest change of linear (columns 0-2) and angular (3-5) momentum relative to its size."""
    linear, angular = rows[:, :3], rows[:, 3:]
    return (
        np.abs(linear - linear[0]).max() / np.linalg.norm(linear[0]),
        np.abs(angular - angular[0]).max() / np.linalg.norm(angular[0]),
    )


def _energy(system, result):
    return np.array([sum(system.energies(q, qd).values()) for q, qd in zip(result.q, result.qd, strict=True)])


def test_kinetic_energy_and_its_gradient_match_the_mass_matrix_and_complex_step():
    _, _, _, body = free_bar()
    rng = np.random.default_rng(3)
    packed, packed_complex = body._packed[:6], body._packed_complex[:6]
    for scale in (1.0, 1.3):  # unit Euler parameters and the midpoint's non-unit ones
        r, p, zeta, rd, pd, zetad = random_state(rng, body.n_modes)
        q, qd = np.concatenate([r, scale * p, zeta]), np.concatenate([rd, pd, zetad])
        assert np.isclose(
            kinetic_energy_of(q, qd, body.moments.mass, *packed), 0.5 * qd @ body.mass_matrix(q) @ qd, rtol=1e-14
        )
        reference = np.array(
            [
                kinetic_energy_of(
                    q + 1e-30j * np.eye(q.size)[k], qd.astype(complex), body.moments.mass, *packed_complex
                ).imag
                / 1e-30
                for k in range(q.size)
            ]
        )
        np.testing.assert_allclose(
            body.kinetic_energy_gradient(q, qd), reference, rtol=0, atol=1e-14 * np.abs(reference).max()
        )
        step = 1e-6
        rate = (body.mass_matrix(q + step * qd) - body.mass_matrix(q - step * qd)) / (2 * step)
        np.testing.assert_allclose(body.mass_matrix_rate(q, qd), rate, rtol=0, atol=1e-8 * np.abs(rate).max())


def test_free_body_keeps_momentum_exactly_and_energy_without_drift():
    """The issue's case: spin, elastic excitation, no damping, 10^4 steps (generalized-alpha with
    rho_inf = 1 drifts by 2e-4 in momentum here; bench/conservation.py)."""
    model, psi, _, body = free_bar()
    system, q0, qd0 = tumbling_start(body)
    result = variational_midpoint(system, q0, qd0, 0.1, 1e-5, output_every=10)
    assert result.complete and len(result.newton_iterations) == 10_000
    linear, angular = _relative_drift(_system_momenta(system, model, psi, result))
    assert linear < 1e-10 and angular < 1e-10
    energy = _energy(system, result)
    error = (energy - energy[0]) / energy[0]
    window = len(error) // 10
    # symplectic: a bounded O(h^2) oscillation (elastic modes up to 14000 rad/s), no secular drift
    assert abs(error[-window:].mean() - error[:window].mean()) < 1e-6
    assert np.abs(error).max() < 1e-3


def test_two_joined_bodies_in_free_flight_keep_the_total_momentum():
    """A revolute joint between two flexible bars is invariant under rigid motions of the pair,
    so the discrete Noether theorem holds for the joined system too."""
    model, psi, ends, body0 = free_bar("bar0")
    _, _, _, body1 = free_bar("bar1")
    far0 = rigid_interface_marker(0, model.nodes, psi, ends[1], name="bar0:far")
    near1 = rigid_interface_marker(1, model.nodes, psi, ends[0], name="bar1:near")
    system = MultibodySystem((body0, body1), (revolute_joint(far0, near1),))
    q0 = system.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
    spin, hinge_rate = np.array([0.3, -0.2, 2.0]), 6.0
    hinge = far0.point
    qd0 = np.zeros_like(q0)
    for i, extra in ((0, 0.0), (1, hinge_rate)):
        s = system.block(i)
        omega = spin + extra * np.array([0.0, 0.0, 1.0])  # world = body frame at the identity
        qd0[s][:3] = (
            np.array([0.05, 0.0, 0.01]) + np.cross(spin, q0[s][:3]) + extra * np.cross([0, 0, 1.0], q0[s][:3] - hinge)
        )
        qd0[s][3:7] = 0.25 * g_bar(q0[s][3:7]).T @ omega
    assert np.abs(system.constraint_jacobian(q0, 0.0) @ qd0).max() < 1e-12  # consistent start
    result = variational_midpoint(system, q0, qd0, 0.02, 1e-5, output_every=20)
    linear, angular = _relative_drift(_system_momenta(system, model, psi, result))
    assert linear < 1e-10 and angular < 1e-10
    assert np.abs(system.constraint_values(result.q[-1], 0.02)).max() < 1e-12
    assert np.abs(result.q[-1][system.block(1)][7:]).max() > 1e-8  # the hinge excites the elastic modes


def test_pendulum_is_second_order_and_agrees_with_generalized_alpha():
    """With a little stiffness-proportional damping, so that the stiff interface modes the
    release excites die out: undamped, their unresolved phase error (omega h > 1) would hide
    the order, as it would for any non-dissipative scheme."""
    system, model, psi, _ = pendulum(n_modes=2, beta=1e-3)
    q0, qd0 = system.initial_state(), np.zeros(system.n_coordinates)
    t_end = 0.2
    tips = {
        h: tip_position(variational_midpoint(system, q0, qd0, t_end, h).q[-1], model, psi)
        for h in (4e-3, 2e-3, 1e-3, 2.5e-4)
    }
    reference = tips[2.5e-4]
    errors = np.array([np.linalg.norm(tips[h] - reference) for h in (4e-3, 2e-3, 1e-3)])
    np.testing.assert_allclose(np.log2(errors[:-1] / errors[1:]), 2.0, atol=0.2)
    alpha = generalized_alpha(system, q0, qd0, t_end, 2.5e-4, rho_inf=0.9)
    assert np.linalg.norm(tip_position(alpha.q[-1], model, psi) - reference) < 1e-6


def test_hinged_pendulum_energy_has_no_drift():
    """Constraints to the ground and gravity: the energy oscillates but does not drift."""
    system, _, _, _ = pendulum(n_modes=2)
    q0, qd0 = system.initial_state(), np.zeros(system.n_coordinates)
    result = variational_midpoint(system, q0, qd0, 0.5, 2e-4, output_every=5)
    energy = _energy(system, result)
    potential = np.array([system.energies(q, qd)["potential"] for q, qd in zip(result.q, result.qd, strict=True)])
    error = (energy - energy[0]) / (potential[0] - potential.min())  # of the energy set in motion
    window = len(error) // 10
    assert abs(error[-window:].mean() - error[:window].mean()) < 1e-6
    assert np.abs(error).max() < 1e-5


def test_bad_input_and_failure_are_reported():
    system, _, _, _ = pendulum(n_modes=2)
    q0, qd0 = system.initial_state(), np.zeros(system.n_coordinates)
    with pytest.raises(ValueError, match="positive"):
        variational_midpoint(system, q0, qd0, 0.1, 0.0)
    bad = q0.copy()
    bad[0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        variational_midpoint(system, bad, qd0, 0.1, 1e-3)
    with pytest.raises(NewtonDivergence) as failure:
        variational_midpoint(system, q0, qd0, 0.1, 1e-3, max_iterations=1)
    assert failure.value.partial.complete is False
    assert np.all(np.isfinite(failure.value.partial.q))
