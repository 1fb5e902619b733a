r"""Mode-by-mode comparison of our Craig-Bampton reduction with Exudyn's.

Exudyn's ``FEMinterface.ComputeHurtyCraigBamptonModes`` (RBE2 interfaces,
``excludeRigidBodyMotion=True``) gets the same nodes, consistent M and K, boundary node sets
and area weights as :func:`ffrf.reduction.craig_bampton.craig_bampton`. We compare

* the fixed-interface frequencies, relative difference per mode;
* the fixed-interface mode shapes by the mass-weighted modal assurance criterion
  :math:`\mathrm{MAC}_{ij} = (\phi_i^T M \psi_j)^2 / ((\phi_i^T M\phi_i)(\psi_j^T M\psi_j))`
  (Allemang and Brown 1982, with the mass as weight so that the value does not depend on
  mesh density); eigenvectors of a repeated frequency are an arbitrary basis of their space,
  so within such a cluster the diagonal MAC is replaced by :math:`\cos^2` of the largest
  principal angle between the two spaces;
* the static (constraint) mode spaces by their largest principal angle (Exudyn's rotation
  columns have the opposite sign, so columns are not compared one by one).

``exudyn`` is imported lazily; the functions take duck-typed models (``.nodes``, ``.mass``,
``.stiffness``) like :mod:`ffrf.reduction.craig_bampton`.

Exudyn's reduction calls SciPy's ``eigsh`` without a start vector, which SciPy then draws from the operating
system's entropy: the twin's basis changed from run to run (mode signs, last digits of the frequencies), and with it
every Exudyn number of a cross-validation. :func:`exudyn_hcb` runs it inside :func:`deterministic_eigsh`, which
gives ``eigsh`` our fixed start (:func:`ffrf.numerics.eigen.lanczos_start`), so that a rerun reproduces every bit.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg
from numpy.typing import NDArray
from scipy.linalg import subspace_angles

from ffrf.numerics.eigen import lanczos_start

__all__ = [
    "ModeComparison",
    "deterministic_eigsh",
    "exudyn_hcb",
    "mass_mac",
    "frequency_clusters",
    "compare_modes",
]


@dataclass(frozen=True)
class ModeComparison:
    """Fixed-interface modes of one body, ours against Exudyn's."""

    frequencies_hz: NDArray[np.float64]  # ours, ascending
    exudyn_frequencies_hz: NDArray[np.float64]  # Exudyn's, ascending
    mac: NDArray[np.float64]  # (n, n): ours (rows) against Exudyn's (columns), both ascending
    diagonal_mac: NDArray[np.float64]  # per mode; cos^2 of the cluster's principal angle for repeated modes
    static_space_angle_rad: float
    setup_s: float  # Exudyn's reduction time

    @property
    def max_rel_freq_diff(self) -> float:
        return float(np.max(np.abs(self.frequencies_hz / self.exudyn_frequencies_hz - 1.0)))

    @property
    def min_mac_diag(self) -> float:
        return float(np.min(self.diagonal_mac))

    def metrics(self) -> dict:
        return {
            "max_rel_freq_diff": self.max_rel_freq_diff,
            "min_mac_diag": self.min_mac_diag,
            "static_space_angle_rad": self.static_space_angle_rad,
            "frequencies_hz": self.frequencies_hz.tolist(),
            "exudyn_frequencies_hz": self.exudyn_frequencies_hz.tolist(),
        }


@contextmanager
def deterministic_eigsh() -> Iterator[None]:
    """While inside, ``scipy.sparse.linalg.eigsh`` starts Lanczos from :func:`ffrf.numerics.eigen.lanczos_start` when
    its caller gives no start vector (module docstring); SciPy's own function is back on the way out. For callers
    that import ``eigsh`` when they run, as Exudyn's ``FEM`` module does; single-threaded use only."""
    original = scipy.sparse.linalg.eigsh

    def eigsh(*args: Any, **kwargs: Any):
        if kwargs.get("v0") is None:
            matrix = args[0] if args else kwargs["A"]
            kwargs["v0"] = lanczos_start(matrix.shape[0])
        return original(*args, **kwargs)

    scipy.sparse.linalg.eigsh = eigsh
    try:
        yield
    finally:
        scipy.sparse.linalg.eigsh = original


def exudyn_hcb(model, interfaces, weights, n_modes: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Exudyn's HCB basis (3N, m) (static modes first) and its fixed-interface frequencies (Hz), the same on every
    call (:func:`deterministic_eigsh`)."""
    from exudyn.FEM import FEMinterface, HCBstaticModeSelection

    fem = FEMinterface()
    fem.nodes = {"Position": np.asarray(model.nodes, dtype=float)}
    fem.massMatrix = sp.csr_matrix(model.mass)
    fem.stiffnessMatrix = sp.csr_matrix(model.stiffness)
    with deterministic_eigsh():
        fem.ComputeHurtyCraigBamptonModes(
            boundaryNodesList=[[int(i) for i in nodes] for nodes in interfaces],
            nEigenModes=n_modes,
            useSparseSolver=True,
            computationMode=HCBstaticModeSelection.RBE2,
            boundaryNodesWeights=[np.asarray(w, dtype=float) for w in weights],
            excludeRigidBodyMotion=True,
        )
    return np.asarray(fem.modeBasis["matrix"]), np.asarray(fem.GetEigenFrequenciesHz())


def mass_mac(a: NDArray, b: NDArray, mass) -> NDArray[np.float64]:
    """Mass-weighted MAC matrix between the columns of ``a`` and ``b`` (module docstring)."""
    ma, mb = mass @ a, mass @ b
    cross = a.T @ mb
    return cross**2 / np.outer(np.einsum("ij,ij->j", a, ma), np.einsum("ij,ij->j", b, mb))


def frequency_clusters(frequencies: NDArray, rel_gap: float = 1e-6) -> list[NDArray[np.int64]]:
    """Index groups of (nearly) repeated frequencies; isolated modes are groups of one."""
    breaks = np.flatnonzero(np.diff(frequencies) > rel_gap * frequencies[1:]) + 1
    return np.split(np.arange(len(frequencies)), breaks)


def compare_modes(
    model, reduction, exudyn_basis: NDArray, exudyn_frequencies_hz: NDArray, setup_s: float = float("nan")
) -> ModeComparison:
    """Compare ``reduction`` (:class:`ffrf.reduction.craig_bampton.CraigBamptonBasis` of ``model``) with
    Exudyn's basis."""
    s = reduction.n_static_modes
    ours = reduction.fixed_interface_frequencies_hz
    order = np.argsort(exudyn_frequencies_hz)
    theirs = np.asarray(exudyn_frequencies_hz)[order]
    if theirs.shape != ours.shape or exudyn_basis.shape != reduction.basis.shape:
        raise ValueError(f"mode counts differ: ours {reduction.basis.shape}, Exudyn's {exudyn_basis.shape}")
    phi, psi = reduction.basis[:, s:], exudyn_basis[:, s:][:, order]
    mac = mass_mac(phi, psi, model.mass)
    diagonal = np.empty(len(ours))
    for group in frequency_clusters(ours):
        if len(group) == 1:
            diagonal[group] = mac[group[0], group[0]]
        else:
            diagonal[group] = np.cos(np.max(subspace_angles(phi[:, group], psi[:, group]))) ** 2
    static_angle = float(np.max(subspace_angles(reduction.basis[:, :s], exudyn_basis[:, :s]))) if s else 0.0
    return ModeComparison(np.asarray(ours), theirs, mac, diagonal, static_angle, setup_s)
