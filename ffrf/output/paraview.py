"""Deformed meshes of a run as a ParaView time series: one ``.vtu`` per output frame and a
``.pvd`` index with the physical times.

Each frame holds all bodies' linear tetrahedra in their current (deformed, moved)
positions, with point data ``displacement`` (current minus reference position, for "Warp
By Vector" from the reference mesh), ``elastic_displacement`` (the modal part in the body
frame, turned into world axes) and ``body`` (the body index), as the style guide asks
(Exudyn writes no ParaView files).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING
from xml.sax.saxutils import quoteattr

import numpy as np
from numpy.typing import NDArray

from ffrf.body.euler_parameters import rotation_matrix

if TYPE_CHECKING:
    from ffrf.fe.fe_model import FEModel

__all__ = ["write_time_series"]


def _frame_points(fe, basis: NDArray, block: NDArray) -> tuple[NDArray, NDArray]:
    """Current vertex positions and world-axis elastic displacements of one body."""
    n = len(fe.mesh.points)  # P2 models: vertices come first; tetrahedra use vertices only
    elastic_local = (basis @ block[7:]).reshape(-1, 3)[:n]
    rotation = rotation_matrix(block[3:7])
    positions = block[:3] + (fe.nodes[:n] + elastic_local) @ rotation.T
    return positions, elastic_local @ rotation.T


def write_time_series(
    directory: str | Path,
    bodies: Sequence[tuple[FEModel, NDArray]],
    blocks: Sequence[slice],
    time: NDArray,
    q: NDArray,
    every: int = 1,
    name: str = "run",
) -> Path:
    """Write ``DIR/vtk/{name}_XXXXX.vtu`` for every ``every``-th row of ``q`` and ``DIR/{name}.pvd``.

    ``bodies`` pairs each body's FE model (``.mesh``, ``.nodes``) with its mode basis (3N, m);
    ``blocks`` are the bodies' coordinate slices in ``q``.
    """
    import meshio

    directory = Path(directory)
    (directory / "vtk").mkdir(parents=True, exist_ok=True)
    offsets = np.cumsum([0] + [len(fe.mesh.points) for fe, _ in bodies])
    tets = np.vstack([fe.mesh.tets + offset for (fe, _), offset in zip(bodies, offsets[:-1], strict=True)])
    reference = np.vstack([fe.nodes[: len(fe.mesh.points)] for fe, _ in bodies])
    body_id = np.concatenate([np.full(len(fe.mesh.points), k, dtype=np.float64) for k, (fe, _) in enumerate(bodies)])
    entries = []
    for row in range(0, len(time), max(1, every)):
        parts = [_frame_points(fe, basis, q[row, block]) for (fe, basis), block in zip(bodies, blocks, strict=True)]
        points = np.vstack([p for p, _ in parts])
        elastic = np.vstack([e for _, e in parts])
        file = directory / "vtk" / f"{name}_{row:05d}.vtu"
        meshio.write(
            file,
            meshio.Mesh(
                points,
                [("tetra", tets)],
                point_data={"displacement": points - reference, "elastic_displacement": elastic, "body": body_id},
            ),
        )
        entries.append(
            f'    <DataSet timestep="{float(time[row]):.9g}" part="0" file={quoteattr(f"vtk/{file.name}")}/>'
        )
    pvd = directory / f"{name}.pvd"
    pvd.write_text(
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
        + "\n".join(entries)
        + "\n  </Collection>\n</VTKFile>\n"
    )
    return pvd
