"""The analytic second derivatives of the fast path (docs/formulation.md, Eqs. (FP1)-(FP3)):
the exponential map's, checked in 40-digit arithmetic (mpmath), and a marker joint frame's,
checked against complex-step differentiation of the analytic first derivatives; and the residual's transposed
map of a joint frame's derivatives, against those derivatives."""

import mpmath
import numpy as np
import pytest

from ffrf.system.marker_kernels import (
    _exp_so3_coefficients,
    exp_so3_hessian,
    marker_frame,
    marker_frame_hessian,
    marker_frame_transpose,
    marker_pose,
)

mpmath.mp.dps = 40


def _exp_action_mp(theta, v, z):
    """z . exp(theta~) v in mpmath (Rodrigues' formula, no series)."""
    theta = [mpmath.mpf(x) for x in theta]
    c = sum(x * x for x in theta)
    phi = mpmath.sqrt(c)
    a, b = mpmath.sin(phi) / phi, (1 - mpmath.cos(phi)) / c
    cross = [theta[1] * v[2] - theta[2] * v[1], theta[2] * v[0] - theta[0] * v[2], theta[0] * v[1] - theta[1] * v[0]]
    tv = sum(t * x for t, x in zip(theta, v, strict=True))
    return sum(zi * (vi + a * ci + b * (tv * ti - c * vi)) for zi, vi, ci, ti in zip(z, v, cross, theta, strict=True))


@pytest.mark.parametrize("scale", [1e-5, 3e-3, 0.2, 0.55, 0.6, 1.7])
def test_exp_so3_hessian_against_high_precision(rng, scale):
    """Eq. (FP2) to 1e-13 relative on both sides of the series switch (c = 1) and for tiny angles,
    where the closed forms of a(c), b(c) cancel."""
    theta, v, z = scale * rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    ours = exp_so3_hessian(theta, v, z)
    ref = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            order = [0, 0, 0]
            order[i] += 1
            order[j] += 1
            ref[i, j] = float(mpmath.diff(lambda *x: _exp_action_mp(x, v, z), list(theta), tuple(order)))
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-13 * np.abs(ref).max())


def test_exp_coefficients_are_continuous_at_the_series_switch():
    below, above = _exp_so3_coefficients(1.0 - 1e-12), _exp_so3_coefficients(1.0 + 1e-12)
    np.testing.assert_allclose(below, above, rtol=1e-12)


@pytest.mark.parametrize("scale", [0.05, 0.5])
def test_marker_frame_hessian_against_complex_step(rng, scale):
    r"""Eq. (FP3): sum_c w_c d^2 p_c/dq^2 + sum_k W_ck d^2 a_k,c/dq^2 equals the complex-step derivative
    of w^T dp/dq + sum_k W_k^T d a_k/dq (marker_frame), for rotations where its closed forms are exact."""
    m = 5
    q = rng.normal(size=7 + m)
    q[3:7] /= np.linalg.norm(q[3:7])
    q[7:] *= scale
    point, modes, rotation_modes = rng.normal(size=3), rng.normal(size=(3, m)), rng.normal(size=(3, m))
    rotation, offset = np.linalg.qr(rng.normal(size=(3, 3)))[0], rng.normal(size=3)
    w_point, w_axes = rng.normal(size=3), rng.normal(size=(3, 3))
    ours = marker_frame_hessian(q, point, modes, rotation_modes, rotation, offset, w_point, w_axes)
    step = 1e-30
    ref = np.empty_like(ours)
    arrays = [a.astype(complex) for a in (point, modes, rotation_modes, rotation, offset)]
    for k in range(q.size):
        shifted = q.astype(complex)
        shifted[k] += 1j * step
        _, _, d_point, d_axes = marker_frame(shifted, *arrays)
        ref[:, k] = (w_point @ d_point + sum(w_axes[:, i] @ d_axes[i] for i in range(3))).imag / step
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-13 * np.abs(ref).max())
    np.testing.assert_allclose(ours, ours.T, rtol=0, atol=1e-14 * np.abs(ours).max())


@pytest.mark.parametrize("modes", [0, 5])
def test_marker_frame_transpose_equals_the_transposed_derivatives(rng, modes):
    """The residual's C_q^T lambda per side: (dp/dq)^T w + sum_k (da_k/dq)^T W_k without forming dp/dq, against
    marker_frame's derivatives (themselves checked against complex steps in test_joints); the pose is its."""
    q = rng.normal(size=7 + modes)
    q[3:7] /= np.linalg.norm(q[3:7])
    q[7:] *= 0.5
    point, position_modes, rotation_modes = rng.normal(size=3), rng.normal(size=(3, modes)), rng.normal(size=(3, modes))
    rotation, offset = np.linalg.qr(rng.normal(size=(3, 3)))[0], rng.normal(size=3)
    w_point, w_axes = rng.normal(size=3), rng.normal(size=(3, 3))
    arrays = (point, position_modes, rotation_modes, rotation, offset)
    position, axes, d_point, d_axes = marker_frame(q, *arrays)
    reference = w_point @ d_point + sum(w_axes[:, k] @ d_axes[k] for k in range(3))
    ours = marker_frame_transpose(q, *arrays, w_point, w_axes)
    np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-14 * np.abs(reference).max())
    pose = marker_pose(q, *arrays)
    np.testing.assert_allclose(pose[0], position, rtol=0, atol=1e-15 * np.abs(position).max())
    np.testing.assert_allclose(pose[1], axes, rtol=0, atol=1e-15)
