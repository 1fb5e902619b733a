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
    order_candidates,
    proxy_clearance,
    sampled_motion,
)
from ffrf.scenes.linkage_description import joint_points
from kinematics import PAPER_A, PAPER_ALPHA, BennettLinkage, SingleLoop

BENNETT = SingleLoop(BennettLinkage(PAPER_A, PAPER_ALPHA).axes)


@pytest.fixture(scope="module")
def fine_motion():
    """The paper's Bennett from its start over one revolution of joint 3 at 1441 poses (0.25 deg apart)."""
    return sampled_motion(BENNETT, 3, _start(), 1441)


def _start() -> np.ndarray:
    from ffrf.scenes.linkage_description import start_pose

    return start_pose(BENNETT, 3, -np.pi / 2)


def test_housings_at_a_joint_are_one_gap_and_the_spacer_apart_about_the_offset():
    """Housing centres on h_j: their middle at the offset from the joint point, their distance L + gap + spacer,
    link j's below link j + 1's along the axis where the order is +1, above where it is -1."""
    design = LinkDesign()
    stacking = Stacking((0.01, -0.02, 0.0, 0.005), (0.0, 0.003, 0.0, 0.01), (1, -1, 1, -1))
    attach = stacking.attach_points(BENNETT, design)
    points = joint_points(BENNETT)
    for j, axis in enumerate(BENNETT.axes):
        lower, upper = attach[j]
        assert (upper - lower) @ axis.direction == pytest.approx(
            (1 if j % 2 == 0 else -1) * (design.housing_length + design.axial_gap + stacking.spacers[j]), abs=1e-15
        )
        assert (0.5 * (lower + upper) - points[j]) @ axis.direction == pytest.approx(stacking.offsets[j], abs=1e-15)
    # the links' build inputs put each link's housing on those centres (s from its joint point, Eq. of build_link)
    s = design.housing_offset
    for k, link in enumerate(link_build_inputs(BENNETT, stacking, design)):
        np.testing.assert_allclose(link.joint_points[0] + s * link.axes[0].direction, attach[k - 1, 1], atol=1e-15)
        np.testing.assert_allclose(link.joint_points[1] - s * link.axes[1].direction, attach[k, 0], atol=1e-15)


def test_the_bound_between_poses_holds_on_a_finer_sampling(fine_motion):
    """The clearance bounded from 181 poses by the links' speeds is never above the one sampled at 1441 poses (the
    same motion), and is within the bound's allowance of it."""
    start = _start()
    coarse = proxy_clearance(BENNETT, sampled_motion(BENNETT, 3, start, 181), Stacking.nominal(4))
    fine = proxy_clearance(BENNETT, fine_motion, Stacking.nominal(4))
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
        design_stacking(BENNETT, 3, _start(), max_offset=0.0, max_spacer=0.0, n_poses=91, max_orders=1)


def test_a_margin_beyond_the_axial_gap_is_refused():
    with pytest.raises(ValueError, match="axial gap"):
        design_stacking(BENNETT, 3, _start(), margin=2e-3, n_poses=91)


def test_stacking_orders_start_with_the_alternating_one_and_are_all_distinct():
    """Even loops: the alternating order first (links 1, 3 outside at both joints), then the nominal one; every
    order once; odd loops start with the nominal order."""
    orders = order_candidates(4, 16)
    assert orders[0] == (1, -1, 1, -1) and orders[1] == (1, 1, 1, 1)
    assert len(set(orders)) == 16
    assert order_candidates(5, 3)[0] == (1, 1, 1, 1, 1) and len(order_candidates(5, 3)) == 3


def _linkage_file(**keys) -> dict:
    dh = {"a": [110, 220, 110, 220], "alpha_deg": [150, 90, 150, 90]}
    return {"linkage": {"dh": dh, "unit": "mm", "driver": 3, **keys}}


