"""Free-free modes as a mode basis (``ffrf.reduction.free_free``; docs/formulation.md (FF-1)-(FF-3)).

Truth, never our own output: Exudyn 1.13.6's ``FEMinterface.ComputeEigenmodes(n,
excludeRigidBodyModes=6, useSparseSolver=True)`` on the Abaqus models of its TestModels; scipy's
dense ``eigh`` of the full (K, M); the Euler-Bernoulli free-free beam (cos(beta L) cosh(beta L) = 1,
Thomson, Theory of Vibration, App. D); and the rigid-body modes built from the node coordinates.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg
from reduction_fixtures import bar_model, end_faces, frequency_clusters
from scipy.linalg import eigh
from scipy.optimize import brentq

from ffrf.body.body_kernels import rotation_mode_coupling
from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.fe_model import FEModel, rigid_body_modes
from ffrf.fe.matrix_import import abaqus_model
from ffrf.fe.node_selection import node_at_point
from ffrf.mesh.tet_mesh import orient_positive
from ffrf.reduction.component_modes_post import free_free_frequencies_hz
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.reduction.free_free import FreeFreeBasis, free_free_basis, rigid_body_coupling
from ffrf.reduction.invariants import inertia_invariants
from ffrf.reduction.mode_basis import ModeBasis

DATA = Path(__file__).parents[2] / "validation" / "data" / "exudyn_testmodels"
#: model -> number of modes asked (a number that does not cut a pair of repeated frequencies)
CASES = {"rotor": 8, "C3D4": 7, "C3D10": 7, "C3D8": 7, "C3D20": 7}


@cache
def abaqus(name: str):
    """objectFFRFreducedOrderTest.py's rotor (0.1 kg unbalance, K x 0.01), or an abaqusImportTest block."""
    if name == "rotor":
        model = abaqus_model(
            DATA / "rotorDiscTest.inp",
            DATA / "rotorDiscTestMASS1.mtx.xz",
            DATA / "rotorDiscTestSTIF1.mtx.xz",
            "rotor-1",
        )
        node = node_at_point(model.nodes, [0.0, 0.19598444, 0.15])
        return model.with_scaled_stiffness(1e-2).with_node_mass(node, 0.1)
    stem = DATA / "abaqus" / f"block{name}"
    return abaqus_model(f"{stem}.inp", f"{stem}_MASS1.mtx.xz", f"{stem}_STIF1.mtx.xz", "block-1")


@cache
def exudyn_eigenmodes(name: str) -> tuple[np.ndarray, np.ndarray]:
    """Exudyn's free-free modes and frequencies of the same matrices."""
    from exudyn.FEM import FEMinterface

    model = abaqus(name)
    fem = FEMinterface()
    fem.nodes = {"Position": model.nodes}
    fem.massMatrix, fem.stiffnessMatrix = model.mass, model.stiffness
    fem.ComputeEigenmodes(CASES[name], excludeRigidBodyModes=6, useSparseSolver=True)
    return np.asarray(fem.modeBasis["matrix"]), np.asarray(fem.GetEigenFrequenciesHz())


@pytest.mark.parametrize("name", CASES)
def test_frequencies_and_modes_equal_exudyns(name):
    """Measured: frequencies to 2e-12 relative (Exudyn's ARPACK starts from a random vector, so its
    last digits vary from run to run: in a run where it converged less far, 2.3e-10, at 1 % of the residual bound
    of its own eigenpair, which the test then takes); every cluster of repeated frequencies spans Exudyn's modes to
    2e-9, or, where Exudyn's modes are less accurate than that in a run, to the Davis-Kahan bound of their
    own eigen-residual: sin(angle) <= |K phi - lambda M phi|_{M^-1} / gap (M-norm of the part of Exudyn's
    modes outside ours; seen: 3.5e-9 outside against a bound of 1.7e-7 for the C3D4 block's first pair)."""
    model = abaqus(name)
    ours = free_free_basis(model, CASES[name])
    theirs, frequencies = exudyn_eigenmodes(name)
    eigenvalues = (2.0 * np.pi * frequencies) ** 2
    mass = scipy.sparse.linalg.splu(scipy.sparse.csc_matrix(model.mass))
    # an exact eigenvalue lies within |K phi - lambda M phi|_{M^-1} / |phi|_M of Exudyn's lambda (Kahan's residual
    # bound): where Exudyn's run converged less far than 1e-10, ours must still lie inside that bound
    residual = model.stiffness @ theirs - (model.mass @ theirs) * eigenvalues
    bound = np.sqrt(np.einsum("ij,ij->j", residual, mass.solve(residual))) / np.sqrt(
        np.einsum("ij,ij->j", theirs, model.mass @ theirs)
    )
    ours_eigenvalues = (2.0 * np.pi * ours.frequencies_hz) ** 2
    assert np.all(np.abs(ours_eigenvalues - eigenvalues) <= np.maximum(2e-10 * eigenvalues, bound))
    for cluster in frequency_clusters(frequencies, rel_gap=1e-8):
        psi, phi = ours.basis[:, cluster], theirs[:, cluster]
        outside = phi - psi @ (psi.T @ (model.mass @ phi))
        residual = model.stiffness @ phi - (model.mass @ phi) * eigenvalues[cluster]
        others = np.delete(eigenvalues, cluster)
        gap = np.min(np.abs(others - eigenvalues[cluster][0])) if others.size else np.inf
        davis_kahan = np.sqrt(np.max(np.einsum("ij,ij->j", residual, mass.solve(residual)))) / gap
        assert np.sqrt(np.max(np.einsum("ij,ij->j", outside, model.mass @ outside))) < max(2e-9, davis_kahan), cluster


