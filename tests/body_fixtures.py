"""A small flexible bar and plain-numpy references built from its full nodal model."""

import numpy as np
import skfem
from scipy.optimize import brentq

from ffrf.body.euler_parameters import g_bar, rotation_matrix
from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.fe_model import FEModel
from ffrf.mesh.tet_mesh import orient_positive
from ffrf.numerics.small_linalg import skew
from ffrf.system.forces import AxialSpringDamper, MarkerLoad
from ffrf.system.joints import GroundFrame, MarkerJoint
from ffrf.system.markers import frame_marker
from ffrf.system.multibody import MultibodySystem


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


def potential_energy(system, q) -> float:
    r"""Strain plus gravity energy of a state (J), from the state alone:

    .. math:: V = \sum_k \tfrac12 \zeta_k^T K_k \zeta_k - m_k\,g\cdot c_k,\qquad
              c_k = R_k + A(p_k)\,(s_0 + S_1 \zeta_k) / m_k

    (``zeta_k``: modal coordinates of body k, ``K_k`` its reduced stiffness, ``c_k`` its centre of
    mass from the modal moments ``s0``, ``s1``). For virtual-work checks of drive torques."""
    energy = 0.0
    for k, body in enumerate(system.bodies):
        block = q[system.block(k)]
        moments, zeta = body.moments, block[7:]
        centre = block[:3] + rotation_matrix(block[3:7]) @ (moments.s0 + moments.s1 @ zeta) / moments.mass
        energy += 0.5 * zeta @ body.stiffness @ zeta - moments.mass * system.gravity @ centre
    return float(energy)


def five_point_slope(values, step: float) -> float:
    """dV/dx at the middle of five equally spaced values: (V_-2 - 8 V_-1 + 8 V_1 - V_2) / (12 h),
    truncation error -h^4 V^(5) / 30."""
    v = np.asarray(values, dtype=float)
    return float((v[0] - 8 * v[1] + 8 * v[3] - v[4]) / (12 * step))


def free_bar(name: str = "bar"):
    """The soft bar (E = 1e8 Pa, 450 kg/m^3) with Craig-Bampton modes of both end faces (2 fixed-
    interface modes), undamped: ``(model, basis, end node sets, body)``."""
    from ffrf.body.flexible_body import FlexibleBody
    from ffrf.body.modal_moments import modal_moments
    from ffrf.reduction.craig_bampton import craig_bampton

    model = bar_model(E=1e8, rho=450.0)
    ends = [np.flatnonzero(model.nodes[:, 0] < 1e-9), np.flatnonzero(model.nodes[:, 0] > 0.2 - 1e-9)]
    basis = craig_bampton(model, ends, 2)
    body = FlexibleBody(
        name,
        modal_moments(model.nodes, model.mass, basis.basis),
        basis.reduced_stiffness,
        0.0 * basis.reduced_stiffness,
    )
    return model, basis.basis, ends, body


def clamped_cantilever(n_modes: int, gravity=(0.0, 0.0, -9.81)):
    """The soft bar (E = 1e8 Pa, 450 kg/m^3) clamped at its x = 0 face (frame held by a point and two perpendicular
    constraints), ``n_modes`` Craig-Bampton modes of that face: ``(model, clamp nodes, basis, system)``."""
    from ffrf.body.flexible_body import FlexibleBody
    from ffrf.body.modal_moments import modal_moments
    from ffrf.reduction.craig_bampton import craig_bampton
    from ffrf.system.constraints import GroundPerpendicular, GroundPoint
    from ffrf.system.multibody import MultibodySystem

    model = bar_model(E=1e8, rho=450.0)
    clamp = np.flatnonzero(model.nodes[:, 0] < 1e-9)
    basis = craig_bampton(model, [clamp], n_modes)
    body = FlexibleBody(
        "bar",
        modal_moments(model.nodes, model.mass, basis.basis),
        basis.reduced_stiffness,
        0.0 * basis.reduced_stiffness,
    )
    e = np.eye(3)
    fixed = (
        GroundPoint((0,), "clamp"),
        GroundPerpendicular((0,), "clamp y", vector=e[1], normals=e[[0, 2]]),
        GroundPerpendicular((0,), "clamp x", vector=e[0], normals=e[[2]]),
    )
    return model, clamp, basis.basis, MultibodySystem((body,), fixed, gravity=np.asarray(gravity, dtype=float))


