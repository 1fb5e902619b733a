"""A free flexible body with spin and elastic excitation (rho_inf = 1, no damping): momentum and
energy are invariants of the exact motion; generalized-alpha keeps them to second order in h.

Generalized-alpha is not a momentum- or energy-conserving scheme for the nonlinear FFRF
equations (Exudyn's solver is the same scheme), so the check is that the drifts are small and
fall as h^2; conservation to round-off would need an energy-momentum integrator."""

import numpy as np
import pytest
from body_fixtures import bar_model, nodal_velocities

from ffrf.craig_bampton import craig_bampton
from ffrf.euler_parameters import g_bar, rotation_matrix
from ffrf.flexible_body import FlexibleBody
from ffrf.generalized_alpha import generalized_alpha
from ffrf.modal_moments import modal_moments
from ffrf.system import MultibodySystem


def _momenta(model, psi, q, qd):
    """Linear and angular momentum (about the origin) summed node by node with the full mass matrix."""
    velocities = nodal_velocities(model.nodes, psi, qd[:3], q[3:7], q[7:], qd[3:7], qd[7:])
    positions = q[:3] + (model.nodes + (psi @ q[7:]).reshape(-1, 3)) @ rotation_matrix(q[3:7]).T
    forces = (model.mass @ velocities).reshape(-1, 3)
    return forces.sum(axis=0), np.cross(positions, forces).sum(axis=0)


def test_momentum_and_energy_drift_are_second_order():
    model = bar_model(E=1e8, rho=450.0)
    ends = [np.flatnonzero(model.nodes[:, 0] < 1e-9), np.flatnonzero(model.nodes[:, 0] > 0.2 - 1e-9)]
    basis = craig_bampton(model, ends, 2)
    body = FlexibleBody("bar", modal_moments(model.nodes, model.mass, basis.basis), basis.reduced_stiffness,
                        0.0 * basis.reduced_stiffness)
    system = MultibodySystem((body,))
    q0 = system.initial_state()
    qd0 = np.zeros_like(q0)
    qd0[:3] = [0.1, 0.0, 0.0]
    qd0[3:7] = 0.25 * g_bar(q0[3:7]).T @ np.array([0.5, 1.0, 5.0])  # body-frame spin (rad/s)
    q0[7:] = 1e-5 * np.random.default_rng(0).normal(size=body.n_modes)
    drifts = []
    for step in (2e-5, 1e-5):
        result = generalized_alpha(system, q0, qd0, 0.01, step, rho_inf=1.0)
        linear, angular = zip(*(_momenta(model, basis.basis, q, qd) for q, qd in zip(result.q, result.qd)))
        energy = np.array([sum(system.energies(q, qd).values()) for q, qd in zip(result.q, result.qd)])
        drifts.append([
            np.abs(np.array(linear) - linear[0]).max() / np.linalg.norm(linear[0]),
            np.abs(np.array(angular) - angular[0]).max() / np.linalg.norm(angular[0]),
            np.abs(energy - energy[0]).max() / energy[0],
        ])
    coarse, fine = np.array(drifts)
    np.testing.assert_allclose(np.log2(coarse / fine), 2.0, atol=0.3)
    assert np.all(fine < 3e-4)
