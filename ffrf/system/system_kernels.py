r"""Numba kernels of a whole multibody system packed into plain arrays (the fast path).

One call evaluates, for every body and constraint of a :class:`ffrf.system.packed_system.PackedSystem`,
what :class:`ffrf.system.multibody.MultibodySystem` assembles body by body and constraint by constraint
in Python (``docs/formulation.md``, Eqs. (G1), (G3), (FP4)-(FP6)):

* body terms: Eqs. (F8)-(F11) with :func:`ffrf.body.flexible_body.body_residual`, exact tangents
  with :func:`ffrf.body.body_tangents.body_tangents` (analytic, Eqs. (F12)-(F14));
* constraints: Euler normalisations (Eq. (R2)) and marker joints (Eqs. (J1)-(J3)) with
  :func:`ffrf.system.marker_kernels.marker_frame`; the term :math:`H = \partial(C_q^T\lambda)/\partial q`
  analytically from :func:`ffrf.system.marker_kernels.marker_frame_hessian` (Eq. (FP5)); the residual's
  :math:`C_q^T\lambda` from the joints' weights, without the Jacobian
  (:func:`ffrf.system.marker_kernels.marker_frame_transpose`, Eq. (FP7)).

Packed data (built by :func:`ffrf.system.packed_system.pack_system`), plain arrays only so that a call
costs microseconds; arrays of different sizes per body or joint are concatenated flat
(``flat[starts[i]:starts[i + 1]]``, reshaped in the kernel):

``bodies = (offsets, mass, exact_gravity, real, starts)``: coordinate offsets (B+1), and
per body the modal moments of Eq. (F4), ``K_r`` and ``D_r``, in the order ``s0, s1, x2, c, d,
mred, kred, dred``: ``real`` is a tuple of eight flat float64 buffers, ``starts`` is (8, B+1).

``joints = (kind, body0, body1, rows, locked, side0, side1)``: per constraint its kind (0: Euler
normalisation of ``body1``, 1: marker joint), bodies (-1: ground), first row (J+1, the last is
the total), locked directions (J, 6); each side is ``(point (J, 3), rotation (J, 3, 3), offset
(J, 3), P flat, Theta flat, starts (J+1))``: the marker point, joint rotation and offset and the
marker's ``3 x m`` matrices ``P`` and :math:`\Theta`. A ground side keeps its joint point in
``point`` and its joint axes in ``rotation`` (already composed) and has no modes.
``phi`` holds each constraint's prescribed angle :math:`\varphi(t)` (0 when it has none).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ffrf.body.body_kernels import mass_matrix
from ffrf.body.body_tangents import body_tangents
from ffrf.body.flexible_body import body_residual
from ffrf.numerics.small_linalg import dot, vec_mat
from ffrf.system.marker_kernels import marker_frame, marker_frame_hessian, marker_frame_transpose, marker_pose

__all__ = [
    "system_residual",
    "system_jacobian",
    "system_hessian",
    "system_body_tangents",
    "system_mass_matrix",
    "system_iteration_matrix",
]

EULER, MARKER_JOINT = 0, 1

# The thin helpers, and the body blocks system_iteration_matrix calls, are inlined at numba's level
# (inline="always"): a kernel compiled on its own re-optimises in LLVM everything it calls, once more
# per level of calls, and that is most of a cold start (issue #22, bench/compile_times.py).
#
# Flags and start indices go to the inner kernels as np.bool_ / np.int64 values, never as Python
# literals: numba types a literal argument as Literal[bool](True) and compiles the callee once per
# value, and _constraints with _marker_joint is the costliest kernel to compile (issue #22). The
# branches it keeps cost nothing at run time.


@njit(cache=True, inline="always")
def _moments(buffers, starts, b, m):
    """Body ``b``'s ``s0, s1, x2, c, d, mred, kred, dred`` (``m`` modes) as views of the flat buffers."""

    def view(k):
        return buffers[k][starts[k, b] : starts[k, b + 1]]

    return (
        view(0),
        view(1).reshape(3, m),
        view(2).reshape(3, 3),
        view(3).reshape(3, 3, m),
        view(4).reshape(3, 3, m, m),
        view(5).reshape(m, m),
        view(6).reshape(m, m),
        view(7).reshape(m, m),
    )


