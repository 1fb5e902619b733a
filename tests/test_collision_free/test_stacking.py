"""Stacking the housings along the joint axes (:mod:`ffrf.scenes.collision_free`): the attach points, the speed
bound between sampled poses, and the refusals."""

import numpy as np
import pytest

from ffrf.errors import GeometryError
from ffrf.geometry.link_geometry import LinkDesign
from ffrf.scenes.collision_free import (
    Stacking,
    design_stacking,
    link_build_inputs,
    proxy_clearance,
    sampled_motion,
)
from ffrf.scenes.linkage_description import joint_points
from kinematics import PAPER_A, PAPER_ALPHA, BennettLinkage, SingleLoop

BENNETT = SingleLoop(BennettLinkage(PAPER_A, PAPER_ALPHA).axes)


def _start() -> np.ndarray:
    from ffrf.scenes.linkage_description import start_pose

    return start_pose(BENNETT, 3, -np.pi / 2)


def test_housings_at_a_joint_are_one_gap_and_the_spacer_apart_about_the_offset():
    """Housing centres on h_j: their middle at the offset from the joint point, their distance L + gap + spacer."""
    design = LinkDesign()
    stacking = Stacking((0.01, -0.02, 0.0, 0.005), (0.0, 0.003, 0.0, 0.01))
    attach = stacking.attach_points(BENNETT, design)
    points = joint_points(BENNETT)
    for j, axis in enumerate(BENNETT.axes):
        lower, upper = attach[j]
        assert (upper - lower) @ axis.direction == pytest.approx(
            design.housing_length + design.axial_gap + stacking.spacers[j], abs=1e-15
        )
        assert (0.5 * (lower + upper) - points[j]) @ axis.direction == pytest.approx(stacking.offsets[j], abs=1e-15)
    # the links' build inputs put each link's housing on those centres (s from its joint point, Eq. of build_link)
    s = design.housing_offset
    for k, link in enumerate(link_build_inputs(BENNETT, stacking, design)):
        np.testing.assert_allclose(link.joint_points[0] + s * link.axes[0].direction, attach[k - 1, 1], atol=1e-15)
        np.testing.assert_allclose(link.joint_points[1] - s * link.axes[1].direction, attach[k, 0], atol=1e-15)


def test_the_bound_between_poses_holds_on_a_finer_sampling():
    """The clearance bounded from 181 poses by the links' speeds is never above the one sampled at 1441 poses (the
    same motion), and is within the bound's allowance of it."""
    start = _start()
    coarse = proxy_clearance(BENNETT, sampled_motion(BENNETT, 3, start, 181), Stacking.nominal(4))
    fine = proxy_clearance(BENNETT, sampled_motion(BENNETT, 3, start, 1441), Stacking.nominal(4))
    assert coarse.pairs == fine.pairs
    assert np.all(coarse.clearance <= fine.clearance + 1e-12)
    assert np.all(fine.clearance - coarse.clearance < 0.05)  # 2 deg steps at < 1 m/rad: at most ~2 cm apart


def test_nominal_bennett_links_pass_through_each_other():
    """The paper's Bennett with the nominal stacking: the proxies of every two links sharing a joint, and of the
    base and the coupler, overlap somewhere along the revolution (the solids do too at the folded poses, where the
    arms lie along one line)."""
    clearance = proxy_clearance(BENNETT, sampled_motion(BENNETT, 3, _start(), 181), Stacking.nominal(4))
    overlapping = {pair for pair, value in zip(clearance.pairs, clearance.clearance, strict=True) if value < 0.0}
    assert overlapping >= {(0, 1), (1, 2), (2, 3), (0, 3), (0, 2)}


def test_no_room_to_move_is_refused_naming_the_pair_and_the_angle():
    """Bounds of zero leave the nominal stacking, which collides: the refusal names the links, angle, clearance."""
    with pytest.raises(GeometryError, match=r"links \d and \d come within -\d+\.\d\d mm at drive angle -?\d+\.\d deg"):
        design_stacking(BENNETT, 3, _start(), max_offset=0.0, max_spacer=0.0, n_poses=91)


def test_a_margin_beyond_the_axial_gap_is_refused():
    with pytest.raises(ValueError, match="axial gap"):
        design_stacking(BENNETT, 3, _start(), margin=2e-3, n_poses=91)
