"""HCB reduction against HCB theory and the full FE model (no Exudyn here).

Independent truths: dense eigen-decompositions of the clamped interior, a
Lagrange-multiplier solution of the full model with rigid interfaces, the full
model's free-free frequencies, and hand-built rigid motions.
"""

import logging

import numpy as np
import pytest
import scipy.sparse as sp
from reduction_fixtures import (
    SmallFEModel,
    assemble,
    bar_model,
    end_faces,
    full_free_free_frequencies_hz,
    max_principal_angle,
    plate_with_bores,
    reduced_elastic_frequencies_hz,
    rigid_interface_free_free_frequencies_hz,
    rigid_interface_transformation,
    surface_area_weights,
)
from scipy.linalg import eigh
from scipy.sparse.linalg import splu, spsolve

from ffrf.errors import FEInputError, InterfaceError, ReductionError
from ffrf.numerics.eigen import count_eigenvalues_below, lowest_eigenpairs
from ffrf.reduction.component_modes_post import free_free_frequencies_hz
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.reduction.invariants import inertia_invariants


def dofs(nodes):
    return (3 * np.asarray(nodes)[:, None] + np.arange(3)).reshape(-1)


def hand_rigid_motion(points, center, translation, rotation):
    """u = t + w x (x - c), written out independently of the library."""
    return (translation + np.cross(rotation, points - center)).reshape(-1)


@pytest.fixture(scope="module")
def plate():
    model, bores = plate_with_bores()
    return model, list(bores), [surface_area_weights(model, b) for b in bores]


def test_columns_vanish_on_frame_interface_and_move_rigidly_on_the_other(plate):
    model, bores, weights = plate
    red = craig_bampton(model, bores, 6, weights)
    assert red.basis.shape == (3 * len(model.nodes), 12) and red.n_static_modes == 6
    assert np.abs(red.basis[dofs(bores[0])]).max() == 0.0
    # Static mode i of interface 1 is the unit rigid motion e_i there; eigenmodes vanish there.
    center = weights[1] @ model.nodes[bores[1]]
    for i in range(6):
        t, w = np.eye(6)[i, :3], np.eye(6)[i, 3:]
        expected = hand_rigid_motion(model.nodes[bores[1]], center, t, w)
        assert np.allclose(red.basis[dofs(bores[1]), i], expected, rtol=0, atol=1e-14)
    assert np.abs(red.basis[dofs(bores[1]), 6:]).max() == 0.0
    assert red.mode_labels[:6] == tuple(f"interface 1 {c}" for c in ("tx", "ty", "tz", "rx", "ry", "rz"))


def test_fixed_interface_modes_equal_dense_clamped_eigenproblem():
    model = bar_model()
    faces = end_faces(model)
    red = craig_bampton(model, faces, 10)
    free = np.setdiff1d(np.arange(3 * len(model.nodes)), dofs(np.concatenate(faces)))
    k, m = model.stiffness.toarray()[np.ix_(free, free)], model.mass.toarray()[np.ix_(free, free)]
    expected = np.sqrt(eigh(k, m, eigvals_only=True, subset_by_index=[0, 9])) / (2 * np.pi)
    assert np.allclose(red.fixed_interface_frequencies_hz, expected, rtol=1e-10, atol=0)
    phi = red.basis[:, 6:]
    assert np.allclose(phi.T @ model.mass @ phi, np.eye(10), atol=1e-12)
    residual = model.stiffness @ phi - model.mass @ phi * (2 * np.pi * red.fixed_interface_frequencies_hz) ** 2
    assert np.abs(residual[free]).max() < 1e-7 * np.abs(model.stiffness @ phi).max()


