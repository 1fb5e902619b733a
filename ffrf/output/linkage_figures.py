"""Figures of linkage runs in the layout of the paper's Fig. "deviation_errors": (a) the coupler's
deviation from the ideal path (the rigid motion, Eq. (L1)) and (b) the driving torque at the
driven joint, both over the drive angle, one curve per run.

The x axis is the drive angle turned since the start of the run (degrees; the ramp's 3 deg plus
one revolution), so runs and other solvers' curves that start at the same pose line up.

Entry points (all return ``(fig, ax)``, a bare matplotlib ``Figure`` rendered with Agg; with
``path`` the figure is also saved):

* :func:`plot_over_drive_angle` ``(series: {label: (angle_rad, values)}, ylabel, path=None)``:
  the generic plot; values are drawn as given (already in display units);
* :func:`plot_coupler_deviation` ``(runs, path=None, extra=None)``: ``|coupler_deviation|`` in mm;
* :func:`plot_driving_torque` ``(runs, path=None, extra=None, magnitude=True)``: N mm, the
  magnitude as in the paper ("joint torque magnitude") or signed.

``runs`` maps a label to a :class:`~ffrf.output.result.Result`, a ``results.npz`` file or a
directory holding one; ``extra`` maps labels to further ``(angle_rad, values)`` series in display
units (e.g. the Exudyn twin's curve: angle from its start in rad, deviation in mm), drawn dashed;
``colors`` maps labels to matplotlib colours (the others take the colour cycle's).
:func:`coupler_deviation_series` and :func:`driving_torque_series` give the curves as plotted.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Protocol

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike, NDArray

from ffrf.output.tables import read_arrays

__all__ = [
    "Series",
    "Run",
    "plot_over_drive_angle",
    "plot_stability",
    "run_sensors",
    "coupler_deviation_series",
    "driving_torque_series",
    "plot_coupler_deviation",
    "plot_driving_torque",
]

#: One curve: drive angle since the start (rad) and values in display units.
Series = tuple[ArrayLike, ArrayLike]


class HasSensors(Protocol):
    """Anything with sensors by name, e.g. a :class:`ffrf.output.result.Result`."""

    @property
    def sensors(self) -> Mapping[str, NDArray]: ...


#: A run: a Result, a results.npz file, or a directory holding results.npz.
Run = HasSensors | str | os.PathLike[str]


def run_sensors(run: Run) -> Mapping[str, NDArray]:
    """Sensors of a run (``drive_angle``, ``coupler_deviation``, ``driving_torque``, ...), SI units."""
    if not isinstance(run, (str, os.PathLike)):
        return run.sensors
    return read_arrays(run)  # checked against its folder's manifest, one-line errors


def _angle_from_start(sensors: Mapping[str, NDArray]) -> NDArray[np.float64]:
    angle = np.asarray(sensors["drive_angle"], dtype=float)
    return angle - angle[0]


def coupler_deviation_series(run: Run) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(drive angle since start in rad, ``|coupler point - ideal point at the same drive angle|`` in mm)."""
    sensors = run_sensors(run)
    return _angle_from_start(sensors), 1e3 * np.linalg.norm(sensors["coupler_deviation"], axis=1)


