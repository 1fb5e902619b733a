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


def free_bar(name: str = "bar"):
    """The soft bar (E = 1e8 Pa, 450 kg/m^3) with Craig-Bampton modes of both end faces (2 fixed-
    interface modes), undamped: ``(model, basis, end node sets, body)``."""
    from ffrf.craig_bampton import craig_bampton
    from ffrf.flexible_body import FlexibleBody
    from ffrf.modal_moments import modal_moments

    model = bar_model(E=1e8, rho=450.0)
    ends = [np.flatnonzero(model.nodes[:, 0] < 1e-9), np.flatnonzero(model.nodes[:, 0] > 0.2 - 1e-9)]
    basis = craig_bampton(model, ends, 2)
    body = FlexibleBody(name, modal_moments(model.nodes, model.mass, basis.basis), basis.reduced_stiffness,
                        0.0 * basis.reduced_stiffness)
    return model, basis.basis, ends, body


def tumbling_start(body):
    """A one-body system of ``body`` thrown at 0.1 m/s, spun at (0.5, 1, 5) rad/s (body frame),
    its modes excited at random (1e-5): ``(system, q0, qd0)``."""
    from ffrf.system import MultibodySystem

    system = MultibodySystem((body,))
    q0 = system.initial_state()
    qd0 = np.zeros_like(q0)
    qd0[:3] = [0.1, 0.0, 0.0]
    qd0[3:7] = 0.25 * g_bar(q0[3:7]).T @ np.array([0.5, 1.0, 5.0])  # G G^T = 4 I
    q0[7:] = 1e-5 * np.random.default_rng(0).normal(size=body.n_modes)
    return system, q0, qd0
