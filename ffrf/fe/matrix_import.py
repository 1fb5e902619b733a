"""Readers of FE models assembled elsewhere: Abaqus input and matrix files, Matrix Market, .npz.

* :func:`read_abaqus_mesh`: the nodes (and volume elements) of one named ``*Part`` or
  ``*Instance`` of an Abaqus input file (``.inp``), as Exudyn's
  ``FEMinterface.ImportFromAbaqusInputFile``, which however ignores the name and takes the
  first block of that kind.
* :func:`read_abaqus_matrix`: a ``*_MASS1.mtx`` / ``*_STIF1.mtx`` file of
  ``*MATRIX OUTPUT, STIFFNESS, MASS, FORMAT=COORDINATE`` (one "row column value" line per entry,
  1-based DOF numbers, row = 3 (node label - 1) + direction, eq. (X1)), as Exudyn's
  ``ReadMassMatrixFromAbaqus`` / ``ReadStiffnessMatrixFromAbaqus``.
* :func:`read_matrix_market`: any Matrix Market file, through :func:`scipy.io.mmread`.
* :func:`read_node_table`: node coordinates as a text table, one node "x y z" per line (row k: node k).
* :func:`read_npz_model` / :func:`write_npz_model`: nodes, matrices and elements in one ``.npz``
  (keys in :data:`NPZ_KEYS`), read without unpickling anything.

Text files may be compressed (``.gz``, ``.bz2``, ``.xz``). Every reader refuses bad input with
:class:`ffrf.errors.ExternalFEError` naming the file, the problem and the fix.
"""

from __future__ import annotations

import bz2
import gzip
import io
import logging
import lzma
import warnings
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ffrf.errors import ExternalFEError
from ffrf.fe.external_model import ELEMENT_NODES, ExternalFEModel

__all__ = [
    "ABAQUS_ELEMENT_TYPES",
    "NPZ_KEYS",
    "AbaqusMesh",
    "abaqus_model",
    "read_abaqus_mesh",
    "read_abaqus_matrix",
    "read_matrix_market",
    "read_node_table",
    "read_npz_model",
    "write_npz_model",
]

logger = logging.getLogger(__name__)

#: Abaqus solid element types read with their topology (the rest keep their Abaqus name).
ABAQUS_ELEMENT_TYPES: dict[str, str] = {
    "C3D4": "Tet4",
    "C3D4H": "Tet4",
    "C3D10": "Tet10",
    "C3D10H": "Tet10",
    "C3D10M": "Tet10",
    "C3D10MH": "Tet10",
    "C3D10HS": "Tet10",
    "C3D8": "Hex8",
    "C3D8R": "Hex8",
    "C3D8I": "Hex8",
    "C3D8H": "Hex8",
    "C3D20": "Hex20",
    "C3D20R": "Hex20",
    "C3D20H": "Hex20",
    "C3D20RH": "Hex20",
}

#: Keys of the ``.npz`` model file. Matrices are COO triplets (0-based) or dense arrays.
NPZ_KEYS: dict[str, str] = {
    "nodes": "(N, 3) float: node coordinates (m)",
    "mass_row, mass_col, mass_value": "COO triplets of M (0-based, duplicates summed); or 'mass': dense (3N, 3N)",
    "stiffness_row, stiffness_col, stiffness_value": "COO triplets of K; or 'stiffness': dense (3N, 3N)",
    "elements_<type>": "optional (k, n) int: 0-based node indices of the elements of <type> (e.g. elements_Tet4)",
    "name": "optional 0-d string: the model's label",
}

_OPENERS: dict[str, Callable[..., IO[str]]] = {".gz": gzip.open, ".bz2": bz2.open, ".xz": lzma.open}


@dataclass(frozen=True, eq=False)
class AbaqusMesh:
    """Nodes and elements of one ``*Part`` or ``*Instance`` of an Abaqus input file.

    ``nodes``: (N, 3) in file order (node label k is row k - 1); ``elements``: type
    (:data:`ABAQUS_ELEMENT_TYPES`) -> (k, n) 0-based node rows; ``name``, ``kind``: the block read.
    """

    nodes: NDArray[np.float64]
    elements: dict[str, NDArray[np.int64]]
    name: str
    kind: str