@njit(cache=True, inline="always")
def _side_data(side, j):
    """Point, P, Theta, rotation and offset of joint ``j``'s ``side`` (layout in the module docstring)."""
    point, rotation, offset, modes, rotation_modes, starts = side
    m = (starts[j + 1] - starts[j]) // 3
    return (
        point[j],
        modes[starts[j] : starts[j + 1]].reshape(3, m),
        rotation_modes[starts[j] : starts[j + 1]].reshape(3, m),
        rotation[j],
        offset[j],
    )


@njit(cache=True)  # not inlined: numba cannot inline a call with *args
def _side(body, point, modes, rotation_modes, rotation, offset, q, offsets):
    """Joint point, axes, dp/dq and d axes/dq of one side of a joint (no columns on the ground, ``body < 0``)."""
    if body < 0:
        return point.copy(), rotation.copy(), np.zeros((3, 0)), np.zeros((3, 3, 0))
    return marker_frame(q[offsets[body] : offsets[body + 1]], point, modes, rotation_modes, rotation, offset)


@njit(cache=True, inline="always")
def _pad(d_point, d_axes, start, total):
    """Side derivatives as columns ``start:`` of the joint's coordinates ``[q_0, q_1]`` (``total`` of them)."""
    n = d_point.shape[1]
    out_point = np.zeros((3, total))
    out_axes = np.zeros((3, 3, total))
    out_point[:, start : start + n] = d_point
    out_axes[:, :, start : start + n] = d_axes
    return out_point, out_axes


@njit(cache=True, inline="always")
def _joint_coordinates(joints, j, offsets):
    """Global indices of the joint's coordinates ``[q_0, q_1]`` and ``n_0``."""
    b0, b1 = joints[1][j], joints[2][j]
    n0 = 0 if b0 < 0 else offsets[b0 + 1] - offsets[b0]
    n1 = offsets[b1 + 1] - offsets[b1]
    index = np.empty(n0 + n1, dtype=np.int64)
    for i in range(n0):
        index[i] = offsets[b0] + i
    for i in range(n1):
        index[n0 + i] = offsets[b1] + i
    return index, n0


@njit(cache=True, inline="always")
def _add_symmetric_product(out, scale, a, b):
    """``out += scale (a^T b + b^T a)`` for ``a``, ``b`` of shape (3, n), in place (no temporaries)."""
    n = a.shape[1]
    for i in range(n):
        for j in range(n):
            total = 0.0
            for k in range(3):
                total += a[k, i] * b[k, j] + b[k, i] * a[k, j]
            out[i, j] += scale * total


@njit(cache=True, inline="always")
def _rotation_row(r, angle):
    """Rotational equation ``r`` of (J2)-(J3), ``x . y`` with ``x = c0 a0_k0 + c1 a0_1`` (side 0) and ``y = a1_k1``
    (side 1): ``(k0, k1, c0, c1)`` for z0.y1, z0.x1 and x0'.y1 (x0' turned by the prescribed ``angle``)."""
    if r == 2:
        return 0, 1, np.cos(angle), np.sin(angle)
    return 2, 1 if r != 1 else 0, 1.0, 0.0


