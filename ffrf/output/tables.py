"""Result files: ``results.npz`` (time and every sensor), the same as CSV columns, and ``metadata.json``.

One row per output time; a sensor of shape ``(rows, ...)`` becomes one column per component,
named ``name`` (scalars), ``name_x``, ``name_y``, ``name_z`` (vectors of 3) or ``name_i_j``
(other shapes, zero-based indices). Units are SI as in the NPZ file.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["csv_columns", "write_csv", "write_results"]


def csv_columns(arrays: dict[str, NDArray]) -> tuple[list[str], NDArray[np.float64]]:
    """Column names and the (rows, columns) table of ``arrays`` (all with the same number of rows)."""
    names, columns = [], []
    rows = {np.asarray(a).shape[0] for a in arrays.values()}
    if len(rows) != 1:
        raise ValueError(f"all arrays need the same number of rows, got {sorted(rows)}")
    for name, values in arrays.items():
        values = np.asarray(values, dtype=float)
        shape = values.shape[1:]
        if not shape:
            names.append(name)
            columns.append(values)
            continue
        for index in itertools.product(*(range(n) for n in shape)):
            suffix = "xyz"[index[0]] if shape == (3,) else "_".join(str(i) for i in index)
            names.append(f"{name}_{suffix}")
            columns.append(values[(slice(None),) + index])
    return names, np.column_stack(columns)


def write_csv(path: str | Path, arrays: dict[str, NDArray]) -> Path:
    """Write ``arrays`` as a CSV table (header row of column names)."""
    names, table = csv_columns(arrays)
    path = Path(path)
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    return path


def _json_value(value):
    """numpy scalars and arrays as JSON numbers and lists; anything else as its string."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)


def write_results(
    directory: str | Path, arrays: dict[str, NDArray], metadata: dict, coordinates: NDArray | None = None
) -> Path:
    """``DIR/results.npz`` (``arrays``: time and one array per sensor, SI units; and the coordinates
    ``q``, rows = times, when given, so that any quantity can be recomputed later), the sensors as
    ``DIR/results.csv`` (:func:`write_csv`) and ``DIR/metadata.json``; returns ``DIR``."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    extra = {} if coordinates is None else {"q": coordinates}
    np.savez(directory / "results.npz", allow_pickle=True, **arrays, **extra)
    write_csv(directory / "results.csv", arrays)
    (directory / "metadata.json").write_text(json.dumps(metadata, indent=2, default=_json_value))
    return directory
