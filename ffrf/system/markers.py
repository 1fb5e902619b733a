r"""Markers: points and frames on a flexible body, in O(m) per evaluation.

A *rigid interface marker* is our equivalent of Exudyn's ``MarkerSuperElementRigid`` with
``useAlternativeApproach=True`` and the exponential map (``docs/formulation.md``, Sect.
"Markers", Eqs. (K1)-(K3)). For interface nodes ``i`` with weights :math:`w_i` (sum 1),
reference positions :math:`x_i`, weighted centre :math:`\bar x = \sum w_i x_i`,
:math:`\bar p_i = x_i - \bar x` and :math:`W = -\sum w_i \tilde{\bar p}_i\tilde{\bar p}_i`:

.. math::
    r_M &= R + A(p)\,(o + \bar x + P\zeta),\qquad P = \textstyle\sum w_i\Psi_i \quad (K1)\\
    \theta_M &= \Theta\zeta,\qquad \Theta = W^{-1}\textstyle\sum w_i\tilde{\bar p}_i\Psi_i \quad (K2)\\
    A_M &= A(p)\,\exp(\tilde\theta_M) \quad (K3)

Everything is linear in :math:`\zeta`, so the ``3 x m`` matrices ``P`` and ``Theta`` are
computed once; Exudyn instead loops over all interface nodes on every evaluation. For a
rigid motion of the interface nodes, :math:`\theta_M` is exactly its rotation vector (to
first order) and :math:`P\zeta` its translation.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.body.euler_parameters import rotation_derivative, rotation_matrix
from ffrf.numerics.small_linalg import skew
from ffrf.system.marker_kernels import exp_so3_kernel

__all__ = [
    "BodyMarker",
    "JOINT_OFFSETS",
    "attach_joint_point",
    "marker_history",
    "rigid_interface_marker",
    "node_marker",
    "frame_marker",
    "exp_so3",
]

#: Where a joint point's offset from its marker lives (see :func:`attach_joint_point`).
JOINT_OFFSETS = ("body", "marker")


def exp_so3(theta: NDArray) -> NDArray:
    r"""Rodrigues' formula :math:`\exp(\tilde\theta) = I + \frac{\sin\phi}{\phi}\tilde\theta +
    \frac{1-\cos\phi}{\phi^2}\tilde\theta^2`, :math:`\phi^2 = \theta\cdot\theta`
    (analytic, also for complex ``theta``)."""
    theta = np.asarray(theta)
    return exp_so3_kernel(theta.astype(np.result_type(theta, float)))


@dataclass(frozen=True, eq=False)
class BodyMarker:
    """A point and a frame on body ``body``: local point :math:`o + \\bar x + P\\zeta`,
    local rotation vector :math:`\\Theta\\zeta` (zero columns for frame and node markers)."""

    body: int
    name: str
    point: NDArray[np.float64]  # o + x_bar (3,)
    position_modes: NDArray[np.float64]  # P (3, m)
    rotation_modes: NDArray[np.float64]  # Theta (3, m)

    def local_point(self, q: NDArray) -> NDArray:
        return self.point + self.position_modes @ q[7:]

    def position(self, q: NDArray) -> NDArray:
        """Eq. (K1): world position; ``q`` is the body's coordinate block."""
        return q[:3] + rotation_matrix(q[3:7]) @ self.local_point(q)

    def position_jacobian(self, q: NDArray) -> NDArray:
        """Exact d(position)/dq: ``[I, d(A u)/dp, A P]`` (3 x (7+m))."""
        out = np.zeros((3, q.shape[0]), dtype=q.dtype)
        out[:, :3] = np.eye(3)
        out[:, 3:7] = rotation_derivative(q[3:7], self.local_point(q).astype(q.dtype))
        out[:, 7:] = rotation_matrix(q[3:7]) @ self.position_modes
        return out

    def rotation_vector(self, q: NDArray) -> NDArray:
        """Eq. (K2): the interface's rotation relative to the body frame."""
        return self.rotation_modes @ q[7:]

    def orientation(self, q: NDArray) -> NDArray:
        """Eq. (K3): world orientation of the marker frame."""
        return rotation_matrix(q[3:7]) @ exp_so3(self.rotation_vector(q))


def _checked_nodes(
    nodes: NDArray, indices: ArrayLike, weights: ArrayLike | None, name: str
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    indices = np.asarray(indices, dtype=np.int64)
    if indices.size == 0:
        raise ValueError(f"marker {name!r}: the interface has no nodes; check the node selection")
    if indices.min() < 0 or indices.max() >= nodes.shape[0]:
        raise ValueError(f"marker {name!r}: node index out of range 0..{nodes.shape[0] - 1}")
    w = np.full(indices.size, 1.0 / indices.size) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != indices.shape or np.any(w < 0) or not np.isclose(w.sum(), 1.0, rtol=1e-10):
        raise ValueError(
            f"marker {name!r}: weights must be non-negative, one per node, and sum to 1 (sum {w.sum():.6g})"
        )
    return indices, w


def rigid_interface_marker(
    body: int,
    nodes: ArrayLike,
    basis: ArrayLike,
    indices: ArrayLike,
    weights: ArrayLike | None = None,
    offset: ArrayLike = (0.0, 0.0, 0.0),
    name: str = "interface",
) -> BodyMarker:
    """Precompute Eqs. (K1)-(K2) for the interface ``indices`` of a body with ``nodes`` (N, 3) and ``basis`` (3N, m)."""
    nodes = np.asarray(nodes, dtype=float)
    basis = np.asarray(basis, dtype=float)
    indices, w = _checked_nodes(nodes, indices, weights, name)
    centre = w @ nodes[indices]
    rel = nodes[indices] - centre
    modes = basis.reshape(nodes.shape[0], 3, -1)[indices]  # (n_i, 3, m)
    position_modes = np.einsum("i,iam->am", w, modes)
    skews = np.array([skew(r) for r in rel])
    w_matrix = -np.einsum("i,iab,ibc->ac", w, skews, skews)
    if np.linalg.cond(w_matrix) > 1e12:
        raise ValueError(
            f"marker {name!r}: interface nodes are (nearly) collinear, so the interface rotation is "
            "undefined; select nodes spread over a surface"
        )
    rotation_modes = np.linalg.solve(w_matrix, np.einsum("i,iab,ibm->am", w, skews, modes))
    return BodyMarker(body, name, centre + np.asarray(offset, dtype=float), position_modes, rotation_modes)


def marker_history(marker: BodyMarker, blocks: NDArray) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """World positions (n, 3) and orientations (n, 3, 3) of ``marker`` for the body's coordinate
    rows ``blocks`` (n, 7 + m), e.g. ``result.q[:, system.block(marker.body)]``: Eqs. (K1), (K3)."""
    blocks = np.atleast_2d(np.asarray(blocks, dtype=float))
    return (np.array([marker.position(b) for b in blocks]), np.array([marker.orientation(b) for b in blocks]))


def attach_joint_point(
    marker: BodyMarker, point: ArrayLike, joint_offsets: str = "body"
) -> tuple[BodyMarker, NDArray[np.float64]]:
    """The marker and joint offset ``o`` that put a joint at ``point`` (body coordinates).

    ``"body"``: the marker itself moves to ``point``, ``o = 0``: Eq. (K1) with the offset in the
    body frame, as Exudyn's ``MarkerSuperElementRigid`` applies its ``localHT`` translation.
    ``"marker"``: the marker stays, ``o = point - marker point`` turns with the marker frame,
    ``p = r_M + A exp(theta_M) o`` (Eq. (J1)): a pin rigidly attached to a rigid interface.
    The two differ by ``A (exp(theta_M) - I) o``."""
    point = np.array(point, dtype=float)
    if joint_offsets == "body":
        return replace(marker, point=point), np.zeros(3)
    if joint_offsets == "marker":
        return marker, point - marker.point
    raise ValueError(f"joint_offsets must be one of {JOINT_OFFSETS}, got {joint_offsets!r}")


def node_marker(body: int, nodes: ArrayLike, basis: ArrayLike, index: int, name: str = "node") -> BodyMarker:
    """A mesh node: position :math:`R + A(x_i + \\Psi_i\\zeta)`; its frame is the body frame."""
    nodes = np.asarray(nodes, dtype=float)
    modes = np.asarray(basis, dtype=float)[3 * index : 3 * index + 3]
    return BodyMarker(body, name, nodes[index].copy(), modes, np.zeros_like(modes))


def frame_marker(body: int, n_modes: int, point: ArrayLike = (0.0, 0.0, 0.0), name: str = "frame") -> BodyMarker:
    """A point fixed in the body frame (not moved by the modes), with the body frame's orientation."""
    return BodyMarker(body, name, np.asarray(point, dtype=float), np.zeros((3, n_modes)), np.zeros((3, n_modes)))
