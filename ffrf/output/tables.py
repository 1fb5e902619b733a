"""Result files: ``results.npz`` (time and every sensor), the same as CSV columns, ``metadata.json`` and
``manifest.json`` (each of the three files' size and SHA-256, written last: :func:`write_results`).

One row per output time; a sensor of shape ``(rows, ...)`` becomes one column per component,
named ``name`` (scalars), ``name_x``, ``name_y``, ``name_z`` (vectors of 3) or ``name_i_j``
(other shapes, zero-based indices). Units are SI as in the NPZ file.

A folder holds one run. The three files are written under temporary names and renamed into place, and the
manifest last, so a kill while writing leaves the folder's earlier run, or a set whose manifest does not match
(:func:`check_results`), never a silent mix. Writing into a folder that held a run also deletes that run's other
outputs (:data:`RUN_OUTPUTS`: figures, ``assembly.vtu``, ParaView series, ...) last written before this run started:
a run that writes no ParaView series does not leave an earlier run's next to its results. Files of other names (the
user's own) are left alone.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import logging
import math
import os
import uuid
import zipfile
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import ResultsError

__all__ = [
    "MANIFEST",
    "RESULT_FILES",
    "RUN_OUTPUTS",
    "check_results",
    "csv_columns",
    "process_started",
    "read_arrays",
    "read_results",
    "write_csv",
    "write_results",
]

log = logging.getLogger(__name__)

#: The list of a folder's result files with their sizes and SHA-256, written after them.
MANIFEST = "manifest.json"
MANIFEST_FORMAT = "ffrf-results-1"
#: The files :func:`write_results` writes (and the manifest lists).
RESULT_FILES = ("results.npz", "results.csv", "metadata.json")
#: What runs of :mod:`ffrf.cli` write besides, by name: an earlier run's are deleted when a run's results are written.
RUN_OUTPUTS = (
    "assembly.vtu",
    "stability_critical.vtu",
    "stability.json",
    "stability.png",
    "coupler_deviation.png",
    "driving_torque.png",
    "reach.json",
    "linkage.json",
)


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


def process_started() -> float:
    """This process's start (s since the epoch, never later than the true start), from ``/proc``; ``-inf`` where
    there is none (then :func:`write_results` removes no earlier run's files)."""
    try:
        fields = Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()
        ticks = int(fields[19])  # field 22 of proc(5), counted after the command's closing parenthesis
        lines = Path("/proc/stat").read_text().splitlines()
        boot = next(int(line.split()[1]) for line in lines if line.startswith("btime "))
        return boot + ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, StopIteration):
        return -math.inf


