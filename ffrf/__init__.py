"""In-house flexible multibody solver: floating frame of reference bodies with Craig-Bampton modes.

The front door (:mod:`ffrf.model`)::

    import ffrf

    model = ffrf.load("scene.toml")  # a scene or linkage file, its mapping, a kinematics SingleLoop, a built scene
    result = model.run()  # quasi-static or dynamic, as the scene says; checks itself
    result.save("out")  # results.npz, results.csv, metadata.json, assembly.vtu, figures

:data:`__all__` holds the facade, the errors and the value types a user passes in; everything else stays in its
module. Data flow: geometry (:mod:`ffrf.geometry.link_geometry`, gmsh OCC) -> linear tetrahedral mesh
(:mod:`ffrf.geometry.meshing`, :mod:`ffrf.mesh.tet_mesh`) -> FE matrices (:mod:`ffrf.fe.fe_model`, scikit-fem)
-> interfaces (:mod:`ffrf.fe.interfaces`) -> Craig-Bampton basis (:mod:`ffrf.reduction.craig_bampton`);
or nodes and matrices from another FE program (:mod:`ffrf.fe.matrix_import`) -> free-free basis
(:mod:`ffrf.reduction.free_free`)
-> modal moments and FFRF body (:mod:`ffrf.body.modal_moments`, :mod:`ffrf.body.flexible_body`)
-> markers and joints (:mod:`ffrf.system.markers`, :mod:`ffrf.system.joints`) -> system
(:mod:`ffrf.system.multibody`) -> generalized-alpha, variational midpoint or static solution
(:mod:`ffrf.solvers.generalized_alpha`, :mod:`ffrf.solvers.variational_midpoint`, :mod:`ffrf.solvers.static_solver`)
-> scenes: one builder from a description (:mod:`ffrf.scenes.builder`) for scene files
(:mod:`ffrf.scenes.scene_file`), linkages (:mod:`ffrf.scenes.linkage_scene`) and the paper's Bennett scenes
(:mod:`ffrf.paper.bennett_scene`); runs in :mod:`ffrf.scenes.linkage_run` and :mod:`ffrf.scenes.scene_file`, one
:class:`~ffrf.output.result.Result`. Layers and where to change what: ``docs/architecture.md``.
The equations are derived in ``docs/formulation.md``.
This package never imports Exudyn.
"""

import os
import sys

# LLVM at optimisation level 2 instead of numba's default 3, unless the user chose one: it is most of the first
# run's compilation, which level 2 cuts by about a quarter with our kernels as fast as before
# (``bench/compile_times.py``, ``docs/speed_vs_error.md``). Read by numba when it is first imported.
os.environ.setdefault("NUMBA_OPT", "2")

from ffrf.numerics.kernel_cache import default_kernel_cache  # imports no numba

# Before numba is imported: compiled kernels in a folder named by their sources (a stale callee cannot survive).
if "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = default_kernel_cache()
    if "numba" in sys.modules:  # imported first by the caller: numba read its settings already, so set its own
        sys.modules["numba"].core.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]

from ffrf.errors import (
    AssemblyDivergence,
    ExternalFEError,
    FEInputError,
    GeometryError,
    InterfaceError,
    Interrupted,
    MaterialError,
    MeshError,
    NewtonDivergence,
    ReductionError,
    ResultsError,
    SceneError,
    SingularIterationMatrix,
    StaticDivergence,
)
from ffrf.fe.materials import Material
from ffrf.geometry.link_geometry import LinkDesign
from ffrf.model import Model, load
from ffrf.output.result import Result
from ffrf.output.tables import read_results
from ffrf.scenes.builder import Scene
from ffrf.scenes.linkage_description import BoreError, LinkageOptions
from ffrf.scenes.linkage_scene import LinkageScene

__all__ = [
    # the facade
    "load",
    "Model",
    "Result",
    "read_results",
    # what a model is built from and runs as
    "Material",
    "LinkDesign",
    "LinkageOptions",
    "BoreError",
    "Scene",
    "LinkageScene",
    # bad input (FEInputError and its kinds) and runs that stop
    "FEInputError",
    "MeshError",
    "InterfaceError",
    "MaterialError",
    "GeometryError",
    "SceneError",
    "ReductionError",
    "ExternalFEError",
    "ResultsError",
    "StaticDivergence",
    "AssemblyDivergence",
    "NewtonDivergence",
    "SingularIterationMatrix",
    "Interrupted",
]
