r"""DH parameters of a Bennett loop from tracked link trajectories.

Links follow the paper's numbering (link 0 = base, fixed; link 2 = coupler). Branch A is
base -> link 1 -> link 2, giving the axes :math:`h_0` (link 1 about the base) and
:math:`h_1` (coupler about link 1); branch B is base -> link 3 -> link 2, giving
:math:`h_3` and :math:`h_2` (:mod:`identification.branches`). The four lines then give the
DH parameters through :func:`kinematics.dh_from_axes`, as the paper does through the
algorithm of Huczala et al. (2022).

A fitted axis has no preferred orientation (the PCA normal's sign is arbitrary), yet the
twists depend on it (flipping :math:`h_{i+1}` turns :math:`\alpha_i` into
:math:`\alpha_i - \pi`). We orient the four axes so that the twists come closest to the
nominal design twists, which the user knows (default: the paper's Table). Twists do not
fix a common flip of all four axes, which changes the signs of ``d_i`` and ``theta_i``; we
fix it by orienting :math:`h_3` so that the DH angle of the driven joint 3 *increases*
along the record (link 3 then turns negatively about :math:`h_3`, because the DH joint
angle of joint 3 is the base's rotation relative to link 3).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kinematics import PAPER_ALPHA, DHParameters, Line, dh_from_axes, wrap_angle

from .branches import LinkAxisFit, identify_branch
from .circle_fit import IdentificationError

__all__ = ["IdentifiedLoop", "identify_dh", "identify_axes", "bennett_ratios"]


@dataclass(frozen=True)
class IdentifiedLoop:
    """Result of an identification: the axes :math:`h_0..h_3` (configuration of the first
    frame), the DH parameters, the Bennett ratios, and the per-link axis fits."""

    axes: tuple[Line, Line, Line, Line]
    dh: DHParameters
    ratios: dict[str, float]
    nominal_alpha: NDArray[np.float64]
    fits: dict[str, LinkAxisFit]

    @property
    def axis3_twist_deviation(self) -> float:
        r"""Identified minus nominal :math:`\alpha_3` (rad): the angular deviation of joint
        axis 3 relative to :math:`h_0` (the frame-independent part of the paper's Fig. 'axis 3')."""
        return float(wrap_angle(self.dh.alpha[3] - self.nominal_alpha[3]))

    def as_dict(self) -> dict:
        """Plain data for JSON: lengths in metres, angles in radians."""
        return {
            "a": self.dh.a.tolist(),
            "alpha": self.dh.alpha.tolist(),
            "d": self.dh.d.tolist(),
            "theta": self.dh.theta.tolist(),
            "bennett_ratios": self.ratios,
            "axis3_twist_deviation": self.axis3_twist_deviation,
            "axes": [{"direction": line.direction.tolist(), "moment": line.moment.tolist()} for line in self.axes],
        }


def bennett_ratios(dh: DHParameters) -> dict[str, float]:
    """Ratios that equal each other for a Bennett linkage: a0/a1 = sin(alpha0)/sin(alpha1), etc."""
    a, s = dh.a, np.sin(dh.alpha)
    return {
        "a0/a1": float(a[0] / a[1]),
        "a2/a3": float(a[2] / a[3]),
        "sin(alpha0)/sin(alpha1)": float(s[0] / s[1]),
        "sin(alpha2)/sin(alpha3)": float(s[2] / s[3]),
    }


def _link_points(trajectories: Mapping[int, ArrayLike], link: int) -> NDArray[np.float64]:
    if link not in trajectories:
        raise IdentificationError(
            f"no trajectory for link {link}: links 1, 2 and 3 must be tracked (link 0 is the fixed base)"
        )
    points = np.asarray(trajectories[link], dtype=float)
    if not np.all(np.isfinite(points)):
        raise IdentificationError(
            f"link {link} has NaN positions; drop or repair those frames first (identification.clean_record)"
        )
    return points


def identify_axes(trajectories: Mapping[int, ArrayLike]) -> tuple[list[Line], dict[str, LinkAxisFit]]:
    """The unoriented axes ``[h0, h1, h2, h3]`` and the link fits, from links 1, 2, 3."""
    link1, link2, link3 = (_link_points(trajectories, k) for k in (1, 2, 3))
    fit1, fit21 = identify_branch([link1, link2], ["link 1 (about h0)", "link 2 seen from link 1 (about h1)"])
    fit3, fit23 = identify_branch([link3, link2], ["link 3 (about h3)", "link 2 seen from link 3 (about h2)"])
    axes = [fit1.axis, fit21.axis, fit23.axis, fit3.axis]
    return axes, {"h0": fit1, "h1": fit21, "h2": fit23, "h3": fit3}


def _orient(axes: list[Line], nominal_alpha: NDArray, keep: int) -> tuple[list[Line], DHParameters]:
    """Flip axes other than ``axes[keep]`` so that the twists come closest to ``nominal_alpha``."""
    best: tuple[float, list[Line], DHParameters] | None = None
    others = [i for i in range(len(axes)) if i != keep]
    for signs in itertools.product((1, -1), repeat=len(others)):
        oriented = list(axes)
        for i, sign in zip(others, signs, strict=True):
            oriented[i] = axes[i] if sign > 0 else axes[i].reversed()
        dh = dh_from_axes(oriented)
        cost = float(np.sum(wrap_angle(dh.alpha - nominal_alpha) ** 2))
        if best is None or cost < best[0]:
            best = (cost, oriented, dh)
    assert best is not None  # product() yields at least one sign pattern
    return best[1], best[2]


def identify_dh(trajectories: Mapping[int, ArrayLike], nominal_alpha: ArrayLike = PAPER_ALPHA) -> IdentifiedLoop:
    """DH parameters of the loop from tracked positions of links 1, 2 and 3.

    ``trajectories`` maps the link index to ``(frames, 3)`` (one tracked point) or
    ``(frames, k, 3)`` (several points) positions in metres, frames in time order.
    ``nominal_alpha`` (rad) only orients the fitted axes (see the module docstring).
    """
    nominal_alpha = np.asarray(nominal_alpha, dtype=float)
    axes, fits = identify_axes(trajectories)
    turn = fits["h3"].angles[-1] - fits["h3"].angles[0]  # link 3 about the fitted h3 direction
    if turn > 0:
        axes[3] = axes[3].reversed()
    oriented, dh = _orient(axes, nominal_alpha, keep=3)
    h0, h1, h2, h3 = oriented
    return IdentifiedLoop((h0, h1, h2, h3), dh, bennett_ratios(dh), nominal_alpha, fits)