@njit(cache=True, inline="always")
def _joint_equations(locked, angle, lam, p0, axes0, p1, axes1):
    r"""Eqs. (J1)-(J3) of one joint from its two sides' points and axes: the values (rows of the locked
    directions, in :meth:`ffrf.system.joints.MarkerJoint.jacobian`'s order) and the weights that
    :math:`\lambda^Tg` puts on each side's point and axes (:math:`\partial(\lambda^Tg)/\partial p_s` and
    :math:`/\partial a_{s,k}`, columns ``k``): :math:`C_q^T\lambda` is their transpose-map (Eq. (FP3)'s weights)."""
    size = 0
    for i in range(6):
        size += locked[i]
    values = np.empty(size)
    weights = np.zeros(24)  # one buffer, four views: no array per weight or per update (bench/memory.py)
    w_p0, w_p1 = weights[0:3], weights[3:6]
    w_a0, w_a1 = weights[6:15].reshape(3, 3), weights[15:24].reshape(3, 3)
    row = 0
    if locked[0] and locked[1] and locked[2]:  # (J1), world components
        for i in range(3):
            values[i] = p1[i] - p0[i]
            w_p1[i] += lam[i]
            w_p0[i] -= lam[i]
        row = 3
    else:  # (J1), components of J_0^T (p_1 - p_0)
        for i in range(3):
            if locked[i]:
                value = 0.0
                for c in range(3):
                    gap = p1[c] - p0[c]
                    value += axes0[c, i] * gap
                    w_a0[c, i] += lam[row] * gap
                    w_p1[c] += lam[row] * axes0[c, i]
                    w_p0[c] -= lam[row] * axes0[c, i]
                values[row] = value
                row += 1
    for r in range(3):  # (J2)-(J3): z0.y1, z0.x1, x0'.y1
        if not locked[3 + r]:
            continue
        k0, k1, c0, c1 = _rotation_row(r, angle)
        value = 0.0
        for c in range(3):
            x, y = c0 * axes0[c, k0] + c1 * axes0[c, 1], axes1[c, k1]
            value += x * y
            w_a0[c, k0] += c0 * lam[row] * y
            w_a0[c, 1] += c1 * lam[row] * y
            w_a1[c, k1] += lam[row] * x
        values[row] = value
        row += 1
    return values, w_p0, w_a0, w_p1, w_a1


@njit(cache=True)
def _marker_joint(joints, j, q, offsets, phi, lam, want_hessian):
    r"""Eqs. (J1)-(J3) of joint ``j``: values, Jacobian rows on ``[q_0, q_1]`` and, with ``want_hessian``,
    :math:`\partial(C_q^T\lambda)/\partial q` on ``[q_0, q_1]`` (Eqs. (FP4)-(FP5)); same row order as
    :meth:`ffrf.system.joints.MarkerJoint.jacobian`."""
    index, n0 = _joint_coordinates(joints, j, offsets)
    total = index.shape[0]
    locked = joints[4][j]
    b0, b1 = joints[1][j], joints[2][j]
    side0 = _side_data(joints[5], j)
    side1 = _side_data(joints[6], j)
    p0, axes0, dp0_side, da0_side = _side(b0, *side0, q, offsets)
    p1, axes1, dp1_side, da1_side = _side(b1, *side1, q, offsets)
    values, w_p0, w_a0, w_p1, w_a1 = _joint_equations(locked, phi[j], lam, p0, axes0, p1, axes1)
    dp0, da0 = _pad(dp0_side, da0_side, np.int64(0), total)
    dp1, da1 = _pad(dp1_side, da1_side, n0, total)
    rows = np.zeros((values.shape[0], total))
    hessian = np.zeros((total, total))
    gap = p1 - p0
    d_gap = dp1 - dp0
    row = 0
    if locked[0] and locked[1] and locked[2]:  # (J1), world components
        for i in range(3):
            rows[i] = d_gap[i]
        row = 3
    else:  # (J1), components of J_0^T (p_1 - p_0)
        for i in range(3):
            if locked[i]:
                rows[row] = vec_mat(axes0[:, i], d_gap) + vec_mat(gap, da0[i])
                if want_hessian:
                    _add_symmetric_product(hessian, lam[row], da0[i], d_gap)
                row += 1
    for r in range(3):  # (J2)-(J3): z0.y1, z0.x1, x0'.y1
        if not locked[3 + r]:
            continue
        k0, k1, c0, c1 = _rotation_row(r, phi[j])
        x = c0 * axes0[:, k0] + c1 * axes0[:, 1]
        dx = c0 * da0[k0] + c1 * da0[1]
        y = axes1[:, k1]
        rows[row] = vec_mat(x, da1[k1]) + vec_mat(y, dx)
        if want_hessian:
            _add_symmetric_product(hessian, lam[row], dx, da1[k1])
        row += 1
    if want_hessian:  # Eq. (FP5): second derivatives of each side's point and axes, weighted
        if b0 >= 0:
            hessian[:n0, :n0] += marker_frame_hessian(q[offsets[b0] : offsets[b0 + 1]], *side0, w_p0, w_a0)
        hessian[n0:, n0:] += marker_frame_hessian(q[offsets[b1] : offsets[b1 + 1]], *side1, w_p1, w_a1)
    return values, rows, hessian, index


