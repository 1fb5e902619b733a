"""Stress recovery (``ffrf.reduction.component_modes_post``, ``ffrf.output.assembly_stress``) against hand formulas:
von Mises from the principal-free formula on closed-form stress states, and a bar in uniform tension
solved by the FE model, whose stress is E times the strain in every element."""

import numpy as np
import pytest
import skfem

from ffrf.fe.fe_model import FEModel
from ffrf.mesh.tet_mesh import orient_positive
from ffrf.output.assembly_stress import element_von_mises
from ffrf.reduction.component_modes_post import von_mises_stress

E, NU = 3.5e9, 0.36


def strain_of(stress: np.ndarray) -> np.ndarray:
    """Hooke's law in compliance form: eps = ((1 + nu) sigma - nu tr(sigma) I) / E."""
    return ((1 + NU) * stress - NU * np.trace(stress) * np.eye(3)) / E


def hand_von_mises(s: np.ndarray) -> float:
    """sqrt(((s11 - s22)^2 + (s22 - s33)^2 + (s33 - s11)^2) / 2 + 3 (s12^2 + s23^2 + s31^2))."""
    normal = (s[0, 0] - s[1, 1]) ** 2 + (s[1, 1] - s[2, 2]) ** 2 + (s[2, 2] - s[0, 0]) ** 2
    shear = s[0, 1] ** 2 + s[1, 2] ** 2 + s[2, 0] ** 2
    return float(np.sqrt(0.5 * normal + 3.0 * shear))


@pytest.mark.parametrize(
    "stress, expected",
    [
        (np.diag([2e6, 0.0, 0.0]), 2e6),  # uniaxial: |sigma|
        (np.diag([-3e6, 0.0, 0.0]), 3e6),  # compression: |sigma|
        (np.array([[0, 1e6, 0], [1e6, 0, 0], [0, 0, 0]]), np.sqrt(3) * 1e6),  # pure shear: sqrt(3) tau
        (np.diag([5e6, 5e6, 5e6]), 0.0),  # hydrostatic: none
        (np.diag([1e6, -1e6, 0.0]), np.sqrt(3) * 1e6),  # shear in principal axes
    ],
)
def test_von_mises_of_closed_form_states(stress, expected):
    # Pa, about 100x the largest error measured on 2026-11-24: 4.7e-10 Pa (2.3e-16 of 2 MPa); 0 for hydrostatic.
    assert von_mises_stress(strain_of(stress), E, NU) == pytest.approx(expected, rel=0, abs=5e-8)


def test_von_mises_of_a_general_state_equals_the_hand_formula(rng):
    for _ in range(20):
        a = rng.normal(size=(3, 3)) * 1e6
        stress = a + a.T
        # measured at most 2.2e-16 relative (2026-11-24)
        assert von_mises_stress(strain_of(stress), E, NU) == pytest.approx(hand_von_mises(stress), rel=2e-14)


def test_bar_in_uniform_tension_has_e_times_strain_in_every_element():
    """Symmetry planes x = 0, y = 0, z = 0 and the end x = L pulled by eps L: the exact solution is
    uniaxial stress E eps, a linear field that P1 elements reproduce, so every element shows it."""
    length, strain = 0.1, 1e-4
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, length, 6), np.linspace(0, 0.02, 3), np.linspace(0, 0.01, 3))
    model = FEModel.from_mesh(mesh.p.T, orient_positive(mesh.p.T, mesh.t.T), E=E, nu=NU, rho=1000.0)
    x = model.nodes
    fixed = np.concatenate(
        [
            3 * np.flatnonzero(x[:, 0] < 1e-12),
            3 * np.flatnonzero(x[:, 0] > length - 1e-12),
            3 * np.flatnonzero(x[:, 1] < 1e-12) + 1,
            3 * np.flatnonzero(x[:, 2] < 1e-12) + 2,
        ]
    )
    prescribed = np.zeros(model.n_dofs)
    prescribed[3 * np.flatnonzero(x[:, 0] > length - 1e-12)] = strain * length
    u = skfem.solve(*skfem.condense(model.stiffness, np.zeros(model.n_dofs), x=prescribed, D=fixed))
    von_mises = element_von_mises(x, model.mesh.tets, u.reshape(-1, 3), E, NU)
    np.testing.assert_allclose(von_mises, E * strain, rtol=5e-13)  # measured 4.4e-15 (2026-11-24, AMD EPYC)
    # Poisson contraction, m: measured 2.8e-21 (y) and 1.6e-21 (z), about 20 ulp of the 7e-7 m contraction
    np.testing.assert_allclose(u[1::3], -NU * strain * x[:, 1], rtol=0, atol=3e-19)
    np.testing.assert_allclose(u[2::3], -NU * strain * x[:, 2], rtol=0, atol=3e-19)
