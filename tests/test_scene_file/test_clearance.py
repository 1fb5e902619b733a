"""Clearance between links along a motion (ffrf.output.clearance): closed forms on spheres, and the paper's
parametric Bennett links, whose arms overlap in the folded home pose (ffrf.paper.bennett_scene)."""

from __future__ import annotations

import numpy as np

from ffrf.output.clearance import link_clearance
from ffrf.paper.bennett_scene import build_bennett


def _sphere(radius: float, n: int = 4000) -> np.ndarray:
    """Fibonacci points on a sphere about the origin."""
    k = np.arange(n) + 0.5
    polar, azimuth = np.arccos(1 - 2 * k / n), np.pi * (1 + 5**0.5) * k
    return radius * np.column_stack([np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)])


def _translations(distances) -> np.ndarray:
    poses = np.tile(np.eye(4), (len(distances), 2, 1, 1))
    poses[:, 1, 0, 3] = distances
    return poses


def test_two_spheres_have_the_closed_form_clearance_at_the_closest_pose():
    r = 0.01
    clearance = link_clearance(
        [_sphere(r), _sphere(r)], _translations([0.10, 0.05, 0.08]), np.radians([0.0, 10.0, 20.0]), {}, 0.0
    )
    assert clearance.pose[0] == 1 and abs(clearance.distance[0] - (0.05 - 2 * r)) < 1e-4
    assert clearance.collisions == []
    touching = link_clearance([_sphere(r), _sphere(r)], _translations([0.0205]), np.zeros(1), {}, 0.0)
    assert touching.collisions and touching.collisions[0][:2] == (0, 1)  # 0.5 mm apart: below the 1 mm threshold
    # Links that share a joint: around the shared point nothing counts (their housings touch there by design).
    shared = link_clearance(
        [_sphere(r), _sphere(r)], _translations([0.0205]), np.zeros(1), {(0, 1): np.array([0.01, 0, 0])}, 0.012
    )
    assert shared.collisions == [] and shared.distance[0] > 0.005


def test_the_papers_parametric_bennett_links_overlap_in_the_folded_pose():
    """The folded home pose (drive angle 0, i.e. 360 deg after the 90 deg start) puts links 1 and 2 onto each
    other."""
    clearance = build_bennett("pla", h=12e-3, order=1, n_modes=2).clearance(n_poses=72)
    found = {(a, b): np.degrees(angle) for a, b, _, angle in clearance.collisions}
    assert (1, 2) in found and abs(found[(1, 2)] - 360.0) <= 10.0
    assert "collide" in clearance.summary()
