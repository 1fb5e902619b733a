"""Stacking the housings along the joint axes (:mod:`ffrf.scenes.collision_free`): the attach points, the speed
bound between sampled poses, and the refusals."""

import numpy as np
import pytest

from ffrf.errors import GeometryError
from ffrf.geometry.link_capsules import segment_distances
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


def test_poses_crowd_where_the_loop_moves_fast():
    """With a travel bound the poses of ``collisions_free_6r`` (joint points up to about 2 m per radian of drive) stay
    in order over one whole turn, keep the uniform poses, and no joint point moves much beyond the bound between two
    of them (judged by its speed at both ends, as the split is made); the uniform sampling moves them 3.5 times as
    far. The clearance bounded on these poses is never above the one sampled 4 times as densely."""
    from ffrf.scenes.linkage_description import joint_points as points_of

    loop = _six_r()
    uniform = sampled_motion(loop, 0, None, 181)
    crowded = sampled_motion(loop, 0, None, 181, travel=0.02)
    assert len(crowded.angles) > len(uniform.angles)
    assert np.all(np.diff(crowded.angles) > 0.0) or np.all(np.diff(crowded.angles) < 0.0)
    assert abs(crowded.angles[-1] - crowded.angles[0]) == pytest.approx(2 * np.pi, abs=1e-12)
    assert np.isin(np.round(uniform.angles, 12), np.round(crowded.angles, 12)).all()
    np.testing.assert_allclose(crowded.steps, np.abs(np.diff(crowded.angles)), rtol=0, atol=1e-15)

    def largest_travel(motion):
        points = points_of(loop)
        placed = np.einsum("mkij,kj->mki", motion.transforms[:, :, :3, :3], points) + motion.transforms[:, :, :3, 3]
        speed = np.linalg.norm(np.cross(motion.omega, placed) + motion.velocity, axis=-1).max(axis=1)
        return (np.maximum(speed[:-1], speed[1:]) * motion.steps).max()

    assert largest_travel(crowded) <= 0.02 * 1.5  # the speeds at the parts' ends differ from the whole's
    assert largest_travel(uniform) > 3 * 0.02
    stacking = Stacking.nominal(loop.n)
    coarse = proxy_clearance(loop, crowded, stacking)
    fine = proxy_clearance(loop, sampled_motion(loop, 0, None, 721, travel=0.005), stacking)
    assert np.all(coarse.clearance <= fine.clearance + 1e-12)


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


@pytest.mark.parametrize("orders", [(1, -1, 1, -1), (-1, -1, 1, 1)])
def test_the_capsule_clearance_gradient_is_that_of_finite_differences(orders):
    """The design's exact gradient of a capsule clearance by the offsets and spacers (mm) agrees with central
    differences of the clearances themselves, at poses and capsule pairs drawn at random (stubbed arms included:
    the paper's Bennett has none, so a 6R with DH offsets is taken too)."""
    from ffrf.scenes import collision_free as cf

    rng = np.random.default_rng(7)
    design = LinkDesign()
    for loop, driver, start in ((BENNETT, 3, _start()), (_six_r(), 0, None)):
        n = loop.n
        motion = sampled_motion(loop, driver, start, 37)
        points = joint_points(loop)
        x = np.concatenate([rng.uniform(-20.0, 20.0, n), rng.uniform(0.0, 10.0, n)])
        order = tuple(orders[k % 4] for k in range(n))

        def stacking(x, order=order, n=n):
            return Stacking(tuple(1e-3 * x[:n]), tuple(1e-3 * x[n:]), order)

        def capsules(x, loop=loop, points=points, stacking=stacking):
            return cf._all_capsules(loop, stacking(x), design, points)

        pairs = cf._capsule_pairs(capsules(x))
        chosen = rng.integers(0, len(pairs.first), len(motion.angles))
        rates = cf._end_rates(cf.link_build_inputs(loop, stacking(x), design, points), design, order, 1e-6)
        exact = cf._pair_clearance_gradients(motion, capsules(x), rates, pairs, chosen)
        step = 1e-4

        def clearances(x, motion=motion, pairs=pairs, chosen=chosen, capsules=capsules):
            """Capsule pair ``chosen[r]``'s clearance at pose ``r`` (closed form, numpy)."""
            a, b, radii = cf._placed_ends(motion.transforms, capsules(x))
            rows, i, j = np.arange(len(chosen)), pairs.first[chosen], pairs.second[chosen]
            return segment_distances(a[rows, i], b[rows, i], a[rows, j], b[rows, j]) - radii[i] - radii[j]

        differences = np.stack(
            [(clearances(x + step * e) - clearances(x - step * e)) / (2 * step) for e in np.eye(2 * n)], axis=1
        )
        assert np.abs(exact).max() > 1e-4  # a clearance moves by up to 1 um per um of shift
        np.testing.assert_allclose(exact, differences, atol=1e-9)