def driving_torque_series(run: Run, magnitude: bool = True) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(drive angle since start in rad, driving torque at the driven joint in N mm, its magnitude by default)."""
    sensors = run_sensors(run)
    torque = 1e3 * np.asarray(sensors["driving_torque"], dtype=float)
    return _angle_from_start(sensors), np.abs(torque) if magnitude else torque


def plot_over_drive_angle(
    series: Mapping[str, Series],
    ylabel: str,
    path: str | Path | None = None,
    title: str | None = None,
    dashed: tuple[str, ...] = (),
    colors: Mapping[str, str] | None = None,
):
    """One line per ``label: (angle_rad, values)``, x in degrees; labels in ``dashed`` drawn dashed, labels in
    ``colors`` in their colour."""
    # A bare Figure renders with the Agg canvas: no pyplot state, no display, no global backend switch.
    fig = Figure(figsize=(6.4, 4.0), layout="constrained")
    ax = fig.subplots()
    for label, (angle, values) in series.items():
        style = "--" if label in dashed else "-"
        ax.plot(
            np.degrees(np.asarray(angle, dtype=float)),
            np.asarray(values, dtype=float),
            style,
            color=(colors or {}).get(label),
            label=label,
            linewidth=1.4,
        )
    ax.set_xlabel("drive angle since start (deg)")
    ax.set_ylabel(ylabel)
    ax.set_xlim(left=0.0)
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title)
    if series:
        ax.legend()
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig, ax


def _overlay(runs: Mapping[str, Run], extract, extra: Mapping[str, Series] | None) -> dict[str, Series]:
    series = {label: extract(run) for label, run in runs.items()}
    series.update(extra or {})
    return series


def plot_coupler_deviation(
    runs: Mapping[str, Run],
    path: str | Path | None = None,
    extra: Mapping[str, Series] | None = None,
    colors: Mapping[str, str] | None = None,
):
    """Paper's Fig. "deviation error": coupler deviation from the ideal path (mm) over the drive angle."""
    return plot_over_drive_angle(
        _overlay(runs, coupler_deviation_series, extra),
        "coupler deviation from the ideal path (mm)",
        path,
        "Deviation from the ideal trajectory",
        dashed=tuple(extra or ()),
        colors=colors,
    )


def plot_driving_torque(
    runs: Mapping[str, Run],
    path: str | Path | None = None,
    extra: Mapping[str, Series] | None = None,
    magnitude: bool = True,
    colors: Mapping[str, str] | None = None,
):
    """Paper's Fig. "joint torque magnitude" at the driven joint (N mm) over the drive angle."""
    label = "driving torque magnitude (N mm)" if magnitude else "driving torque (N mm)"
    return plot_over_drive_angle(
        _overlay(runs, lambda run: driving_torque_series(run, magnitude), extra),
        label,
        path,
        "Driving torque",
        dashed=tuple(extra or ()),
        colors=colors,
    )


def plot_stability(
    angle: ArrayLike,
    squared_frequencies: ArrayLike,
    torque: ArrayLike,
    path: str | Path | None = None,
    folds: ArrayLike = (),
):
    """Stability along a quasi-static run: (a) the smallest squared frequencies of Eq. (B1) (rad^2/s^2, one line
    per mode, zero marked) and (b) the driving torque (N mm), over the drive angle (deg, absolute), with the folds
    of the path (deg) as vertical lines."""
    fig = Figure(figsize=(6.4, 5.6), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    degrees = np.degrees(np.asarray(angle, dtype=float))
    values = np.asarray(squared_frequencies, dtype=float)
    for k in range(values.shape[1]):
        top.plot(degrees, values[:, k], ".-", markersize=2, linewidth=1.0, label=f"mode {k + 1}")
    top.axhline(0.0, color="black", linewidth=0.8)
    top.set_yscale("symlog", linthresh=max(1.0, float(np.min(np.abs(values[:, 0]))) or 1.0))
    top.set_ylabel("squared frequency (rad^2/s^2)")
    top.legend(loc="best", fontsize=8)
    bottom.plot(degrees, 1e3 * np.asarray(torque, dtype=float), linewidth=1.2)
    bottom.set_ylabel("driving torque (N mm)")
    bottom.set_xlabel("drive angle (deg)")
    for axes in (top, bottom):
        for fold in np.atleast_1d(np.asarray(folds, dtype=float)):
            axes.axvline(fold, color="tab:red", linestyle="--", linewidth=0.9)
        axes.grid(True, alpha=0.3)
    top.set_title("Stability (Eq. (B1)); folds of the path dashed")
    if path is not None:
        fig.savefig(os.fspath(path), dpi=120)
    return fig, (top, bottom)
