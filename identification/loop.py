r"""DH parameters of a single loop (the Bennett 4R first, any nR) from tracked link trajectories.

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

__all__ = ["IdentifiedLoop", "identify_dh", "identify_axes", "identify_loop", "identify_loop_axes", "bennett_ratios"]


@dataclass(frozen=True)
class IdentifiedLoop:
    """Result of an identification: the axes :math:`h_0..h_{n-1}` (configuration of the first
    frame), the DH parameters, the Bennett ratios (4R only, else empty), and the per-link axis fits."""

    axes: tuple[Line, ...]
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


def _link_points(trajectories: Mapping[int, ArrayLike], link: int, n: int) -> NDArray[np.float64]:
    if link not in trajectories:
        raise IdentificationError(
            f"no trajectory for link {link}: links 1 to {n - 1} must be tracked (link 0 is the fixed base)"
        )
    points = np.asarray(trajectories[link], dtype=float)
    if not np.all(np.isfinite(points)):
        raise IdentificationError(
            f"link {link} has NaN positions; drop or repair those frames first (identification.clean_record)"
        )
    return points


def identify_loop_axes(
    trajectories: Mapping[int, ArrayLike], n: int, tool_link: int
) -> tuple[list[Line], dict[str, LinkAxisFit]]:
    r"""The unoriented axes ``[h_0, ..., h_{n-1}]`` of an nR loop and their fits, from links 1 .. n-1.

    Branch A runs base -> link 1 -> ... -> ``tool_link`` and gives :math:`h_0 \dots h_{m-1}`
    (``m = tool_link``); branch B runs base -> link n-1 -> ... -> ``tool_link`` and gives
    :math:`h_{n-1}, h_{n-2} \dots h_m` (:func:`identification.branches.identify_branch`).
    """
    if n < 4 or not 0 < tool_link < n:
        raise IdentificationError(
            f"a loop of n >= 4 joints with a tool link 1..n-1 is needed, got n = {n}, tool {tool_link}"
        )
    points = {k: _link_points(trajectories, k, n) for k in range(1, n)}
    first = list(range(1, tool_link + 1))
    second = list(range(n - 1, tool_link - 1, -1))
    fits_a = identify_branch(
        [points[k] for k in first],
        [
            f"link {k} (about h{k - 1})" if k == 1 else f"link {k} seen from link {k - 1} (about h{k - 1})"
            for k in first
        ],
    )
    fits_b = identify_branch(
        [points[k] for k in second],
        [f"link {k} (about h{k})" if k == n - 1 else f"link {k} seen from link {k + 1} (about h{k})" for k in second],
    )
    fits = {f"h{k - 1}": fit for k, fit in zip(first, fits_a, strict=True)}
    fits |= {f"h{k}": fit for k, fit in zip(second, fits_b, strict=True)}
    return [fits[f"h{i}"].axis for i in range(n)], fits


def identify_axes(trajectories: Mapping[int, ArrayLike]) -> tuple[list[Line], dict[str, LinkAxisFit]]:
    """The unoriented axes ``[h0, h1, h2, h3]`` and the link fits of the Bennett loop, from links 1, 2, 3."""
    return identify_loop_axes(trajectories, 4, 2)


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


def identify_loop(
    trajectories: Mapping[int, ArrayLike], nominal_alpha: ArrayLike, tool_link: int | None = None
) -> IdentifiedLoop:
    """DH parameters of an nR loop (n = ``len(nominal_alpha)``) from tracked positions of links 1 .. n-1.

    ``trajectories`` maps the link index to ``(frames, 3)`` (one tracked point) or ``(frames, k, 3)``
    (several points) positions in metres, frames in time order; ``tool_link`` is where the two branches
    meet (default ``n // 2``, the coupler of a 4R). ``nominal_alpha`` (rad) only orients the fitted
    axes: every axis but the last is flipped to bring the twists closest to it, and :math:`h_{n-1}` so
    that link ``n - 1`` turns negatively about it along the record (module docstring).
    """
    nominal_alpha = np.asarray(nominal_alpha, dtype=float)
    n = nominal_alpha.size
    axes, fits = identify_loop_axes(trajectories, n, n // 2 if tool_link is None else tool_link)
    last = fits[f"h{n - 1}"]
    if last.angles[-1] - last.angles[0] > 0:  # link n-1 about the fitted direction of h_{n-1}
        axes[n - 1] = axes[n - 1].reversed()
    oriented, dh = _orient(axes, nominal_alpha, keep=n - 1)
    ratios = bennett_ratios(dh) if n == 4 else {}
    return IdentifiedLoop(tuple(oriented), dh, ratios, nominal_alpha, fits)


def identify_dh(trajectories: Mapping[int, ArrayLike], nominal_alpha: ArrayLike = PAPER_ALPHA) -> IdentifiedLoop:
    """DH parameters of the Bennett loop from tracked positions of links 1, 2 and 3 (:func:`identify_loop`).

    ``trajectories`` maps the link index to ``(frames, 3)`` (one tracked point) or
    ``(frames, k, 3)`` (several points) positions in metres, frames in time order.
    ``nominal_alpha`` (rad) only orients the fitted axes (see the module docstring).
    """
    return identify_loop(trajectories, nominal_alpha, tool_link=2)
