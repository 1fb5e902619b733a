"""Our HCB basis mode by mode against Exudyn's FEMinterface.ComputeHurtyCraigBamptonModes.

Both get the same nodes, M, K, boundary node sets and weights (RBE2,
excludeRigidBodyMotion=True). Exudyn's rotation columns have the opposite sign
and eigenvectors of repeated frequencies are an arbitrary basis of their
space, so static modes and repeated modes are compared as spaces (principal
angles), isolated modes by MAC.
"""

import numpy as np
import pytest
from reduction_fixtures import (
    bar_model,
    end_faces,
    exudyn_hcb,
    frequency_clusters,
    mac,
    max_principal_angle,
    plate_with_bores,
    reduced_elastic_frequencies_hz,
    surface_area_weights,
    symmetric_bar_model,
)

from ffrf.reduction.craig_bampton import craig_bampton


def case_data(name):
    if name == "bar, uniform weights":
        model = bar_model()
        interfaces = end_faces(model)
        return model, interfaces, [np.full(len(i), 1.0 / len(i)) for i in interfaces], 12
    if name == "square bar, repeated modes":
        model = symmetric_bar_model()
        interfaces = end_faces(model)
        return model, interfaces, [np.full(len(i), 1.0 / len(i)) for i in interfaces], 11  # clusters kept whole
    model, bores = plate_with_bores()
    return model, list(bores), [surface_area_weights(model, b) for b in bores], 16


@pytest.fixture(
    scope="module", params=["bar, uniform weights", "square bar, repeated modes", "plate with bores, area weights"]
)
def both(request):
    model, interfaces, weights, n_modes = case_data(request.param)
    ours = craig_bampton(model, interfaces, n_modes, weights)
    exudyn_basis, exudyn_frequencies = exudyn_hcb(model, interfaces, weights, n_modes)
    return model, ours, exudyn_basis, exudyn_frequencies


def test_same_mode_count_and_order(both):
    _, ours, exudyn_basis, _ = both
    assert ours.basis.shape == exudyn_basis.shape
    assert ours.n_static_modes == 6 * (len(ours.interfaces) - 1)


def test_fixed_interface_frequencies_equal(both):
    _, ours, _, exudyn_frequencies = both
    relative = np.abs(ours.fixed_interface_frequencies_hz / np.sort(exudyn_frequencies) - 1.0).max()
    assert relative < 5e-12  # measured 6.3e-14


def test_fixed_interface_modes_match(both):
    """MAC >= 1 - 3e-13 for isolated modes (measured 1 - 2.7e-15); principal angles < 1e-12 within clusters of
    repeated frequencies (measured 6.8e-15)."""
    _, ours, exudyn_basis, exudyn_frequencies = both
    s = ours.n_static_modes
    order = s + np.argsort(exudyn_frequencies)
    clusters = frequency_clusters(ours.fixed_interface_frequencies_hz)
    for group in clusters:
        if len(group) == 1:
            assert mac(ours.basis[:, s + group[0]], exudyn_basis[:, order[group[0]]]) >= 1.0 - 3e-13
        else:
            assert max_principal_angle(ours.basis[:, s + group], exudyn_basis[:, order[group]]) < 1e-12


def test_repeated_modes_are_present_in_the_symmetric_case(both):
    """Guard: the square bar must really exercise the cluster branch (else the check above is vacuous there)."""
    model, ours, _, _ = both
    if len(model.nodes) == len(symmetric_bar_model().nodes):
        assert any(len(g) > 1 for g in frequency_clusters(ours.fixed_interface_frequencies_hz))


def test_static_mode_spaces_identical(both):
    _, ours, exudyn_basis, _ = both
    s = ours.n_static_modes
    assert max_principal_angle(ours.basis[:, :s], exudyn_basis[:, :s]) < 5e-12  # measured 7.1e-14
    # Columns agree up to the sign convention of the rotations (Exudyn: u = (x - p0) x e_i).
    signs = np.array([1, 1, 1, -1, -1, -1] * (s // 6), dtype=float)
    difference = np.abs(ours.basis[:, :s] - exudyn_basis[:, :s] * signs).max()
    assert difference < 1e-11 * np.abs(ours.basis[:, :s]).max()  # measured 1.1e-13


def test_free_free_frequencies_of_both_reduced_models_equal(both):
    model, ours, exudyn_basis, _ = both
    n = 8
    assert np.allclose(
        reduced_elastic_frequencies_hz(model, ours.basis, n),
        reduced_elastic_frequencies_hz(model, exudyn_basis, n),
        rtol=5e-12,
        atol=0,
    )  # measured 5.4e-14