def test_sparse_lanczos_path_equals_reference_eigsh(plate):
    """The plate's interior exceeds the dense limit: shift-invert Lanczos with reused LU + Sturm check,
    against plain scipy eigsh (own factorisation, more modes) on the clamped interior."""
    from scipy.sparse.linalg import eigsh

    model, bores, weights = plate
    red = craig_bampton(model, bores, 8, weights)
    free = np.setdiff1d(np.arange(3 * len(model.nodes)), dofs(np.concatenate(bores)))
    assert len(free) > 600
    k, m = model.stiffness[free][:, free].tocsc(), model.mass[free][:, free].tocsc()
    values, vectors = eigsh(k, k=14, M=m, sigma=0, which="LM", tol=1e-14)
    order = np.argsort(values)[:8]
    assert np.allclose(red.fixed_interface_frequencies_hz, np.sqrt(values[order]) / (2 * np.pi), rtol=1e-10, atol=0)
    assert max_principal_angle(red.basis[free, 6:], vectors[:, order]) < 1e-8


def solve_full_with_rigid_interfaces(model, clamped, loaded, weights, load):
    """Full model, ``clamped`` nodes fixed and ``loaded`` nodes rigid, by hand-built constraint elimination."""
    t = rigid_interface_transformation(model, [loaded], [weights], clamped=clamped)
    return t @ spsolve((t.T @ model.stiffness @ t).tocsc(), t.T @ load)


@pytest.mark.parametrize("n_modes", [0, 6])
def test_static_modes_reproduce_static_deflection_under_interface_load_exactly(plate, rng, n_modes):
    model, bores, weights = plate
    load = np.zeros(3 * len(model.nodes))
    load[dofs(bores[1])] = rng.normal(size=3 * len(bores[1]))  # any nodal load on the rigid interface
    full = solve_full_with_rigid_interfaces(model, bores[0], bores[1], weights[1], load)
    red = craig_bampton(model, bores, n_modes, weights)
    reduced = red.basis @ np.linalg.solve(red.reduced_stiffness, red.basis.T @ load)
    assert np.abs(reduced - full).max() < 1e-9 * np.abs(full).max()


def test_static_modes_alone_are_not_exact_for_interior_loads(plate, rng):
    """The same check must be able to fail: an interior load needs the fixed-interface modes."""
    model, bores, weights = plate
    load = np.zeros(3 * len(model.nodes))
    interior = np.setdiff1d(np.arange(len(model.nodes)), np.concatenate(bores))
    load[dofs(interior[::7])] = rng.normal(size=3 * len(interior[::7]))
    full = solve_full_with_rigid_interfaces(model, bores[0], bores[1], weights[1], load)
    red = craig_bampton(model, bores, 0, weights)
    reduced = red.basis @ np.linalg.solve(red.reduced_stiffness, red.basis.T @ load)
    assert np.abs(reduced - full).max() > 1e-3 * np.abs(full).max()


def test_free_free_frequencies_converge_to_full_model_with_rigid_interfaces(plate):
    """HCB with RBE2 interfaces converges to the full model whose interfaces are rigid (its exact limit);
    the unconstrained full model stays a lower bound (the rigid bores stiffen the body)."""
    model, bores, weights = plate
    limit = rigid_interface_free_free_frequencies_hz(model, bores, weights, 6)
    unconstrained = full_free_free_frequencies_hz(model, 6)
    errors = []
    for n_modes in (0, 4, 8, 16, 32):
        reduced = reduced_elastic_frequencies_hz(model, craig_bampton(model, bores, n_modes, weights).basis, 6)
        assert np.all(reduced > unconstrained * (1 - 1e-9))
        errors.append(reduced / limit - 1.0)
    errors = np.array(errors)
    assert np.all(errors > -1e-9)  # Rayleigh-Ritz: reduced frequencies are upper bounds
    assert np.all(np.diff(errors, axis=0) < 1e-9)  # nested bases: never worse with more modes
    assert errors[-1, :5].max() < 1e-3 and errors[-1].max() < 1e-2 and np.all(errors[-1] < 0.1 * errors[0])


