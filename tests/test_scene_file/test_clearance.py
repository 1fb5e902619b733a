"""Signed clearance along a motion (ffrf.output.clearance, docs/formulation.md Eqs. (CL1)-(CL4)): the bound between
poses catches an obstacle passed between two samples, the loop's twists are the derivatives of its poses, and the
paper's parametric Bennett links overlap in the folded home pose by as much as their arm boxes do."""

from __future__ import annotations

import fcl
import numpy as np
import pytest
import trimesh

from ffrf.output.clearance import signed_clearance
from ffrf.output.loop_poses import LoopPoses
from ffrf.output.solid_distance import LinkSolid, signed_distance
from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.linkage_description import drive_sign


class _Sweep:
    """Link 0 at rest, link 1 moving along x at ``speed`` m per rad of drive, through x = ``offset`` at drive angle
    0.5 rad; sampled at ``drive_angles``."""

    def __init__(self, drive_angles, speed: float, offset: float = 0.0) -> None:
        self.drive_angles = np.asarray(drive_angles, dtype=float)
        self.speed, self.offset = speed, offset

    def poses(self, angles):
        angles = np.asarray(angles, dtype=float)
        transforms = np.tile(np.eye(4), (len(angles), 2, 1, 1))
        transforms[:, 1, 0, 3] = self.offset + self.speed * (angles - 0.5)
        twists = np.zeros((len(angles), 2, 6))
        twists[:, 1, 3] = self.speed
        return transforms, twists


def _box(extents) -> LinkSolid:
    box = trimesh.creation.box(extents)
    return LinkSolid(box.vertices, box.faces)


def test_an_obstacle_passed_between_two_samples_is_caught_by_the_bound():
    """A 1 mm plate at x = 0 and a 10 mm cube sweeping 100 mm along x: at the two sampled ends 40 mm apart, at the
    middle (drive angle 0.5 rad) through the plate. Eq. (CL4) with speed 0.1 m/rad and safety 1.5 bounds the interval
    at (0.0445 + 0.0445 - 0.15)/2 < 0, so it is bisected: the middle pose shows the overlap, the plate's faces
    (0.5 mm from the cube's centre) 4.5 mm inside the cube."""
    plate, cube = _box((0.001, 0.1, 0.1)), _box((0.01, 0.01, 0.01))
    blind = signed_clearance([plate, cube], _Sweep([0.0, 1.0], 0.1), margin=1e-3, max_bisections=0)
    assert blind.distance[0] == pytest.approx(0.05 - 0.0005 - 0.005)  # both samples clear: 44.5 mm
    assert blind.bound[0] == pytest.approx(0.5 * (2 * 0.0445 - 1.5 * 0.1)) and not blind.margin_met
    assert "only -30.50 mm is proven" in blind.summary() and "not proven between them by links 0-1" in blind.summary()
    caught = signed_clearance([plate, cube], _Sweep([0.0, 1.0], 0.1), margin=1e-3)
    assert caught.distance[0] == pytest.approx(-0.0045) and caught.drive_angle[0] == pytest.approx(0.5)
    assert "links 0-1: overlap by" in caught.summary()
    # Far from the plate all along (x from 45 to 55 mm): the margin is proven without a bisection.
    clear = signed_clearance([plate, cube], _Sweep(np.linspace(0.0, 1.0, 5), 0.01, 0.05), margin=1e-3)
    assert clear.margin_met and clear.poses[0] == 5 and "closest 39.50 mm" in clear.summary()


class _Glide(_Sweep):
    """Link 1 gliding along y at ``speed`` m per rad of drive, its centre ``gap`` in x from link 0's origin: a
    constant distance."""

    def __init__(self, drive_angles, speed: float, gap: float) -> None:
        super().__init__(drive_angles, speed)
        self.gap = gap

    def poses(self, angles):
        transforms, twists = super().poses(angles)
        transforms[:, 1, 1, 3], transforms[:, 1, 0, 3] = transforms[:, 1, 0, 3], self.gap
        twists[:, 1, 4], twists[:, 1, 3] = twists[:, 1, 3], 0.0
        return transforms, twists


