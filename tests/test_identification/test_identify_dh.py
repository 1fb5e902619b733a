"""Identification of DH parameters from tracked trajectories (paper, Sect. "Kinematic Parameters
Identification"), checked against ideal Bennett motions generated exactly with `kinematics`."""

import warnings

import numpy as np
import pytest
from identification_fixtures import ideal_record
from kinematics_reference import random_bennett

from identification import IdentificationError, LinkRecord, identify_dh, identify_record, run_statistics
from kinematics import BennettLinkage, wrap_angle


def _check_exact(loop, a, alpha, tol=1e-8):
    np.testing.assert_allclose(loop.dh.a, a, atol=tol * max(a))
    np.testing.assert_allclose(wrap_angle(loop.dh.alpha - np.asarray(alpha)), 0, atol=tol)
    np.testing.assert_allclose(loop.dh.d, 0, atol=tol * max(a))


@pytest.mark.parametrize("sweep_deg, points", [(360, 1), (360, 3), (120, 1), (60, 3)])
def test_exact_recovery_for_random_bennett_linkages(rng, sweep_deg, points):
    for _ in range(5):
        a, alpha = random_bennett(rng)
        linkage = BennettLinkage(a, alpha)
        start = rng.uniform(0, 2 * np.pi)
        angles = start + np.linspace(0, np.radians(sweep_deg), 300, endpoint=sweep_deg < 360)
        loop = identify_dh(ideal_record(linkage, angles, points, rng), nominal_alpha=alpha)
        _check_exact(loop, a, alpha)
        ratios = list(loop.ratios.values())
        np.testing.assert_allclose(ratios[0], ratios[2], rtol=1e-8)  # Bennett condition a0/a1 = sin a0 / sin a1


def test_identified_joint_angles_are_those_of_the_first_frame(rng):
    linkage = BennettLinkage.paper()
    angles = 0.7 + np.linspace(0, 2 * np.pi, 400, endpoint=False)
    loop = identify_dh(ideal_record(linkage, angles, 2, rng))
    expected = linkage.joint_angles_from_driver(linkage.home_theta[3] + 0.7, joint=3)
    np.testing.assert_allclose(wrap_angle(loop.dh.theta - expected), 0, atol=1e-8)


def test_noise_bounds_and_standard_deviation_against_monte_carlo(rng):
    """0.1 mm Gaussian marker noise, five runs: a_i within 0.05 mm and alpha_i within 0.03 deg of
    the nominal values, and the five-run standard deviations scatter around the Monte-Carlo
    standard deviation of 200 runs (mean ratio within 25 %)."""
    linkage = BennettLinkage.paper()
    frames = 720
    clean = ideal_record(linkage, np.linspace(0, 2 * np.pi, frames, endpoint=False), 1, rng)

    def run():
        noisy = {k: v + 1e-4 * rng.normal(size=v.shape) for k, v in clean.items()}
        return identify_record(LinkRecord(np.arange(frames) / 100.0, noisy, "noisy"), window=1).loop

    loops = [run() for _ in range(200)]
    monte_carlo_std = np.array([loop.dh.a for loop in loops]).std(axis=0, ddof=1)
    groups = [run_statistics(loops[i : i + 5]) for i in range(0, 200, 5)]
    for stats in groups[:3]:
        assert np.all(np.abs(stats.mean["a"] - linkage.a) < 5e-5)
        assert np.all(np.abs(np.degrees(wrap_angle(stats.mean["alpha"] - np.array(linkage.alpha)))) < 0.03)
    five_run_std = np.array([g.std["a"] for g in groups])
    ratio = five_run_std.mean(axis=0) / monte_carlo_std
    # E[s] for n = 5 normal samples is c4 = 0.940 times sigma.
    np.testing.assert_allclose(ratio, 0.940, rtol=0.25)


def test_moving_average_bias_shrinks_quadratically_with_sampling(rng):
    """The paper's 10-frame moving average averages chords of a non-uniformly traversed circle,
    which biases the fit by O((window * step)^2): 2.78x more frames -> ~7.7x smaller bias."""
    linkage = BennettLinkage.paper()
    errors = []
    for frames in (720, 2000):
        clean = ideal_record(linkage, np.linspace(0, 2 * np.pi, frames, endpoint=False), 1, rng)
        loop = identify_record(LinkRecord(np.arange(frames) / 100.0, clean, "ideal"), window=10).loop
        errors.append(np.abs(loop.dh.a - linkage.a).max())
    assert errors[0] > 1e-6  # the bias is real ...
    assert errors[0] / errors[1] == pytest.approx((2000 / 720) ** 2, rel=0.15)  # ... and second order


def _record(rng, frames=360, sweep=2 * np.pi):
    linkage = BennettLinkage.paper()
    points = ideal_record(linkage, np.linspace(0, sweep, frames, endpoint=False), 1, rng)
    return linkage, LinkRecord(np.arange(frames) / 50.0, points, "test record")


def test_dropped_duplicated_and_unsorted_frames(rng):
    linkage, record = _record(rng)
    points = {k: v.copy() for k, v in record.points.items()}
    points[2][[10, 11, 12, 200]] = np.nan  # dropped frames
    time = record.time.copy()
    order = np.arange(record.n_frames)
    order[[50, 51]] = order[[51, 50]]  # two frames swapped
    order = np.r_[order, 100]  # one frame recorded twice
    messy = LinkRecord(time[order], {k: v[order] for k, v in points.items()}, "messy")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = identify_record(messy, window=1)
    messages = " ".join(str(w.message) for w in caught)
    assert "not in order" in messages and "duplicated" in messages and "missing positions" in messages
    _check_exact(result.loop, linkage.a, linkage.alpha)
    assert result.frames_used == record.n_frames - 4


def test_gaps_split_the_filter(rng):
    """The moving average never runs across dropped frames: each side is filtered on its own."""
    linkage, record = _record(rng, frames=720)
    points = {k: v.copy() for k, v in record.points.items()}
    for v in points.values():
        v[300:340] = np.nan
    with pytest.warns(UserWarning, match="missing positions"):
        result = identify_record(LinkRecord(record.time, points, "gap"), window=10)
    assert result.frames_used == 720 - 40 - 2 * 9


def test_record_shorter_than_a_revolution(rng):
    linkage, record = _record(rng, sweep=np.radians(90))
    result = identify_record(record, window=1)
    _check_exact(result.loop, linkage.a, linkage.alpha)
    assert result.revolutions == pytest.approx(0.25, abs=0.01)
    _, too_short = _record(rng, sweep=np.radians(4))
    with pytest.raises(IdentificationError, match="turns only"):
        identify_record(too_short, window=1)


def test_link_that_barely_moves_and_missing_links(rng):
    _, record = _record(rng)
    frozen = dict(record.points)
    frozen[1] = np.repeat(frozen[1][:1], record.n_frames, axis=0) + 1e-9 * rng.normal(size=frozen[1].shape)
    with pytest.raises(IdentificationError, match="link 1"):
        identify_record(LinkRecord(record.time, frozen, "frozen"), window=1)
    with pytest.raises(IdentificationError, match="links \\[3\\] are not tracked"):
        identify_record(LinkRecord(record.time, {1: record.points[1], 2: record.points[2]}, "two links"))
