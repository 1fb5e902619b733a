"""What the body builder needs of a reduction, whichever kind: the protocol :class:`ModeBasis`.

:class:`ffrf.reduction.craig_bampton.CraigBamptonBasis` (component modes with rigid interfaces)
and :class:`ffrf.reduction.free_free.FreeFreeBasis` (unconstrained eigenmodes) both satisfy it; a
:class:`ffrf.body.flexible_body.FlexibleBody` is built from either as
``FlexibleBody(name, modal_moments(nodes, M, b.basis), b.reduced_stiffness, b.reduced_damping(beta, alpha))``.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import ReductionError

__all__ = ["ModeBasis", "ReducedMatrices", "rayleigh_damping"]


@runtime_checkable
class ModeBasis(Protocol):
    """A mode basis Psi (3N, m) with its reduced matrices.

    ``reference`` names the reference condition the basis implies ("interface", "mean_axis" or
    "none"; ``docs/formulation.md`` (HCB-5), (HCB-6), (FF-3)).
    """

    # Read-only members: the bases are frozen dataclasses.
    @property
    def basis(self) -> NDArray[np.float64]: ...

    @property
    def reduced_mass(self) -> NDArray[np.float64]: ...

    @property
    def reduced_stiffness(self) -> NDArray[np.float64]: ...

    @property
    def mode_labels(self) -> tuple[str, ...]: ...

    @property
    def reference(self) -> str: ...

    @property
    def n_modes(self) -> int: ...

    def reduced_damping(self, beta: float = 0.005, alpha: float = 0.0) -> NDArray[np.float64]: ...

    def summary(self) -> str: ...


def rayleigh_damping(
    reduced_mass: NDArray[np.float64], reduced_stiffness: NDArray[np.float64], beta: float, alpha: float = 0.0
) -> NDArray[np.float64]:
    """D = alpha M_red + beta K_red (eq. (HCB-8)); the paper uses beta = 0.005 s, alpha = 0."""
    if not (np.isfinite(beta) and beta >= 0.0):
        raise ReductionError(f"damping factor beta={beta!r} must be finite and >= 0 (seconds)")
    if not (np.isfinite(alpha) and alpha >= 0.0):
        raise ReductionError(f"damping factor alpha={alpha!r} must be finite and >= 0 (1/s)")
    return alpha * reduced_mass + beta * reduced_stiffness


class ReducedMatrices:
    """What every basis derives from its ``basis`` and reduced matrices: the mode count and Rayleigh damping."""

    basis: NDArray[np.float64]
    reduced_mass: NDArray[np.float64]
    reduced_stiffness: NDArray[np.float64]

    @property
    def n_modes(self) -> int:
        return self.basis.shape[1]

    def reduced_damping(self, beta: float = 0.005, alpha: float = 0.0) -> NDArray[np.float64]:
        """Rayleigh damping D = alpha M_red + beta K_red (eq. (HCB-8)); the paper uses beta = 0.005 s, alpha = 0."""
        return rayleigh_damping(self.reduced_mass, self.reduced_stiffness, beta, alpha)
