"""In-house flexible multibody solver: floating frame of reference bodies with Craig-Bampton modes.

Data flow: geometry (:mod:`ffrf.geometry.link_geometry`, gmsh OCC) -> linear tetrahedral mesh
(:mod:`ffrf.geometry.meshing`, :mod:`ffrf.mesh.tet_mesh`) -> FE matrices (:mod:`ffrf.fe.fe_model`, scikit-fem)
-> interfaces (:mod:`ffrf.fe.interfaces`) -> Craig-Bampton basis (:mod:`ffrf.reduction.craig_bampton`);
or nodes and matrices from another FE program (:mod:`ffrf.fe.matrix_import`) -> free-free basis
(:mod:`ffrf.reduction.free_free`)
-> modal moments and FFRF body (:mod:`ffrf.body.modal_moments`, :mod:`ffrf.body.flexible_body`)
-> markers and joints (:mod:`ffrf.system.markers`, :mod:`ffrf.system.joints`) -> system
(:mod:`ffrf.system.multibody`) -> generalized-alpha, variational midpoint or static solution
(:mod:`ffrf.solvers.generalized_alpha`, :mod:`ffrf.solvers.variational_midpoint`, :mod:`ffrf.solvers.static_solver`)
-> scenes: one builder from a description (:mod:`ffrf.scenes.builder`) for scene files
(:mod:`ffrf.scenes.scene_file`) and the paper's Bennett scenes (:mod:`ffrf.paper.bennett_scene`,
runs and sensors in :mod:`ffrf.scenes.linkage_run`). Layers and where to change what:
``docs/architecture.md``.
The equations are derived in ``docs/formulation.md``.
This package never imports Exudyn.
"""

import os

# LLVM at optimisation level 2 instead of numba's default 3, unless the user chose one: it is most of the first
# run's compilation, which level 2 cuts by about a quarter with our kernels as fast as before
# (``bench/compile_times.py``, ``docs/speed_vs_error.md``). Read by numba when it is first imported.
os.environ.setdefault("NUMBA_OPT", "2")

from ffrf.body.flexible_body import FlexibleBody

# Floating frame of reference bodies, constraints, joints and solvers.
from ffrf.body.modal_moments import ModalMoments, modal_moments
from ffrf.errors import (
    ExternalFEError,
    FEInputError,
    GeometryError,
    InterfaceError,
    MaterialError,
    MeshError,
    NewtonDivergence,
    ReductionError,
    SceneError,
    SingularIterationMatrix,
    StaticDivergence,
)
from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.fe_model import FEModel, rigid_body_modes
from ffrf.fe.interfaces import (
    InterfaceNodes,
    boundary_triangles,
    interface_from_group,
    interface_from_nodes,
    interface_from_nodes_file,
    interface_from_triangles,
    interface_in_cylinder,
)
from ffrf.fe.materials import PLA, RIGID, Material
from ffrf.fe.matrix_import import (
    abaqus_model,
    read_abaqus_matrix,
    read_abaqus_mesh,
    read_matrix_market,
    read_npz_model,
    write_npz_model,
)
from ffrf.fe.modal import Modes, clamped_modes
from ffrf.fe.node_selection import node_at_point, nodes_in_plane, surface_area_weights, surface_triangles
from ffrf.geometry.joint_axes import Axis
from ffrf.geometry.link_geometry import LinkDesign, LinkGeometry, build_link, mesh_link
from ffrf.geometry.meshing import gmsh_session, mesh_stl
from ffrf.mesh.tet_mesh import (
    TetMesh,
    check_mesh,
    mesh_quality,
    orient_positive,
    quality_summary,
    read_mesh,
    write_vtu,
)
from ffrf.reduction.component_modes_post import element_strains, free_free_frequencies_hz, mode_displacements

