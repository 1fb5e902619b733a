"""The Goldberg 5R (two Bennett linkages with a common link, welded and without it) against independent truth.

- the classical Goldberg DH table ``a = (a, b, c, a, b + c)``, ``alpha = (alpha, beta, gamma, alpha, beta + gamma)``,
  ``d = 0`` (Goldberg 1943; Baker 1979), built from plain 4x4 matrices in ``kinematics_reference.goldberg_5r``;
- Bennett's closed-form motion (kinematics.bennett) of each of the two linkages it is made of;
- the first-order law of a misfit: a perturbed 5R is rigid, and its closure gap grows linearly with the perturbation.
"""

from __future__ import annotations

import numpy as np
import pytest
from kinematics_reference import Goldberg5R, goldberg_5r

from kinematics import (
    BennettLinkage,
    LoopMotion,
    SingleLoop,
    explain_mobility,
    open_loop_axes,
    rigid_mobility,
    trace_motion,
    wrap_angle,
)

# Common link 100 mm at 75 deg, the Bennett partners at 45 deg (73.2 mm) and 100 deg (102.0 mm); I's joint on the
# common link's axis h0 at 0.7 rad: a generic home (0 would fold both Bennett linkages flat).
ALPHA, BETA, GAMMA = np.radians([75.0, 45.0, 100.0])


@pytest.fixture(scope="module")
def goldberg() -> Goldberg5R:
    return goldberg_5r(0.1, ALPHA, BETA, GAMMA, theta0=0.7)


@pytest.fixture(scope="module")
def loop(goldberg: Goldberg5R) -> SingleLoop:
    return SingleLoop.from_points_directions(goldberg.points, goldberg.directions)


@pytest.fixture(scope="module")
def motion(loop: SingleLoop) -> LoopMotion:
    """One full revolution of joint 0 (h1), both ends included."""
    return trace_motion(loop, driver=0, n_poses=121, endpoint=True)


def test_the_construction_has_goldbergs_dh_table(goldberg, loop):
    dh = loop.dh()
    a, alpha = goldberg.dh
    assert np.max(np.abs(dh.a - a)) < 1e-14  # measured 5.6e-17 m
    assert np.max(np.abs(wrap_angle(dh.alpha - alpha))) < 1e-12  # measured 0
    assert np.max(np.abs(dh.d)) < 1e-14  # measured 6.7e-17 m


def test_the_loop_closes_is_mobile_and_turns_a_full_revolution(loop, motion):
    assert np.max(np.abs(loop.residual_weights * loop.closure_residual(np.zeros(5)))) < 1e-12
    assert loop.mobility() == 1
    assert loop.mobility(motion.phi[40]) == 1  # a generic pose a third of a revolution on
    assert np.max(motion.residual) < 1e-12  # relative to the loop's size; measured 2.3e-15
    assert motion.driver_angles[-1] == pytest.approx(2.0 * np.pi)
    # The motion is one closed circuit: after a revolution of joint 0 every joint is back where it started.
    assert np.max(np.abs(wrap_angle(motion.phi[-1]))) < 1e-10  # measured 5.3e-15 rad
    # No singular pose on the way (a 1-dof loop keeps rank n - 1 = 4); measured 0.23 at the worst pose.
    assert np.min(motion.singularity_measure) > 0.02
    report = explain_mobility(loop, driver=0)
    assert report.mobile and report.first_order == 1 and "mobile (overconstrained" in report.summary()


def _perturbed(loop: SingleLoop, delta: float) -> SingleLoop:
    """The Goldberg chain with its twist alpha_1 off by ``delta`` (rad); the closing link h4 -> h0 takes the misfit."""
    dh = loop.dh()
    alpha = dh.alpha.copy()
    alpha[1] += delta
    axes, _ = open_loop_axes(dh.a, alpha, dh.d, dh.theta)
    return SingleLoop(tuple(axes))


def test_a_perturbed_5r_is_rigid_and_its_gap_is_first_order(loop):
    """A twist 1e-3 rad off: the loop assembles (its axes exist) but cannot move; twice the error, twice the gap."""
    small = explain_mobility(_perturbed(loop, 1e-3), driver=0)
    large = explain_mobility(_perturbed(loop, 2e-3), driver=0)
    for report in (small, large):
        assert not report.mobile and report.first_order == 0
        assert "NOT mobile, rigid" in report.summary()
    assert small.gap_translation > 1e3 * 1e-9 * small.scale  # measured 3.9e-6 m; mobile below 1.8e-10 m
    assert large.gap_translation / small.gap_translation == pytest.approx(2.0, rel=0.02)  # measured 2.001
    # The same table, only alpha_1 changed, never closes along a revolution of the driver ...
    dh = loop.dh()
    alpha = dh.alpha.copy()
    alpha[1] += 1e-3
    report = rigid_mobility(dh.a, alpha, dh.d, driver_joint=0, n_angles=24, start=dh.theta)
    assert not report.mobile and "NOT mobile" in report.summary()
    assert report.max_rotation_residual > 0.1e-3  # measured 1.0e-3 rad
    # ... while the nominal table closes at every angle.
    nominal = rigid_mobility(dh.a, dh.alpha, dh.d, driver_joint=0, n_angles=24, start=dh.theta)
    assert nominal.mobile and nominal.max_translation_residual < 1e-12  # measured 5.8e-16 m


def test_the_motion_is_the_composition_of_the_two_bennett_motions(goldberg, motion):
    """Joint 0 of the 5R is Bennett I's joint 1 and joint 4 is Bennett II's joint 1 turned back: each fixes its
    Bennett linkage's pose by Bennett's closed form. Then the weld (II's joint on h0 half a turn from I's) and the
    5R's other joints, h2 (I's joint 2), h3 (I's joint 3 less II's) and g2 (II's joint 2 turned back), must follow."""
    one, two = BennettLinkage(*goldberg.bennett_1), BennettLinkage(*goldberg.bennett_2)
    phi = motion.phi
    first = one.joint_angles_from_driver(goldberg.theta_1[1] + phi[:, 0], joint=1)
    second = two.joint_angles_from_driver(goldberg.theta_2[1] - phi[:, 4], joint=1)
    turn_1 = wrap_angle(first - goldberg.theta_1)  # rotations from the 5R's home, per Bennett joint
    turn_2 = wrap_angle(second - goldberg.theta_2)
    assert np.max(np.abs(wrap_angle(second[:, 0] - first[:, 0] - np.pi))) < 1e-10  # the weld; measured 8.9e-15 rad
    expected = np.stack([turn_1[:, 2], turn_1[:, 3] - turn_2[:, 3], -turn_2[:, 2]], axis=1)
    assert np.max(np.abs(wrap_angle(phi[:, 1:4] - expected))) < 1e-10  # measured 8.0e-15 rad
