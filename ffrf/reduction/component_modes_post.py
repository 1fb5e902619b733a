"""Post-processing of component modes: nodal displacements, P1 strains and stresses, and the
free-free frequencies of the reduced floating body.

The free-free check uses the FFRF mass matrix linearised about the undeformed
rest state (A = I, G = I, zeta = 0; Zwoelfer and Gerstmayr 2021, Acta Mech. 232,
mass matrix of sec. 4 evaluated at rest; ``docs/formulation.md`` eq. (INV-6)):

    M_0 = [[ m I3,           -m chi~,          M_PhitPsi   ],
           [ m chi~,          Theta,           -M_xTildePsi ],
           [ M_PhitPsi^T,    -M_xTildePsi^T,    M_red       ]],   K_0 = blockdiag(0, 0, K_red),

whose eigenvalues are 6 zeros (rigid motions) and the elastic free-free
eigenvalues of the reduced body. It is built from the inertia invariants only,
so it also checks them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigh

from ffrf.errors import ReductionError
from ffrf.numerics.small_linalg import skew
from ffrf.reduction.invariants import InertiaInvariants
from ffrf.reduction.mode_basis import ModeBasis

__all__ = [
    "mode_displacements",
    "displacement_gradients",
    "element_strains",
    "von_mises_stress",
    "linearized_ffrf_matrices",
    "free_free_frequencies_hz",
]


def mode_displacements(reduction: ModeBasis | NDArray, modes: ArrayLike | None = None) -> NDArray[np.float64]:
    """Nodal displacement vectors of modes (default: all), shape (n_selected, N, 3)."""
    basis = np.asarray(getattr(reduction, "basis", reduction))
    selected = np.arange(basis.shape[1]) if modes is None else np.atleast_1d(np.asarray(modes, dtype=np.int64))
    if selected.size and (selected.min() < -basis.shape[1] or selected.max() >= basis.shape[1]):
        raise ReductionError(f"mode index out of range: {selected.tolist()} for {basis.shape[1]} modes")
    return basis[:, selected].T.reshape(len(selected), -1, 3)


def displacement_gradients(nodes: ArrayLike, tets: ArrayLike, displacement: ArrayLike) -> NDArray[np.float64]:
    """Constant displacement gradient H_ij = du_i/dx_j of each linear tetrahedron, shape (n_tets, 3, 3).

    For P1 elements u is linear: H (p_k - p_0) = u_k - u_0 for k = 1, 2, 3.
    """
    nodes = np.asarray(nodes, dtype=float)
    tets = np.asarray(tets, dtype=np.int64)
    u = np.asarray(displacement, dtype=float).reshape(len(nodes), 3)
    edges = nodes[tets[:, 1:]] - nodes[tets[:, :1]]  # (n, 3 edges, 3): rows p_k - p_0
    du = u[tets[:, 1:]] - u[tets[:, :1]]  # (n, 3 edges, 3): rows u_k - u_0
    return np.swapaxes(np.linalg.solve(edges, du), 1, 2)  # edges H^T = du


def element_strains(nodes: ArrayLike, tets: ArrayLike, displacement: ArrayLike) -> NDArray[np.float64]:
    """Small-strain tensors eps = (H + H^T)/2 of each P1 tetrahedron, shape (n_tets, 3, 3)."""
    h = displacement_gradients(nodes, tets, displacement)
    return 0.5 * (h + np.swapaxes(h, 1, 2))


def von_mises_stress(strains: ArrayLike, E: float, nu: float) -> NDArray[np.float64]:
    """Von Mises equivalent stress of isotropic linear elastic strains (Hooke: sigma = 2 mu eps + lam tr(eps) I)."""
    eps = np.asarray(strains, dtype=float)
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    trace = np.trace(eps, axis1=-2, axis2=-1)
    sigma = 2 * mu * eps + lam * trace[..., None, None] * np.eye(3)
    deviator = sigma - np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3.0
    return np.sqrt(1.5 * np.sum(deviator * deviator, axis=(-2, -1)))


def linearized_ffrf_matrices(
    invariants: InertiaInvariants, reduced_stiffness: NDArray
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(M_0, K_0) of the floating reduced body at rest (module docstring, eq. (INV-6))."""
    m, n = invariants.mass, invariants.n_modes
    chi_tilde = skew(invariants.center_of_mass)
    mass = np.zeros((6 + n, 6 + n))
    mass[:3, :3] = m * np.eye(3)
    mass[:3, 3:6] = -m * chi_tilde
    mass[3:6, :3] = m * chi_tilde
    mass[3:6, 3:6] = invariants.theta
    mass[:3, 6:] = invariants.m_phit_psi
    mass[3:6, 6:] = -invariants.m_x_tilde_psi
    mass[6:, :6] = mass[:6, 6:].T
    mass[6:, 6:] = invariants.reduced_mass
    stiffness = np.zeros_like(mass)
    stiffness[6:, 6:] = reduced_stiffness
    return mass, stiffness


def free_free_frequencies_hz(reduction: ModeBasis, invariants: InertiaInvariants) -> NDArray[np.float64]:
    """Elastic free-free frequencies (Hz, ascending) of the reduced floating body.

    Needs a basis without rigid-body content (reference "interface" or "mean_axis");
    with "none" the rigid motions are in the basis twice and M_0 is singular.
    """
    if reduction.reference == "none":
        raise ReductionError(
            "free-free frequencies need reference conditions; recompute the reduction with "
            "reference='interface' or 'mean_axis'"
        )
    mass, stiffness = linearized_ffrf_matrices(invariants, reduction.reduced_stiffness)
    values = eigh(stiffness, mass, eigvals_only=True)
    return np.sqrt(np.clip(values[6:], 0.0, None)) / (2.0 * np.pi)
