r"""The outputs of Exudyn's ``SensorSuperElement`` on an ``ObjectFFRFreducedOrder``, on our results
(``CObjectFFRFreducedOrder::GetOutputVariableSuperElement``): for mesh node i with reference position
:math:`x` and modes :math:`\Psi_i`,

* ``Displacement``: the world position minus the reference one, :math:`R + A(x + \Psi_i\zeta) - (R_0 + A_0x)`;
* ``DisplacementLocal``: :math:`\Psi_i\zeta`;
* ``Acceleration`` (``GetMeshNodeAcceleration``): :math:`\ddot R + A\Psi_i\ddot\zeta + 2\omega\times A\Psi_i\dot\zeta
  + \alpha\times Ax' + \omega\times(\omega\times Ax')` with :math:`x' = x + \Psi_i\zeta`,
  :math:`\omega = A\bar G\dot p` and :math:`\alpha = A\bar G\ddot p`.

Exudyn's other definition a TestModel depends on, the marker velocity its ``CartesianSpringDamper`` damps
(:math:`\dot p` tangent to :math:`p\cdot p = 1`), is our spring-damper's own
(:func:`ffrf.system.forces.tangent_rates`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.body.euler_parameters import g_bar, rotation_matrix

__all__ = [
    "node_displacement",
    "node_local_displacement",
    "node_acceleration",
]


def node_displacement(
    q: NDArray, nodes: NDArray, basis: NDArray, node: int, reference: ArrayLike = (0.0, 0.0, 0.0)
) -> NDArray[np.float64]:
    """``Displacement`` of mesh ``node`` for the body's coordinate rows ``q`` (n, 7 + m), its frame's
    reference position ``reference`` and identity reference rotation: (n, 3)."""
    local = nodes[node] + q[:, 7:] @ basis[3 * node : 3 * node + 3].T
    world = np.array(
        [row[:3] + rotation_matrix(np.ascontiguousarray(row[3:7])) @ x for row, x in zip(q, local, strict=True)]
    )
    return world - (np.asarray(reference, dtype=float) + nodes[node])


def node_local_displacement(q: NDArray, basis: NDArray, node: int) -> NDArray[np.float64]:
    """``DisplacementLocal`` of mesh ``node``: :math:`\\Psi_i\\zeta` for each row of ``q``: (n, 3)."""
    return np.asarray(q[:, 7:] @ basis[3 * node : 3 * node + 3].T)


def node_acceleration(
    q: NDArray, qd: NDArray, qdd: NDArray, nodes: NDArray, basis: NDArray, node: int
) -> NDArray[np.float64]:
    """``Acceleration`` of mesh ``node`` (world) for rows of coordinates, velocities and accelerations."""
    modes = basis[3 * node : 3 * node + 3]
    out = np.empty((q.shape[0], 3))
    for k, (qk, vk, ak) in enumerate(zip(q, qd, qdd, strict=True)):
        p = np.ascontiguousarray(qk[3:7])
        a, g = rotation_matrix(p), g_bar(p)
        x = a @ (nodes[node] + modes @ qk[7:])
        omega, alpha = a @ (g @ vk[3:7]), a @ (g @ ak[3:7])
        out[k] = ak[:3] + a @ (modes @ ak[7:]) + 2.0 * np.cross(omega, a @ (modes @ vk[7:]))
        out[k] += np.cross(alpha, x) + np.cross(omega, np.cross(omega, x))
    return out
