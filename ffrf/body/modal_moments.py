r"""Modal moments of the consistent mass matrix: what an FFRF body needs of its mesh.

For an isotropic FE mass matrix :math:`M = M_s\otimes I_3` (``docs/formulation.md``, Eq. (F4)),
every inertia term of the reduced body is a component-wise Gram product of
``W_a = [1, x^(a), Psi^(a)]`` (rows of component ``a``) with the scalar mass matrix M_s:
the total mass ``m``, the first moments ``S0, S1``, the second moments ``X`` and the
couplings ``C, D`` (see :mod:`ffrf.body.body_kernels` for the table). They are computed once,
with one sparse product ``M_s W`` (:func:`ffrf.reduction.invariants.component_gram`, shared with the
Exudyn-style invariants); no lumped mass is involved (Zwoelfer and Gerstmayr 2021).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import FEInputError
from ffrf.reduction.invariants import component_gram, is_isotropic_mass

__all__ = ["ModalMoments", "modal_moments"]


@dataclass(frozen=True, eq=False)
class ModalMoments:
    """Constant mass data of a reduced body; arrays as in :mod:`ffrf.body.body_kernels`."""

    mass: float
    s0: NDArray[np.float64]  # (3,)
    s1: NDArray[np.float64]  # (3, m)
    x2: NDArray[np.float64]  # (3, 3)
    c: NDArray[np.float64]  # (3, 3, m)
    d: NDArray[np.float64]  # (3, 3, m, m)

    @property
    def n_modes(self) -> int:
        return self.s1.shape[1]

    @property
    def reduced_mass(self) -> NDArray[np.float64]:
        """:math:`\\Psi^TM\\Psi = \\sum_a D_{aa}`."""
        return self.d[0, 0] + self.d[1, 1] + self.d[2, 2]


def modal_moments(nodes: ArrayLike, mass: sp.spmatrix, basis: ArrayLike) -> ModalMoments:
    """Modal moments of ``basis`` ``(3N, m)`` over ``nodes`` ``(N, 3)`` (body-frame coordinates)."""
    nodes = np.asarray(nodes, dtype=float)
    basis = np.asarray(basis, dtype=float)
    n, m = nodes.shape[0], basis.shape[1]
    if basis.shape[0] != 3 * n:
        raise FEInputError(f"mode basis has {basis.shape[0]} rows, expected 3 x {n} nodes")
    if not is_isotropic_mass(mass):
        raise FEInputError(
            "the mass matrix is not of the form M_s kron I3 (x, y, z uncoupled and equal); the FFRF body "
            "needs an isotropic consistent mass matrix as assembled by ffrf.FEModel"
        )
    gram = component_gram(nodes, mass, basis)
    modes = [slice(4 + a * m, 4 + (a + 1) * m) for a in range(3)]
    s1 = np.stack([gram[0, modes[a]] for a in range(3)])
    c = np.stack([np.stack([gram[modes[a], 1 + b] for b in range(3)]) for a in range(3)])
    d = np.stack([np.stack([gram[modes[a], modes[b]] for b in range(3)]) for a in range(3)])
    return ModalMoments(
        mass=float(gram[0, 0]),
        s0=gram[0, 1:4].copy(),
        s1=s1,
        x2=gram[1:4, 1:4].copy(),
        c=np.ascontiguousarray(c),
        d=np.ascontiguousarray(d),
    )