def test_a_linkage_file_stacking_becomes_the_attach_points():
    """``stacking = {offsets, spacers, orders}`` (in the file's unit) gives the same attach points as the Stacking."""
    from ffrf.scenes.linkage_file import linkage_options

    table = {"offsets": [1.0, -2.0, 0.0, 3.0], "spacers": [0.0, 2.0, 0.0, 1.0], "orders": [1, -1, 1, -1]}
    loop, options, _ = linkage_options(_linkage_file(stacking=table))
    expected = Stacking((1e-3, -2e-3, 0.0, 3e-3), (0.0, 2e-3, 0.0, 1e-3), (1, -1, 1, -1)).attach_points(loop)
    np.testing.assert_allclose(options.attach_points, expected, atol=1e-15)


@pytest.mark.parametrize(
    "keys, message",
    [
        ({"stacking": {"offsets": [0, 0, 0]}}, "one offset, spacer and order per joint"),
        ({"stacking": {"offsets": [0, 0, 0, 0], "orders": [1, 0, 1, 1]}}, "orders 1 or -1"),
        ({"collision_free": True, "stacking": {"offsets": [0, 0, 0, 0]}}, "give one of"),
        ({"clearance_margin": 1.0}, "margin of collision_free"),
        ({"collision_free": True, "clearance_margin": 2.0}, "axial gap"),
    ],
)
def test_bad_stacking_keys_are_refused(keys, message):
    from ffrf.errors import SceneError
    from ffrf.scenes.linkage_file import linkage_options

    with pytest.raises(SceneError, match=message):
        linkage_options(_linkage_file(**keys))


def test_the_paper_bennett_stacking_keeps_the_margin(fine_motion):
    """The stored collision-free stacking of the paper's Bennett (rounded to 0.1 mm) keeps 1 mm between every two
    links' capsules along the revolution from the paper's start, bounded between 1441 poses."""
    from ffrf.paper.bennett_scene import COLLISION_FREE_STACKING

    clearance = proxy_clearance(BENNETT, fine_motion, COLLISION_FREE_STACKING)
    assert clearance.smallest[0] >= 1e-3, clearance.summary()


def test_the_collision_free_bennett_links_clear_each_other_on_their_meshes():
    """Built with ``collision_free=True``, the meshed link solids keep the 1 mm margin along the revolution (the signed
    clearance, proven between poses), where the nominal links pass through each other."""
    from ffrf.paper.bennett_scene import build_bennett

    scene = build_bennett("pla", h=8e-3, order=1, n_modes=2, collision_free=True)
    clearance = scene.clearance(n_poses=144)
    assert clearance.margin_met, clearance.summary()


@pytest.mark.slow
def test_the_paper_bennett_is_designed_collision_free():
    """design_stacking finds a stacking of the paper's Bennett that keeps 1 mm (the one stored, to 0.1 mm)."""
    from ffrf.paper.bennett_scene import COLLISION_FREE_STACKING

    designed = design_stacking(BENNETT, 3, _start())
    assert designed.clearance.smallest[0] >= 1e-3
    assert designed.stacking.orders == COLLISION_FREE_STACKING.orders
    np.testing.assert_allclose(designed.stacking.offsets, COLLISION_FREE_STACKING.offsets, atol=0.05e-3)
    np.testing.assert_allclose(designed.stacking.spacers, COLLISION_FREE_STACKING.spacers, atol=0.05e-3)


def test_stiff_collision_free_bennett_links_follow_their_ideal_path():
    """Links housed along their axes (attach points) carry the coupler point where their joints sit, in the run and
    in its ideal path alike: stiff links follow the ideal path (the closed form: a rigid loop moves every point of a
    link rigidly). Before, the ideal path was that of the nominal joint points, tens of mm away."""
    from ffrf import load
    from ffrf.paper.bennett_scene import build_bennett

    scene = build_bennett("rigid", h=12e-3, order=1, n_modes=2, collision_free=True)
    nominal = build_bennett("rigid", h=12e-3, order=1, n_modes=2, collision_free=False)
    assert np.linalg.norm(scene.home_coupler_point() - nominal.home_coupler_point()) > 1e-2  # not a vacuous test
    summary = load(scene).run(mode="quasi_static", outputs=13).summary()
    assert summary["max_coupler_deviation_m"] < 1e-9
