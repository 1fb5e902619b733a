"""Bad external FE input (``ffrf.fe.matrix_import``, ``ffrf.fe.external_model``,
``ffrf.fe.node_selection``, ``ffrf.reduction.free_free``) is refused with one line naming the
problem and the fix. Every case is a row of docs/bad_input.md."""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.io import mmwrite

from ffrf.errors import ExternalFEError, FEInputError, InterfaceError, MeshError, ReductionError
from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.matrix_import import (
    abaqus_model,
    read_abaqus_matrix,
    read_abaqus_mesh,
    read_matrix_market,
    read_npz_model,
)
from ffrf.fe.node_selection import node_at_point, nodes_in_plane, surface_area_weights, surface_triangles
from ffrf.reduction.free_free import free_free_basis

DATA = Path(__file__).parents[2] / "validation" / "data" / "exudyn_testmodels"

INP = """*Part, name=Bar
*Node
1, 0., 0., 0.
2, 1., 0., 0.
3, 0., 1., 0.
4, 0., 0., 1.
*Element, type=C3D4
1, 1, 2, 3, 4
*End Part
*Assembly, name=Assembly
*Instance, name=Bar-1, part=Bar
*End Instance
*End Assembly
"""


@cache
def block() -> ExternalFEModel:
    """abaqusImportTest.py's C3D8 block: 176 nodes, lumped mass."""
    stem = DATA / "abaqus" / "blockC3D8"
    return abaqus_model(f"{stem}.inp", f"{stem}_MASS1.mtx.xz", f"{stem}_STIF1.mtx.xz", "block-1")


def _tet(**changes) -> ExternalFEModel:
    """One tetrahedron's worth of nodes with simple SPD matrices, with ``changes`` applied."""
    arguments = {
        "nodes": np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
        "mass": sp.identity(12),
        "stiffness": sp.identity(12) * 1e3,
        "elements": {"Tet4": np.array([[0, 1, 2, 3]])},
        "name": "tet",
    }
    return ExternalFEModel(**(arguments | changes))


def _write(tmp_path: Path, name: str, text: str) -> Path:
    (tmp_path / name).write_text(text)
    return tmp_path / name


def _npz(tmp_path: Path, **arrays: np.ndarray) -> Path:
    np.savez(tmp_path / "m.npz", allow_pickle=False, **arrays)  # plain arrays: nothing to pickle
    return tmp_path / "m.npz"


def _inp(tmp_path: Path, old: str, new: str) -> Path:
    assert old in INP
    return _write(tmp_path, "bar.inp", INP.replace(old, new, 1))


def _exudyn_npz(tmp_path: Path) -> Path:
    """What Exudyn's ``FEMinterface.SaveToFile(..., mode='NPZ')`` writes: dictionaries as object arrays."""
    np.savez(tmp_path / "fem.npz", nodes=np.array({"Position": np.zeros((2, 3))}, dtype=object))
    return tmp_path / "fem.npz"


def _matrix_market(tmp_path: Path, matrix) -> Path:
    mmwrite(tmp_path / "k.mtx", matrix)
    return tmp_path / "k.mtx"


def _supported_block() -> ExternalFEModel:
    """Exudyn's AddElasticSupportAtNode: a 1e12 N/m spring on the 3 DOFs of node 0."""
    model = block()
    return ExternalFEModel(model.nodes, model.mass, model.stiffness + sp.diags(np.r_[np.full(3, 1e12), np.zeros(525)]))


def _block_with_a_loose_node() -> ExternalFEModel:
    """A 177th node with mass but no element (no stiffness)."""
    model = block()
    nodes = np.vstack([model.nodes, [5.0, 0.0, 0.0]])
    return ExternalFEModel(
        nodes, sp.block_diag([model.mass, sp.identity(3)]), sp.block_diag([model.stiffness, sp.csr_matrix((3, 3))])
    )


def _block_with_swapped_dofs() -> ExternalFEModel:
    """K numbered [y0, x0, z0, y1, ...] while the nodes say [x0, y0, z0, ...]."""
    model = block()
    order = np.arange(model.n_dofs).reshape(-1, 3)[:, [1, 0, 2]].reshape(-1)
    return ExternalFEModel(model.nodes, model.mass, model.stiffness[order][:, order])


def _indefinite_block() -> SimpleNamespace:
    """K - 2 omega_1^2 M: two negative eigenvalues' worth of instability (a duck-typed model)."""
    model = block()
    return SimpleNamespace(nodes=model.nodes, mass=model.mass, stiffness=model.stiffness - 2.0 * 7.6e6 * model.mass)