@pytest.mark.parametrize("name", CASES)
def test_modes_are_mass_orthonormal_and_free_of_rigid_motion(name):
    """(FF-3): R^T M Psi = 0 with R built from the node coordinates. Measured: 5e-14 (cosines);
    Psi^T M Psi = I to 2.3e-15, Psi^T K Psi = diag(omega^2) to 2.6e-14; the rigid modes left out
    have |omega^2| below 7e-14 of the first elastic omega^2."""
    model = abaqus(name)
    ours = free_free_basis(model, CASES[name])
    rigid = rigid_body_modes(model.nodes)
    rigid = rigid @ np.linalg.inv(np.linalg.cholesky(rigid.T @ (model.mass @ rigid))).T  # M-orthonormal
    assert np.abs(rigid.T @ (model.mass @ ours.basis)).max() < 3e-12
    assert ours.reference_residual < 3e-12
    np.testing.assert_allclose(ours.reduced_mass, np.eye(ours.n_modes), rtol=0, atol=2e-13)
    np.testing.assert_allclose(
        np.diag(ours.reduced_stiffness), (2 * np.pi * ours.frequencies_hz) ** 2, rtol=3e-12, atol=0
    )
    assert np.abs(ours.rigid_body_eigenvalues).max() < 1e-11 * (2 * np.pi * ours.frequencies_hz[0]) ** 2


def test_the_reference_condition_check_can_fail():
    """A Craig-Bampton basis attached to one end face moves the centre of mass: its coupling is O(1)."""
    model = bar_model()
    cb = craig_bampton(model, end_faces(model), 4)
    assert np.abs(rigid_body_coupling(model.nodes, model.mass, cb.basis)).max() > 0.1


def test_frequencies_equal_dense_eigh_of_the_full_model():
    """A 612-DOF P1 bar (Lanczos path): scipy.linalg.eigh of the full (K, M), rigid modes dropped.
    Measured: 1e-12 relative."""
    model = bar_model()
    values = eigh(model.stiffness.toarray(), model.mass.toarray(), eigvals_only=True, subset_by_index=[0, 17])
    expected = np.sqrt(values[6:]) / (2 * np.pi)
    ours = free_free_basis(model, 12)
    assert 3 * len(model.nodes) > 600  # not the dense path of lowest_eigenpairs
    np.testing.assert_allclose(ours.frequencies_hz, expected, rtol=1e-10)


@cache
def _beam(h: float):
    """Steel bar 400 x 20 x 10 mm (x, y, z), quadratic tetrahedra of edge h."""
    from skfem import MeshTet

    length, width, thick = 0.4, 0.02, 0.01
    mesh = MeshTet.init_tensor(
        np.linspace(0, length, round(length / h) + 1),
        np.linspace(0, width, max(round(width / h), 1) + 1),
        np.linspace(0, thick, max(round(thick / h), 1) + 1),
    )
    tets = orient_positive(mesh.p.T, mesh.t.T)  # scikit-fem's tensor mesh mixes both node orders
    model = FEModel.from_mesh(mesh.p.T, tets, 2.1e11, 0.3, 7850.0, order=2)
    return model, free_free_basis(model, 1)


