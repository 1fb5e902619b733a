"""The paper's Bennett axes h0..h3: as given in the folded home configuration (:data:`PAPER_AXES`) and from
the DH table with any base-link twist (:func:`bennett_axes`); link ``k`` carries (h_{k-1}, h_k)
(:func:`paper_link_axes`), the two axes a parametric link (:func:`ffrf.geometry.link_geometry.mesh_link`) is
built on.
"""

from __future__ import annotations

import numpy as np

from ffrf.errors import GeometryError
from ffrf.geometry.joint_axes import Axis
from kinematics import PAPER_A, PAPER_ALPHA, open_loop_axes

__all__ = ["PAPER_AXES", "bennett_axes", "paper_link_axes"]

#: The paper's four joint axes h0..h3 in the folded home configuration (metres).
PAPER_AXES: tuple[Axis, ...] = (
    Axis((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    Axis((-0.11, 0.0, 0.0), (0.0, 0.5, -np.sqrt(3.0) / 2.0)),
    Axis((0.11, 0.0, 0.0), (0.0, np.sqrt(3.0) / 2.0, 0.5)),
    Axis((0.22, 0.0, 0.0), (0.0, -1.0, 0.0)),
)


def bennett_axes(alpha3_deg: float = 90.0) -> tuple[Axis, Axis, Axis, Axis]:
    """Joint axes h0..h3 of the paper's linkage (:data:`kinematics.PAPER_A`, ``PAPER_ALPHA``)
    with the base-link twist ``alpha3_deg``.

    The base link (link 0) carries (h3, h0). With alpha_3 != 90 deg the loop does not
    close, so its h3 is where the *base link* puts it: :func:`kinematics.open_loop_axes`
    chains h0..h3 through links 0..2 (nominal) and returns that closing axis, which
    replaces h3 here (the base's bore axis; link 3 keeps the nominal h3).
    """
    if not np.isfinite(alpha3_deg):
        raise GeometryError(
            f"base-link twist alpha3_deg={alpha3_deg!r} is not a finite angle; give it in degrees, "
            "e.g. 90 (paper: 90, 91, 92)"
        )
    alpha = np.array(PAPER_ALPHA)
    alpha[3] = np.radians(alpha3_deg)
    axes, closing_axis = open_loop_axes(PAPER_A, alpha)
    return Axis.of(axes[0]), Axis.of(axes[1]), Axis.of(axes[2]), Axis.of(closing_axis)


def paper_link_axes(link: int, axes=PAPER_AXES) -> tuple[Axis, Axis, tuple[str, str]]:
    """Axes and interface names of link ``link`` (0 = base): it carries (h_{i-1}, h_i)."""
    if link not in (0, 1, 2, 3):
        raise GeometryError(f"link index {link!r} must be 0, 1, 2 or 3 (0 = base)")
    first, second = (link - 1) % 4, link
    return Axis.of(axes[first]), Axis.of(axes[second]), (f"joint{first}", f"joint{second}")
