"""Saving and reloading reduced (HCB) bodies as ``.npz`` files, guarded by a version tag and a hash.

The SHA-256 fingerprint covers everything the reduction depends on: nodes,
mass and stiffness matrices (hence mesh and material), interface node sets and
weights, the number of fixed-interface modes and the options. A scene can then
reuse a stored body only when it was computed from exactly the same input
(:func:`cached_craig_bampton`). Files are written without pickles and read
with ``allow_pickle=False``.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ffrf.errors import ReductionError
from ffrf.reduction.craig_bampton import (
    CraigBamptonBasis,
    RigidInterface,
    checked_model,
    craig_bampton,
    rigid_interfaces,
)
from ffrf.reduction.invariants import InertiaInvariants

__all__ = [
    "FORMAT_VERSION",
    "ReducedBodyFileError",
    "SavedReducedBody",
    "reduction_fingerprint",
    "save_reduced_body",
    "load_reduced_body",
    "cached_craig_bampton",
]

logger = logging.getLogger(__name__)

#: Format tag written into every file; bump it when the stored fields or their meaning change.
FORMAT_VERSION = "ffrf-hcb-npz-1"


class ReducedBodyFileError(ReductionError):
    """A stored reduced body has another format version or was computed from other input."""


@dataclass(frozen=True, eq=False)
class SavedReducedBody:
    """A reduced body as stored: the HCB basis, optional inertia invariants and the input fingerprint."""

    reduction: CraigBamptonBasis
    invariants: InertiaInvariants | None
    fingerprint: str


def _update_with_array(digest: hashlib._Hash, name: str, array: Any, dtype: str) -> None:
    array = np.ascontiguousarray(array, dtype=dtype)
    digest.update(f"{name}:{array.shape}:{dtype};".encode())
    digest.update(array.tobytes())


def reduction_fingerprint(
    fe_model: Any, interfaces: Sequence[Any], n_modes: int, weights: Sequence[ArrayLike] | None = None, **options: Any
) -> str:
    """SHA-256 (hex) of nodes, M and K (canonical CSR), interfaces, normalised weights, n_modes and options.

    ``options`` are the keyword options of :func:`ffrf.reduction.craig_bampton.craig_bampton`; they must be
    JSON-serialisable.
    """
    nodes, mass, stiffness = checked_model(fe_model)
    digest = hashlib.sha256(FORMAT_VERSION.encode())
    _update_with_array(digest, "nodes", nodes, "<f8")
    for name, matrix in (("mass", mass), ("stiffness", stiffness)):
        canonical = sp.csr_matrix(matrix, copy=True)
        canonical.sum_duplicates()  # also sorts the indices: one byte string per matrix
        for part in ("data", "indices", "indptr"):
            _update_with_array(digest, f"{name}.{part}", getattr(canonical, part), "<f8" if part == "data" else "<i8")
    for k, itf in enumerate(rigid_interfaces(nodes, interfaces, weights)):
        _update_with_array(digest, f"interface{k}.nodes", itf.nodes, "<i8")
        _update_with_array(digest, f"interface{k}.weights", itf.weights, "<f8")
    digest.update(json.dumps({"n_modes": int(n_modes), **options}, sort_keys=True).encode())
    return digest.hexdigest()


def save_reduced_body(
    path: str | Path, reduction: CraigBamptonBasis, fingerprint: str, invariants: InertiaInvariants | None = None
) -> Path:
    """Write ``reduction`` (and ``invariants``) to ``path`` (.npz), atomically (temp file + rename)."""
    path = Path(path)
    data: dict[str, Any] = {
        "format_version": np.array(FORMAT_VERSION),
        "fingerprint": np.array(fingerprint),
        "basis": reduction.basis,
        "n_static_modes": np.array(reduction.n_static_modes),
        "fixed_interface_frequencies_hz": reduction.fixed_interface_frequencies_hz,
        "reduced_mass": reduction.reduced_mass,
        "reduced_stiffness": reduction.reduced_stiffness,
        "mode_labels": np.array(reduction.mode_labels, dtype=str),
        "reference": np.array(reduction.reference),
        "orthonormalized": np.array(reduction.orthonormalized),
        "interface_sizes": np.array([len(itf.nodes) for itf in reduction.interfaces]),
        "interface_nodes": np.concatenate([itf.nodes for itf in reduction.interfaces]),
        "interface_weights": np.concatenate([itf.weights for itf in reduction.interfaces]),
        "interface_centers": np.array([itf.center for itf in reduction.interfaces]),
    }
    if invariants is not None:
        data.update({f"invariants.{f.name}": np.asarray(getattr(invariants, f.name)) for f in fields(invariants)})
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(suffix=".npz", dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as stream:
            np.savez(stream, **data)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    logger.info("saved reduced body (%d modes) to %s", reduction.n_modes, path)
    return path


def load_reduced_body(path: str | Path, expected_fingerprint: str | None = None) -> SavedReducedBody:
    """Read a file written by :func:`save_reduced_body`; check its version tag and, if given, its fingerprint."""
    path = Path(path)
    with np.load(path, allow_pickle=False) as data:
        version = str(data["format_version"]) if "format_version" in data.files else "<none>"
        if version != FORMAT_VERSION:
            raise ReducedBodyFileError(
                f"{path}: format version {version!r}, this code reads {FORMAT_VERSION!r}; "
                "delete the file and recompute the reduction"
            )
        fingerprint = str(data["fingerprint"])
        if expected_fingerprint is not None and fingerprint != expected_fingerprint:
            raise ReducedBodyFileError(
                f"{path} was computed from another mesh, material, interface set or option "
                f"(hash {fingerprint[:12]}..., expected {expected_fingerprint[:12]}...); "
                "delete it or recompute the reduction"
            )
        bounds = np.cumsum(np.concatenate([[0], data["interface_sizes"]]))
        interfaces = tuple(
            RigidInterface(data["interface_nodes"][a:b], data["interface_weights"][a:b], center)
            for a, b, center in zip(bounds[:-1], bounds[1:], data["interface_centers"], strict=True)
        )
        reduction = CraigBamptonBasis(
            data["basis"],
            int(data["n_static_modes"]),
            data["fixed_interface_frequencies_hz"],
            data["reduced_mass"],
            data["reduced_stiffness"],
            interfaces,
            tuple(str(s) for s in data["mode_labels"]),
            str(data["reference"]),
            bool(data["orthonormalized"]),
        )
        invariants = None
        if "invariants.mass" in data.files:
            values = {f.name: data[f"invariants.{f.name}"] for f in fields(InertiaInvariants)}
            invariants = InertiaInvariants(**{**values, "mass": float(values["mass"])})
    return SavedReducedBody(reduction, invariants, fingerprint)


def cached_craig_bampton(
    path: str | Path,
    fe_model: Any,
    interfaces: Sequence[Any],
    n_modes: int,
    weights: Sequence[ArrayLike] | None = None,
    *,
    with_invariants: bool = True,
    **options: Any,
) -> SavedReducedBody:
    """Load the reduced body from ``path`` if it was computed from the same input, else compute and save it.

    ``options`` are passed to :func:`ffrf.reduction.craig_bampton.craig_bampton`.
    """
    from ffrf.reduction.invariants import inertia_invariants

    fingerprint = reduction_fingerprint(fe_model, interfaces, n_modes, weights, **options)
    path = Path(path)
    if path.exists():
        try:
            saved = load_reduced_body(path, fingerprint)
            if saved.invariants is not None or not with_invariants:
                logger.info("reusing reduced body %s", path)
                return saved
        except ReducedBodyFileError as exc:
            logger.info("recomputing reduced body: %s", exc)
    reduction = craig_bampton(fe_model, interfaces, n_modes, weights, **options)
    invariants = inertia_invariants(fe_model, reduction) if with_invariants else None
    save_reduced_body(path, reduction, fingerprint, invariants)
    return SavedReducedBody(reduction, invariants, fingerprint)
