"""A free flexible body with spin and elastic excitation (rho_inf = 1, no damping): momentum and
energy are invariants of the exact motion; generalized-alpha keeps them to second order in h.

Generalized-alpha is not a momentum- or energy-conserving scheme for the nonlinear FFRF
equations (Exudyn's solver is the same scheme), so the check is that the drifts are small and
fall as h^2. Conservation to round-off is the variational midpoint integrator's
(test_variational_midpoint.py)."""

import numpy as np
from body_fixtures import free_bar, nodal_velocities, tumbling_start

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.solvers.generalized_alpha import generalized_alpha


def _momenta(model, psi, q, qd):
    """Linear and angular momentum (about the origin) summed node by node with the full mass matrix."""
    velocities = nodal_velocities(model.nodes, psi, qd[:3], q[3:7], q[7:], qd[3:7], qd[7:])
    positions = q[:3] + (model.nodes + (psi @ q[7:]).reshape(-1, 3)) @ rotation_matrix(q[3:7]).T
    forces = (model.mass @ velocities).reshape(-1, 3)
    return forces.sum(axis=0), np.cross(positions, forces).sum(axis=0)


def test_momentum_and_energy_drift_are_second_order():
    model, psi, _, body = free_bar()
    system, q0, qd0 = tumbling_start(body)
    drifts = []
    for step in (2e-5, 1e-5):
        result = generalized_alpha(system, q0, qd0, 0.01, step, rho_inf=1.0)
        linear, angular = zip(
            *(_momenta(model, psi, q, qd) for q, qd in zip(result.q, result.qd, strict=True)), strict=True
        )
        energy = np.array([sum(system.energies(q, qd).values()) for q, qd in zip(result.q, result.qd, strict=True)])
        drifts.append(
            [
                np.abs(np.array(linear) - linear[0]).max() / np.linalg.norm(linear[0]),
                np.abs(np.array(angular) - angular[0]).max() / np.linalg.norm(angular[0]),
                np.abs(energy - energy[0]).max() / energy[0],
            ]
        )
    coarse, fine = np.array(drifts)
    np.testing.assert_allclose(np.log2(coarse / fine), 2.0, atol=0.3)
    assert np.all(fine < 3e-4)
