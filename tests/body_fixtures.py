"""A small flexible bar and plain-numpy references built from its full nodal model."""

import numpy as np
import skfem

from ffrf import FEModel
from ffrf.mesh import orient_positive
from ffrf.euler_parameters import g_bar, rotation_matrix, skew


def bar_model(order: int = 1, E: float = 2.1e11, rho: float = 7850.0):
    """Steel-like bar 0.2 x 0.02 x 0.01 m, coarse tetrahedra."""
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, 0.2, 9), np.linspace(0, 0.02, 3), np.linspace(0, 0.01, 2))
    tets = orient_positive(mesh.p.T, mesh.t.T)
    return FEModel.from_mesh(mesh.p.T, tets, E=E, nu=0.3, rho=rho, order=order)


def random_state(rng, m):
    p = rng.normal(size=4)
    p /= np.linalg.norm(p)
    pd = rng.normal(size=4)
    pd -= p * (p @ pd)  # tangent: p . pd = 0
    return rng.normal(size=3), p, 1e-3 * rng.normal(size=m), rng.normal(size=3), pd, rng.normal(size=m)


def nodal_jacobian(nodes, basis, p, zeta):
    """L (3N x (7+m)): nodal velocities = L qd, node rows [I, -A u~ G, A Psi_i] (docs Eq. (F2))."""
    a, g = rotation_matrix(p), g_bar(p)
    n, m = nodes.shape[0], basis.shape[1]
    u = nodes + (basis @ zeta).reshape(n, 3)
    out = np.zeros((3 * n, 7 + m))
    for i in range(n):
        rows = slice(3 * i, 3 * i + 3)
        out[rows, 0:3] = np.eye(3)
        out[rows, 3:7] = -(a @ skew(u[i])) @ g
        out[rows, 7:] = a @ basis[rows]
    return out


def nodal_velocities(nodes, basis, r_dot, p, zeta, pd, zetad):
    """rd_i = Rd + A(omega x u_i + Psi_i zetad), omega = G pd: straight from the kinematics."""
    a, omega = rotation_matrix(p), g_bar(p) @ pd
    n = nodes.shape[0]
    u = nodes + (basis @ zeta).reshape(n, 3)
    w = (basis @ zetad).reshape(n, 3)
    return (r_dot + (np.cross(omega, u) + w) @ a.T).reshape(-1)
