"""The paper's cosine-ramp drive: continuity and derivatives."""

import numpy as np
import pytest

from ffrf.system.drives import CosineRamp, rpm


def test_cosine_ramp_is_smooth_and_consistent():
    drive = CosineRamp(rpm(1.0), 1.0)
    assert rpm(60.0) == pytest.approx(2 * np.pi)
    assert float(drive.angle(0.0)) == 0.0 and float(drive.rate(0.0)) == 0.0 and float(drive.acceleration(0.0)) == 0.0
    t = np.linspace(0.0, 3.0, 3001)
    h = 1e-6
    np.testing.assert_allclose((drive.angle(t + h) - drive.angle(t - h)) / (2 * h), drive.rate(t), atol=1e-8)
    np.testing.assert_allclose((drive.rate(t + h) - drive.rate(t - h)) / (2 * h), drive.acceleration(t), atol=1e-6)
    assert float(drive.rate(1.0)) == pytest.approx(rpm(1.0))
    # The paper's run: ramp, then exactly one revolution at 1 rpm: 1 s + 60 s.
    assert drive.time_for_angle(float(drive.angle(1.0)) + 2 * np.pi) == pytest.approx(61.0)
    assert drive.time_for_angle(float(drive.angle(0.4))) == pytest.approx(0.4)