def test_a_constant_clearance_is_proven_above_the_margin_and_never_bisected_at_it():
    """A 10 mm cube gliding 10 mm along a 1 mm plate at a constant distance (its face 1.5 mm or 1 mm from the
    plate's), 5 poses: 0.5 mm above a 1 mm margin, bisecting proves it (S h = 1.5 x 10 mm/rad x 0.25 rad = 3.75 mm,
    proven once halved twice); at the margin itself no bisection could, and none is made."""
    plate, cube = _box((0.001, 0.1, 0.1)), _box((0.01, 0.01, 0.01))
    angles = np.linspace(0.0, 1.0, 5)
    above = signed_clearance([plate, cube], _Glide(angles, 0.01, 0.0055 + 0.0015), margin=1e-3)
    assert above.distance[0] == pytest.approx(1.5e-3) and above.margin_met and above.poses[0] > 5
    glide = _Glide(angles, 0.01, 0.0055 + 0.001)
    constant = signed_clearance([plate, cube], glide, margin=0.0).distance[0]
    assert constant == pytest.approx(1e-3, abs=1e-12)
    at = signed_clearance([plate, cube], glide, margin=constant)
    assert not at.margin_met and at.poses[0] == 5 and "not proven between them by links 0-1" in at.summary()


@pytest.fixture(scope="module")
def bennett():
    """The paper's loop with the housings centred on the joint points (not the default collision-free links)."""
    return build_bennett("pla", h=12e-3, order=1, n_modes=2, collision_free=False)


def test_the_loops_twists_are_the_derivatives_of_its_poses(bennett):
    """Point velocities from the twists of ffrf.output.loop_poses against central differences of the poses."""
    sign = drive_sign(bennett.driver, bennett.loop.n)
    motion = LoopPoses.revolution(bennett.loop, bennett.driver, 12, bennett.start_phi, sign)
    angles = motion.drive_angles[:-1] + 0.1
    step = 1e-6
    transforms, twists = motion.poses(angles)
    ahead, _ = motion.poses(angles + step)
    behind, _ = motion.poses(angles - step)
    point = np.array([0.05, 0.02, -0.01, 1.0])  # any point, fixed to each link
    moving = transforms @ point
    velocity = np.cross(twists[..., :3], moving[..., :3]) + twists[..., 3:]
    difference = ((ahead - behind) @ point)[..., :3] / (2 * step)
    np.testing.assert_allclose(velocity, difference, atol=1e-7)


def test_the_folded_bennett_links_overlap_by_as_much_as_their_arm_boxes(bennett):
    """Home (drive angle 0, 360 deg after the 90 deg start) folds the paper's Bennett flat: links 1 and 2 (and 0 and
    3) lie along one line, their arms overlapping. Independent check: FCL's box-box penetration of the two arms as
    boxes (16 x 12 mm from housing centre to housing centre, ffrf.geometry.link_geometry) is 3.6 mm; the meshed links
    (12 mm elements) measure the same to 0.5 mm. Along the revolution (24 poses) every pair but 1-3 overlaps."""
    solids = [LinkSolid(*_surface(body)) for body in bennett.bodies]
    zones = bennett.joint_zones()
    arms = fcl.CollisionResult()
    fcl.collide(_arm(bennett.bodies[1]), _arm(bennett.bodies[2]), fcl.CollisionRequest(enable_contact=True), arms)
    boxes = arms.contacts[0].penetration_depth
    assert signed_distance(solids[1], solids[2], None, zones[(1, 2)]) == pytest.approx(-boxes, abs=5e-4)
    clearance = bennett.clearance(n_poses=24)
    found = {(int(a), int(b)): (gap, np.degrees(angle)) for (a, b), gap, angle in
             zip(clearance.pairs, clearance.distance, clearance.drive_angle, strict=True)}  # fmt: skip
    assert found[(1, 2)][0] <= -boxes + 5e-4
    assert all(found[pair][0] < 0.0 for pair in found if pair != (1, 3)) and found[(1, 3)][0] > 0.05
    assert not clearance.margin_met and "margin 1 mm not met" in clearance.summary()


def _surface(body):
    from ffrf.fe.interfaces import boundary_triangles

    mesh = body.mesh_model.mesh
    return mesh.points, boundary_triangles(mesh, outward=True)


def _arm(body) -> fcl.CollisionObject:
    """The link's straight arm as a box: along the housing centres, its width along the first axis made normal."""
    geometry = body.geometry
    start, end = geometry.housing_centers
    along = (end - start) / np.linalg.norm(end - start)
    width = geometry.axes[0].direction - (geometry.axes[0].direction @ along) * along
    width /= np.linalg.norm(width)
    frame = np.column_stack([along, width, np.cross(along, width)])
    design = geometry.design
    box = fcl.Box(np.linalg.norm(end - start), design.arm_width, design.arm_thickness)
    return fcl.CollisionObject(box, fcl.Transform(frame, 0.5 * (start + end)))
