r"""CAD files of a parametric link: the OpenCASCADE solid of :func:`~ffrf.geometry.link_geometry.build_link` as STEP
and as STL, in millimetres, and an assembly STEP of several links.

**Units.** The link is built in metres, as everywhere in :mod:`ffrf`; CAD tools and slicers expect millimetres, so
the solid is scaled by 1000 on the way out: gmsh writes it as a BREP and reads it back with
``Geometry.OCCScaling = 1000`` (an exact similarity: planes and cylinders stay planes and cylinders, where gmsh's
``dilate`` would turn every face into a B-spline). The STEP file then holds millimetre coordinates and says so
(``SI_UNIT(.MILLI.,.METRE.)``); an STL file has no unit field, and ours are in millimetres (read them back with
``unit = "mm"``, :func:`ffrf.geometry.meshing.mesh_stl`).

**Facets.** The STL is gmsh's surface mesh of the solid: at most ``h`` on flat faces (the FE edge, so that the
solver's STL path, which keeps the STL's triangles, meshes it about as finely as the parametric link), and on
curved faces fine enough that no facet is farther than ``tolerance`` from the exact surface. With ``n`` segments per
circle the chord of a circle of radius :math:`R` departs from it by the sagitta

.. math:: s = R \left(1 - \cos \frac{\pi}{n}\right), \qquad n = \left\lceil \frac{\pi}{\arccos(1 - t / R)} \right\rceil

for a tolerance :math:`t` (``tolerance``; :math:`R`: the largest radius of curvature of the solid's faces). gmsh's
element sizes are targets, so the deviation is then measured (:func:`_facet_deviation`: the facets' centroids and
edge midpoints against the exact faces) and the surface remeshed finer until it is within ``tolerance``.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import GeometryError, MeshError
from ffrf.geometry.link_geometry import LinkDesign, LinkGeometry, build_link
from ffrf.geometry.meshing import configure_meshing, gmsh_session

__all__ = ["MM", "LinkPart", "bore_for_pin", "segments_per_circle", "write_link_cad", "write_assembly_step"]

#: Metres per CAD unit: STEP and STL files are written in millimetres.
MM = 1e-3
#: Remeshing rounds of the STL surface before a facet deviation above the tolerance is an error.
_MAX_REFINEMENTS = 6


@dataclass(frozen=True)
class LinkPart:
    """One link as written by :func:`write_link_cad`: its files and what was measured on the OpenCASCADE solid
    (SI units): ``volume`` (m^3), ``area`` (m^2), ``bounding_box`` ``(2, 3)`` (lower and upper corner, m; OCC's box,
    which may be larger than the solid by its tolerance, 1e-7 m), the STL's ``triangles`` and their largest distance
    from the exact surface, ``facet_deviation`` (m); ``geometry``: the link as :func:`build_link` made it (axes,
    housing centres, the design with the bore as made, the mount face)."""

    name: str
    step: Path
    stl: Path
    geometry: LinkGeometry
    volume: float
    area: float
    bounding_box: NDArray[np.float64]
    triangles: int
    facet_deviation: float


def bore_for_pin(design: LinkDesign, pin_diameter: float, radial_clearance: float) -> LinkDesign:
    """``design`` with its bores sized for a pin: radius ``pin_diameter / 2 + radial_clearance`` (m). A negative
    clearance (the pin would not fit) or a bore that leaves no housing wall is a :class:`GeometryError` naming the
    fix."""
    if not (math.isfinite(pin_diameter) and pin_diameter > 0.0):
        raise GeometryError(f"pin diameter {pin_diameter / MM:g} mm must be > 0; give the pin's diameter, e.g. 19 mm")
    if not math.isfinite(radial_clearance):
        raise GeometryError(f"radial clearance {radial_clearance!r} m is no number; give it in metres, e.g. 1e-4")
    if radial_clearance < 0.0:
        raise GeometryError(
            f"radial clearance {radial_clearance / MM:g} mm is negative: the pin would not fit its bore; give a "
            "clearance >= 0, e.g. 0.1 mm"
        )
    radius = 0.5 * pin_diameter + radial_clearance
    outer = design.housing_outer_radius
    if radius >= outer:
        raise GeometryError(
            f"a {pin_diameter / MM:g} mm pin with {radial_clearance / MM:g} mm radial clearance needs a "
            f"{2 * radius / MM:g} mm bore, which leaves no wall in the {2 * outer / MM:g} mm housing; give a pin "
            f"smaller than {2 * (outer - radial_clearance) / MM:g} mm or a larger housing_outer_radius"
        )
    return replace(design, bore_radius=radius)


def segments_per_circle(tolerance: float, radius: float) -> int:
    """Segments of a circle of ``radius`` whose chords depart from it by at most ``tolerance`` (module docstring).

    >>> segments_per_circle(0.05e-3, 17e-3)
    41
    """
    if not 0.0 < tolerance < radius:
        raise GeometryError(
            f"facet tolerance {tolerance / MM:g} mm must be > 0 and smaller than the radius {radius / MM:g} mm; "
            "give e.g. 0.05 mm"
        )
    return max(3, math.ceil(math.pi / math.acos(1.0 - tolerance / radius)))


@contextlib.contextmanager
def _quiet_stdout() -> Iterator[None]:
    """Silence OpenCASCADE's STEP writer, which reports on the C library's standard output (file descriptor 1),
    out of reach of Python's ``sys.stdout``."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _import_in_mm(gmsh, brep: Path) -> int:
    """Replace the session's model by the metre BREP ``brep`` scaled to millimetres; the solid's tag."""
    gmsh.clear()
    gmsh.option.setNumber("Geometry.OCCScaling", 1.0 / MM)
    try:
        solids = [tag for dim, tag in gmsh.model.occ.importShapes(str(brep)) if dim == 3]
    finally:
        gmsh.option.setNumber("Geometry.OCCScaling", 1.0)
    gmsh.model.occ.synchronize()
    return solids[0]


