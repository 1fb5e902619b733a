"""Finite-element link models for the flexible (FFRF) Bennett-linkage solver.

Data flow: geometry (:mod:`ffrf.link_geometry`, gmsh OCC) -> linear tetrahedral
mesh (:mod:`ffrf.meshing`, :mod:`ffrf.mesh`) -> FE matrices
(:mod:`ffrf.fe_model`, scikit-fem) -> interfaces (:mod:`ffrf.interfaces`) and
modes (:mod:`ffrf.modal`).
"""

from .errors import FEInputError, GeometryError, InterfaceError, MaterialError, MeshError
from .fe_model import FEModel, rigid_body_modes
from .interfaces import (InterfaceNodes, boundary_triangles, interface_from_group, interface_from_nodes,
                         interface_from_triangles, interface_in_cylinder)
from .link_geometry import PAPER_AXES, Axis, LinkDesign, LinkGeometry, build_link, mesh_link, paper_link_axes
from .materials import PLA, RIGID, Material
from .mesh import TetMesh, check_mesh, mesh_quality, orient_positive, quality_summary, read_mesh, write_vtu
from .meshing import gmsh_session, mesh_stl
from .modal import Modes, clamped_modes, free_free_modes

__all__ = [
    "FEInputError", "GeometryError", "InterfaceError", "MaterialError", "MeshError",
    "FEModel", "rigid_body_modes",
    "InterfaceNodes", "boundary_triangles", "interface_from_group", "interface_from_nodes", "interface_from_triangles",
    "interface_in_cylinder",
    "PAPER_AXES", "Axis", "LinkDesign", "LinkGeometry", "build_link", "mesh_link", "paper_link_axes",
    "PLA", "RIGID", "Material",
    "TetMesh", "check_mesh", "mesh_quality", "orient_positive", "quality_summary", "read_mesh", "write_vtu",
    "gmsh_session", "mesh_stl",
    "Modes", "clamped_modes", "free_free_modes",
]
