"""Figures of a Bennett cross-validation (matplotlib, Agg): each function writes one PNG.

Every function takes plain arrays or runs (ours :class:`~ffrf.output.result.Result` s, the twin's
:class:`validation.twin_run.TwinRun` s: their sensors of :mod:`validation.bennett_trajectory`) and a path, and returns
the path; the data drawn are exactly the arrays given (no smoothing).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .bennett_trajectory import TRACKED

__all__ = [
    "coupler_deviation_figure",
    "difference_figure",
    "torque_figure",
    "mac_figure",
    "coupler_path_figure",
    "series_difference_figure",
]

#: One colour and line style per run label, the same in every figure.
STYLE = {
    "production": dict(color="tab:blue", ls="-", label="ours (exact gravity)"),
    "equivalent": dict(color="tab:green", ls="-", label="ours, Exudyn's gravity"),
    "exudyn_jacobian": dict(color="tab:purple", ls=":", label="ours, Exudyn's gravity and marker Jacobian"),
    "exudyn": dict(color="tab:red", ls="--", label="Exudyn"),
    "ideal": dict(color="k", ls="-", label="ideal (motion polynomial)"),
}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> Path:
    path = Path(path)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _pyplot().close(fig)
    return path


def _turn_deg(run) -> NDArray[np.float64]:
    """Drive angle turned since t = 0 (deg): the x-axis of the paper's figures."""
    angle = run.sensors["drive_angle"]
    return np.degrees(angle - angle[0])


def coupler_deviation_figure(runs: dict, ideal: NDArray, path: Path, title: str = "") -> Path:
    """``|coupler point - ideal coupler point|`` (mm) at the same drive angle, per run."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.6))
    for label, run in runs.items():
        ax.plot(_turn_deg(run), 1e3 * np.linalg.norm(run.sensors["coupler_point"] - ideal, axis=1), **STYLE[label])
    ax.set_xlabel("drive angle turned (deg)")
    ax.set_ylabel("coupler deviation (mm)")
    ax.set_title(title or "Coupler deviation from the ideal path")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)


def difference_figure(a, b, path: Path, title: str = "") -> Path:
    """``|a - b|`` (m, log scale) over the drive angle: coupler point and the nine tracked nodes."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.6))
    x = _turn_deg(a)
    floor = 1e-16
    coupler = a.sensors["coupler_point"] - b.sensors["coupler_point"]
    ax.semilogy(x, np.maximum(np.linalg.norm(coupler, axis=1), floor), color="k", lw=2, label="coupler point")
    for name in TRACKED:
        difference = np.linalg.norm(a.sensors[name] - b.sensors[name], axis=1)
        ax.semilogy(x, np.maximum(difference, floor), lw=0.8, label=name)
    ax.set_xlabel("drive angle turned (deg)" if x[-1] > 1 else "drive angle turned (deg), dynamic window")
    ax.set_ylabel("|ours - Exudyn| (m)")
    ax.set_title(title or f"{STYLE[a.metadata['label']]['label']} minus {STYLE[b.metadata['label']]['label']}")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    return _save(fig, path)


def torque_figure(runs: dict, path: Path, title: str = "") -> Path:
    """Driving torque (N mm) per run, and the relative difference of each run to Exudyn's."""
    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5.2), sharex=True)
    reference = runs.get("exudyn")
    for label, run in runs.items():
        torque = run.sensors["driving_torque"]
        top.plot(_turn_deg(run), 1e3 * torque, **STYLE[label])
        if reference is not None and label != "exudyn":
            theirs = reference.sensors["driving_torque"]
            difference = np.abs(torque - theirs) / np.abs(theirs).max()
            bottom.semilogy(_turn_deg(run), np.maximum(difference, 1e-16), **STYLE[label])
    top.set_ylabel("driving torque (N mm)")
    top.set_title(title or "Driving torque")
    top.grid(alpha=0.3)
    top.legend(fontsize=8)
    bottom.set_xlabel("drive angle turned (deg)")
    bottom.set_ylabel("|difference| / max |torque|")
    bottom.grid(alpha=0.3, which="both")
    return _save(fig, path)


def mac_figure(modes: dict, path: Path) -> Path:
    """Mass-weighted MAC of our fixed-interface modes (rows) against Exudyn's (columns), per link."""
    plt = _pyplot()
    n = len(modes)
    fig, axes = plt.subplots(1, n, figsize=(3.0 * n + 1.0, 3.4), squeeze=False, constrained_layout=True)
    for k, (ax, (name, comparison)) in enumerate(zip(axes[0], modes.items(), strict=True)):
        image = ax.imshow(comparison.mac, vmin=0.0, vmax=1.0, cmap="viridis")
        ticks = np.arange(comparison.mac.shape[0])
        ax.set_xticks(ticks)
        ax.set_yticks(ticks)
        ax.tick_params(labelsize=6)
        ax.set_title(f"{name}\nmin diagonal {comparison.min_mac_diag:.10f}", fontsize=8)
        ax.set_xlabel("Exudyn mode", fontsize=8)
        if k == 0:
            ax.set_ylabel("our mode", fontsize=8)
    fig.colorbar(image, ax=axes[0].tolist(), shrink=0.8, label="MAC")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def coupler_path_figure(runs: dict, ideal: NDArray, path: Path, magnify: float = 100.0) -> Path:
    """The coupler point's path seen along the world z-axis, deviations from the ideal path
    magnified ``magnify`` times so that the elastic sag is visible."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(1e3 * ideal[:, 0], 1e3 * ideal[:, 1], **STYLE["ideal"])
    for label, run in runs.items():
        shown = ideal + magnify * (run.sensors["coupler_point"] - ideal)
        ax.plot(1e3 * shown[:, 0], 1e3 * shown[:, 1], **STYLE[label])
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"Coupler path (deviation x {magnify:g})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, path)


def series_difference_figure(
    time: NDArray, pairs: dict[str, tuple[NDArray, NDArray]], path: Path, title: str = ""
) -> Path:
    """``|a - b|`` (m, log scale) over time for named pairs of (n, 3) position series."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.6))
    for name, (a, b) in pairs.items():
        ax.semilogy(time, np.maximum(np.linalg.norm(a - b, axis=1), 1e-16), label=name)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("|ours - Exudyn| (m)")
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return _save(fig, path)