def _largest_radius(gmsh) -> float:
    """The largest radius of curvature of the model's curved faces (model units), at each face's middle."""
    radius = 0.0
    for _, tag in gmsh.model.getEntities(2):
        lo, hi = gmsh.model.getParametrizationBounds(2, tag)
        middle = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]
        k_max, k_min, *_ = gmsh.model.getPrincipalCurvatures(tag, middle)
        k = max(abs(float(k_max[0])), abs(float(k_min[0])))
        if k > 1e-9:
            radius = max(radius, 1.0 / k)
    return radius


def _facet_deviation(gmsh) -> float:
    """Largest distance (model units) of the surface mesh's facets from the exact faces: of each triangle's centroid
    and edge midpoints to the face it meshes (the farthest points of a chord triangle on a cylinder)."""
    tags, points, _ = gmsh.model.mesh.getNodes()
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    points = points.reshape(-1, 3)
    worst = 0.0
    for _, tag in gmsh.model.getEntities(2):
        types, _, nodes = gmsh.model.mesh.getElements(2, tag)
        for etype, enodes in zip(types, nodes, strict=True):
            if etype != 2:  # 3-node triangles
                continue
            coords = points[index[enodes.astype(np.int64)]].reshape(-1, 3, 3)
            probes = np.concatenate([coords.mean(axis=1), 0.5 * (coords + np.roll(coords, -1, axis=1)).reshape(-1, 3)])
            closest, _ = gmsh.model.getClosestPoint(2, tag, probes.ravel())
            worst = max(worst, float(np.max(np.linalg.norm(np.reshape(closest, (-1, 3)) - probes, axis=1))))
    return worst


def _surface_mesh(gmsh, h: float, tolerance: float) -> tuple[int, float]:
    """Mesh the model's surface (module docstring) until its facets are within ``tolerance`` (m) of the faces;
    the triangle count and the deviation (m)."""
    largest = _largest_radius(gmsh) * MM
    segments = segments_per_circle(tolerance, largest) if largest > 0.0 else 12
    for _ in range(_MAX_REFINEMENTS):
        gmsh.model.mesh.clear()
        configure_meshing(h, elements_per_circle=segments, length_scale=MM)
        gmsh.model.mesh.generate(2)
        deviation = _facet_deviation(gmsh) * MM
        if deviation <= tolerance:
            _, triangles = gmsh.model.mesh.getElementsByType(2)
            return len(triangles) // 3, deviation
        segments = math.ceil(1.2 * segments * math.sqrt(deviation / tolerance))  # s ~ 1/n^2
    raise MeshError(
        f"the STL facets stay {deviation / MM:.3g} mm from the exact surface after {_MAX_REFINEMENTS} refinements "
        f"({segments} segments per circle), more than the tolerance {tolerance / MM:g} mm; give a larger tolerance"
    )


def write_link_cad(
    folder: str | Path,
    name: str,
    axis_a,
    axis_b,
    design: LinkDesign | None = None,
    names: tuple[str, str] = ("joint_a", "joint_b"),
    mount: bool = False,
    joint_points: ArrayLike | None = None,
    trim: tuple[float | None, float | None] | None = None,
    *,
    h: float = 6e-3,
    tolerance: float = 0.05e-3,
) -> LinkPart:
    """Write the link :func:`~ffrf.geometry.link_geometry.build_link` makes of these arguments as
    ``folder/name.step`` and ``folder/name.stl`` (millimetres; module docstring); ``design`` defaults to
    :class:`~ffrf.geometry.link_geometry.LinkDesign`'s. ``h``: the largest facet edge (m);
    ``tolerance``: the largest distance of a facet from the exact surface (m)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    step, stl = folder / f"{name}.step", folder / f"{name}.stl"
    with gmsh_session(name) as gmsh, tempfile.TemporaryDirectory() as scratch:
        geometry = build_link(gmsh, axis_a, axis_b, design or LinkDesign(), names, mount, joint_points, trim)
        brep = Path(scratch) / f"{name}.brep"
        gmsh.write(str(brep))
        solid = _import_in_mm(gmsh, brep)
        volume = gmsh.model.occ.getMass(3, solid) * MM**3
        area = sum(gmsh.model.occ.getMass(2, tag) for _, tag in gmsh.model.getEntities(2)) * MM**2
        box = np.reshape(gmsh.model.occ.getBoundingBox(3, solid), (2, 3)) * MM
        with _quiet_stdout():
            gmsh.write(str(step))
        triangles, deviation = _surface_mesh(gmsh, h, tolerance)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.write(str(stl))
    return LinkPart(name, step, stl, geometry, volume, area, box, triangles, deviation)


def write_assembly_step(parts: Sequence[LinkPart], path: str | Path) -> Path:
    """One STEP file (millimetres) with the solids of ``parts`` where their own files put them."""
    path = Path(path)
    with gmsh_session(path.stem) as gmsh:
        for part in parts:
            gmsh.model.occ.importShapes(str(part.step))
        gmsh.model.occ.synchronize()
        with _quiet_stdout():
            gmsh.write(str(path))
    return path