@pytest.mark.parametrize("reference", ["interface", "mean_axis"])
def test_free_free_frequencies_from_invariants_equal_direct_rayleigh_ritz(plate, reference):
    model, bores, weights = plate
    red = craig_bampton(model, bores, 8, weights, reference=reference)
    from_invariants = free_free_frequencies_hz(red, inertia_invariants(model, red))
    direct = reduced_elastic_frequencies_hz(model, red.basis, len(from_invariants))
    assert np.allclose(from_invariants, direct, rtol=1e-9, atol=0)


def test_reference_conditions_and_orthonormalisation_keep_the_span_with_rigid_motions(plate):
    model, bores, weights = plate
    base = craig_bampton(model, bores, 8, weights)
    mean_axis = craig_bampton(model, bores, 8, weights, reference="mean_axis")
    ortho = craig_bampton(model, bores, 8, weights, orthonormalize=True)
    none = craig_bampton(model, bores, 8, weights, reference="none")
    x = model.nodes
    rigid = np.column_stack([hand_rigid_motion(x, np.zeros(3), e[:3], e[3:]) for e in np.eye(6)])
    span = np.hstack([rigid, base.basis])
    for other in (mean_axis, ortho):
        assert max_principal_angle(np.hstack([rigid, other.basis]), span) < 1e-8
    assert max_principal_angle(none.basis, span) < 1e-8 and none.n_modes == base.n_modes + 6
    # Mean-axis (linearised Tisserand) conditions: no linear or angular momentum from elastic motion.
    momentum = rigid.T @ (model.mass @ mean_axis.basis)
    assert np.abs(momentum).max() < 1e-12 * np.abs(rigid.T @ (model.mass @ base.basis)).max()
    assert np.allclose(ortho.reduced_mass, np.eye(ortho.n_modes), atol=1e-10)
    k = ortho.reduced_stiffness
    assert np.abs(k - np.diag(np.diag(k))).max() < 1e-9 * np.abs(k).max() and np.all(np.diff(np.diag(k)) >= 0)
    assert np.abs(ortho.basis[dofs(bores[0])]).max() < 1e-12  # frame interface condition kept
    assert np.sum(np.abs(np.linalg.eigvalsh(none.reduced_stiffness)) < 1e-8 * np.abs(k).max()) == 6


def test_reduced_damping_is_stiffness_proportional():
    red = craig_bampton(bar_model(), end_faces(bar_model()), 4)
    assert np.array_equal(red.reduced_damping(0.005), 0.005 * red.reduced_stiffness)
    with pytest.raises(ReductionError, match="beta"):
        red.reduced_damping(-1.0)