def _digest(path: Path) -> dict[str, int | str]:
    """A file's size (bytes) and SHA-256, as the manifest lists them."""
    digest = hashlib.sha256()
    with path.open("rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return {"bytes": path.stat().st_size, "sha256": digest.hexdigest()}


def _stale_outputs(directory: Path, since: float) -> list[Path]:
    """The files of :data:`RUN_OUTPUTS` and ParaView series (``*.pvd`` of ``vtk/`` frames, as
    :func:`ffrf.output.paraview.write_time_series` writes them, and ``vtk/*.vtu``) in ``directory`` last written before
    ``since``: an earlier run's, which the run being written may not write again."""
    series = [path for path in directory.glob("*.pvd") if 'file="vtk/' in path.read_text(errors="replace")]
    candidates = [directory / name for name in RUN_OUTPUTS] + series + list((directory / "vtk").glob("*.vtu"))
    stale = []
    for path in candidates:
        try:
            if path.is_file() and path.stat().st_mtime < since:
                stale.append(path)
        except OSError:
            continue
    return stale


def write_results(
    directory: str | Path,
    arrays: dict[str, NDArray],
    metadata: dict,
    coordinates: NDArray | None = None,
    *,
    since: float | None = None,
) -> Path:
    """``DIR/results.npz`` (``arrays``: time and one array per sensor, SI units; and the coordinates
    ``q``, rows = times, when given, so that any quantity can be recomputed later), the sensors as
    ``DIR/results.csv`` (:func:`write_csv`), ``DIR/metadata.json`` and, last, ``DIR/manifest.json``; returns ``DIR``.

    The three files are written whole under temporary names first (a failure or a kill then leaves the folder as it
    was), then renamed into place, then the files of an earlier run in the folder (:data:`RUN_OUTPUTS` last written
    before ``since``, default :func:`process_started`; only where results were) are deleted, then the manifest (each
    file's size and SHA-256: the three, and the :data:`RUN_OUTPUTS` this run wrote before them) is written, atomically
    too: a folder holds a complete set of one run exactly when its manifest matches its files (:func:`check_results`).
    Outputs written after the results (figures) are not listed."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    extra = {} if coordinates is None else {"q": coordinates}
    staged: dict[str, Path] = {}
    tag = f".{os.getpid()}-{uuid.uuid4().hex[:8]}.tmp"
    try:
        staged["results.npz"] = directory / f".results.npz{tag}"
        with staged["results.npz"].open("wb") as stream:  # a file object: np.savez adds no ".npz"
            np.savez(stream, allow_pickle=True, **arrays, **extra)
        staged["results.csv"] = directory / f".results.csv{tag}"
        write_csv(staged["results.csv"], arrays)
        staged["metadata.json"] = directory / f".metadata.json{tag}"
        staged["metadata.json"].write_text(json.dumps(metadata, indent=2, default=_json_value))
        files = {name: _digest(path) for name, path in staged.items()}
    except BaseException:
        for path in staged.values():
            path.unlink(missing_ok=True)
        raise
    # From here on only renames and deletions: the folder stops claiming the old set before it changes.
    held_run = any((directory / name).exists() for name in (*RESULT_FILES, MANIFEST))
    (directory / MANIFEST).unlink(missing_ok=True)
    for name, path in staged.items():
        os.replace(path, directory / name)
    since = process_started() if since is None else since
    for path in _stale_outputs(directory, since) if held_run else ():
        log.info("removing %s: an earlier run's output, older than this run", path)
        path.unlink(missing_ok=True)
    for name in RUN_OUTPUTS:  # what this run wrote before its results (assembly.vtu, linkage.json, ...) is its too
        path = directory / name
        if since > -math.inf and path.is_file() and path.stat().st_mtime >= since:
            files[name] = _digest(path)
    manifest = {"format": MANIFEST_FORMAT, "files": files}
    temporary = directory / f".{MANIFEST}{tag}"
    temporary.write_text(json.dumps(manifest, indent=2))
    os.replace(temporary, directory / MANIFEST)
    return directory


def check_results(directory: str | Path) -> dict:
    """The manifest of a results folder (:func:`write_results`), after checking that every file it lists is there
    with its size and SHA-256; :class:`ffrf.errors.ResultsError` names the first that is not (an interrupted write,
    a file changed or copied over since). A folder written before manifests existed is checked for its files only."""
    directory = Path(directory)
    remedy = "write the results again (run the simulation with --out to a folder of its own)"
    path = directory / MANIFEST
    if not path.is_file():
        missing = [name for name in RESULT_FILES if not (directory / name).is_file()]
        if missing:
            raise ResultsError(f"{directory} holds no complete results: {', '.join(missing)} missing; {remedy}")
        return {"format": None, "files": {}}
    try:
        manifest = json.loads(path.read_text())
        files = manifest["files"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ResultsError(f"{path} cannot be read ({error}); {remedy}") from error
    for name, expected in files.items():
        file = directory / name
        if not file.is_file():
            raise ResultsError(f"{file} is missing (listed in {path}); {remedy}")
        found = _digest(file)
        if found != expected:
            raise ResultsError(
                f"{file} is not the file the run wrote ({found['bytes']} bytes, SHA-256 {str(found['sha256'])[:12]}; "
                f"{path} lists {expected.get('bytes')} bytes, {str(expected.get('sha256'))[:12]}): the write was "
                f"cut short or the file changed since; {remedy}"
            )
    return manifest


def read_arrays(path: str | os.PathLike[str]) -> dict[str, NDArray]:
    """The arrays of a ``results.npz`` file (or of a folder holding one), after :func:`check_results` when its folder
    has a manifest; a missing, damaged or unreadable file is a :class:`ffrf.errors.ResultsError` naming it."""
    path = Path(path)
    if path.is_dir():
        path = path / "results.npz"
    if (path.parent / MANIFEST).is_file():
        check_results(path.parent)
    try:
        with np.load(path, allow_pickle=False) as archive:
            if not isinstance(archive, np.lib.npyio.NpzFile):  # a bare .npy renamed
                raise ValueError("one array, not an archive of named arrays")
            return {name: archive[name] for name in archive.files}
    except (OSError, EOFError, ValueError, zipfile.BadZipFile) as error:  # EOFError: an empty file
        raise ResultsError(
            f"{path} cannot be read as results ({type(error).__name__}: {error}); write the results again"
        ) from error


def read_results(directory: str | Path) -> tuple[dict[str, NDArray], dict]:
    """The arrays of ``DIR/results.npz`` and the metadata of ``DIR/metadata.json``, after :func:`check_results`;
    a damaged or unreadable file is a :class:`ffrf.errors.ResultsError` naming it, never a traceback."""
    directory = Path(directory)
    check_results(directory)
    arrays = read_arrays(directory / "results.npz")
    path = directory / "metadata.json"
    try:
        metadata = json.loads(path.read_text())
    except (OSError, ValueError) as error:
        raise ResultsError(f"{path} cannot be read ({error}); write the results again") from error
    return arrays, metadata
