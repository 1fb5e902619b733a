r"""The strain averaged over a ball of material around each vertex: a link's stress where the elastic solution is
singular (``docs/formulation.md``, Eq. (D14)).

Where an arm meets its housing the links have re-entrant edges, and there the elastic stress is unbounded: the
corner stresses of Eq. (D9) grow without limit as the mesh is refined, so a bound on them is a bound on the mesh.
The theory of critical distances (D. Taylor, *The Theory of Critical Distances*, Elsevier 2007; its volume method)
judges a notch by the stress averaged over a small volume of material instead, of a size that is the material's own
(its critical distance). Here each mesh vertex :math:`x_v` gets the strain averaged over the material within a ball
of radius :math:`\rho` around it,

.. math:: \bar\varepsilon_v = \frac{1}{|B_\rho(x_v)\cap\Omega|}\int_{B_\rho(x_v)\cap\Omega}\varepsilon\,dV,

and the von Mises stress of :math:`\bar\sigma = C\bar\varepsilon`. The average of an integrable singularity is
finite, and it converges as the mesh is refined. It is linear in the strain, so in the link's modal coordinates it
is a sum of averaged strain modes, and Eqs. (D9), (D10) apply to it unchanged.

The integral is a sum over sample points: element :math:`e` is cut into :math:`(n_e + 1)^3` pieces of its
regular subdivision, and its points are the centroids of the :math:`N_e = \binom{n_e + 3}{3}` pieces that stand as
the element does (barycentric :math:`(a + \tfrac14)/(n_e + 1)` for every :math:`a` of non-negative integers summing
to :math:`n_e`), each of weight :math:`V_e / N_e`: symmetric, so exact for the strain of a P1 or P2 element (linear),
and inside the element, so a ball's volume is sampled without bias. :math:`n_e` is chosen so that the points lie
about :data:`LATTICE_SPACING` radii apart; a point is in a vertex's ball when it lies within :math:`\rho` of it.
The membership is fixed with the average (:class:`BallAverage`: per centre and element, the sum of the barycentric
coordinates of the element's points in the ball); on a mesh whose nodes have moved (a morphed design, Eq. (D5)) the
weights follow the moved elements' volumes, so the average is smooth in the node positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ffrf.fe.fe_model import FEModel
from ffrf.mesh.tet_mesh import signed_volumes

__all__ = ["LATTICE_SPACING", "BallAverage", "ball_average", "sample_points"]

#: The distance between an element's sample points, in radii of the ball: how finely a ball's edge is resolved.
LATTICE_SPACING = 0.25
#: The highest subdivision order (816 points per element): elements far larger than the ball are sampled coarser.
MAX_ORDER = 15
#: Vertices whose balls are gathered at once (bounds the memory of the point pairs).
CHUNK = 1024


def sample_points(order: int) -> NDArray[np.float64]:
    """The barycentric coordinates of the centroids of the upright pieces of a tetrahedron's regular subdivision of
    order ``order + 1``: ``(a + 1/4) / (order + 1)`` for every ``a`` of non-negative integers summing to ``order``,
    ``((order + 1)(order + 2)(order + 3) / 6, 4)``."""
    rows = [(i, j, k, order - i - j - k) for i, j, k in product(range(order + 1), repeat=3) if i + j + k <= order]
    return (np.array(rows, dtype=float).reshape(-1, 4) + 0.25) / (order + 1)


@dataclass(frozen=True)
class BallAverage:
    """The averaging of Eq. (D14) on one mesh: ``vertices`` (mesh vertex indices, the balls' centres), each
    element's number of sample points ``points``, and per ``pairs`` ``(2, P)`` (row in ``vertices``, element) whose
    element has sample points within ``radius`` (m) of the centre, the sum of their barycentric coordinates
    ``inside`` ``(P, 4)``."""

    radius: float
    vertices: NDArray[np.int64]
    points: NDArray[np.int64]
    pairs: NDArray[np.int64]
    inside: NDArray[np.float64]

    def operator(self, fe: FEModel) -> sp.csr_matrix:
        """The matrix ``(len(vertices), 4 n_tets)`` from the corner strains of ``fe`` (any mesh with this one's
        elements; the weights are its element volumes) to the averaged strains at the centres."""
        tets = fe.mesh.tets
        centre, element = self.pairs
        weight = (np.abs(signed_volumes(fe.mesh.points, tets)) / self.points)[element]
        volume = np.bincount(centre, weights=weight * self.inside.sum(axis=1), minlength=len(self.vertices))
        values = (weight / volume[centre])[:, None] * self.inside
        columns = 4 * element[:, None] + np.arange(4)
        shape = (len(self.vertices), 4 * len(tets))
        return sp.csr_matrix((values.ravel(), (np.repeat(centre, 4), columns.ravel())), shape=shape)

    def strains(self, fe: FEModel, corner_strains: NDArray) -> NDArray[np.float64]:
        """The averaged strains ``(len(vertices), 1, 3, 3, ...)`` of the corner strains ``(n_tets, 4, 3, 3, ...)``
        of ``fe`` (:meth:`FEModel.vertex_strains`, or strain modes): one 'corner' per centre, so that the functions
        of :mod:`ffrf.output.peak_stress` read them as they read the corners."""
        flat = np.asarray(corner_strains, dtype=float).reshape(4 * len(fe.mesh.tets), -1)
        averaged = self.operator(fe) @ flat
        return averaged.reshape(len(self.vertices), 1, *corner_strains.shape[2:])


def ball_average(fe: FEModel, radius: float) -> BallAverage:
    """:class:`BallAverage` of radius ``radius`` (m) around every vertex of ``fe``'s elements (module docstring)."""
    if not radius > 0.0:
        raise ValueError(f"the stress averaging radius must be > 0 m, got {radius!r}: give the material's own")
    points, tets = fe.mesh.points, fe.mesh.tets
    edges = points[tets[:, [0, 0, 0, 1, 1, 2]]] - points[tets[:, [1, 2, 3, 2, 3, 3]]]
    longest = np.linalg.norm(edges, axis=2).max(axis=1)
    orders = np.clip(np.ceil(longest / (LATTICE_SPACING * radius)) - 1, 0, MAX_ORDER).astype(np.int64)
    element, barycentric = [], []
    for order in np.unique(orders):
        chosen = np.flatnonzero(orders == order)
        grid = sample_points(int(order))
        element.append(np.repeat(chosen, len(grid)))
        barycentric.append(np.tile(grid, (len(chosen), 1)))
    element_of = np.concatenate(element)
    weights = np.concatenate(barycentric)
    samples = cKDTree(np.einsum("pc,pcx->px", weights, points[tets[element_of]]))
    vertices = np.unique(tets)
    pairs, inside = [], []
    for start in range(0, len(vertices), CHUNK):
        centres = cKDTree(points[vertices[start : start + CHUNK]])
        found = centres.sparse_distance_matrix(samples, radius, output_type="ndarray")
        key = (start + found["i"].astype(np.int64)) * len(tets) + element_of[found["j"]]
        unique, which = np.unique(key, return_inverse=True)
        pairs.append(np.stack([unique // len(tets), unique % len(tets)]))
        inside.append(np.stack([np.bincount(which, weights=weights[found["j"], c]) for c in range(4)], axis=1))
    counts = np.bincount(element_of, minlength=len(tets))
    return BallAverage(float(radius), vertices, counts, np.concatenate(pairs, axis=1), np.concatenate(inside))
