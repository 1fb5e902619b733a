"""Rigid mobility: the Bennett loop moves, the paper's misaligned loops do not."""

import numpy as np
import pytest

from kinematics import PAPER_A, PAPER_ALPHA, rigid_mobility


def test_bennett_loop_is_mobile():
    report = rigid_mobility(PAPER_A, PAPER_ALPHA, n_angles=48)
    assert report.mobile
    assert report.max_translation_residual < 1e-10


@pytest.mark.parametrize("alpha3_deg", [91.0, 92.0])
def test_misaligned_loops_are_reported_not_mobile(alpha3_deg):
    alpha = np.array(PAPER_ALPHA)
    alpha[3] = np.radians(alpha3_deg)
    report = rigid_mobility(PAPER_A, alpha, n_angles=48)
    assert not report.mobile
    assert "NOT mobile" in report.summary()
    # The twists no longer sum consistently, so no rigid closure removes the 1 or 2 deg misfit,
    # and the translational misfit is of the order of a link length times the misalignment.
    misfit = np.radians(alpha3_deg - 90.0)
    assert report.max_rotation_residual == pytest.approx(misfit, rel=0.05)
    assert 0.1 * misfit * 0.11 < report.max_translation_residual < 2 * misfit * 0.22


def _bennett_with_turned_axis(degrees: float):
    """The paper's Bennett axes with h3 turned about the common normal of h0 and h3 (through its foot on h3)."""
    from scipy.spatial.transform import Rotation

    from kinematics import BennettLinkage, Line, SingleLoop, common_normal

    axes = list(BennettLinkage.paper().axes)
    normal = common_normal(axes[0], axes[3])
    rotation = Rotation.from_rotvec(np.radians(degrees) * normal.unit).as_matrix()
    foot = normal.foot1
    axes[3] = Line.from_point_direction(foot, rotation @ axes[3].direction)
    return SingleLoop(tuple(axes))


def test_explain_mobility_of_mobile_and_rigid_loops():
    from kinematics import BennettLinkage, SingleLoop, explain_mobility
    from kinematics.rational_mechanism import load_model, loop_from_mechanism

    bennett = explain_mobility(SingleLoop(BennettLinkage.paper().axes), driver=3)
    assert bennett.mobile and bennett.first_order == 1 and bennett.conditions == ()
    assert bennett.gap_translation < 1e-12
    six = explain_mobility(loop_from_mechanism(load_model("collisions_free_6r"), scale=0.1))
    assert six.mobile and "mobile (overconstrained" in six.summary()
    rng = np.random.default_rng(7)
    generic = explain_mobility(SingleLoop.from_points_directions(rng.normal(size=(4, 3)), rng.normal(size=(4, 3))))
    assert not generic.mobile and generic.first_order == 0 and "NOT mobile, rigid" in generic.summary()


def test_a_turned_bennett_axis_names_the_twist_condition_and_its_gap_grows_linearly():
    from kinematics import explain_mobility

    small = explain_mobility(_bennett_with_turned_axis(0.5), driver=3)
    large = explain_mobility(_bennett_with_turned_axis(1.0), driver=3)
    assert not small.mobile and not large.mobile
    assert any("alpha0 = alpha2" in c for c in large.conditions)
    # First order in the misalignment: twice the error, twice the gap (to 2 %).
    assert large.gap_translation / small.gap_translation == pytest.approx(2.0, rel=0.02)