def _six_r() -> SingleLoop:
    """Rational Linkages' ``collisions_free_6r`` at a quarter of its size (DH offsets up to 107 mm)."""
    from kinematics.rational_mechanism import load_model, loop_from_mechanism

    return loop_from_mechanism(load_model("collisions_free_6r"), 0.25)


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


def test_a_models_shipped_design_is_one_more_start_of_a_linkage_files_design(monkeypatch):
    """``collision_free = true`` on a Rational Linkages model that ships a design (its two points at a joint apart)
    hands that design, read as a stacking, to the design as a start; a loop without one (a DH table) hands none."""
    import ffrf.scenes.linkage_file as linkage_file
    from kinematics.rational_mechanism import attach_points, load_model, loop_from_mechanism

    seen = []

    def recorded(loop, driver, start, design, margin, starts=()):
        seen.append((starts, design))
        raise GeometryError("recorded")

    monkeypatch.setattr(linkage_file, "design_stacking", recorded)
    for document in (
        {"linkage": {"model": "collisions_free_6r", "scale": 0.25, "collision_free": True}},
        _linkage_file(collision_free=True),
    ):
        with pytest.raises(Exception, match="recorded"):
            linkage_file.linkage_options(document)
    mechanism = load_model("collisions_free_6r")
    loop = loop_from_mechanism(mechanism, 0.25)
    (given,), design = seen[0]
    assert design.axial_gap == 1.5e-3  # designed links: the margin + 0.5 mm (designed_axial_gap)
    points = attach_points(mechanism, 0.25)
    np.testing.assert_allclose(given.attach_points(loop, design), points, atol=1e-12)
    assert seen[1][0] == ()