@njit(cache=True)
def _marker_joint_forces(joints, j, q, offsets, phi, lam, forces):
    r"""Eqs. (J1)-(J3) of joint ``j`` for the residual: its values, and :math:`C_q^T\lambda` added to ``forces``
    through each side's :func:`ffrf.system.marker_kernels.marker_frame_transpose`, no Jacobian rows formed."""
    b0, b1 = joints[1][j], joints[2][j]
    point0, modes0, rotation_modes0, rotation0, offset0 = _side_data(joints[5], j)
    point1, modes1, rotation_modes1, rotation1, offset1 = _side_data(joints[6], j)
    q1 = q[offsets[b1] : offsets[b1 + 1]]
    p1, axes1 = marker_pose(q1, point1, modes1, rotation_modes1, rotation1, offset1)
    if b0 < 0:  # the ground keeps its joint point and axes composed
        p0, axes0 = point0, rotation0
    else:
        p0, axes0 = marker_pose(q[offsets[b0] : offsets[b0 + 1]], point0, modes0, rotation_modes0, rotation0, offset0)
    values, w_p0, w_a0, w_p1, w_a1 = _joint_equations(joints[4][j], phi[j], lam, p0, axes0, p1, axes1)
    forces[offsets[b1] : offsets[b1 + 1]] += marker_frame_transpose(
        q1, point1, modes1, rotation_modes1, rotation1, offset1, w_p1, w_a1
    )
    if b0 >= 0:
        forces[offsets[b0] : offsets[b0 + 1]] += marker_frame_transpose(
            q[offsets[b0] : offsets[b0 + 1]], point0, modes0, rotation_modes0, rotation0, offset0, w_p0, w_a0
        )
    return values


@njit(cache=True, inline="always")
def _euler(joints, j, q, offsets):
    """Eq. (R2) normalisation p.p - 1 of body ``joints[2][j]``: value and its Jacobian on ``p``."""
    start = offsets[joints[2][j]] + 3
    p = q[start : start + 4]
    return dot(p, p) - 1.0, (2.0 * p[0], 2.0 * p[1], 2.0 * p[2], 2.0 * p[3]), start


@njit(cache=True)
def _constraints(joints, offsets, q, phi, lam, want_jacobian, want_hessian, n):
    """The Jacobian ``C_q`` (k x n) and ``H`` (n x n), each only if wanted (else empty); the values and
    ``C_q^T lambda`` are the residual's (:func:`_constraint_forces`)."""
    row_starts = joints[3]
    k = row_starts[-1]
    jacobian = np.zeros((k if want_jacobian else 0, n))
    hessian = np.zeros((n if want_hessian else 0, n if want_hessian else 0))
    for j in range(joints[0].shape[0]):
        r0 = row_starts[j]
        if joints[0][j] == EULER:
            _, grad, start = _euler(joints, j, q, offsets)
            for i in range(4):
                if want_jacobian:
                    jacobian[r0, start + i] += grad[i]
                if want_hessian:
                    hessian[start + i, start + i] += 2.0 * lam[r0]
            continue
        size = row_starts[j + 1] - r0
        _, rows, block, index = _marker_joint(joints, j, q, offsets, phi, lam[r0 : r0 + size], want_hessian)
        for a in range(index.shape[0]):
            if want_jacobian:
                for r in range(size):
                    jacobian[r0 + r, index[a]] += rows[r, a]
            if want_hessian:
                for b in range(index.shape[0]):
                    hessian[index[a], index[b]] += block[a, b]
    return jacobian, hessian


@njit(cache=True, inline="always")
def _body_residuals(bodies, q, qd, qdd, gravity):
    """Eqs. (F8)-(F11) of every body: ``M qdd - Q``."""
    offsets = bodies[0]
    out = np.empty(offsets[-1])
    for b in range(offsets.shape[0] - 1):
        s, e = offsets[b], offsets[b + 1]
        moments = _moments(bodies[3], bodies[4], b, e - s - 7)
        out[s:e] = body_residual(q[s:e], qd[s:e], qdd[s:e], gravity, bodies[1][b], *moments, bodies[2][b])
    return out


