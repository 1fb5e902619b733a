"""Tracked link trajectories: readers (motion capture, simulation results) and cleaning.

A :class:`LinkRecord` holds a time vector and, per link index (paper's numbering, 1..3),
positions ``(frames, k, 3)`` in metres. Cleaning never invents data: unsorted frames are
sorted, duplicated and NaN frames are dropped with a warning, and the record is split
into contiguous segments at every dropped frame or time gap, so the moving-average filter
(paper, Sect. "Setup and Measurements": centred, 10 frames) never averages across a gap.
"""

from __future__ import annotations

import csv
import itertools
import logging
import math
import re
import warnings
import zipfile
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import uniform_filter1d

from ffrf.errors import ResultsError
from ffrf.output.tables import MANIFEST, check_results

from .circle_fit import IdentificationError

__all__ = ["LinkRecord", "read_vicon_csv", "read_simulation_result", "clean_record", "moving_average"]

log = logging.getLogger(__name__)

#: Farthest segment origin (m) taken from a motion-capture export: beyond, a cell or the unit is wrong.
MAX_COORDINATE_M = 1e3


@dataclass(frozen=True)
class LinkRecord:
    """``time`` (s, ``(frames,)``), ``points`` {link: ``(frames, k, 3)`` m}, contiguous
    ``segments`` as (start, stop) frame ranges, and where it came from."""

    time: NDArray[np.float64]
    points: dict[int, NDArray[np.float64]]
    source: str = ""
    segments: tuple[tuple[int, int], ...] = field(default=())

    def __post_init__(self):
        n = self.time.shape[0]
        for link, p in self.points.items():
            if p.ndim != 3 or p.shape[0] != n or p.shape[2] != 3:
                raise IdentificationError(
                    f"{self.source}: link {link} positions have shape {p.shape}, expected ({n}, k, 3)"
                )
        if not self.segments:
            object.__setattr__(self, "segments", ((0, n),))

    @property
    def n_frames(self) -> int:
        return self.time.shape[0]

    def select(self, keep: NDArray) -> LinkRecord:
        return LinkRecord(self.time[keep], {k: p[keep] for k, p in self.points.items()}, self.source)


def _link_index(name: str) -> int | None:
    match = re.search(r"(\d+)\s*$", name.split(":")[-1])
    return int(match.group(1)) if match else None


def _numbers(cells: list[str], path: Path, line: int) -> list[float]:
    """A data row of a Vicon export as floats (empty cells: NaN, a missing frame)."""
    try:
        values = [float(c) if c.strip() else np.nan for c in cells]
    except ValueError as error:
        raise IdentificationError(
            f"{path}, line {line}: {error}; data rows hold numbers or empty cells only"
        ) from error
    for column, (cell, value) in enumerate(zip(cells, values, strict=True)):
        if cell.strip() and not math.isfinite(value):  # "inf", "nan", or 1e400 that overflows
            raise IdentificationError(
                f"{path}, line {line}, column {column + 1}: {cell.strip()!r} is not a finite number; a missing "
                "frame is an empty cell"
            )
    return values


