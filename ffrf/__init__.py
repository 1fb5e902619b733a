"""In-house flexible multibody solver: floating frame of reference bodies with Craig-Bampton modes.

Data flow: geometry (:mod:`ffrf.link_geometry`, gmsh OCC) -> linear tetrahedral mesh
(:mod:`ffrf.meshing`, :mod:`ffrf.mesh`) -> FE matrices (:mod:`ffrf.fe_model`, scikit-fem)
-> interfaces (:mod:`ffrf.interfaces`) -> Craig-Bampton basis (:mod:`ffrf.craig_bampton`)
-> modal moments and FFRF body (:mod:`ffrf.modal_moments`, :mod:`ffrf.flexible_body`)
-> markers and joints (:mod:`ffrf.markers`, :mod:`ffrf.joints`) -> system
(:mod:`ffrf.system`) -> generalized-alpha, variational midpoint or static solution
(:mod:`ffrf.generalized_alpha`, :mod:`ffrf.variational_midpoint`, :mod:`ffrf.static_solver`)
-> the Bennett scene and its sensors (:mod:`ffrf.bennett_scene`, :mod:`ffrf.bennett_run`).
The equations are derived in ``docs/formulation.md``.
This package never imports Exudyn.
"""

from .errors import FEInputError, GeometryError, InterfaceError, MaterialError, MeshError
from .fe_model import FEModel, rigid_body_modes
from .interfaces import (InterfaceNodes, boundary_triangles, interface_from_group, interface_from_nodes,
                         interface_from_nodes_file, interface_from_triangles, interface_in_cylinder)
from .link_geometry import PAPER_AXES, Axis, LinkDesign, LinkGeometry, build_link, mesh_link, paper_link_axes
from .materials import PLA, RIGID, Material
from .mesh import (TetMesh, check_mesh, mesh_quality, orient_positive, oriented, quality_summary, read_mesh,
                   write_vtu)
from .meshing import gmsh_session, mesh_stl
from .modal import Modes, clamped_modes, free_free_modes

# Reduction (Craig-Bampton), inertia invariants and reduced-body files.
from .craig_bampton import REFERENCE_CONDITIONS, CraigBamptonBasis, ReductionError, craig_bampton
from .invariants import InertiaInvariants, inertia_invariants
from .reduced_io import (ReducedBodyFileError, cached_craig_bampton, load_reduced_body,
                         reduction_fingerprint, save_reduced_body)
from .component_modes_post import element_strains, free_free_frequencies_hz, mode_displacements

# Floating frame of reference bodies, constraints, joints and solvers.
from .modal_moments import ModalMoments, modal_moments
from .flexible_body import FlexibleBody
from .markers import BodyMarker, frame_marker, node_marker, rigid_interface_marker
from .constraints import EulerNormalization, GroundPerpendicular, GroundPoint
from .joints import GroundFrame, MarkerJoint, driven_revolute_joint, fixed_joint, revolute_joint
from .drives import CosineRamp, rpm
from .system import MultibodySystem
from .generalized_alpha import IntegrationResult, NewtonDivergence, generalized_alpha
from .variational_midpoint import variational_midpoint
from .static_solver import StaticDivergence, StaticSolution, quasi_static, static_equilibrium

__all__ = [
    "FEInputError", "GeometryError", "InterfaceError", "MaterialError", "MeshError",
    "FEModel", "rigid_body_modes",
    "InterfaceNodes", "boundary_triangles", "interface_from_group", "interface_from_nodes", "interface_from_triangles",
    "interface_from_nodes_file", "interface_in_cylinder",
    "PAPER_AXES", "Axis", "LinkDesign", "LinkGeometry", "build_link", "mesh_link", "paper_link_axes",
    "PLA", "RIGID", "Material",
    "TetMesh", "check_mesh", "mesh_quality", "orient_positive", "oriented", "quality_summary", "read_mesh", "write_vtu",
    "gmsh_session", "mesh_stl",
    "Modes", "clamped_modes", "free_free_modes",
    "REFERENCE_CONDITIONS", "CraigBamptonBasis", "ReductionError", "craig_bampton",
    "InertiaInvariants", "inertia_invariants",
    "ReducedBodyFileError", "cached_craig_bampton", "load_reduced_body", "reduction_fingerprint", "save_reduced_body",
    "element_strains", "free_free_frequencies_hz", "mode_displacements",
    "ModalMoments", "modal_moments", "FlexibleBody",
    "BodyMarker", "frame_marker", "node_marker", "rigid_interface_marker",
    "EulerNormalization", "GroundPerpendicular", "GroundPoint",
    "GroundFrame", "MarkerJoint", "driven_revolute_joint", "fixed_joint", "revolute_joint",
    "CosineRamp", "rpm", "MultibodySystem",
    "IntegrationResult", "NewtonDivergence", "generalized_alpha", "variational_midpoint",
    "StaticDivergence", "StaticSolution", "quasi_static", "static_equilibrium",
]
