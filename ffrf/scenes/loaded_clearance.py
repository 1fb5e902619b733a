r"""The clearance of the links along the loaded motion, and its derivatives along the equilibria's response
(``docs/formulation.md``, Eq. (CL7)).

The clearance check of Eqs. (CL1)-(CL4) follows the nominal linkage's rigid motion. A print differs from it: its
links sag under the load and, with bore errors, the loop closes only by bending them and moving their frames. Here
each link is placed as the model has it at an equilibrium ``q``: its mesh's vertices deformed by its modes,
:math:`x + \Psi\zeta`, in its own frame, and the frame placed at :math:`(R, A(\theta))` (Eq. (F1)); the clearance
of two links is that of these solids, measured in the first one's frame, :math:`T_a^{-1} T_b`, with the joint
zones of the nominal design (Eq. (CL3)). Its derivatives by a parameter that leaves the links' meshes (a bore error,
a material) follow the response of Eq. (D1), :math:`dq/dp`: central differences of the clearance at
:math:`q \pm h\,dq/dp`, a step that moves no coordinate by more than :data:`CLEARANCE_STEP`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.output.solid_distance import LinkSolid, SolidPair
from ffrf.scenes.linkage_scene import LinkageScene

__all__ = ["CLEARANCE_STEP", "LoadedClearance", "loaded_clearance", "placed_solids"]

#: Largest coordinate change of the central differences along the response (m or rad, or a modal coordinate):
#: the clearance is a distance between faceted surfaces, smooth between switches of the closest features.
CLEARANCE_STEP = 1e-7


@dataclass(frozen=True)
class LoadedClearance:
    """The clearance of each of ``pairs`` ``(k, 2)`` at each equilibrium, ``distance`` ``(poses, k)`` (m, negative
    where the links overlap), and where asked its derivatives ``slopes`` ``(poses, k, parameters)``."""

    pairs: NDArray[np.int64]
    distance: NDArray[np.float64]
    slopes: NDArray[np.float64] | None = None

    @property
    def smallest(self) -> NDArray[np.float64]:
        """Each pair's smallest clearance over the poses ``(k,)``."""
        return self.distance.min(axis=0)


def placed_solids(scene: LinkageScene, q: NDArray) -> tuple[list[LinkSolid], NDArray[np.float64]]:
    """Every link's solid deformed by its modal coordinates in ``q`` (its own frame) and the frames' placements
    ``(links, 4, 4)`` (module docstring)."""
    solids, frames = [], np.tile(np.eye(4), (len(scene.bodies), 1, 1))
    for k, (body, home) in enumerate(zip(scene.bodies, scene.link_solids(), strict=True)):
        block = np.asarray(q, dtype=float)[scene.system.block(k)]
        basis = np.asarray(body.reduction.basis, dtype=float)
        vertices = len(home.vertices)  # the mesh's vertices come first among the FE nodes
        deformed = home.vertices + (basis[: 3 * vertices] @ block[7:]).reshape(vertices, 3)
        solids.append(LinkSolid(deformed, home.triangles, home.name))
        frames[k, :3, :3] = rotation_matrix(block[3:7])
        frames[k, :3, 3] = block[:3]
    return solids, frames


def loaded_clearance(
    scene: LinkageScene,
    q: NDArray,
    response: NDArray | None = None,
    pairs: NDArray[np.int64] | None = None,
    step: float = CLEARANCE_STEP,
) -> LoadedClearance:
    """The clearance of ``pairs`` (default every pair of links) at each of the equilibria ``q`` ``(poses, n)`` of
    ``scene`` and, with the equilibria's ``response`` ``(poses, n, k)`` (:attr:`PathSensitivity.coordinates`), its
    derivatives by the response's parameters (module docstring)."""
    n = len(scene.bodies)
    pairs = np.array([(a, b) for a in range(n) for b in range(a + 1, n)]) if pairs is None else np.asarray(pairs)
    zones = scene.joint_zones()
    q = np.atleast_2d(np.asarray(q, dtype=float))

    def at(row: NDArray) -> NDArray[np.float64]:
        solids, frames = placed_solids(scene, row)
        return np.array(
            [
                SolidPair(solids[a], solids[b], zones.get((a, b))).clearance(np.linalg.solve(frames[a], frames[b]))
                for a, b in pairs.tolist()
            ]
        )

    distance = np.array([at(row) for row in q])
    if response is None:
        return LoadedClearance(pairs, distance)
    response = np.asarray(response, dtype=float)
    slopes = np.zeros((len(q), len(pairs), response.shape[2]))
    for i, row in enumerate(q):
        for j in range(response.shape[2]):
            direction = response[i, :, j]
            largest = float(np.abs(direction).max())
            if largest == 0.0:
                continue
            h = step / largest
            slopes[i, :, j] = (at(row + h * direction) - at(row - h * direction)) / (2.0 * h)
    return LoadedClearance(pairs, distance, slopes)
