r"""One modally reduced body as both solvers take it (:class:`ReducedBody`: nodes, consistent M
and K, the mode basis Psi and the weights of its two interfaces), the test bar of the Exudyn
cross-checks (:func:`bar_body`) and its static deflection under a tip force.

The basis vanishes on the frame interface (bore 0, the face x = 0 of the bar): Craig-Bampton
with the frame interface's rigid motion taken by the reference frame. DOF order
[x0, y0, z0, x1, ...], SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

__all__ = ["ReducedBody", "bar_body", "tip_node", "static_deflection"]


@dataclass(frozen=True, eq=False)
class ReducedBody:
    """FE data of one modally reduced body, shared verbatim by both solvers.

    Attributes
    ----------
    nodes : (N, 3) reference node positions in the body frame (m).
    mass, stiffness : (3N, 3N) consistent mass and stiffness (CSR), DOFs [x0, y0, z0, x1, ...].
    basis : (3N, m) mode basis Psi (vanishes on the frame interface).
    frame_nodes, frame_weights : node indices and weights (sum 1) of the frame interface (bore 0).
    tip_nodes, tip_weights : node indices and weights of the second interface (bore 1).
    length : characteristic length (m) used to scale tolerances.
    """

    nodes: NDArray[np.float64]
    mass: sp.csr_matrix
    stiffness: sp.csr_matrix
    basis: NDArray[np.float64]
    frame_nodes: NDArray[np.int64]
    frame_weights: NDArray[np.float64]
    tip_nodes: NDArray[np.int64]
    tip_weights: NDArray[np.float64]
    length: float
    reduced_mass: NDArray[np.float64] = field(init=False, repr=False)
    reduced_stiffness: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self):
        n = len(self.nodes)
        if self.basis.shape[0] != 3 * n:
            raise ValueError(f"basis has {self.basis.shape[0]} rows, expected 3 x {n} nodes")
        for label, w in (("frame", self.frame_weights), ("tip", self.tip_weights)):
            if abs(float(np.sum(w)) - 1.0) > 1e-12:
                raise ValueError(f"{label} interface weights must sum to 1, got {np.sum(w)!r}")
        reduced_mass = self.basis.T @ (self.mass @ self.basis)
        reduced_stiffness = self.basis.T @ (self.stiffness @ self.basis)
        object.__setattr__(self, "reduced_mass", 0.5 * (reduced_mass + reduced_mass.T))
        object.__setattr__(self, "reduced_stiffness", 0.5 * (reduced_stiffness + reduced_stiffness.T))

    @property
    def n_modes(self) -> int:
        return self.basis.shape[1]

    @property
    def frame_center(self) -> NDArray[np.float64]:
        """Weighted mean of the frame-interface reference positions (body frame)."""
        return self.frame_weights @ self.nodes[self.frame_nodes]

    def max_mode_on_frame_interface(self) -> float:
        """Largest ``|Psi|`` entry on the frame-interface DOFs (0 for the RBE2 reference condition)."""
        dofs = (3 * self.frame_nodes[:, None] + np.arange(3)).ravel()
        return float(np.abs(self.basis[dofs]).max())


def bar_body(
    divisions: tuple[int, int, int] = (8, 2, 2),
    size: tuple[float, float, float] = (0.2, 0.02, 0.01),
    E: float = 1.2e9,
    nu: float = 0.33,
    rho: float = 450.0,
    n_modes: int = 4,
    weights: str = "uniform",
) -> ReducedBody:
    """Prismatic bar along x, centred in y and z, bore 0 = face x = 0 (frame interface).

    Parameters
    ----------
    divisions : elements (boxes of 6 tetrahedra) along x, y, z; at least 2 across.
    size : bar dimensions (m).
    n_modes : fixed-interface modes (the basis has 6 + n_modes columns).
    weights : "uniform" (1/n) or "area" (tributary face areas of the structured end-face grid,
        trapezoidal rule) for both interfaces. Either way both solvers get the same weights.
    """
    import skfem

    from ffrf.fe.fe_model import FEModel
    from ffrf.mesh.tet_mesh import orient_positive
    from ffrf.reduction.craig_bampton import craig_bampton

    nx, ny, nz = divisions
    if ny < 2 or nz < 2:
        raise ValueError(f"use at least 2 elements across the section, got {divisions}")
    lx, ly, lz = size
    mesh = skfem.MeshTet.init_tensor(
        np.linspace(0.0, lx, nx + 1), np.linspace(-ly / 2, ly / 2, ny + 1), np.linspace(-lz / 2, lz / 2, nz + 1)
    )
    points = mesh.p.T
    tets = orient_positive(points, mesh.t.T)
    model = FEModel.from_mesh(points, tets, E=E, nu=nu, rho=rho, order=1)
    nodes = np.asarray(model.nodes)
    tol = 1e-9 * lx
    bores = [np.flatnonzero(np.abs(nodes[:, 0]) < tol), np.flatnonzero(np.abs(nodes[:, 0] - lx) < tol)]
    if weights == "uniform":
        w = [np.full(len(b), 1.0 / len(b)) for b in bores]
    elif weights == "area":
        w = [_face_area_weights(nodes[b][:, 1:], ny, nz) for b in bores]
    else:
        raise ValueError(f"weights={weights!r}: use 'uniform' or 'area'")
    cb = craig_bampton(model, bores, n_modes, w)
    return ReducedBody(
        nodes,
        sp.csr_matrix(model.mass),
        sp.csr_matrix(model.stiffness),
        np.asarray(cb.basis),
        bores[0],
        w[0],
        bores[1],
        w[1],
        float(lx),
    )


def _face_area_weights(yz: NDArray[np.float64], ny: int, nz: int) -> NDArray[np.float64]:
    """Tributary areas of a structured rectangular face grid (trapezoidal rule), normalised."""
    ys, zs = np.unique(np.round(yz[:, 0], 12)), np.unique(np.round(yz[:, 1], 12))
    if len(ys) != ny + 1 or len(zs) != nz + 1:
        raise ValueError("face nodes do not form the expected structured grid")
    wy = np.diff(ys, prepend=ys[0]) / 2 + np.diff(ys, append=ys[-1]) / 2
    wz = np.diff(zs, prepend=zs[0]) / 2 + np.diff(zs, append=zs[-1]) / 2
    iy = np.searchsorted(ys, np.round(yz[:, 0], 12))
    iz = np.searchsorted(zs, np.round(yz[:, 1], 12))
    w = wy[iy] * wz[iz]
    return w / w.sum()


def tip_node(body: ReducedBody) -> int:
    """The tip node closest to the tip-interface centre."""
    centre = body.tip_weights @ body.nodes[body.tip_nodes]
    return int(body.tip_nodes[np.argmin(np.linalg.norm(body.nodes[body.tip_nodes] - centre, axis=1))])


def static_deflection(body: ReducedBody, tip_force: ArrayLike) -> NDArray[np.float64]:
    """Modal coordinates of the static deflection under ``tip_force`` (N, body frame), spread over
    the tip interface with its weights, with the frame interface clamped: K_red zeta = Psi^T f."""
    f = np.zeros(3 * len(body.nodes))
    for i, w in zip(body.tip_nodes, body.tip_weights, strict=True):
        f[3 * i : 3 * i + 3] = w * np.asarray(tip_force, dtype=float)
    return np.asarray(np.linalg.solve(body.reduced_stiffness, body.basis.T @ f), dtype=np.float64)