def diagonal_problem(multiplicity: int, size: int = 2400):
    values = np.repeat(np.arange(1.0, size // multiplicity + 1.0), multiplicity)[:size]
    return sp.diags(values).tocsc(), sp.identity(size, format="csc"), values


@pytest.mark.parametrize("multiplicity", [2, 3, 4])
def test_repeated_eigenvalues_are_not_lost(multiplicity):
    k, m, values = diagonal_problem(multiplicity)
    n = 5 * multiplicity  # clusters kept whole
    lu = splu(k)
    found, vectors = lowest_eigenpairs(k, m, n, lu.solve)
    assert np.allclose(found, values[:n], rtol=1e-12, atol=0)
    assert np.allclose(vectors.T @ vectors, np.eye(n), atol=1e-10)
    assert count_eigenvalues_below(k, m, 5.5) == 5 * multiplicity


def test_cutting_a_cluster_is_reported(caplog):
    k, m, values = diagonal_problem(3)
    with caplog.at_level(logging.WARNING, logger="ffrf.reduction.craig_bampton"):
        found, _ = lowest_eigenpairs(k, m, 4, splu(k).solve)
    assert np.allclose(found, values[:4])
    assert "same frequency" in caplog.text


def line_interfaces(model):
    """Two node sets on the same straight edge (y = z = 0): rotation about that edge is unrestrained."""
    on_edge = np.flatnonzero(np.isclose(model.nodes[:, 1], 0) & np.isclose(model.nodes[:, 2], 0))
    return [on_edge[:3], on_edge[-3:]]


def with_floating_tet(model):
    """The bar plus one tetrahedron not connected to it: its motion is not restrained by any interface."""
    extra = np.array([[1.0, 1.0, 1.0], [1.01, 1.0, 1.0], [1.0, 1.01, 1.0], [1.0, 1.0, 1.01]])
    points = np.vstack([model.nodes, extra])
    tets = np.vstack([model.tets, len(model.nodes) + np.arange(4)[None]])
    return assemble(points, tets)


@pytest.mark.parametrize(
    "case, error, match",
    [
        ("empty", InterfaceError, "empty node set"),
        ("overlap", InterfaceError, "overlaps"),
        ("out_of_range", InterfaceError, "out of range"),
        ("collinear", ReductionError, "interfaces do not restrain the body"),
        ("floating_part", ReductionError, "interfaces do not restrain the body"),
        ("too_many_modes", ReductionError, "too many modes"),
        ("nan_mass", ReductionError, "NaN"),
        ("weights_length", InterfaceError, "weights for"),
        ("reference", ReductionError, "reference"),
        ("no_interfaces", InterfaceError, "no interfaces"),
    ],
)
def test_clear_errors(case, error, match):
    model = bar_model()
    faces = end_faces(model)
    args = {"fe_model": model, "interfaces": faces, "n_modes": 2}
    if case == "empty":
        args["interfaces"] = [faces[0], np.array([], dtype=int)]
    elif case == "overlap":
        args["interfaces"] = [faces[0], np.concatenate([faces[1], faces[0][:1]])]
    elif case == "out_of_range":
        args["interfaces"] = [faces[0], np.array([0, len(model.nodes)])]
    elif case == "collinear":
        args["interfaces"] = line_interfaces(model)
    elif case == "floating_part":
        args["fe_model"] = with_floating_tet(model)
    elif case == "too_many_modes":
        args["n_modes"] = 3 * len(model.nodes)
    elif case == "nan_mass":
        mass = model.mass.copy()
        mass.data[5] = np.nan
        args["fe_model"] = SmallFEModel(model.nodes, mass, model.stiffness, model.tets)
    elif case == "weights_length":
        args["weights"] = [np.ones(3), np.ones(len(faces[1]))]
    elif case == "reference":
        args["reference"] = "tisserand-exact"
    elif case == "no_interfaces":
        args["interfaces"] = []
    with pytest.raises(error, match=match):
        craig_bampton(**args)
    assert issubclass(error, FEInputError)


def test_accepts_the_team_fe_model_and_interface_objects():
    """ffrf.fe.fe_model.FEModel and ffrf.fe.interfaces-style objects (``.nodes``, ``.weights``) work unchanged."""
    from ffrf.fe.fe_model import FEModel
    from ffrf.mesh.tet_mesh import orient_positive

    reference = bar_model()
    tets = orient_positive(reference.nodes, reference.tets)
    team = FEModel.from_mesh(reference.nodes, tets, 3.5e9, 0.36, 1250.0)

    class Interface:  # duck-typed like ffrf.fe.interfaces.InterfaceNodes
        def __init__(self, nodes):
            self.nodes, self.weights = nodes, np.full(len(nodes), 1.0 / len(nodes))

    faces = end_faces(reference)
    ours = craig_bampton(reference, faces, 4)
    theirs = craig_bampton(team, [Interface(f) for f in faces], 4)
    assert np.allclose(theirs.fixed_interface_frequencies_hz, ours.fixed_interface_frequencies_hz, rtol=1e-10)
    assert max_principal_angle(theirs.basis, ours.basis) < 1e-8
