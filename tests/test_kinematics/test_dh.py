"""DH transforms, axes of closed loops, and the inverse map from axes to DH parameters."""

import numpy as np
import pytest
from kinematics_reference import dh_step, random_bennett

from kinematics import (
    PAPER_A,
    PAPER_ALPHA,
    Line,
    LoopClosureError,
    dh_axes,
    dh_from_axes,
    dh_matrix,
    dh_transform,
    loop_closure_residual,
    open_loop_axes,
    wrap_angle,
)

SQRT3 = np.sqrt(3.0)
# The paper's Eq. for h_0..h_3 (Sect. "Recovery of Motion Polynomials"), typed in from the text:
# h = l + eps * (dual vector) with coefficients [0, i, j, k, 0, eps i, eps j, eps k].
PAPER_AXES = np.array(
    [
        [0, 0, 0, 1, 0, 0, 0, 0],
        [0, 0, 0.5, -SQRT3 / 2, 0, 0, 11 * SQRT3 / 200, 11 / 200],
        [0, 0, SQRT3 / 2, 0.5, 0, 0, 11 / 200, -11 * SQRT3 / 200],
        [0, 0, -1, 0, 0, 0, 0, 11 / 50],
    ]
)


def test_dh_transform_matches_lynch_park_matrices(rng):
    for _ in range(20):
        a, alpha, d, theta = rng.normal(size=4)
        expected = dh_step(a, alpha, d, theta)
        np.testing.assert_allclose(dh_matrix(a, alpha, d, theta), expected, atol=1e-14)
        np.testing.assert_allclose(dh_transform(a, alpha, d, theta).to_matrix(), expected, atol=1e-14)


def test_dh_transform_broadcasts_over_theta():
    thetas = np.linspace(0, 2 * np.pi, 7)
    batch = dh_transform(0.1, 0.2, 0.3, thetas)
    assert batch.shape == (7,)
    np.testing.assert_allclose(batch.to_matrix(), [dh_step(0.1, 0.2, 0.3, t) for t in thetas], atol=1e-14)


def test_paper_axes_reproduced():
    """dh_axes on the paper's Table gives exactly the paper's h_0..h_3 (to 1e-12)."""
    axes = dh_axes(PAPER_A, PAPER_ALPHA)
    for ours, theirs in zip(axes, PAPER_AXES, strict=True):
        np.testing.assert_allclose(ours.to_dual_quaternion().coeffs, theirs, atol=1e-12)


def test_round_trip_for_random_bennett_linkages(rng):
    """DH -> axes -> DH to 1e-10, negative twists included."""
    for _ in range(200):
        a, alpha = random_bennett(rng)
        recovered = dh_from_axes(dh_axes(a, alpha))
        np.testing.assert_allclose(recovered.a, a, atol=1e-10)
        np.testing.assert_allclose(wrap_angle(recovered.alpha - np.array(alpha)), 0, atol=1e-10)
        np.testing.assert_allclose(recovered.d, 0, atol=1e-10)
        np.testing.assert_allclose(wrap_angle(recovered.theta - [0, np.pi, 0, np.pi]), 0, atol=1e-10)


@pytest.mark.parametrize("alpha0", [1e-3, -1e-3, np.pi - 1e-3, -(np.pi - 1e-3)])
def test_round_trip_with_twists_near_zero_or_pi(alpha0):
    alpha1 = 0.8 * np.sign(alpha0)
    a0 = 0.05
    a1 = a0 * np.sin(alpha1) / np.sin(alpha0)
    a, alpha = (a0, a1, a0, a1), (alpha0, alpha1, alpha0, alpha1)
    recovered = dh_from_axes(dh_axes(a, alpha))
    np.testing.assert_allclose(recovered.a, a, rtol=1e-10)
    np.testing.assert_allclose(wrap_angle(recovered.alpha - np.array(alpha)), 0, atol=1e-10)
    np.testing.assert_allclose(recovered.d, 0, atol=1e-10 * a1)


def test_round_trip_for_general_closed_loops(rng):
    """A 4R with a3 + a0 = a1 + a2 and alpha3 + alpha0 = alpha1 + alpha2 closes folded without being Bennett."""
    for _ in range(50):
        a0, a1, a2 = rng.uniform(0.05, 0.3, 3)
        al0, al1, al2 = rng.uniform(-3, 3, 3)
        a = (a0, a1, a2, a1 + a2 - a0)
        if a[3] <= 0.01:
            continue
        alpha = (al0, al1, al2, wrap_angle(al1 + al2 - al0))
        recovered = dh_from_axes(dh_axes(a, alpha))
        np.testing.assert_allclose(recovered.a, a, atol=1e-10)
        np.testing.assert_allclose(wrap_angle(recovered.alpha - np.array(alpha)), 0, atol=1e-9)


def test_offsets_d_are_recovered():
    """Three skew axes built by hand: DH read off (with offsets d), the loop closes, and it rebuilds."""
    lines = [
        Line.from_point_direction([0, 0, 0], [0, 0, 1]),
        Line.from_point_direction([0.3, 0, 0.1], [0, 1, 0.2]),
        Line.from_point_direction([0.1, 0.4, -0.2], [1, 0.3, 0.1]),
    ]
    p = dh_from_axes(lines)
    assert np.max(np.abs(p.d)) > 0.01
    np.testing.assert_allclose(loop_closure_residual(p.a, p.alpha, p.d, p.theta), 0, atol=1e-12)
    rebuilt = dh_axes(p.a, p.alpha, p.d, p.theta)
    again = dh_from_axes(rebuilt)
    for name in ("a", "alpha", "d", "theta"):
        np.testing.assert_allclose(getattr(again, name), getattr(p, name), atol=1e-12)


def test_non_closing_chain_is_refused_and_misfit_reported():
    alpha = np.array(PAPER_ALPHA)
    alpha[3] = np.radians(91.0)
    with pytest.raises(LoopClosureError, match="does not close"):
        dh_axes(PAPER_A, alpha)
    axes, closing = open_loop_axes(PAPER_A, alpha)
    # Links 0..2 are nominal; the base link's own h_3' is tilted by the 1 deg misalignment.
    nominal = dh_axes(PAPER_A, PAPER_ALPHA)
    for ours, theirs in zip(axes, nominal, strict=True):
        assert ours.is_close(theirs, tol=1e-12)
    tilt = np.arccos(np.clip(closing.direction @ axes[3].direction, -1, 1))
    assert np.degrees(tilt) == pytest.approx(1.0, abs=1e-9)


def test_bad_parameters_are_named():
    with pytest.raises(ValueError, match="a_i must be >= 0"):
        dh_axes([-0.1, 0.2, 0.1, 0.2], PAPER_ALPHA)
    with pytest.raises(ValueError, match="NaN"):
        dh_axes([np.nan, 0.2, 0.1, 0.2], PAPER_ALPHA)
    with pytest.raises(ValueError, match="give theta"):
        dh_axes(PAPER_A, PAPER_ALPHA, d=[0.01, 0, 0, 0])