def _open_text(path: Path) -> IO[str]:
    """The file as text, decompressed by its suffix (.gz, .bz2, .xz)."""
    if not path.is_file():
        raise ExternalFEError(f"{path}: file not found; check the path (relative paths start at {Path.cwd()})")
    opener = _OPENERS.get(path.suffix.lower())
    return opener(path, "rt") if opener else open(path)  # closed by the caller's with


# ------------------------------------------------------------------------------------------------
# Abaqus input file
# ------------------------------------------------------------------------------------------------


def _keyword(line: str) -> tuple[str, dict[str, str]]:
    """('instance', {'name': 'rotor-1', 'part': 'rotor'}) of '*Instance, name=rotor-1, part=rotor'
    (keywords and parameter names are case-insensitive in Abaqus)."""
    parts = [part.strip() for part in line[1:].split(",")]
    params = {}
    for part in parts[1:]:
        key, _, value = part.partition("=")
        if key:
            params[key.strip().lower()] = value.strip().strip('"')
    return parts[0].lower(), params


@dataclass
class _Block:
    kind: str
    name: str
    part: str = ""
    labels: list[int] = field(default_factory=list)
    coordinates: list[list[float]] = field(default_factory=list)
    elements: dict[str, list[list[int]]] = field(default_factory=dict)


def _parse_inp(path: Path) -> list[_Block]:
    """Every part, instance and the model level (nodes outside any part) with its nodes and elements."""
    model = _Block("model", "")
    blocks, current = [model], model
    section: str | None = None  # "node", "element" or None (data of other keywords is skipped)
    element_type, pending = "", list[int]()
    with _open_text(path) as stream:
        for number, raw in enumerate(stream, start=1):
            line = raw.strip()
            if not line or line.startswith("**"):
                continue
            if line.startswith("*"):
                if pending:
                    raise ExternalFEError(
                        f"{path}, line {number}: element {pending[0]} ends before its last node (a line ending in ',' "
                        "continues on the next); complete the element's node list"
                    )
                keyword, params = _keyword(line)
                section = None
                if keyword in ("part", "instance"):
                    current = _Block(keyword, params.get("name", ""), params.get("part", ""))
                    blocks.append(current)
                elif keyword in ("end part", "end instance"):
                    current = model
                elif keyword == "node":
                    if params.get("system", "r").lower() != "r":
                        raise ExternalFEError(
                            f"{path}, line {number}: nodes in a non-rectangular system (SYSTEM={params['system']}); "
                            "export Cartesian coordinates"
                        )
                    section = "node"
                elif keyword == "element":
                    element_type, section = params.get("type", "").upper(), "element"
                    if not element_type:
                        raise ExternalFEError(f"{path}, line {number}: *Element without type=; give the element type")
                elif keyword == "include":
                    raise ExternalFEError(
                        f"{path}, line {number}: *Include is not read; merge the included file into the input file"
                    )
                continue
            if section == "node":
                _node_line(path, number, line, current)
            elif section == "element":
                pending = _element_line(path, number, line, current, element_type, pending)
    return blocks


def _node_line(path: Path, number: int, line: str, block: _Block) -> None:
    fields = [f for f in line.split(",") if f.strip()]
    if len(fields) != 4:
        raise ExternalFEError(
            f"{path}, line {number}: a node line holds a label and 3 coordinates, got {len(fields)} fields "
            f"({line!r}); only 3D solid models are read"
        )
    try:
        label, coordinates = int(fields[0]), [float(f) for f in fields[1:]]
    except ValueError as error:
        raise ExternalFEError(f"{path}, line {number}: cannot read the node line {line!r} ({error})") from None
    block.labels.append(label)
    block.coordinates.append(coordinates)


def _element_line(path: Path, number: int, line: str, block: _Block, kind: str, pending: list[int]) -> list[int]:
    """Add the entries of one data line; an element may continue on the next lines (returned)."""
    try:
        pending = pending + [int(f) for f in line.split(",") if f.strip()]
    except ValueError:
        raise ExternalFEError(f"{path}, line {number}: cannot read the element line {line!r}") from None
    size = ELEMENT_NODES.get(ABAQUS_ELEMENT_TYPES.get(kind, ""), 0)
    complete = len(pending) >= size + 1 if size else not line.endswith(",")
    if not complete:
        return pending
    if size and len(pending) != size + 1:
        raise ExternalFEError(
            f"{path}, line {number}: element {pending[0]} of type {kind} lists {len(pending) - 1} nodes, "
            f"expected {size}"
        )
    block.elements.setdefault(kind, []).append(pending[1:])
    return []