def tumbling_start(body):
    """A one-body system of ``body`` thrown at 0.1 m/s, spun at (0.5, 1, 5) rad/s (body frame),
    its modes excited at random (1e-5): ``(system, q0, qd0)``."""
    from ffrf.system.multibody import MultibodySystem

    system = MultibodySystem((body,))
    q0 = system.initial_state()
    qd0 = np.zeros_like(q0)
    qd0[:3] = [0.1, 0.0, 0.0]
    qd0[3:7] = 0.25 * g_bar(q0[3:7]).T @ np.array([0.5, 1.0, 5.0])  # G G^T = 4 I
    q0[7:] = 1e-5 * np.random.default_rng(0).normal(size=body.n_modes)
    return system, q0, qd0


def two_bar_chain():
    """Two soft flexible bars (3 fixed-interface modes, beta K damping): bar 0 on a driven
    revolute to the ground (frame marker, offsets, turned frames), bar 1 on bar 0's far bore by a
    joint locking a subset (tx, tz, rx, rz) with a prescribed angle, between rigid interface
    markers with offsets: every branch of Eqs. (J1)-(J3). Bar 1 keeps two free motions (its
    unlocked translation and rotation), so the static tangent is exactly singular."""
    from ffrf.body.flexible_body import FlexibleBody
    from ffrf.body.modal_moments import modal_moments
    from ffrf.reduction.craig_bampton import craig_bampton
    from ffrf.system.joints import GroundFrame, MarkerJoint, driven_revolute_joint, revolute_joint
    from ffrf.system.markers import frame_marker, rigid_interface_marker
    from ffrf.system.multibody import MultibodySystem

    model = bar_model(E=1e8, rho=450.0)
    ends = [np.flatnonzero(model.nodes[:, 0] < 1e-9), np.flatnonzero(model.nodes[:, 0] > 0.2 - 1e-9)]
    basis = craig_bampton(model, ends, 3)
    bodies = [
        FlexibleBody(
            name,
            modal_moments(model.nodes, model.mass, basis.basis),
            basis.reduced_stiffness,
            0.01 * basis.reduced_stiffness,
        )
        for name in ("bar0", "bar1")
    ]
    psi = basis.basis
    rng = np.random.default_rng(7)
    turn = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    turn *= np.sign(np.linalg.det(turn))
    ground = GroundFrame(np.array([0.0, 0.01, 0.005]), turn)
    drive = driven_revolute_joint(
        ground,
        frame_marker(0, bodies[0].n_modes, (0.0, 0.01, 0.005)),
        lambda t: 0.3 * np.sin(2 * t),
        rotation1=turn,
        offset0=np.array([0.0, 0.0, 0.002]),
        offset1=np.array([0.0, 0.0, 0.002]),
        name="drive",
    )
    far0 = rigid_interface_marker(0, model.nodes, psi, ends[1], name="bar0:far")
    near1 = rigid_interface_marker(1, model.nodes, psi, ends[0], name="bar1:near")
    hinge = revolute_joint(far0, near1, offset0=np.array([0.001, 0.0, 0.003]), offset1=np.array([-0.2, 0.0, 0.002]))
    subset = MarkerJoint(
        hinge.bodies,
        "subset",
        hinge.marker0,
        hinge.marker1,
        turn,
        turn.T,
        hinge.offset0,
        hinge.offset1,
        (True, False, True, True, False, True),
        lambda t: 0.1 * t,
    )
    return MultibodySystem(tuple(bodies), (drive, subset), gravity=np.array([0.0, 0.0, -9.81]))