# Reduction (Craig-Bampton), inertia invariants and reduced-body files.
from ffrf.reduction.craig_bampton import REFERENCE_CONDITIONS, CraigBamptonBasis, craig_bampton
from ffrf.reduction.free_free import FreeFreeBasis, free_free_basis
from ffrf.reduction.invariants import InertiaInvariants, inertia_invariants
from ffrf.reduction.mode_basis import ModeBasis
from ffrf.reduction.reduced_io import (
    ReducedBodyFileError,
    cached_craig_bampton,
    load_reduced_body,
    reduction_fingerprint,
    save_reduced_body,
)
from ffrf.scenes.assembly import assemble
from ffrf.scenes.builder import Scene, build_scene
from ffrf.scenes.scene_file import load_scene, run_scene
from ffrf.solvers.common import IntegrationResult
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.simulate import simulate
from ffrf.solvers.static_solver import StaticSolution, quasi_static, static_equilibrium
from ffrf.solvers.step_control import StepControl
from ffrf.solvers.variational_midpoint import variational_midpoint
from ffrf.system.constraints import EulerNormalization, GroundPerpendicular, GroundPoint
from ffrf.system.drives import CosineRamp, rpm
from ffrf.system.joints import GroundFrame, MarkerJoint, driven_revolute_joint, fixed_joint, revolute_joint
from ffrf.system.markers import BodyMarker, frame_marker, node_marker, rigid_interface_marker
from ffrf.system.multibody import MultibodySystem

__all__ = [
    "FEInputError",
    "ExternalFEError",
    "GeometryError",
    "InterfaceError",
    "MaterialError",
    "MeshError",
    "SceneError",
    "SingularIterationMatrix",
    "FEModel",
    "rigid_body_modes",
    "ExternalFEModel",
    "abaqus_model",
    "read_abaqus_mesh",
    "read_abaqus_matrix",
    "read_matrix_market",
    "read_npz_model",
    "write_npz_model",
    "node_at_point",
    "nodes_in_plane",
    "surface_triangles",
    "surface_area_weights",
    "InterfaceNodes",
    "boundary_triangles",
    "interface_from_group",
    "interface_from_nodes",
    "interface_from_triangles",
    "interface_from_nodes_file",
    "interface_in_cylinder",
    "Axis",
    "LinkDesign",
    "LinkGeometry",
    "build_link",
    "mesh_link",
    "PLA",
    "RIGID",
    "Material",
    "TetMesh",
    "check_mesh",
    "mesh_quality",
    "orient_positive",
    "quality_summary",
    "read_mesh",
    "write_vtu",
    "gmsh_session",
    "mesh_stl",
    "Modes",
    "clamped_modes",
    "REFERENCE_CONDITIONS",
    "CraigBamptonBasis",
    "ReductionError",
    "craig_bampton",
    "FreeFreeBasis",
    "free_free_basis",
    "ModeBasis",
    "InertiaInvariants",
    "inertia_invariants",
    "ReducedBodyFileError",
    "cached_craig_bampton",
    "load_reduced_body",
    "reduction_fingerprint",
    "save_reduced_body",
    "element_strains",
    "free_free_frequencies_hz",
    "mode_displacements",
    "ModalMoments",
    "modal_moments",
    "FlexibleBody",
    "BodyMarker",
    "frame_marker",
    "node_marker",
    "rigid_interface_marker",
    "EulerNormalization",
    "GroundPerpendicular",
    "GroundPoint",
    "GroundFrame",
    "MarkerJoint",
    "driven_revolute_joint",
    "fixed_joint",
    "revolute_joint",
    "CosineRamp",
    "rpm",
    "MultibodySystem",
    "IntegrationResult",
    "NewtonDivergence",
    "generalized_alpha",
    "variational_midpoint",
    "StaticDivergence",
    "StaticSolution",
    "quasi_static",
    "static_equilibrium",
    "StepControl",
    "simulate",
    "Scene",
    "build_scene",
    "assemble",
    "load_scene",
    "run_scene",
]