def _describe(blocks: list[_Block]) -> str:
    named = [f"{b.kind} {b.name!r} ({len(b.labels)} nodes)" for b in blocks if b.kind != "model" or b.labels]
    return ", ".join(named) or "no *Part or *Instance"


def _select(path: Path, blocks: list[_Block], name: str | None) -> _Block:
    with_nodes = [b for b in blocks if b.labels]
    if name is None:
        if len(with_nodes) != 1:
            raise ExternalFEError(
                f"{path}: {len(with_nodes)} parts/instances hold nodes ({_describe(blocks)}); pass name= to choose one"
            )
        return with_nodes[0]
    matches = [b for b in blocks if b.kind != "model" and b.name.lower() == name.lower()]
    if not matches:
        raise ExternalFEError(f"{path}: no *Part or *Instance named {name!r}; the file has {_describe(blocks)}")
    found = [b for b in matches if b.labels]
    if len(found) == 1:
        return found[0]
    if len(found) > 1:
        raise ExternalFEError(f"{path}: a *Part and an *Instance are both named {name!r} and hold nodes; rename one")
    block = matches[0]
    hint = f"; its part {block.part!r} holds nodes: read name={block.part!r}" if block.kind == "instance" else ""
    raise ExternalFEError(f"{path}: {block.kind} {name!r} holds no *Node data{hint}")


def read_abaqus_mesh(path: str | Path, name: str | None = None) -> AbaqusMesh:
    """Nodes and elements of the ``*Part`` or ``*Instance`` called ``name`` (case-insensitive; by
    default the only block with nodes) of an Abaqus input file.

    Node labels must be 1..N in file order: the DOF numbers of the ``.mtx`` matrices count them so
    (eq. (X1)). Elements map node label k to row k - 1. Instance placements (translation,
    rotation lines) are not applied: nodes are in the coordinates the file lists them in.
    """
    path = Path(path)
    blocks = _parse_inp(path)
    block = _select(path, blocks, name)
    labels = np.asarray(block.labels, dtype=np.int64)
    broken = np.flatnonzero(labels != np.arange(1, len(labels) + 1))
    if broken.size:
        k = int(broken[0])
        raise ExternalFEError(
            f"{path}: node labels of {block.kind} {block.name!r} must be 1..N in file order (the .mtx DOF numbers "
            f"count them so), but row {k + 1} has label {labels[k]}; renumber the nodes before exporting"
        )
    elements: dict[str, NDArray[np.int64]] = {}
    for kind, table in block.elements.items():
        rows = np.asarray(table, dtype=np.int64) - 1
        if rows.min() < 0 or rows.max() >= len(labels):
            raise ExternalFEError(
                f"{path}: {kind} elements of {block.kind} {block.name!r} refer to node labels outside 1..{len(labels)}"
            )
        key = ABAQUS_ELEMENT_TYPES.get(kind, kind)
        elements[key] = np.vstack([elements[key], rows]) if key in elements else rows
    logger.info("%s: %s %r, %d nodes, elements %s", path, block.kind, block.name, len(labels), sorted(elements))
    return AbaqusMesh(np.asarray(block.coordinates, dtype=float), elements, block.name, block.kind)


# ------------------------------------------------------------------------------------------------
# Matrix files
# ------------------------------------------------------------------------------------------------


def _mirrored_triangle(matrix: sp.coo_matrix) -> sp.coo_matrix:
    """A matrix stored as one triangle (all entries on one side of the diagonal) completed to the
    full symmetric matrix; a full matrix unchanged."""
    lower, upper = np.any(matrix.row > matrix.col), np.any(matrix.row < matrix.col)
    if lower == upper:
        return matrix
    strict = sp.triu(matrix, k=1) if upper else sp.tril(matrix, k=-1)
    return sp.coo_matrix(matrix + strict.T)