@njit(cache=True, inline="always")
def _constraint_forces(joints, offsets, q, phi, lam, forces):
    """Values ``g`` (k) of every constraint, and ``C_q^T lambda`` added to ``forces`` (n): the residual's share,
    without the Jacobian :func:`_constraints` forms."""
    row_starts = joints[3]
    values = np.empty(row_starts[-1])
    for j in range(joints[0].shape[0]):
        r0 = row_starts[j]
        if joints[0][j] == EULER:
            value, grad, start = _euler(joints, j, q, offsets)
            values[r0] = value
            for i in range(4):
                forces[start + i] += grad[i] * lam[r0]
            continue
        r1 = row_starts[j + 1]
        values[r0:r1] = _marker_joint_forces(joints, j, q, offsets, phi, lam[r0:r1], forces)
    return values


@njit(cache=True)
def system_residual(bodies, joints, q, qd, qdd, lam, gravity, phi):
    r"""Eq. (G1): ``M qdd - Q + C_q^T lambda`` (n) and ``g`` (k)."""
    out = _body_residuals(bodies, q, qd, qdd, gravity)
    values = _constraint_forces(joints, bodies[0], q, phi, lam, out)
    return out, values


@njit(cache=True)
def system_jacobian(bodies, joints, q, phi):
    """``C_q`` (k x n)."""
    lam = np.zeros(joints[3][-1])
    return _constraints(joints, bodies[0], q, phi, lam, np.bool_(True), np.bool_(False), q.shape[0])[0]


@njit(cache=True)
def system_hessian(bodies, joints, q, lam, phi):
    r"""Eq. (FP4): :math:`H = \partial(C_q^T\lambda)/\partial q` (n x n)."""
    return _constraints(joints, bodies[0], q, phi, lam, np.bool_(False), np.bool_(True), q.shape[0])[1]


@njit(cache=True, inline="always")
def system_body_tangents(bodies, q, qd, qdd, gravity, velocity=True):
    """Block-diagonal exact ``d(M qdd - Q)/dq`` and ``d(M qdd - Q)/dqd`` (zero with ``velocity=False``)."""
    offsets = bodies[0]
    n = offsets[-1]
    jac_q, jac_qd = np.zeros((n, n)), np.zeros((n, n))
    for b in range(offsets.shape[0] - 1):
        s, e = offsets[b], offsets[b + 1]
        moments = _moments(bodies[3], bodies[4], b, e - s - 7)
        jq, jqd = body_tangents(q[s:e], qd[s:e], qdd[s:e], gravity, bodies[1][b], *moments, bodies[2][b], velocity)
        jac_q[s:e, s:e] = jq
        jac_qd[s:e, s:e] = jqd
    return jac_q, jac_qd


@njit(cache=True, inline="always")
def system_mass_matrix(bodies, q):
    """Block-diagonal Eq. (F8)."""
    offsets = bodies[0]
    n = offsets[-1]
    out = np.zeros((n, n))
    for b in range(offsets.shape[0] - 1):
        s, e = offsets[b], offsets[b + 1]
        s0, s1, x2, c, d, mred, _, _ = _moments(bodies[3], bodies[4], b, e - s - 7)
        out[s:e, s:e] = mass_matrix(q[s + 3 : s + 7], q[s + 7 : e], bodies[1][b], s0, s1, x2, c, d, mred)
    return out


@njit(cache=True)
def system_iteration_matrix(bodies, joints, q, qd, qdd, lam, gravity, phi, mass_factor, beta_p, gamma_p):
    r"""Eq. (FP6): ``[[c M + beta' (K_t + H) + gamma' D_t, C_q^T], [C_q, 0]]`` in one pass;
    ``c = 1`` for generalized-alpha (Eq. (G3)), ``c = 0, beta' = 1, gamma' = 0`` for statics (Eq. (S1))."""
    n = q.shape[0]
    jacobian, hessian = _constraints(joints, bodies[0], q, phi, lam, np.bool_(True), np.bool_(True), n)
    k = jacobian.shape[0]
    jac_q, jac_qd = system_body_tangents(bodies, q, qd, qdd, gravity, gamma_p != 0.0)
    out = np.zeros((n + k, n + k))
    out[:n, :n] = beta_p * (jac_q + hessian)
    if gamma_p != 0.0:
        out[:n, :n] += gamma_p * jac_qd
    if mass_factor != 0.0:
        out[:n, :n] += mass_factor * system_mass_matrix(bodies, q)
    out[:n, n:] = jacobian.T
    out[n:, :n] = jacobian
    return out
