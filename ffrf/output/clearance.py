r"""Clearance between the links of a linkage along its rigid motion: collisions are reported, not fixed.

Each link is represented by the surface vertices of its mesh in the home pose; along the motion every link
moves rigidly by its displacement (Eq. (L1) of ``docs/formulation.md``), and the clearance of two links is the
smallest distance between their surface vertices (a k-d tree, :class:`scipy.spatial.cKDTree`). Two links
that share a joint always touch there (their housings are stacked one axial gap apart), so near their
shared joint point (within ``joint_radius``) their vertices are left out. The clearance is that of the
vertex clouds: it is accurate to about the mesh's element size, and a clearance below ``contact`` (default
1 mm) is reported as a collision of the two links at that drive angle.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

__all__ = ["Clearance", "link_clearance"]


@dataclass(frozen=True)
class Clearance:
    """Smallest clearance (m) of each pair of links over the motion and the pose where it occurs.

    ``pairs`` ``(k, 2)`` link indices, ``distance`` ``(k,)``, ``pose`` ``(k,)`` the index of the pose,
    ``drive_angles`` the driver's angle at every pose, ``contact`` the collision threshold (m).
    """

    pairs: NDArray[np.int64]
    distance: NDArray[np.float64]
    pose: NDArray[np.int64]
    drive_angles: NDArray[np.float64]
    contact: float

    @property
    def collisions(self) -> list[tuple[int, int, float, float]]:
        """``(link, link, clearance m, drive angle rad)`` of every pair that comes closer than ``contact``."""
        return [
            (int(a), int(b), float(d), float(self.drive_angles[p]))
            for (a, b), d, p in zip(self.pairs, self.distance, self.pose, strict=True)
            if d < self.contact
        ]

    def summary(self) -> str:
        worst = int(np.argmin(self.distance))
        a, b = self.pairs[worst]
        head = (
            f"smallest clearance {1e3 * self.distance[worst]:.2f} mm (links {a} and {b} at drive angle "
            f"{np.degrees(self.drive_angles[self.pose[worst]]):.1f} deg)"
        )
        found = self.collisions
        if not found:
            return head + f"; no collision (threshold {1e3 * self.contact:g} mm)"
        listed = ", ".join(f"links {a}-{b} at {np.degrees(angle):.1f} deg" for a, b, _, angle in found)
        return head + f"; {len(found)} pair(s) collide: {listed}"


def link_clearance(
    surfaces: Sequence[NDArray[np.float64]],
    transforms: NDArray[np.float64],
    drive_angles: NDArray[np.float64],
    shared_joints: dict[tuple[int, int], NDArray[np.float64]],
    joint_radius: float,
    contact: float = 1e-3,
) -> Clearance:
    """Clearance of every pair of links (module docstring).

    ``surfaces[k]`` are link ``k``'s surface vertices at home ``(m_k, 3)``; ``transforms`` ``(poses, n, 4, 4)``
    the links' displacements from home; ``shared_joints[(a, b)]`` the home joint point that links ``a < b``
    share, around which ``joint_radius`` (m) of both is left out.
    """
    n = len(surfaces)
    pairs, distances, where = [], [], []
    for a in range(n):
        for b in range(a + 1, n):
            cloud_a, cloud_b = surfaces[a], surfaces[b]
            point = shared_joints.get((a, b))
            if point is not None:
                cloud_a = cloud_a[np.linalg.norm(cloud_a - point, axis=1) > joint_radius]
                cloud_b = cloud_b[np.linalg.norm(cloud_b - point, axis=1) > joint_radius]
            best, best_pose = np.inf, 0
            tree = cKDTree(cloud_a)
            for k, pose in enumerate(transforms):
                # Relative placement: b's vertices in a's frame, so a's tree is built once.
                relative = np.linalg.solve(pose[a], pose[b])
                moved = cloud_b @ relative[:3, :3].T + relative[:3, 3]
                gap = float(tree.query(moved, k=1)[0].min())
                if gap < best:
                    best, best_pose = gap, k
            pairs.append((a, b))
            distances.append(best)
            where.append(best_pose)
    return Clearance(np.array(pairs), np.array(distances), np.array(where), np.asarray(drive_angles), contact)
