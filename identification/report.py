"""Tables in the layout of the paper's Tab. dh_deviation, and figures. Plots return ``(fig, ax)``."""

from __future__ import annotations

import csv
import io

import numpy as np

from .branches import LinkAxisFit
from .runs import RunStatistics

__all__ = ["dh_table_markdown", "dh_table_csv", "plot_axis_fits", "plot_axis3_deviation"]


def _rows(stats: RunStatistics):
    a, alpha, d = stats.mean["a"], stats.mean["alpha"], stats.mean["d"]
    sa, salpha, sd = stats.std["a"], stats.std["alpha"], stats.std["d"]
    for i in range(a.shape[0]):
        yield i, 1e3 * a[i], 1e3 * sa[i], np.degrees(alpha[i]), np.degrees(salpha[i]), 1e3 * d[i], 1e3 * sd[i]


def dh_table_markdown(stats: RunStatistics, label: str = "") -> str:
    """``| i | a_i [mm] | +-sigma | alpha_i [deg] | +-sigma | d_i [mm] | +-sigma |`` (mean over runs)."""
    lines = [
        f"**{label}** ({stats.n_runs} run{'s' if stats.n_runs != 1 else ''})" if label else "",
        "| i | a_i [mm] | ± σ | α_i [deg] | ± σ | d_i [mm] | ± σ |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for i, a, sa, al, sal, d, sd in _rows(stats):
        lines.append(f"| {i} | {a:.3f} | {sa:.3f} | {al:.3f} | {sal:.3f} | {d:.3f} | {sd:.3f} |")
    ratios = stats.mean["ratios"]
    lines.append("")
    lines.append(
        "Bennett ratios: a0/a1 = {:.5f}, a2/a3 = {:.5f}, sin α0/sin α1 = {:.5f}, sin α2/sin α3 = {:.5f}; "
        "axis-3 twist deviation {:.4f} deg".format(*ratios, np.degrees(stats.mean["axis3_twist_deviation"][0]))
    )
    return "\n".join(line for line in lines if line is not None)


def dh_table_csv(stats: RunStatistics, label: str = "") -> str:
    out = io.StringIO()
    writer = csv.writer(out)
    writer.writerow(["label", "i", "a_mm", "a_std_mm", "alpha_deg", "alpha_std_deg", "d_mm", "d_std_mm", "runs"])
    for row in _rows(stats):
        writer.writerow([label, row[0], *(f"{v:.6f}" for v in row[1:]), stats.n_runs])
    return out.getvalue()


def plot_axis_fits(points: dict[int, np.ndarray], fits: dict[str, LinkAxisFit]):
    """Tracked paths (mm) with the fitted circles and axes of h0 and h3 (the fixed axes)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    colours = {1: "tab:red", 2: "tab:green", 3: "tab:blue"}
    for link, p in points.items():
        for k in range(p.shape[1]):
            ax.plot(*(1e3 * p[:, k].T), color=colours.get(link, "k"), lw=1, label=f"link {link}" if k == 0 else None)
    for name in ("h0", "h3"):
        fit = fits[name]
        for circle in fit.fits:
            phi = np.linspace(0, 2 * np.pi, 200)
            ring = circle.centre + circle.radius * (
                np.outer(np.cos(phi), circle.e_x) + np.outer(np.sin(phi), circle.e_y)
            )
            ax.plot(*(1e3 * ring.T), color="gray", lw=0.8, ls="--")
        ends = fit.axis.point_at(np.array([-0.1, 0.1])) + (fit.centre - fit.axis.point)
        ax.plot(*(1e3 * ends.T), color="tab:purple", lw=2)
        ax.text(*(1e3 * ends[1]), name, color="tab:purple")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    ax.legend()
    ax.set_title("Tracked paths, fitted circles and fixed joint axes")
    return fig, ax


def plot_axis3_deviation(labels: list[str], stats: list[RunStatistics]):
    """Axis-3 twist deviation (deg) per configuration with +-1 standard deviation bars."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5))
    mean = [np.degrees(s.mean["axis3_twist_deviation"][0]) for s in stats]
    std = [np.degrees(s.std["axis3_twist_deviation"][0]) for s in stats]
    ax.errorbar(range(len(labels)), mean, yerr=std, fmt="s", capsize=4)
    ax.set_xticks(range(len(labels)), labels)
    ax.set_ylabel("α3 identified − nominal [deg]")
    ax.axhline(0.0, color="gray", lw=0.8)
    ax.set_title("Angular deviation of joint axis 3")
    return fig, ax
