"""Saving, reloading and reusing reduced bodies; post-processing of component modes."""

import numpy as np
import pytest
from reduction_fixtures import SmallFEModel, bar_model, end_faces

import ffrf.reduction.reduced_io as reduced_io
from ffrf.reduction.component_modes_post import element_strains, mode_displacements, von_mises_stress
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.reduction.invariants import inertia_invariants
from ffrf.reduction.reduced_io import (
    FORMAT_VERSION,
    ReducedBodyFileError,
    cached_craig_bampton,
    load_reduced_body,
    reduction_fingerprint,
    save_reduced_body,
)


@pytest.fixture(scope="module")
def bar():
    model = bar_model(divisions=(8, 2, 2))
    return model, end_faces(model)


def test_round_trip_is_exact(bar, tmp_path):
    model, faces = bar
    red = craig_bampton(model, faces, 5, reference="mean_axis", orthonormalize=True)
    inv = inertia_invariants(model, red)
    fingerprint = reduction_fingerprint(model, faces, 5, reference="mean_axis", orthonormalize=True)
    saved = load_reduced_body(save_reduced_body(tmp_path / "link.npz", red, fingerprint, inv), fingerprint)
    back = saved.reduction
    for name in ("basis", "fixed_interface_frequencies_hz", "reduced_mass", "reduced_stiffness"):
        assert np.array_equal(getattr(back, name), getattr(red, name)), name
    assert (back.n_static_modes, back.mode_labels, back.reference, back.orthonormalized) == (
        red.n_static_modes,
        red.mode_labels,
        red.reference,
        red.orthonormalized,
    )
    for a, b in zip(back.interfaces, red.interfaces, strict=True):
        assert np.array_equal(a.nodes, b.nodes) and np.array_equal(a.weights, b.weights)
        assert np.array_equal(a.center, b.center)
    assert saved.invariants.mass == inv.mass and np.array_equal(saved.invariants.m_psi_tilde_psi, inv.m_psi_tilde_psi)


def test_fingerprint_changes_with_every_input(bar):
    model, faces = bar
    base = reduction_fingerprint(model, faces, 5)
    stiffer = SmallFEModel(model.nodes, model.mass, model.stiffness * 1.001, model.tets)
    moved = SmallFEModel(model.nodes + 1e-9, model.mass, model.stiffness, model.tets)
    weights = [np.linspace(1, 2, len(f)) for f in faces]
    variants = [
        reduction_fingerprint(stiffer, faces, 5),
        reduction_fingerprint(moved, faces, 5),
        reduction_fingerprint(model, faces, 6),
        reduction_fingerprint(model, faces[::-1], 5),
        reduction_fingerprint(model, faces, 5, weights),
        reduction_fingerprint(model, faces, 5, orthonormalize=True),
    ]
    assert len({base, *variants}) == 1 + len(variants)
    assert reduction_fingerprint(model, faces, 5) == base  # deterministic


def test_mismatching_hash_and_version_are_rejected(bar, tmp_path):
    model, faces = bar
    red = craig_bampton(model, faces, 3)
    path = save_reduced_body(tmp_path / "a.npz", red, reduction_fingerprint(model, faces, 3))
    with pytest.raises(ReducedBodyFileError, match="another mesh"):
        load_reduced_body(path, reduction_fingerprint(model, faces, 4))
    with np.load(path) as data:
        content = dict(data)
    content["format_version"] = np.array("ffrf-hcb-npz-0")
    np.savez(tmp_path / "old.npz", **content)
    with pytest.raises(ReducedBodyFileError, match=FORMAT_VERSION):
        load_reduced_body(tmp_path / "old.npz")


def test_cache_reuses_and_recomputes(bar, tmp_path, monkeypatch):
    model, faces = bar
    path = tmp_path / "cache.npz"
    first = cached_craig_bampton(path, model, faces, 4)

    def fail(*args, **kwargs):
        raise AssertionError("recomputed although the stored body matches")

    monkeypatch.setattr(reduced_io, "craig_bampton", fail)
    again = cached_craig_bampton(path, model, faces, 4)
    assert np.array_equal(again.reduction.basis, first.reduction.basis) and again.invariants is not None
    monkeypatch.undo()
    changed = cached_craig_bampton(path, model, faces, 5)
    assert changed.reduction.n_modes == first.reduction.n_modes + 1
    assert load_reduced_body(path).fingerprint == changed.fingerprint


def test_mode_displacements_and_strains(bar, rng):
    model, faces = bar
    red = craig_bampton(model, faces, 3)
    shapes = mode_displacements(red, [0, 7])
    assert shapes.shape == (2, len(model.nodes), 3)
    assert np.array_equal(shapes[1].reshape(-1), red.basis[:, 7])
    # A linear field u = G x has the constant strain (G + G^T)/2 in every element.
    gradient = rng.normal(size=(3, 3))
    strains = element_strains(model.nodes, model.tets, model.nodes @ gradient.T)
    assert np.allclose(strains, 0.5 * (gradient + gradient.T), atol=1e-12)
    # Uniaxial stress state sigma_xx = s: strains s/E, -nu s/E, -nu s/E; von Mises = |s|.
    E, nu, s = 3.5e9, 0.36, 2e6
    eps = np.diag([s / E, -nu * s / E, -nu * s / E])
    assert np.isclose(von_mises_stress(eps, E, nu), s, rtol=1e-12)