def read_abaqus_matrix(path: str | Path, n_dofs: int | None = None) -> sp.csr_matrix:
    """The matrix of an Abaqus ``FORMAT=COORDINATE`` file (``*_MASS1.mtx``, ``*_STIF1.mtx``).

    One "row column value" line per entry, 1-based (eq. (X1)); entries given twice are summed (as
    scipy's COO and Exudyn do); a matrix stored as one triangle is mirrored. The size is ``n_dofs``
    (3 x the number of nodes), by default the largest DOF number in the file.
    """
    path = Path(path)
    with _open_text(path) as stream:
        text = stream.read().replace(",", " ")  # Abaqus writes some formats comma-separated
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # numpy warns on an empty file; refused below
        try:
            table = np.loadtxt(io.StringIO(text), ndmin=2)
        except ValueError as error:
            raise ExternalFEError(
                f"{path}: not a table of numbers ({error}); export with *MATRIX OUTPUT, ..., FORMAT=COORDINATE"
            ) from None
    if table.size == 0:
        raise ExternalFEError(f"{path}: the file holds no matrix entries; export the matrix again")
    if table.shape[1] != 3:
        hint = " (node, DOF, node, DOF, value: the LABELS format)" if table.shape[1] == 5 else ""
        raise ExternalFEError(
            f"{path}: {table.shape[1]} columns{hint}, expected 3 (row, column, value); export with "
            "*MATRIX OUTPUT, STIFFNESS, MASS, FORMAT=COORDINATE"
        )
    indices = table[:, :2]
    if not np.all(indices == np.round(indices)) or indices.min() < 1:
        raise ExternalFEError(f"{path}: row and column numbers must be integers >= 1 (Abaqus counts DOFs from 1)")
    rows, cols = indices.astype(np.int64).T - 1
    largest = int(max(rows.max(), cols.max())) + 1
    size = largest if n_dofs is None else int(n_dofs)
    if largest > size:
        raise ExternalFEError(
            f"{path}: refers to DOF {largest} but the model has {size} DOFs ({size // 3} nodes x 3); is the matrix "
            "from another model, or from elements with rotational DOFs (beams, shells)?"
        )
    matrix = _mirrored_triangle(sp.coo_matrix((table[:, 2], (rows, cols)), shape=(size, size)))
    return sp.csr_matrix(matrix)


def read_matrix_market(path: str | Path, n_dofs: int | None = None) -> sp.csr_matrix:
    """A square real matrix from a Matrix Market file (:func:`scipy.io.mmread`; ``symmetric``
    storage expanded, ``.gz`` and ``.bz2`` read), checked to be ``n_dofs`` square if given."""
    from scipy.io import mmread

    path = Path(path)
    if not path.is_file():
        raise ExternalFEError(f"{path}: file not found; check the path (relative paths start at {Path.cwd()})")
    try:
        raw = mmread(path)
    except (ValueError, OSError, TypeError) as error:
        raise ExternalFEError(f"{path}: not a Matrix Market file ({error}); write it with scipy.io.mmwrite") from None
    matrix = sp.csr_matrix(raw)
    if np.iscomplexobj(matrix.data):
        raise ExternalFEError(f"{path}: the matrix is complex; mass and stiffness matrices are real")
    if matrix.shape[0] != matrix.shape[1] or (n_dofs is not None and matrix.shape[0] != n_dofs):
        expected = "square" if n_dofs is None else f"{n_dofs} x {n_dofs} (3 DOFs per node)"
        raise ExternalFEError(f"{path}: the matrix is {matrix.shape[0]} x {matrix.shape[1]}, expected {expected}")
    return sp.csr_matrix(matrix, dtype=float)


def read_node_table(path: str | Path) -> NDArray[np.float64]:
    """(N, 3) node coordinates from a text file, one node "x y z" per line (spaces or commas; ``#`` comments),
    row k is node k: the DOFs 3k, 3k + 1, 3k + 2 of the matrices."""
    path = Path(path)
    with _open_text(path) as stream:
        text = stream.read().replace(",", " ")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # numpy warns on an empty file; refused below
        try:
            table = np.loadtxt(io.StringIO(text), ndmin=2)
        except ValueError as error:
            raise ExternalFEError(f"{path}: not a table of numbers ({error}); write one node x y z per line") from None
    if table.size == 0 or table.shape[1] != 3:
        raise ExternalFEError(
            f"{path}: {table.shape[1] if table.size else 0} columns, expected 3 (x y z of one node per line, row k "
            "is node k)"
        )
    return table


def abaqus_model(inp: str | Path, mass: str | Path, stiffness: str | Path, name: str | None = None) -> ExternalFEModel:
    """Nodes of ``name`` in ``inp`` with M and K from the Abaqus ``.mtx`` files (Exudyn's
    ``ImportFromAbaqusInputFile`` + ``ReadMassMatrixFromAbaqus`` + ``ReadStiffnessMatrixFromAbaqus``)."""
    mesh = read_abaqus_mesh(inp, name)
    n_dofs = 3 * len(mesh.nodes)
    return ExternalFEModel(
        mesh.nodes,
        read_abaqus_matrix(mass, n_dofs),
        read_abaqus_matrix(stiffness, n_dofs),
        mesh.elements,
        f"{Path(inp).name}:{mesh.name}",
    )


