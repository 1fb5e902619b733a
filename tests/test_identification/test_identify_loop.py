"""Identification of any single loop (identification.loop.identify_loop) on exact rigid motions.

The tracked points move with their links along the rigid motion that kinematics.trace_motion finds (itself
checked against Rational Linkages' motion polynomials); the identified axes and DH parameters must be the
mechanism's own, to 1e-12 (an exact record: only round-off in the circle fits remains; measured 3e-15).
"""

from __future__ import annotations

import numpy as np
import pytest
from kinematics_reference import goldberg_5r

from identification import IdentificationError
from identification.loop import identify_loop
from kinematics import BennettLinkage, SingleLoop, dh_from_axes, trace_motion, wrap_angle
from kinematics.rational_mechanism import load_model, loop_from_mechanism, tool_link


def _record(loop: SingleLoop, driver: int, poses: int, rng: np.random.Generator) -> dict[int, np.ndarray]:
    """Three points per moving link, 20-60 mm off its first axis, moved along one revolution of the driver."""
    motion = trace_motion(loop, driver=driver, n_poses=poses)
    transforms = motion.link_transforms()  # (poses, n, 4, 4)
    record = {}
    for k in range(1, loop.n):
        axis = loop.axes[k - 1]
        points = axis.point + rng.uniform(0.02, 0.06, size=(3, 3)) * rng.choice([-1, 1], size=(3, 3))
        record[k] = np.einsum("jab,kb->jka", transforms[:, k, :3, :3], points) + transforms[:, k, None, :3, 3]
    return record


def _same_lines(identified, true) -> float:
    """Largest difference of direction and moment between identified and true axes, up to each one's sign."""
    worst = 0.0
    for a, b in zip(identified, true, strict=True):
        sign = np.sign(a.direction @ b.direction)
        worst = max(worst, float(np.max(np.abs(a.direction - sign * b.direction))))
        worst = max(worst, float(np.max(np.abs(a.moment - sign * b.moment))))
    return worst


@pytest.mark.parametrize("name", ["collisions_free_6r", "interp_4poses_6r", "bennett_ark24"])
def test_rational_mechanisms_are_identified_exactly(name):
    mechanism = load_model(name)
    loop = loop_from_mechanism(mechanism, scale=0.1)
    rng = np.random.default_rng(3)
    record = _record(loop, driver=0, poses=90, rng=rng)
    nominal = loop.dh().alpha + rng.normal(0.0, np.radians(2.0), loop.n)  # a design off by a few degrees
    identified = identify_loop(record, nominal, tool_link=tool_link(mechanism))
    assert _same_lines(identified.axes, loop.axes) < 1e-12
    # The DH parameters of the true axes, oriented as identified, are the identified ones.
    oriented = [
        b if a.direction @ b.direction > 0 else b.reversed() for a, b in zip(identified.axes, loop.axes, strict=True)
    ]
    true = dh_from_axes(oriented)
    assert np.max(np.abs(identified.dh.a - true.a)) < 1e-12
    assert np.max(np.abs(identified.dh.d - true.d)) < 1e-12
    assert np.max(np.abs(wrap_angle(identified.dh.alpha - true.alpha))) < 1e-12
    assert (identified.ratios != {}) == (loop.n == 4)


def test_the_goldberg_5r_is_identified_exactly():
    """A 5R (kinematics_reference.goldberg_5r): the identified DH table is Goldberg's, which our DH code never made."""
    reference = goldberg_5r(0.1, *np.radians([75.0, 45.0, 100.0]), theta0=0.7)
    loop = SingleLoop.from_points_directions(reference.points, reference.directions)
    rng = np.random.default_rng(3)
    record = _record(loop, driver=0, poses=90, rng=rng)
    a, alpha = reference.dh
    nominal = alpha + rng.normal(0.0, np.radians(2.0), loop.n)  # a design off by a few degrees
    identified = identify_loop(record, nominal, tool_link=2)
    assert _same_lines(identified.axes, loop.axes) < 1e-12  # measured 6.1e-16
    assert np.max(np.abs(identified.dh.a - a)) < 1e-12  # measured 4.2e-17 m
    assert np.max(np.abs(identified.dh.d)) < 1e-12  # Goldberg's offsets are all zero; measured 9.9e-17 m
    assert np.max(np.abs(wrap_angle(identified.dh.alpha - alpha))) < 1e-12  # measured 0
    assert identified.ratios == {}


def test_the_paper_bennett_is_a_4r_case_of_the_same_identification():
    loop = SingleLoop(BennettLinkage.paper().axes)
    record = _record(loop, driver=3, poses=60, rng=np.random.default_rng(5))
    identified = identify_loop(record, BennettLinkage.paper().alpha, tool_link=2)
    assert np.max(np.abs(identified.dh.a - np.array(BennettLinkage.paper().a))) < 1e-12
    assert np.max(np.abs(wrap_angle(identified.dh.alpha - np.array(BennettLinkage.paper().alpha)))) < 1e-12


def test_a_missing_link_is_named():
    loop = loop_from_mechanism(load_model("collisions_free_6r"), scale=0.1)
    record = _record(loop, driver=0, poses=30, rng=np.random.default_rng(1))
    del record[4]
    with pytest.raises(IdentificationError, match="no trajectory for link 4: links 1 to 5 must be tracked"):
        identify_loop(record, loop.dh().alpha, tool_link=3)