def read_vicon_csv(path: str | Path, segments: dict[str, int] | None = None, unit: str = "mm") -> LinkRecord:
    """Read a Vicon Nexus segment export: a title row, the frame rate, a row of segment names,
    a header ``Frame, Sub Frame, RX, RY, RZ, TX, TY, TZ, ...`` and a row of units; missing
    frames are empty cells. Only the translations (the segment origins) are kept, converted
    from ``unit`` to metres. Segment names map to link indices by their trailing number
    (``Bennett:Link2`` -> 2) unless ``segments`` maps names explicitly.
    """
    path = Path(path)
    scale = {"mm": 1e-3, "m": 1.0}.get(unit)
    if scale is None:
        raise IdentificationError(f"unit must be 'mm' or 'm', got {unit!r}")
    try:
        with path.open(newline="") as handle:
            rows = list(csv.reader(handle))
    except UnicodeDecodeError as error:  # a binary file (a .c3d or .x2d) given for the CSV export
        raise IdentificationError(
            f"{path}: not a text file ({error.reason} at byte {error.start}); give the Vicon segment export as CSV"
        ) from error
    header_row = next((i for i, r in enumerate(rows) if r and r[0].strip().lower() == "frame"), None)
    if header_row is None or header_row < 1:
        raise IdentificationError(
            f"{path}: no 'Frame, Sub Frame, ...' header row found; is this a Vicon segment export?"
        )
    names, header = rows[header_row - 1], [h.strip().upper() for h in rows[header_row]]
    rate = None
    for r in rows[: header_row - 1]:
        if r and r[0].strip():
            try:
                rate = float(r[0])
            except ValueError:
                continue
    data_rows = [r for r in rows[header_row + 2 :] if r and r[0].strip()]
    if not data_rows:
        raise IdentificationError(f"{path}: no data rows below the header and unit rows; export the trajectories")
    table = np.array(
        [
            _numbers(r[: len(header)], path, header_row + 3 + k) + [np.nan] * (len(header) - len(r))
            for k, r in enumerate(data_rows)
        ]
    )
    points: dict[int, NDArray] = {}
    for column, name in enumerate(names):
        if not name.strip():
            continue
        link = segments.get(name.strip()) if segments else _link_index(name)
        if link is None or link == 0:
            continue
        tx = next((c for c in range(column, min(column + 6, len(header))) if header[c] == "TX"), None)
        if tx is None:
            raise IdentificationError(f"{path}: segment {name!r} has no TX, TY, TZ columns")
        points[link] = scale * table[:, tx : tx + 3][:, None, :]
        far = np.flatnonzero(np.nanmax(np.abs(points[link][:, 0, :]), axis=1, initial=0.0) > MAX_COORDINATE_M)
        if far.size:
            raise IdentificationError(
                f"{path}, line {header_row + 3 + int(far[0])}: segment {name.strip()!r} is "
                f"{np.nanmax(np.abs(points[link][far[0]])):.3g} m from the origin (more than {MAX_COORDINATE_M:g} m "
                f"of a capture volume); check the cell and --unit ({unit!r})"
            )
    frame = table[:, 0]  # the sub-frame index only counts analog samples within a frame
    time = frame / rate if rate else frame
    log.info("read %s: %d frames, links %s", path, len(time), sorted(points))
    return LinkRecord(time.astype(float), points, str(path))


def read_simulation_result(directory: str | Path) -> LinkRecord:
    """Read ``DIR/results.npz`` of this project's simulations: ``time`` and the tracked
    surface nodes ``link{k}_node{j}`` (``(frames, 3)`` m each) of links 1, 2, 3."""
    path = Path(directory) / "results.npz"
    if not path.exists():
        raise IdentificationError(f"{path} not found: run a simulation first (python -m ffrf bennett --out DIR)")
    if (path.parent / MANIFEST).is_file():  # written by this project's solver: the set must be the one it wrote
        try:
            check_results(path.parent)
        except ResultsError as error:
            raise IdentificationError(str(error)) from error
    data = _npz_arrays(path)
    if "time" not in data:
        raise IdentificationError(f"{path} has no 'time' array")
    points = {}
    for link in (1, 2, 3):
        keys = sorted(k for k in data if re.fullmatch(rf"link{link}_node\d+", k))
        if keys:
            points[link] = np.stack([data[k] for k in keys], axis=1)
    return LinkRecord(np.asarray(data["time"], dtype=float), points, str(path))