@pytest.mark.parametrize(
    "keys, message",
    [
        ({"stacking": {"offsets": [0, 0, 0]}}, "one offset, spacer and order per joint"),
        ({"stacking": {"offsets": [0, 0, 0, 0], "orders": [1, 0, 1, 1]}}, "orders 1 or -1"),
        ({"collision_free": True, "stacking": {"offsets": [0, 0, 0, 0]}}, "give one of"),
        ({"clearance_margin": 1.0, "check_clearance": False}, "check_clearance = false; drop one"),
        ({"collision_free": True, "clearance_margin": 2.0, "link_design": {"axial_gap": 1.0}}, "axial gap"),
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
    """design_stacking finds a stacking of the paper's Bennett whose capsules keep 1 mm along the revolution, bounded
    between 1441 poses."""
    designed = design_stacking(BENNETT, 3, _start())
    assert designed.clearance.smallest[0] >= 1e-3, designed.summary()


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


def test_a_spacer_beyond_the_default_trimming_has_its_links_trimmed_past_the_other_housing():
    """Where a spacer puts the other housing beyond the default trimming's reach (80 mm past the end face), the
    scene asks both links at that joint to trim as far as that housing's far end face plus one gap, L + 2 gap +
    spacer; elsewhere, and for the paper's stored stacking, the scene is as before (no ``trim``)."""
    from ffrf.paper.bennett_scene import COLLISION_FREE_STACKING
    from ffrf.scenes.linkage_description import LinkageOptions, linkage_description

    design = LinkDesign()
    stacking = Stacking((0.0, 0.0, 0.0, 0.0), (0.0, 0.1, 0.0, 0.0))
    bodies = linkage_description(BENNETT, LinkageOptions(attach_points=stacking.attach_points(BENNETT)))["bodies"]
    trims = {(k, a["name"]): a.get("trim") for k, body in enumerate(bodies) for a in body["parametric"]["axes"]}
    wanted = design.housing_length + 2 * design.axial_gap + 0.1
    assert trims.pop((1, "joint1")) == pytest.approx(wanted, abs=1e-12)
    assert trims.pop((2, "joint1")) == pytest.approx(wanted, abs=1e-12)
    assert set(trims.values()) == {None}
    paper = LinkageOptions(attach_points=COLLISION_FREE_STACKING.attach_points(BENNETT))
    assert all("trim" not in a for b in linkage_description(BENNETT, paper)["bodies"] for a in b["parametric"]["axes"])


def test_attach_points_read_back_as_their_stacking():
    """A stacking's housing centres give back its offsets, spacers and orders; points closer than two housings'
    offsets give spacer 0 about their middle."""
    stacking = Stacking((0.01, -0.02, 0.0, 0.005), (0.0, 0.003, 0.0, 0.01), (1, -1, 1, -1))
    back = Stacking.from_attach_points(BENNETT, stacking.attach_points(BENNETT))
    np.testing.assert_allclose(back.offsets, stacking.offsets, atol=1e-15)
    np.testing.assert_allclose(back.spacers, stacking.spacers, atol=1e-15)
    assert back.orders == stacking.orders
    points = joint_points(BENNETT)
    touching = np.stack([points + 1e-3 * np.array([a.direction for a in BENNETT.axes]) * side for side in (1, -1)], 1)
    close = Stacking.from_attach_points(BENNETT, touching)
    assert close.spacers == (0.0,) * 4 and close.orders == (-1,) * 4
    np.testing.assert_allclose(close.offsets, 0.0, atol=1e-15)


@pytest.mark.slow
def test_from_a_design_that_keeps_the_margin_the_local_design_keeps_it_for_less():
    """Rational Linkages' own design of ``collisions_free_6r`` at scale 1 keeps 1 mm between our links' capsules; the
    local design from it (all 1441+ poses) keeps the margin on every interval and costs less (its first long step
    toward the nominal offsets leaves the margin at poses that were not constraints, and is refused)."""
    from ffrf.scenes import collision_free as cf
    from kinematics.rational_mechanism import attach_points, load_model, loop_from_mechanism

    mechanism = load_model("collisions_free_6r")
    loop = loop_from_mechanism(mechanism, 1.0)
    start = Stacking.from_attach_points(loop, attach_points(mechanism, 1.0))
    motion = sampled_motion(loop, 0, None, cf.DEFAULT_POSES, cf._TRAVEL)
    assert proxy_clearance(loop, motion, start).smallest[0] >= 1e-3
    n = loop.n
    x = 1e3 * np.concatenate([start.offsets, np.maximum(start.spacers, 0.5e-3)])
    limits = cf._Bounds(1e3 * max(abs(t) for t in start.offsets), 1e3 * loop.scale, 0.5)
    y = cf._design_order(loop, motion, LinkDesign(), 1e-3, limits, start.orders, x)
    designed = Stacking(tuple(1e-3 * y[:n]), tuple(1e-3 * y[n:]), start.orders)
    assert proxy_clearance(loop, motion, designed).smallest[0] >= 1e-3
    assert cf._cost(y, n) < 0.9 * cf._cost(x, n)