def rigid_bar(rho: float = 450.0):
    """The 0.2 x 0.02 x 0.01 m bar (``bar_model(E=1e8, rho)``) as one rigid body (no modes), its FE model and mass."""
    from ffrf.body.flexible_body import FlexibleBody
    from ffrf.body.modal_moments import modal_moments

    model = bar_model(E=1e8, rho=rho)
    body = FlexibleBody(
        "bar",
        modal_moments(model.nodes, model.mass, np.zeros((3 * len(model.nodes), 0))),
        np.zeros((0, 0)),
        np.zeros((0, 0)),
    )
    return body, model, rho * 0.2 * 0.02 * 0.01


#: The spring truss's half span and rise (m), its springs' stiffness (N/m) and its load per unit of t (N).
TRUSS_HALF_SPAN, TRUSS_RISE, TRUSS_STIFFNESS, TRUSS_LOAD_RATE = 0.3, 0.1, 1e4, 10.0


def spring_truss() -> tuple[MultibodySystem, float]:
    """A von Mises truss of axial springs (Eq. (E6)) whose apex, a rigid bar, slides along world z at its centre of
    mass under a downward load TRUSS_LOAD_RATE t; and the limit load of its closed form
    P_max = 2 k (L0 - L*) z* / L*, L* = (L0 a^2)^(1/3), z* = sqrt(L*^2 - a^2)."""
    model = bar_model(E=1e8, rho=450.0)
    body = FlexibleBody(
        "apex",
        modal_moments(model.nodes, model.mass, np.zeros((3 * len(model.nodes), 0))),
        np.zeros((0, 0)),
        np.zeros((0, 0)),
    )
    centre = model.center_of_mass
    marker = frame_marker(0, 0, centre, "apex")
    slide = MarkerJoint((0,), "slide", GroundFrame(point=centre), marker, locked=(True, True, False, True, True, True))
    length = float(np.hypot(TRUSS_HALF_SPAN, TRUSS_RISE))
    springs = tuple(
        AxialSpringDamper(
            (0,),
            f"bar {side}",
            GroundFrame(point=centre + [side * TRUSS_HALF_SPAN, 0.0, -TRUSS_RISE]),
            marker,
            TRUSS_STIFFNESS,
            0.0,
            length,
        )
        for side in (-1.0, 1.0)
    )
    load = MarkerLoad((0,), "load", marker, force=lambda t: [0.0, 0.0, -TRUSS_LOAD_RATE * t])
    system = MultibodySystem((body,), (slide,), forces=springs + (load,))
    critical = (length * TRUSS_HALF_SPAN**2) ** (1.0 / 3.0)
    rise = np.sqrt(critical**2 - TRUSS_HALF_SPAN**2)
    return system, 2.0 * TRUSS_STIFFNESS * (length - critical) * rise / critical


def spring_truss_landing(load: float) -> float:
    """The rise (m) of the spring truss's apex on its inverted branch under ``load`` (N, downward), from the closed
    form P(z) = 2 k (L0 - L) z / L, L = sqrt(a^2 + z^2), beyond the other fold z < -z*."""
    length0 = np.hypot(TRUSS_HALF_SPAN, TRUSS_RISE)

    def closed_form(rise: float) -> float:
        length = np.hypot(TRUSS_HALF_SPAN, rise)
        return 2.0 * TRUSS_STIFFNESS * (length0 - length) * rise / length

    critical_rise = np.sqrt((length0 * TRUSS_HALF_SPAN**2) ** (2.0 / 3.0) - TRUSS_HALF_SPAN**2)
    return float(brentq(lambda z: closed_form(z) - load, -10.0 * TRUSS_RISE, -critical_rise, xtol=1e-15))
