"""Inertia invariants (shape integrals) of a modally reduced FFRF body.

With the consistent mass matrix M, reference nodal positions x (3N, about the
body-frame origin = FE mesh origin, as in Exudyn), the mode matrix Psi (3N, m),
Phi_t = kron(ones(N), I3)^T (3N, 3) and the "nodal tilde" a~ of a 3N-vector
(3N, 3; node blocks Skew(a_i), Skew(v) w = v x w), the invariants are
(Zwoelfer and Gerstmayr 2021, Acta Mech. 232, sec. 3 and 4; ``docs/formulation.md``
eqs. (INV-1) to (INV-4)):

    m = 1^T M_s 1,  chi = Phi_t^T M x / m,  Theta = x~^T M x~,
    M_PsiTildePsi = Psi~^T M Psi (3m, m),  M_PsiTildePsiTilde = Psi~^T M Psi~ (3m, 3m),
    M_PhitPsi = Phi_t^T M Psi (3, m),  M_PhitPsiTilde = Phi_t^T M Psi~ (3, 3m),
    M_xTildePsi = x~^T M Psi (3, m),  M_xTildePsiTilde = x~^T M Psi~ (3, 3m),

where Psi~ (3N, 3m) holds the nodal tilde of column j in columns 3j..3j+2. No
lumped mass is used. For the usual FE mass M = M_s kron I3 (isotropic: the same
scalar mass for x, y and z, no coupling) every invariant is a signed sum of
the Gram matrices G_cd = W_c^T M_s W_d of W = [1, x_c, Psi_c] (per-component
rows), eq. (INV-5); that avoids the dense Psi~ and costs one sparse product
M_s W. Other mass matrices use a general path that forms Psi~ explicitly.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ffrf.errors import ReductionError
from ffrf.reduction.craig_bampton import checked_model

__all__ = ["InertiaInvariants", "inertia_invariants", "is_isotropic_mass", "component_gram", "nodal_tilde"]

logger = logging.getLogger(__name__)

# Entries below this fraction of max|M| count as zero when testing M = M_s kron I3.
_ISOTROPY_REL_TOL = 1e-14

_LEVI_CIVITA = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _LEVI_CIVITA[_i, _j, _k], _LEVI_CIVITA[_i, _k, _j] = 1.0, -1.0


@dataclass(frozen=True, eq=False)
class InertiaInvariants:
    """Constant inertia data of a reduced FFRF body (body frame = FE mesh frame).

    Attributes
    ----------
    mass : total mass m (kg).
    center_of_mass : chi (3,), frame coordinates (m).
    inertia_tensor : (3, 3) about the centre of mass, frame axes (kg m^2).
    theta : (3, 3) x~^T M x~, inertia about the frame origin.
    reduced_mass : (m, m) Psi^T M Psi.
    m_phit_psi, m_phit_psi_tilde, m_x_tilde_psi, m_x_tilde_psi_tilde, m_psi_tilde_psi,
    m_psi_tilde_psi_tilde : the six invariant matrices (module docstring), Exudyn's
        mPhitTPsi, mPhitTPsiTilde, mXRefTildePsi, mXRefTildePsiTilde, mPsiTildePsi, mPsiTildePsiTilde.
    """

    mass: float
    center_of_mass: NDArray[np.float64]
    inertia_tensor: NDArray[np.float64]
    theta: NDArray[np.float64]
    reduced_mass: NDArray[np.float64]
    m_phit_psi: NDArray[np.float64]
    m_phit_psi_tilde: NDArray[np.float64]
    m_x_tilde_psi: NDArray[np.float64]
    m_x_tilde_psi_tilde: NDArray[np.float64]
    m_psi_tilde_psi: NDArray[np.float64]
    m_psi_tilde_psi_tilde: NDArray[np.float64]

    @property
    def n_modes(self) -> int:
        return self.reduced_mass.shape[0]


def nodal_tilde(vectors: NDArray) -> NDArray[np.float64]:
    """Nodal tilde of a 3N-vector (-> (3N, 3)) or of each column of a (3N, m) matrix (-> (3N, 3m)).

    Node block i of column j is Skew(v_i) with Skew(v) w = v x w, as Exudyn's
    ``ComputeSkewMatrix``; Skew(v)[b, a] = eps_abc v_c.
    """
    v = np.asarray(vectors, dtype=float)
    columns = v.reshape(len(v) // 3, 3, -1)  # (N, 3, m)
    # tilde[i, b, j, a] = Skew(v_ij)[b, a] = sum_c eps[a, b, c] v[i, c, j]
    tilde = np.einsum("abc,icj->ibja", _LEVI_CIVITA, columns)
    return tilde.reshape(len(v), 3 * columns.shape[2])


def is_isotropic_mass(mass: sp.spmatrix) -> bool:
    """True if M = M_s kron I3: no x-y-z coupling and equal component blocks (to round-off)."""
    coo = sp.coo_matrix(mass)
    tol = _ISOTROPY_REL_TOL * (np.abs(coo.data).max() if coo.nnz else 1.0)
    if np.any(np.abs(coo.data[coo.row % 3 != coo.col % 3]) > tol):
        return False
    csr = sp.csr_matrix(mass)
    blocks = [csr[c::3, c::3] for c in range(3)]
    return all(abs(blocks[0] - b).max() <= tol for b in blocks[1:])


def component_gram(nodes: NDArray, mass: sp.spmatrix, psi: NDArray) -> NDArray[np.float64]:
    """Eq. (INV-5): G = W^T M_s W with W = [1, x_0, x_1, x_2, Psi_0, Psi_1, Psi_2] (component rows)
    and the scalar mass M_s of an isotropic M = M_s kron I3; one sparse product."""
    scalar_mass = sp.csr_matrix(mass)[0::3, 0::3]
    w = np.hstack([np.ones((len(nodes), 1)), nodes, psi[0::3], psi[1::3], psi[2::3]])
    g = w.T @ (scalar_mass @ w)
    return 0.5 * (g + g.T)


def inertia_invariants(fe_model: Any, basis: Any, *, isotropic: bool | None = None) -> InertiaInvariants:
    """Inertia invariants of ``fe_model`` (``.nodes``, ``.mass``, ``.stiffness``) reduced by ``basis``.

    Parameters
    ----------
    fe_model : duck-typed FE model; only ``.nodes`` and ``.mass`` are used (consistent mass).
    basis : (3N, m) array or an object with ``.basis`` (e.g. :class:`ffrf.reduction.craig_bampton.CraigBamptonBasis`).
    isotropic : force the isotropic-mass fast path (True) or the general path (False);
        default: decided by :func:`is_isotropic_mass`.
    """
    nodes, mass, _ = checked_model(fe_model)
    psi = np.asarray(getattr(basis, "basis", basis), dtype=float)
    if psi.ndim != 2 or psi.shape[0] != 3 * len(nodes):
        raise ReductionError(f"mode basis has shape {psi.shape}, expected (3N, m) = ({3 * len(nodes)}, m)")
    if not np.all(np.isfinite(psi)):
        raise ReductionError("mode basis contains NaN or inf entries; recompute the reduction")
    if isotropic is None:
        isotropic = is_isotropic_mass(mass)
    logger.debug(
        "inertia invariants: %s path, %d nodes, %d modes",
        "isotropic" if isotropic else "general",
        len(nodes),
        psi.shape[1],
    )
    return _isotropic(nodes, mass, psi) if isotropic else _general(nodes, mass, psi)


def _from_rigid_part(m: float, first: NDArray, theta: NDArray, **matrices: NDArray) -> InertiaInvariants:
    chi = first / m
    # Parallel-axis theorem (Steiner): J_c = Theta - m (|chi|^2 I - chi chi^T), eq. (INV-2).
    inertia = theta - m * (chi @ chi * np.eye(3) - np.outer(chi, chi))
    return InertiaInvariants(float(m), chi, 0.5 * (inertia + inertia.T), 0.5 * (theta + theta.T), **matrices)


def _isotropic(nodes: NDArray, mass: sp.csr_matrix, psi: NDArray) -> InertiaInvariants:
    """Eq. (INV-5): all invariants from G = W^T M_s W, W = [1, x_0, x_1, x_2, Psi_0, Psi_1, Psi_2]."""
    m = psi.shape[1]
    g = component_gram(nodes, mass, psi)
    u = [slice(4 + c * m, 4 + (c + 1) * m) for c in range(3)]
    one_u = np.stack([g[0, u[c]] for c in range(3)])  # (c, k): 1^T M_s Psi_c
    x_u = np.stack([np.stack([g[1 + c, u[d]] for d in range(3)]) for c in range(3)])  # (c, d, k)
    u_u = np.stack([np.stack([g[u[c], u[d]] for d in range(3)]) for c in range(3)])  # (c, d, j, k)
    second = g[1:4, 1:4]
    eye = np.eye(3)
    reduced = u_u[0, 0] + u_u[1, 1] + u_u[2, 2]
    # eps_abc eps_dbe = delta_ad delta_ce - delta_ae delta_cd turns double tildes into traces.
    theta = np.trace(second) * eye - second.T
    m_phit_psi_tilde = -np.einsum("ade,ek->akd", _LEVI_CIVITA, one_u).reshape(3, 3 * m)
    m_x_tilde_psi = np.einsum("abc,cbk->ak", _LEVI_CIVITA, x_u)
    m_x_tilde_psi_tilde = (np.einsum("ad,k->akd", eye, np.einsum("cck->k", x_u)) - np.einsum("dak->akd", x_u)).reshape(
        3, 3 * m
    )
    m_psi_tilde_psi = np.einsum("abc,cbjk->jak", _LEVI_CIVITA, u_u).reshape(3 * m, m)
    m_psi_tilde_psi_tilde = (np.einsum("ad,jk->jakd", eye, reduced) - np.einsum("dajk->jakd", u_u)).reshape(
        3 * m, 3 * m
    )
    return _from_rigid_part(
        g[0, 0],
        g[0, 1:4],
        theta,
        reduced_mass=0.5 * (reduced + reduced.T),
        m_phit_psi=one_u,
        m_phit_psi_tilde=m_phit_psi_tilde,
        m_x_tilde_psi=m_x_tilde_psi,
        m_x_tilde_psi_tilde=m_x_tilde_psi_tilde,
        m_psi_tilde_psi=m_psi_tilde_psi,
        m_psi_tilde_psi_tilde=0.5 * (m_psi_tilde_psi_tilde + m_psi_tilde_psi_tilde.T),
    )


def _general(nodes: NDArray, mass: sp.csr_matrix, psi: NDArray) -> InertiaInvariants:
    """Direct products with the dense Psi~ (Zwoelfer and Gerstmayr 2021; as Exudyn's FEM.py)."""
    x = nodes.reshape(-1)
    phi_t = np.tile(np.eye(3), (len(nodes), 1))
    x_tilde, psi_tilde = nodal_tilde(x), nodal_tilde(psi)
    m_psi, m_psi_tilde, m_phi_t = mass @ psi, mass @ psi_tilde, mass @ phi_t
    m = float(np.trace(phi_t.T @ m_phi_t)) / 3.0
    reduced = psi.T @ m_psi
    mtt = psi_tilde.T @ m_psi_tilde
    return _from_rigid_part(
        m,
        m_phi_t.T @ x,
        x_tilde.T @ (mass @ x_tilde),
        reduced_mass=0.5 * (reduced + reduced.T),
        m_phit_psi=phi_t.T @ m_psi,
        m_phit_psi_tilde=phi_t.T @ m_psi_tilde,
        m_x_tilde_psi=x_tilde.T @ m_psi,
        m_x_tilde_psi_tilde=x_tilde.T @ m_psi_tilde,
        m_psi_tilde_psi=psi_tilde.T @ m_psi,
        m_psi_tilde_psi_tilde=0.5 * (mtt + mtt.T),
    )
