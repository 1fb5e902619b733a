"""Bodies of a scene given by their mass and stiffness matrices (``matrices = {...}`` instead of a mesh).

Another FE program assembled M and K; the scene reads them with :mod:`ffrf.fe.matrix_import` into an
:class:`~ffrf.fe.external_model.ExternalFEModel` (SI units, DOFs [x0, y0, z0, x1, ...] in the order of the
nodes), the model the Exudyn TestModel twins use (``validation/testmodels``)::

    matrices = {format = "abaqus", nodes = "block.inp", instance = "block-1",      # nodes and elements
                mass = "block_MASS1.mtx", stiffness = "block_STIF1.mtx"}         # *MATRIX OUTPUT, COORDINATE
    matrices = {format = "matrix_market", nodes = "nodes.txt", mass = "M.mtx", stiffness = "K.mtx"}
    matrices = {format = "npz", file = "body.npz"}                               # ffrf.fe.matrix_import.NPZ_KEYS

``nodes`` is an Abaqus input file (nodes and volume elements of ``instance``, a ``*Part`` or ``*Instance``) or a
text table, one node "x y z" per line (no elements). Optional: ``scale_stiffness`` (K times the factor,
Exudyn's ``ScaleStiffnessMatrix``) and ``point_masses = [{node = 9, mass = 0.1}, {point = [x, y, z], mass = ...}]``
(Exudyn's ``AddNodeMass``). Interfaces select nodes by ``cylinder``, ``plane`` or ``nodes_file``
(:func:`matrices_interface`); a body from matrices has no named groups and no surface mesh of ours.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ffrf.errors import ExternalFEError, InterfaceError, MeshError, SceneError
from ffrf.fe.external_interfaces import external_interface
from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.interfaces import InterfaceNodes, read_nodes_file
from ffrf.fe.matrix_import import (
    read_abaqus_matrix,
    read_abaqus_mesh,
    read_matrix_market,
    read_node_table,
    read_npz_model,
)
from ffrf.fe.node_selection import node_at_point, nodes_in_plane, on_cylinder

__all__ = ["MATRIX_FORMATS", "MATRIX_FILES", "matrices_model", "matrices_interface", "is_abaqus_input"]

#: How ``mass`` and ``stiffness`` are stored: Abaqus ``FORMAT=COORDINATE`` .mtx, Matrix Market, or all in one .npz.
MATRIX_FORMATS = ("abaqus", "matrix_market", "npz")
#: The file keys each format takes.
MATRIX_FILES = {
    "abaqus": ("nodes", "mass", "stiffness"),
    "matrix_market": ("nodes", "mass", "stiffness"),
    "npz": ("file",),
}
_MATRIX_READERS = {"abaqus": read_abaqus_matrix, "matrix_market": read_matrix_market}
#: Default distance (m) within which a plane selection or a point mass's point finds nodes (Exudyn's 1e-5).
NODE_TOLERANCE = 1e-5


def is_abaqus_input(name: str) -> bool:
    """Whether a file name is an Abaqus input file (``.inp``, possibly compressed)."""
    return ".inp" in Path(name.lower()).suffixes


def _read(spec: dict, files: dict[str, Path], name: str) -> ExternalFEModel:
    if spec["format"] == "npz":
        return read_npz_model(files["file"])
    nodes_file = files["nodes"]
    if is_abaqus_input(nodes_file.name):
        mesh = read_abaqus_mesh(nodes_file, spec.get("instance"))
        nodes, elements = mesh.nodes, mesh.elements
    else:
        nodes, elements = read_node_table(nodes_file), {}
    read = _MATRIX_READERS[spec["format"]]
    n_dofs = 3 * len(nodes)
    return ExternalFEModel(nodes, read(files["mass"], n_dofs), read(files["stiffness"], n_dofs), elements, name)


def matrices_model(spec: dict, base: Path, name: str, where: str) -> ExternalFEModel:
    """The model of a ``matrices`` table (files relative to ``base``) with its scaled stiffness and point masses;
    every problem with the files is a one-line :class:`SceneError` naming ``where``."""
    files = {key: base / spec[key] for key in MATRIX_FILES[spec["format"]]}
    for key, path in files.items():
        if not path.is_file():
            raise SceneError(
                f"{where}, matrices: {key} = {spec[key]!r}: {path} not found; give a path relative to the scene file"
            )
    try:
        model = _read(spec, files, name)
        if "scale_stiffness" in spec:
            model = model.with_scaled_stiffness(float(spec["scale_stiffness"]))
        for point_mass in spec.get("point_masses", []):
            node = point_mass.get("node")
            if node is None:
                node = node_at_point(
                    model.nodes, point_mass["point"], float(point_mass.get("tolerance", NODE_TOLERANCE))
                )
            model = model.with_node_mass(node, float(point_mass["mass"]))
    except (ExternalFEError, InterfaceError, MeshError) as error:
        raise SceneError(f"{where}, matrices: {error}") from error
    return model


def matrices_interface(model: ExternalFEModel, spec: dict, base: Path) -> InterfaceNodes:
    """Interface ``spec`` (a scene's interface table) of a body from matrices: the nodes on a ``cylinder``, in a
    ``plane`` or listed in a ``nodes_file``, weighted by :func:`~ffrf.fe.external_interfaces.external_interface`
    (``weights = "equal"``: all alike)."""
    name = spec["name"]
    weights = None
    if "cylinder" in spec:
        c = spec["cylinder"]
        nodes = np.flatnonzero(
            on_cylinder(
                model.nodes,
                c["point"],
                c["direction"],
                float(c["radius"]),
                tuple(c["axial_extent"]),
                float(c.get("tolerance", 1e-4)),
            )
        )
    elif "plane" in spec:
        p = spec["plane"]
        nodes = nodes_in_plane(model.nodes, p["point"], p["normal"], float(p.get("tolerance", NODE_TOLERANCE)))
    else:
        nodes, weights = read_nodes_file(name, base / spec["nodes_file"])
    if spec.get("weights", "area") == "equal":
        weights = np.ones(len(nodes))
    return external_interface(model, name, nodes, weights)