#: case -> (action raising the error, error class, words the one-line message must contain)
CASES: dict[str, tuple[Callable[[Path], object], type[FEInputError], list[str]]] = {
    "missing matrix file": (lambda p: read_abaqus_matrix(p / "job_STIF1.mtx"), ExternalFEError, ["file not found"]),
    "matrix in the LABELS format": (
        lambda p: read_abaqus_matrix(_write(p, "m.mtx", "1, 1, 1, 1, 2.0\n")),
        ExternalFEError,
        ["5 columns", "FORMAT=COORDINATE"],
    ),
    "matrix file that is not numbers": (
        lambda p: read_abaqus_matrix(_write(p, "m.mtx", "*HEADING\n1 1 2.0\n")),
        ExternalFEError,
        ["not a table of numbers"],
    ),
    "empty matrix file": (
        lambda p: read_abaqus_matrix(_write(p, "m.mtx", "")),
        ExternalFEError,
        ["holds no matrix entries"],
    ),
    "DOF numbers from 0": (
        lambda p: read_abaqus_matrix(_write(p, "m.mtx", "0 0 1.0\n")),
        ExternalFEError,
        ["integers >= 1"],
    ),
    "matrix of a bigger model": (
        lambda p: read_abaqus_matrix(_write(p, "m.mtx", "30 30 1.0\n"), n_dofs=12),
        ExternalFEError,
        ["refers to DOF 30", "12 DOFs (4 nodes x 3)", "another model"],
    ),
    "instance name not in the file": (
        lambda p: read_abaqus_mesh(DATA / "abaqus" / "blockC3D4.inp", "rotor-1"),
        ExternalFEError,
        ["no *Part or *Instance named 'rotor-1'", "instance 'block-1' (214 nodes)"],
    ),
    "several parts with nodes and no name": (
        lambda p: read_abaqus_mesh(_inp(p, "*End Assembly", "*End Assembly\n*Part, name=B\n*Node\n1, 0., 0., 0.\n")),
        ExternalFEError,
        ["2 parts/instances hold nodes", "pass name="],
    ),
    "instance whose nodes are in its part": (
        lambda p: read_abaqus_mesh(_write(p, "bar.inp", INP), "bar-1"),
        ExternalFEError,
        ["instance 'bar-1' holds no *Node data", "read name='Bar'"],
    ),
    "node labels not 1..N": (
        lambda p: read_abaqus_mesh(_inp(p, "3, 0., 1., 0.", "7, 0., 1., 0.")),
        ExternalFEError,
        ["must be 1..N in file order", "row 3 has label 7", "renumber"],
    ),
    "two-dimensional nodes": (
        lambda p: read_abaqus_mesh(_inp(p, "2, 1., 0., 0.", "2, 1., 0.")),
        ExternalFEError,
        ["line 4", "3 coordinates", "only 3D solid models"],
    ),
    "included file": (
        lambda p: read_abaqus_mesh(_inp(p, "*End Part", "*Include, input=more.inp\n*End Part")),
        ExternalFEError,
        ["*Include is not read", "merge"],
    ),
    "element with a node missing": (
        lambda p: read_abaqus_mesh(
            _inp(p, "*Element, type=C3D4\n1, 1, 2, 3, 4", "*Element, type=C3D4\n1, 1, 2, 3,\n*")
        ),
        ExternalFEError,
        ["element 1 ends before its last node"],
    ),
    "not a Matrix Market file": (
        lambda p: read_matrix_market(_write(p, "k.mtx", "1 1 2.0\n")),
        ExternalFEError,
        ["not a Matrix Market file", "mmwrite"],
    ),
    "complex Matrix Market matrix": (
        lambda p: read_matrix_market(_matrix_market(p, sp.identity(3) * (1 + 1j))),
        ExternalFEError,
        ["complex"],
    ),
    "Matrix Market matrix of another size": (
        lambda p: read_matrix_market(_matrix_market(p, sp.identity(9)), n_dofs=12),
        ExternalFEError,
        ["9 x 9, expected 12 x 12 (3 DOFs per node)"],
    ),
    "Exudyn's own .npz": (
        lambda p: read_npz_model(_exudyn_npz(p)),
        ExternalFEError,
        ["Exudyn FEMinterface file stores pickled objects", "NPZ_KEYS"],
    ),
    "npz that is not an archive": (
        lambda p: read_npz_model(_write(p, "m.npz", "nodes")),
        ExternalFEError,
        ["not an .npz archive", "write_npz_model"],
    ),
    "npz without nodes": (
        lambda p: read_npz_model(_npz(p, mass=np.eye(3))),
        ExternalFEError,
        ["no 'nodes' array", "['mass']"],
    ),
    "npz without stiffness": (
        lambda p: read_npz_model(_npz(p, nodes=np.zeros((1, 3)), mass=np.eye(3))),
        ExternalFEError,
        ["no 'stiffness' and no ['stiffness_row', 'stiffness_col', 'stiffness_value']"],
    ),
    "matrix and nodes of different models": (
        lambda p: _tet(stiffness=sp.identity(15)),
        ExternalFEError,
        ["stiffness matrix is 15 x 15, expected 12 x 12 for 4 nodes"],
    ),
    "unsymmetric matrix": (
        lambda p: _tet(stiffness=sp.identity(12) * 1e3 + sp.csr_matrix(([5.0], ([0], [4])), shape=(12, 12))),
        ExternalFEError,
        ["not symmetric", "(node 0 x, node 1 y)", "export the full symmetric matrix"],
    ),
    "zero mass on a DOF": (
        lambda p: _tet(mass=sp.diags(np.r_[np.ones(11), 0.0])),
        ExternalFEError,
        ["1 diagonal entries of the mass matrix are <= 0", "node 3 z"],
    ),
    "NaN in a matrix": (
        lambda p: _tet(mass=sp.diags(np.r_[np.ones(11), np.nan])),
        ExternalFEError,
        ["mass matrix contains NaN or inf"],
    ),
    "nodes with two coordinates": (
        lambda p: _tet(nodes=np.zeros((6, 2))),
        ExternalFEError,
        ["(N, 3) array", "shape (6, 2)"],
    ),
    "element node out of range": (
        lambda p: _tet(elements={"Tet4": np.array([[0, 1, 2, 4]])}),
        ExternalFEError,
        ["refer to node 4, outside [0, 4)", "0-based"],
    ),
    "negative point mass": (
        lambda p: _tet().with_node_mass(1, -0.1),
        ExternalFEError,
        ["point mass -0.1 kg at node 1 must be finite and >= 0"],
    ),
    "point mass at a node that does not exist": (
        lambda p: _tet().with_node_mass(4, 0.1),
        ExternalFEError,
        ["point mass at node 4", "[0, 4)"],
    ),
    "zero stiffness factor": (
        lambda p: _tet().with_scaled_stiffness(0.0),
        ExternalFEError,
        ["stiffness factor 0.0 must be finite and > 0"],
    ),
    "no node at the point": (
        lambda p: node_at_point(block().nodes, [2.0, 0.5, 0.55]),
        InterfaceError,
        ["no node within 1e-05 of [2.0, 0.5, 0.55]", "nearest", "units"],
    ),
    "no node in the plane": (
        lambda p: nodes_in_plane(block().nodes, [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
        InterfaceError,
        ["no node within 1e-05 of the plane"],
    ),
    "nodes spanning no surface triangle": (
        lambda p: surface_area_weights(block().nodes, surface_triangles(block().elements), [0, 1]),
        InterfaceError,
        ["the 2 nodes span no surface triangle"],
    ),
    "surface of unknown elements": (
        lambda p: surface_triangles({"C3D6": np.zeros((1, 6), dtype=int)}),
        MeshError,
        ["surface of 'C3D6' elements is not known", "weights explicitly"],
    ),
    "no free-free mode asked": (lambda p: free_free_basis(block(), 0), ReductionError, ["n_modes=0", "positive"]),
    "seven rigid-body modes": (
        lambda p: free_free_basis(block(), 4, n_rigid=7),
        ReductionError,
        ["n_rigid=7", "from 0 to 6"],
    ),
    "more modes than DOFs": (
        lambda p: free_free_basis(_tet(), 8),
        ReductionError,
        ["too many modes requested", "at most 5"],
    ),
    "free-free modes of a supported body": (
        lambda p: free_free_basis(_supported_block(), 4),
        ReductionError,
        ["only 3 modes have zero frequency", "supported", "n_rigid=3"],
    ),
    "free-free modes of a mechanism": (
        lambda p: free_free_basis(_block_with_a_loose_node(), 4),
        ReductionError,
        ["9 modes have zero frequency where 6", "mechanism"],
    ),
    "matrices numbered unlike the nodes": (
        lambda p: free_free_basis(_block_with_swapped_dofs(), 4),
        ReductionError,
        ["not rigid-body motions of the nodes", "[x0, y0, z0, x1, ...]"],
    ),
    "stiffness with negative eigenvalues": (
        lambda p: free_free_basis(_indefinite_block(), 4),
        ReductionError,
        ["K + s M is not positive definite"],
    ),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_external_fe_input_is_refused(tmp_path, case):
    action, error, words = CASES[case]
    with pytest.raises(error) as raised:
        action(tmp_path)
    message = str(raised.value)
    assert "\n" not in message, message
    for word in words:
        assert word in message, (case, message)