def _npz_arrays(path: Path) -> dict[str, NDArray]:
    """Every array of an ``.npz`` archive, read now so that a damaged member fails here, by name."""
    try:
        archive = np.load(path)
        if not isinstance(archive, np.lib.npyio.NpzFile):  # a bare .npy array renamed
            raise ValueError("one array, not an archive of named arrays")
        with archive:
            return {name: archive[name] for name in archive.files}
    except (OSError, EOFError, ValueError, zipfile.BadZipFile) as error:  # damaged or empty, pickles, not numpy
        raise IdentificationError(
            f"{path} cannot be read as a results archive ({type(error).__name__}: "
            f"{error}); write it again with python -m ffrf bennett --out DIR"
        ) from error


def clean_record(record: LinkRecord, gap_factor: float = 1.5) -> LinkRecord:
    """Sort frames by time, drop duplicated timestamps and frames with NaN, and split the
    record into segments at dropped frames and at time steps above ``gap_factor`` times the
    median step. Every change is reported with a warning."""
    order = np.argsort(record.time, kind="stable")
    if np.any(order != np.arange(record.n_frames)):
        warnings.warn(f"{record.source}: timestamps were not in order; frames sorted by time", stacklevel=2)
        record = record.select(order)
    duplicate = np.r_[False, np.diff(record.time) == 0.0]
    if duplicate.any():
        warnings.warn(f"{record.source}: dropped {duplicate.sum()} frame(s) with a duplicated timestamp", stacklevel=2)
    missing = np.zeros(record.n_frames, dtype=bool)
    for p in record.points.values():
        missing |= ~np.all(np.isfinite(p), axis=(1, 2))
    if missing.any():
        warnings.warn(
            f"{record.source}: dropped {missing.sum()} frame(s) with missing positions (not interpolated)", stacklevel=2
        )
    keep = ~(duplicate | missing)
    if keep.sum() < 5:
        raise IdentificationError(f"{record.source}: only {keep.sum()} usable frames remain")
    # A segment break wherever frames were dropped or the time step jumps.
    kept_index = np.flatnonzero(keep)
    cleaned = record.select(keep)
    steps = np.diff(cleaned.time)
    typical = np.median(steps) if steps.size else 0.0
    breaks = (np.diff(kept_index) > 1) | (steps > gap_factor * typical)
    edges = np.r_[0, np.flatnonzero(breaks) + 1, cleaned.n_frames]
    segments = tuple((int(a), int(b)) for a, b in itertools.pairwise(edges))
    return replace(cleaned, segments=segments)


def moving_average(record: LinkRecord, window: int = 10) -> LinkRecord:
    """Centred moving average over ``window`` frames within each segment (paper: 10 frames).

    Only frames with a full window inside their segment are kept (a padded edge would pull
    the path off its circle); segments shorter than the window are dropped with a warning.
    On a uniformly sampled circle the average shrinks the radius but keeps the centre and
    the plane, so the fitted axes are unchanged.
    """
    if window < 1:
        raise IdentificationError(
            f"moving-average window must be >= 1 frame, got {window}; give --window 1 (no filter) or more"
        )
    if window == 1:
        return record
    left, right = window // 2, window - 1 - window // 2
    keep: list[NDArray[np.int64]] = []
    segments: list[tuple[int, int]] = []
    smoothed: dict[int, list[NDArray]] = {link: [] for link in record.points}
    for start, stop in record.segments:
        if stop - start < window:
            warnings.warn(
                f"{record.source}: dropped a segment of {stop - start} frames, shorter than the "
                f"{window}-frame filter window",
                stacklevel=2,
            )
            continue
        for link, p in record.points.items():
            smoothed[link].append(uniform_filter1d(p[start:stop], size=window, axis=0)[left : stop - start - right])
        first = sum(b - a for a, b in segments)
        segments.append((first, first + stop - start - left - right))
        keep.append(np.arange(start + left, stop - right))
    if not keep:
        raise IdentificationError(f"{record.source}: no segment is longer than the {window}-frame filter window")
    kept = np.concatenate(keep)
    points = {link: np.concatenate(parts) for link, parts in smoothed.items()}
    return LinkRecord(record.time[kept], points, record.source, tuple(segments))