# ------------------------------------------------------------------------------------------------
# .npz model files
# ------------------------------------------------------------------------------------------------


def _npz_matrix(path: Path, data, label: str, n_dofs: int) -> sp.csr_matrix:
    if label in data:
        dense = np.asarray(data[label], dtype=float)
        if dense.shape != (n_dofs, n_dofs):
            raise ExternalFEError(f"{path}: {label!r} is {dense.shape}, expected ({n_dofs}, {n_dofs}) for the nodes")
        return sp.csr_matrix(dense)
    keys = [f"{label}_row", f"{label}_col", f"{label}_value"]
    missing = [k for k in keys if k not in data]
    if missing:
        raise ExternalFEError(f"{path}: no {label!r} and no {missing}; store {label} as in NPZ_KEYS")
    row, col, value = (np.asarray(data[k]) for k in keys)
    if not (row.shape == col.shape == value.shape and row.ndim == 1):
        raise ExternalFEError(f"{path}: {keys} must be 1-D arrays of one length")
    if row.size and (not np.issubdtype(row.dtype, np.integer) or not np.issubdtype(col.dtype, np.integer)):
        raise ExternalFEError(f"{path}: {keys[0]} and {keys[1]} must be integer (0-based) indices")
    if row.size and (min(row.min(), col.min()) < 0 or max(row.max(), col.max()) >= n_dofs):
        raise ExternalFEError(f"{path}: {label} indices outside [0, {n_dofs}); indices are 0-based DOFs of the nodes")
    return sp.csr_matrix(sp.coo_matrix((value.astype(float), (row, col)), shape=(n_dofs, n_dofs)))


def read_npz_model(path: str | Path) -> ExternalFEModel:
    """An :class:`ExternalFEModel` from an ``.npz`` file with the keys of :data:`NPZ_KEYS`
    (never unpickled: object arrays are refused)."""
    path = Path(path)
    if not path.is_file():
        raise ExternalFEError(f"{path}: file not found; check the path (relative paths start at {Path.cwd()})")
    if not zipfile.is_zipfile(path):
        raise ExternalFEError(f"{path}: not an .npz archive; write it with write_npz_model or numpy.savez")
    try:
        with np.load(path, allow_pickle=False) as archive:
            data = {key: archive[key] for key in archive.files}
    except ValueError as error:
        hint = ""
        if "pickle" in str(error).lower():
            hint = " (an Exudyn FEMinterface file stores pickled objects; save nodes and matrices as NPZ_KEYS)"
        raise ExternalFEError(f"{path}: cannot be read as arrays{hint}: {error}") from None
    except (OSError, zipfile.BadZipFile, EOFError) as error:
        raise ExternalFEError(f"{path}: not an .npz archive ({error}); write it with write_npz_model") from None
    if "nodes" not in data:
        raise ExternalFEError(f"{path}: no 'nodes' array (keys: {sorted(data)}); store the model as in NPZ_KEYS")
    nodes = np.asarray(data["nodes"], dtype=float)
    n_dofs = 3 * len(nodes) if nodes.ndim == 2 else 0
    elements = {key[len("elements_") :]: data[key] for key in data if key.startswith("elements_")}
    name = str(data["name"]) if "name" in data else path.stem
    return ExternalFEModel(
        nodes, _npz_matrix(path, data, "mass", n_dofs), _npz_matrix(path, data, "stiffness", n_dofs), elements, name
    )


def write_npz_model(path: str | Path, model: ExternalFEModel) -> Path:
    """Write ``model`` as a compressed ``.npz`` with the keys of :data:`NPZ_KEYS` (COO matrices)."""
    path = Path(path)
    arrays: dict[str, NDArray] = {"nodes": model.nodes, "name": np.array(model.name)}
    for label in ("mass", "stiffness"):
        coo = sp.coo_matrix(getattr(model, label))
        arrays |= {f"{label}_row": coo.row, f"{label}_col": coo.col, f"{label}_value": coo.data}
    arrays |= {f"elements_{kind}": table for kind, table in model.elements.items()}
    np.savez_compressed(path, **arrays)  # type: ignore[arg-type]
    return path
