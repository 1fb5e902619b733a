r"""The Netgen meshes of Exudyn's examples ``NGsolveModalAnalysis.py`` and ``NGsolveFFRF.py``
(``main/pythonDev/Examples`` at commit e44aca1b), built at run time, and their FE data.

Netgen meshes a geometry the same way for the same settings (NGsolve 6.2.2504: equal node
coordinates and stiffness entries, bit for bit, in repeated runs), so the examples need no stored mesh.
Exudyn's ``FEMinterface.ImportMeshFromNGsolve`` assembles M and K with NGsolve (4-node tetrahedra) as the
scripts do; both solvers take these matrices, Exudyn through its ``FEMinterface``, ours as an
:class:`ffrf.fe.external_model.ExternalFEModel` (:func:`external_model`).

* crane (``NGsolveModalAnalysis``): four feet, a 2.5 x 6 x 0.3 m plate and a hollow arm 16 m long at
  60 degrees, Netgen CSG, maxh 0.25 m, steel (E = 2.1e11 Pa, nu = 0.3, rho = 7800 kg/m^3): 4544 nodes,
  13373 tetrahedra;
* frame (``NGsolveFFRF``): a closed rectangular frame (1 m, 0.12 x 0.09 m section, filleted) with two
  pins on the axis x = 0.12 m, y = 0 and a thin-walled drum holding a soft filling, OpenCascade
  geometry, maxh 0.06 m, curvaturesafety 0.5, grading 0.8, two materials (frame E = 2.1e9 Pa,
  nu = 0.3, rho = 7800; filling E = 5e8 Pa, nu = 0.4, rho = 2800): 5303 nodes, 18742 tetrahedra; the
  four pin end faces are named boundaries, Exudyn's node sets.

``exudyn`` and ``ngsolve`` are imported only here, inside the functions.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ffrf.fe.external_model import ExternalFEModel

__all__ = [
    "CRANE",
    "FRAME",
    "crane_fem",
    "frame_fem",
    "external_model",
]


class CRANE:
    """Dimensions (m) and material of the crane, as ``NGsolveModalAnalysis.py`` sets them."""

    foot_height, foot_width = 1.0, 0.4
    plate = (2.5, 6.0, 0.3)
    arm_diameter, hole_diameter, arm_length = 0.5, 0.4, 16.0
    arm_angle = np.deg2rad(60.0)
    mesh_size = 0.25  # wArm * 0.5
    density, youngs_modulus, poissons_ratio = 7800.0, 2.1e11, 0.3

    @classmethod
    def feet(cls) -> NDArray[np.float64]:
        """(4, 3) lower corners of the four feet (the script's pFoot0..pFoot3)."""
        wx, wy, _ = cls.plate
        w = cls.foot_width
        return np.array(
            [[-0.5 * wx - w, -0.5 * wy, 0.0], [0.5 * wx, -0.5 * wy, 0.0], [-0.5 * wx - w, 0.5 * wy - w, 0.0]]
            + [[0.5 * wx, 0.5 * wy - w, 0.0]]
        )

    @classmethod
    def arm_direction(cls) -> NDArray[np.float64]:
        return np.array([0.0, np.cos(cls.arm_angle), np.sin(cls.arm_angle)])

    @classmethod
    def tip(cls) -> NDArray[np.float64]:
        """Centre of the arm's end face."""
        return np.array([0.0, 0.0, cls.foot_height]) + cls.arm_length * cls.arm_direction()


class FRAME:
    """Dimensions (m) and materials of the frame, as ``NGsolveFFRF.py`` sets them."""

    height = 0.12  # a: beam section along y
    width = 0.09  # b = 0.75 a: beam section along z
    length = 1.0
    mesh_size = 0.06  # 0.5 a
    wall = 0.04  # drum wall
    materials = {
        "default": {"youngsModulus": 2.1e11 * 0.01, "poissonsRatio": 0.3, "density": 7800.0},
        "filling": {"youngsModulus": 5e8, "poissonsRatio": 0.4, "density": 2800.0},
    }
    boundaries = ("cyl0_minZ", "cyl0_maxZ", "cyl2_minZ", "cyl2_maxZ")


def _crane_mesh() -> Any:
    """The crane as Netgen CSG: feet and plate boxes, the arm a tube cut by two planes."""
    import ngsolve
    from netgen.csg import CSGeometry, Cylinder, OrthoBrick, Plane, Pnt, Vec

    c = CRANE
    wx, wy, wz = c.plate
    h, w = c.foot_height, c.foot_width
    solid = None
    for corner in c.feet():
        foot = OrthoBrick(Pnt(*corner), Pnt(*(corner + [w, w, h])))
        solid = foot if solid is None else solid + foot
    solid += OrthoBrick(Pnt(-0.5 * wx, -0.5 * wy, h - wz), Pnt(0.5 * wx, 0.5 * wy, h))
    base, tip = Pnt(0.0, 0.0, h), Pnt(*c.tip())
    tube = Cylinder(base, tip, 0.5 * c.arm_diameter) - Cylinder(base, tip, 0.5 * c.hole_diameter)
    # half spaces (normals point outwards): above 0.99 of the plate top, below the end face
    tube = tube * Plane(Pnt(0.0, 0.0, 0.99 * h), Vec(0.0, 0.0, -1.0)) * Plane(tip, Vec(*c.arm_direction()))
    geometry = CSGeometry()
    geometry.Add(solid + tube)
    mesh = ngsolve.Mesh(geometry.GenerateMesh(maxh=c.mesh_size))
    mesh.Curve(1)
    return mesh


def _frame_mesh() -> Any:
    """The frame as OpenCascade solids: filleted boxes, two chamfered pins with named end faces, the drum
    and its filling glued (a filling of its own material)."""
    import ngsolve
    from netgen.occ import Box, Cylinder, Glue, OCCGeometry, Pnt, X, Z

    f = FRAME
    a, b, length, t = f.height, f.width, f.length, f.wall
    beams = (
        Box((0, -0.5 * a, -0.5 * b), (length, 0.5 * a, 0.5 * b))
        + Box((length - 0.5 * b, -0.5 * a, -0.5 * b), (length + 0.5 * b, 0.5 * a, 0.5 * b + length))
        + Box((0, -0.5 * a, -0.5 * b + length), (length, 0.5 * a, 0.5 * b + length))
    )
    beams = beams.MakeFillet(beams.edges, 0.1 * a)
    pins = []
    for k, z in ((0, 0.0), (2, length)):
        pin = Cylinder(Pnt(a, 0, z - b), Z, r=0.44 * a, h=2 * b)
        pin = pin.MakeChamfer(pin.edges, 0.05 * a)
        pin.faces.Min(Z).name = f"cyl{k}_minZ"
        pin.faces.Max(Z).name = f"cyl{k}_maxZ"
        pins.append(pin)
    drum_start = length - 0.5 * b
    drum = Cylinder(Pnt(drum_start + 0.5 * t, 0, 0.5 * length), -X, r=0.4 * length, h=1.2 * length) - Cylinder(
        Pnt(drum_start - 0.5 * t, 0, 0.5 * length), -X, r=0.4 * length - t, h=1.2 * length
    )
    drum = drum.MakeFillet(drum.edges, 0.4 * t)
    filling = Cylinder(Pnt(drum_start - 0.5 * t, 0, 0.5 * length), -X, r=0.4 * length - 0.95 * t, h=0.5 * length)
    filling.name = "filling"
    geometry = OCCGeometry(Glue((beams + pins[0] + pins[1] + drum, filling)))
    return ngsolve.Mesh(geometry.GenerateMesh(maxh=f.mesh_size, curvaturesafety=0.5, grading=0.8))


@cache
def crane_fem() -> Any:
    """Exudyn's ``FEMinterface`` of the crane (M, K, surface), imported once per process."""
    from exudyn.FEM import FEMinterface

    fem = FEMinterface()
    c = CRANE
    fem.ImportMeshFromNGsolve(
        _crane_mesh(), density=c.density, youngsModulus=c.youngs_modulus, poissonsRatio=c.poissons_ratio, meshOrder=1
    )
    return fem


@cache
def frame_fem() -> Any:
    """Exudyn's ``FEMinterface`` of the frame (M, K, surface, the node sets of the four pin end faces)."""
    from exudyn.FEM import FEMinterface

    fem = FEMinterface()
    fem.ImportMeshFromNGsolve(
        _frame_mesh(), materials=FRAME.materials, boundaryNamesList=list(FRAME.boundaries), meshOrder=1
    )
    return fem


def external_model(fem: Any, name: str) -> tuple[ExternalFEModel, NDArray[np.int64]]:
    """Nodes, M and K of an Exudyn ``FEMinterface`` as our external model, and its surface triangles."""
    (elements,) = fem.elements
    model = ExternalFEModel(
        np.asarray(fem.GetNodePositionsAsArray(), dtype=float),
        fem.GetMassMatrix().tocsr(),
        fem.GetStiffnessMatrix().tocsr(),
        {"Tet4": np.asarray(elements["Tet4"], dtype=np.int64)},
        name,
    )
    return model, np.asarray(fem.surface[0]["Trigs"], dtype=np.int64)
