"""Figures of ideal linkage motion. Functions take data and return ``(fig, ax)``."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .bennett import BennettLinkage
from .pluecker import common_normal

__all__ = ["plot_coupler_path"]


def plot_coupler_path(linkage: BennettLinkage, path: NDArray[np.float64], axis_length: float = 0.08):
    """3-D view of the home configuration (axes and common normals) and a coupler path (mm)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    axes = linkage.axes
    for i, line in enumerate(axes):
        ends = 1e3 * line.point_at(np.array([-axis_length, axis_length]))
        ax.plot(*ends.T, color="tab:purple", lw=1.5)
        ax.text(*(1e3 * line.point_at(axis_length)), f"$h_{i}$", color="tab:purple")
        normal = common_normal(line, axes[(i + 1) % 4])
        feet = 1e3 * np.array([normal.foot0, normal.foot1])
        ax.plot(*feet.T, color="black", lw=2.5)
    closed = 1e3 * np.vstack([path, path[:1]])
    ax.plot(*closed.T, color="tab:gray", lw=1.5, label="ideal coupler path (motion polynomial)")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    ax.set_aspect("equal")
    ax.legend(loc="upper left")
    ax.set_title("Bennett linkage, home configuration, and ideal coupler path")
    return fig, ax
