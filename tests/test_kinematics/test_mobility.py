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
