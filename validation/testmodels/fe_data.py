r"""The input files of Exudyn's TestModels (``validation/data/exudyn_testmodels``, see its README),
read for our solver: the rotor and the five Abaqus blocks with :func:`ffrf.fe.matrix_import.abaqus_model`,
the Netgen beam of ``netgenTestMesh.pkl`` with :func:`read_fem_pickle`.

``netgenTestMesh.pkl`` is Exudyn's ``FEMinterface.SaveToFile(..., mode='PKL')``, a Python pickle, and
unpickling runs code the file names. :func:`read_fem_pickle` therefore checks the file's git blob id
first and then unpickles with an allow-list: NumPy arrays, and stand-ins that only store the state of
SciPy's ``csr_matrix`` and of Exudyn's ``OutputVariableType`` (nothing is imported from either).
"""

from __future__ import annotations

import hashlib
import importlib
import io
import pickle
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.matrix_import import abaqus_model

__all__ = [
    "DATA",
    "BLOCKS",
    "NETGEN_PICKLE_BLOB",
    "git_blob_id",
    "rotor_model",
    "block_model",
    "read_fem_pickle",
    "netgen_model",
]

#: The vendored files (README.md there: source commit, licence, blob ids).
DATA = Path(__file__).resolve().parents[1] / "data" / "exudyn_testmodels"
#: The element types of ``abaqusImportTest.py``, in its order.
BLOCKS = ("C3D4", "C3D10", "C3D8", "C3D20", "C3D20R")
#: Git blob id of ``netgenTestMesh.pkl`` at Exudyn commit e44aca1b (the data README's table).
NETGEN_PICKLE_BLOB = "9b3f1c501976e7617b2a82462fb4d2cf85ece792"


def git_blob_id(content: bytes) -> str:
    """The id git gives a file with these bytes: sha1 of ``b"blob <size>\\0" + content``."""
    return hashlib.sha1(b"blob %d\0" % len(content) + content).hexdigest()


@cache
def rotor_model() -> ExternalFEModel:
    """``rotorDiscTest``: the rotor (shaft along z from 0 to 0.5 m, disc at z = 0.15 m) as the
    TestModels import it, instance ``rotor-1``; lumped mass."""
    return abaqus_model(
        DATA / "rotorDiscTest.inp", DATA / "rotorDiscTestMASS1.mtx.xz", DATA / "rotorDiscTestSTIF1.mtx.xz", "rotor-1"
    )


@cache
def block_model(element: str) -> ExternalFEModel:
    """``abaqus/block<element>``: the 4 x 1 x 1 m block of ``abaqusImportTest.py`` (instance
    ``block-1``, which Exudyn reads whatever name the script passes)."""
    if element not in BLOCKS:
        raise ValueError(f"unknown block element {element!r}; the TestModel uses {BLOCKS}")
    stem = DATA / "abaqus" / f"block{element}"
    return abaqus_model(
        stem.with_suffix(".inp"),
        stem.with_name(stem.name + "_MASS1.mtx.xz"),
        stem.with_name(stem.name + "_STIF1.mtx.xz"),
        "block-1",
    )


class _State:
    """Stand-in for a class of the pickle that we do not import: keeps what it was built from."""

    def __init__(self, *args: Any) -> None:
        self.args = args
        self.state: Any = None

    def __setstate__(self, state: Any) -> None:
        self.state = state


#: (module, name) the pickle may name -> where it is found; anything else is refused.
_NUMPY = {("numpy", "ndarray"), ("numpy", "dtype")}
_RECONSTRUCT = {("numpy.core.multiarray", "_reconstruct"), ("numpy._core.multiarray", "_reconstruct")}
_STAND_INS = {("scipy.sparse._csr", "csr_matrix"), ("exudyn.exudynCPP", "OutputVariableType")}


class _AllowListUnpickler(pickle.Unpickler):
    def find_class(self, module: str, name: str) -> Any:
        if (module, name) in _NUMPY:
            return getattr(np, name)
        if (module, name) in _RECONSTRUCT:
            try:  # NumPy 2 moved the module; the file names the old path
                return getattr(importlib.import_module("numpy._core.multiarray"), name)
            except ImportError:  # pragma: no cover - NumPy 1
                return getattr(importlib.import_module("numpy.core.multiarray"), name)
        if (module, name) in _STAND_INS:
            return _State
        raise pickle.UnpicklingError(f"{module}.{name} is not on the allow-list of read_fem_pickle")


def read_fem_pickle(path: Path, blob: str) -> dict[str, Any]:
    """The dictionary of an ``FEMinterface`` PKL file whose git blob id is ``blob``; sparse matrices
    as :class:`_State` objects (``.state``: SciPy's CSR attributes)."""
    raw = Path(path).read_bytes()
    if git_blob_id(raw) != blob:
        raise ValueError(f"{path}: git blob id {git_blob_id(raw)} is not the vendored file's {blob}; not unpickled")
    data = _AllowListUnpickler(io.BytesIO(raw)).load()
    if not isinstance(data, dict) or data.get("type") != "FEMinterface":
        raise ValueError(f"{path} is not an FEMinterface file")
    return data


def _csr(stored: _State) -> sp.csr_matrix:
    s = stored.state
    return sp.csr_matrix((s["data"], s["indices"], s["indptr"]), shape=tuple(s["_shape"]))


@cache
def netgen_model() -> tuple[ExternalFEModel, NDArray[np.int64]]:
    """``netgenTestMesh.pkl`` (NGsolveCMStest): the 1 x 0.2 x 0.2 m beam, 29 nodes, 4-node
    tetrahedra, consistent M and K, and its surface triangles (Exudyn's ``surface[0]['Trigs']``)."""
    data = read_fem_pickle(DATA / "netgenTestMesh.pkl", NETGEN_PICKLE_BLOB)
    (elements,) = data["elements"]
    (surface,) = data["surface"]
    model = ExternalFEModel(
        np.asarray(data["nodes"]["Position"], dtype=float),
        _csr(data["massMatrix"]),
        _csr(data["stiffnessMatrix"]),
        {"Tet4": np.asarray(elements["Tet4"], dtype=np.int64)},
        "netgenTestMesh",
    )
    return model, np.asarray(surface["Trigs"], dtype=np.int64)
