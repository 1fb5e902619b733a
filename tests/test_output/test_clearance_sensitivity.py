"""The derivative of two solids' clearance by their shape (ffrf.output.clearance_sensitivity, docs/formulation.md
Eq. (CL5)) on boxes with a closed form: a box stretched towards another closes the gap as fast as its face moves."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from ffrf.output.clearance_sensitivity import clearance_slopes
from ffrf.output.solid_distance import LinkSolid

SIZE, GAP = 0.02, 0.005


def _box() -> LinkSolid:
    """A 20 mm cube from the origin to (SIZE, SIZE, SIZE), its faces split into triangles of 5 mm at most."""
    mesh = trimesh.creation.box((SIZE, SIZE, SIZE))
    vertices, faces = trimesh.remesh.subdivide_to_size(mesh.vertices + 0.5 * SIZE, mesh.faces, 5e-3)
    return LinkSolid(vertices, faces, "box")


def _stretch(solid: LinkSolid, axis: int) -> np.ndarray:
    """The velocity ``(m, 3)`` of a stretch along ``axis`` that holds the face at 0 and moves the face at SIZE by 1."""
    velocity = np.zeros_like(solid.vertices)
    velocity[:, axis] = solid.vertices[:, axis] / SIZE
    return velocity


@pytest.mark.parametrize("turned", [False, True])
def test_a_box_stretched_towards_another_closes_the_gap_as_fast_as_its_face_moves(turned):
    """b sits GAP beyond a's face x = SIZE (turned 90 deg about z, its own y axis pointing back at a, or not turned);
    stretching a along x moves that face at unit speed and b's stretch along its own axis facing a moves b's near
    face at unit speed too: dc/dp = -1 for each, and a stretch across the gap (a along y) leaves it: 0."""
    a, b = _box(), _box()
    relative = np.eye(4)
    if turned:  # b's y axis along -x: its face y = SIZE faces a
        relative[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        relative[:3, 3] = [2.0 * SIZE + GAP, 0.0, 0.3 * SIZE]
        towards = _stretch(b, 1)
    else:  # b's face x = 0 faces a; its stretch along -x: hold x = SIZE, move x = 0
        relative[:3, 3] = [SIZE + GAP, 0.3 * SIZE, 0.0]
        towards = np.zeros_like(b.vertices)
        towards[:, 0] = -(SIZE - b.vertices[:, 0]) / SIZE
    zeros = np.zeros_like(a.vertices)
    velocities_a = np.stack([_stretch(a, 0), zeros, _stretch(a, 1)], axis=-1)
    velocities_b = np.stack([np.zeros_like(b.vertices), towards, np.zeros_like(b.vertices)], axis=-1)
    value, slopes = clearance_slopes(a, b, relative, velocities_a, velocities_b, np.full(3, 1e-6))
    assert value == pytest.approx(GAP, abs=1e-12)
    np.testing.assert_allclose(slopes, [-1.0, -1.0, 0.0], atol=1e-9)
