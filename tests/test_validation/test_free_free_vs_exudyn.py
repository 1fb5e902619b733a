"""A body with a free-free mode basis, in our solver and in Exudyn's ObjectFFRFreducedOrder.

objectFFRFreducedOrderTest.py's rotor (Abaqus matrices, 0.1 kg unbalance on the disc, stiffness
x 0.01, 8 free-free modes) spinning freely at 50 rev/s about z, no supports and no gravity (the
test model's spring-dampers to ground are not part of this check), 0.01 s at h = 1e-4,
rho_inf = 0.5, as in the test model. Both solvers get the same nodes, M, K and basis
(``validation.exudyn_ffrf``). Physics that uses neither solver: the centre of mass moves on a
straight line at the initial velocity omega x c (its position in the body frame does not change
with the deformation: the modes carry no first moment, (FF-3)).
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
from validation_fixtures import centre_of_mass_path, exudyn_run, ffrf_run, max_difference, tracked_nodes

from ffrf.fe.matrix_import import abaqus_model
from ffrf.fe.node_selection import node_at_point, nodes_in_plane
from ffrf.reduction.free_free import free_free_basis
from validation.reduced_body import ReducedBody
from validation.single_body_scenes import SingleBodyScene

DATA = Path(__file__).parents[2] / "validation" / "data" / "exudyn_testmodels"
OMEGA = (0.0, 0.0, 50.0 * 2.0 * np.pi)


@cache
def rotor_scene() -> SingleBodyScene:
    model = abaqus_model(
        DATA / "rotorDiscTest.inp", DATA / "rotorDiscTestMASS1.mtx.xz", DATA / "rotorDiscTestSTIF1.mtx.xz", "rotor-1"
    )
    unbalance = node_at_point(model.nodes, [0.0, 0.19598444, 0.15])
    model = model.with_scaled_stiffness(1e-2).with_node_mass(unbalance, 0.1)
    basis = free_free_basis(model, 8)
    left, right = (nodes_in_plane(model.nodes, [0, 0, z], [0, 0, 1]) for z in (0.0, 0.5))
    body = ReducedBody(
        model.nodes,
        model.mass,
        model.stiffness,
        basis.basis,
        left,
        np.full(len(left), 1.0 / len(left)),
        right,
        np.full(len(right), 1.0 / len(right)),
        length=0.5,
    )
    middle = node_at_point(model.nodes, [0.0, 0.0, 0.25])
    return SingleBodyScene(body, (middle, unbalance), omega_bar=OMEGA, t_end=0.01, step=1e-4, rho_inf=0.5)


def test_spinning_rotor_agrees_with_exudyn():
    """Measured: tracked nodes 2.4e-13 m apart (they move 0.39 m), Euler parameters 6e-13, modal
    coordinates 5e-12 of their largest value (the centrifugal deformation, zeta up to 5e-4)."""
    scene = rotor_scene()
    ours, theirs = ffrf_run(scene), exudyn_run(scene)
    np.testing.assert_allclose(ours.time, theirs.time, rtol=0, atol=1e-12)
    scale = np.abs(theirs.q[:, 7:]).max()
    assert scale > 1e-4  # the rotor does deform
    assert max_difference(tracked_nodes(ours), tracked_nodes(theirs)) < 2.5e-11
    assert max_difference(ours.q[:, 3:7], theirs.q[:, 3:7]) < 6e-11
    assert max_difference(ours.q[:, 7:], theirs.q[:, 7:]) < 5e-10 * scale


def test_centre_of_mass_moves_uniformly():
    """No external force: c(t) = c(0) + (omega x c(0)) t, c(0) 0.25 mm off the spin axis (the
    unbalance). Generalized-alpha keeps it to second order in h: measured drift 1.58e-7 m at
    h = 1e-4 and 3.96e-8 m at h = 5e-5 (ratio 4.0), the same in Exudyn to 1e-15 m."""
    scene = rotor_scene()
    drifts = []
    for step in (1e-4, 5e-5):
        run = ffrf_run(scene.with_step(step))
        com = centre_of_mass_path(scene.body, run)
        velocity = np.cross(OMEGA, com[0])
        assert np.linalg.norm(velocity) > 0.05  # the unbalance puts c off the spin axis
        drifts.append(np.abs(com - com[0] - np.outer(run.time, velocity)).max())
    assert drifts[0] < 1e-3 * 2.5e-4
    assert 3.5 < drifts[0] / drifts[1] < 4.5
    exudyn_com = centre_of_mass_path(scene.body, exudyn_run(scene))
    assert max_difference(centre_of_mass_path(scene.body, ffrf_run(scene)), exudyn_com) < 1e-12