def test_first_bending_frequency_converges_to_the_beam_closed_form():
    """Free-free bending in z (the thin direction): Euler-Bernoulli f1 = (beta L)^2 / (2 pi L^2)
    sqrt(E I / (rho A)), cos(beta L) cosh(beta L) = 1 (beta L = 4.73004), and Timoshenko's beam
    (shear and rotary inertia, ``tests/test_fe_models/ffrf_reference.py``), 0.23 % lower at L/t = 40.
    Measured (P2): +0.040 % at h = 10 mm, +0.012 % at h = 5 mm above Timoshenko (converging from
    above, as a Rayleigh-Ritz bound); 0.19 % and 0.22 % below Euler-Bernoulli."""
    from test_fe_models.ffrf_reference import timoshenko_bending_frequencies

    beta_l = brentq(lambda x: np.cos(x) * np.cosh(x) - 1.0, 4.0, 5.0)
    length, width, thick, e_modulus, rho = 0.4, 0.02, 0.01, 2.1e11, 7850.0
    inertia = width * thick**3 / 12.0
    euler_bernoulli = beta_l**2 / (2 * np.pi * length**2) * np.sqrt(e_modulus * inertia / (rho * width * thick))
    timoshenko = timoshenko_bending_frequencies(e_modulus, 0.3, rho, width * thick, inertia, length, "free-free", n=1)
    coarse, fine = (_beam(h)[1].frequencies_hz[0] for h in (0.01, 0.005))
    assert timoshenko[0] < fine < coarse < euler_bernoulli
    assert fine / timoshenko[0] - 1.0 < 0.5 * (coarse / timoshenko[0] - 1.0)
    assert fine / timoshenko[0] - 1.0 < 1e-3
    assert fine / euler_bernoulli - 1.0 == pytest.approx(-0.0022, abs=5e-4)


@pytest.mark.parametrize("name", ["rotor", "C3D10"])
def test_a_flexible_body_takes_the_basis_and_keeps_its_frequencies(name):
    """Built as the scene builder builds a Craig-Bampton body. The floating body linearised at rest
    (eq. (INV-6), from the inertia invariants) has Exudyn's free-free frequencies, and its first
    moment and the rotation-mode coupling at rest do not depend on the modes (S1 = 0, M_wz(0) = 0;
    (FF-3)). Measured: frequencies to 7e-14 (to 1.3e-14 against the basis' own), |S1| / (m L) below
    5.4e-15, |M_wz(0)| / (m L^2) below 1.5e-15."""
    model = abaqus(name)
    ours = free_free_basis(model, CASES[name])
    assert isinstance(ours, ModeBasis) and isinstance(ours, FreeFreeBasis)
    moments = modal_moments(model.nodes, model.mass, ours.basis)
    body = FlexibleBody(name, moments, ours.reduced_stiffness, ours.reduced_damping(0.005))
    assert body.n_coordinates == 7 + CASES[name]
    size = np.ptp(model.nodes, axis=0).max()
    assert np.abs(moments.s1).max() < 5e-13 * moments.mass * size
    coupling = rotation_mode_coupling(np.zeros(ours.n_modes), moments.c, moments.d)  # eq. (F7) at zeta = 0
    assert np.abs(coupling).max() < 5e-13 * moments.mass * size**2
    linearised = free_free_frequencies_hz(ours, inertia_invariants(model, ours))
    np.testing.assert_allclose(linearised, exudyn_eigenmodes(name)[1], rtol=1e-10)


def test_scaled_stiffness_scales_the_frequencies_by_its_root():
    """(X3): K x 0.01 gives frequencies x 0.1, the same modes. Measured: 7e-15 and 5e-12."""
    model = abaqus("C3D10")
    stiff, soft = free_free_basis(model, 7), free_free_basis(model.with_scaled_stiffness(0.01), 7)
    np.testing.assert_allclose(soft.frequencies_hz, 0.1 * stiff.frequencies_hz, rtol=1e-12)
    np.testing.assert_allclose(soft.basis, stiff.basis, rtol=0, atol=5e-10 * np.abs(stiff.basis).max())


def test_the_solve_is_repeatable_to_the_bit():
    model = abaqus("C3D4")
    first, second = free_free_basis(model, 7), free_free_basis(model, 7)
    np.testing.assert_array_equal(first.basis, second.basis)
    np.testing.assert_array_equal(first.frequencies_hz, second.frequencies_hz)
