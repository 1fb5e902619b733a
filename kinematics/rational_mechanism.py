r"""Mechanisms of Rational Linkages read as single loops, and their joint angles.

A ``rational_linkages.RationalMechanism`` holds two factorisations of one motion polynomial,
:math:`C(t) = (t - h_1)(t - h_2)\cdots = (t - k_1)(t - k_2)\cdots`, with the axes in the home pose
:math:`C(\infty) = 1`. Read as a loop (:class:`kinematics.single_loop.SingleLoop`), its joints are
:math:`h_1, h_2, \dots` followed by the second factorisation reversed, :math:`\dots, k_2, k_1`
(``RationalMechanism.get_screw_axes``), and the tool link is link ``m``, ``m`` the length of the
first factorisation. A factor :math:`t - h` with :math:`h = s + v + \varepsilon w` turns by

.. math:: \varphi = 2\,\mathrm{atan2}(-|v|,\; t - s)                          \qquad (L5)

about the line of :math:`v` (``docs/formulation.md``; for a unit axis :math:`t = -\cot(\varphi/2)`,
the convention of :mod:`kinematics.bennett`). In the loop's product (L2) the second factorisation
appears inverted, so its joints turn by :math:`-\varphi`. Rational Linkages' own joint angle
(``joint_angle_to_t_param``) is :math:`-\varphi_0` modulo :math:`2\pi`.

``rational_linkages`` is imported only here and only when a mechanism is read.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .pluecker import Line
from .single_loop import SingleLoop

__all__ = [
    "MODELS",
    "attach_points",
    "factor_joint_angles",
    "load_model",
    "loop_from_mechanism",
    "regular_start",
    "tool_link",
]

#: The 4R and 6R mechanisms that ``rational_linkages.models`` ships.
MODELS = ("bennett_ark24", "collisions_free_6r", "plane_fold_6r", "interp_4poses_6r")


def load_model(name: str) -> Any:
    """The ``RationalMechanism`` ``rational_linkages.models.<name>()``, one of :data:`MODELS`."""
    if name not in MODELS:
        raise ValueError(f"unknown Rational Linkages model {name!r}; choose one of {', '.join(MODELS)}")
    try:
        from rational_linkages import models
    except ImportError as error:  # pragma: no cover - rational_linkages is a test dependency
        raise ImportError(
            "reading Rational Linkages mechanisms needs the package rational_linkages: "
            "pip install 'rational_linkages~=3.0.1'"
        ) from error
    return getattr(models, name)()


def loop_from_mechanism(mechanism: Any, scale: float = 1.0) -> SingleLoop:
    """The mechanism's axes in its home pose as a :class:`SingleLoop`, lengths times ``scale``."""
    if not (np.isfinite(scale) and scale > 0.0):
        raise ValueError(f"scale must be a positive number, got {scale}")
    lines = [
        Line(np.asarray(axis.direction, dtype=float), scale * np.asarray(axis.moment, dtype=float))
        for axis in mechanism.get_screw_axes()
    ]
    return SingleLoop(tuple(lines))


def tool_link(mechanism: Any) -> int:
    """Index of the link that the motion polynomial moves (the end of the first factorisation)."""
    return len(mechanism.factorizations[0].dq_axes)


def _factor_angles(factorization: Any, t: float) -> NDArray[np.float64]:
    """Eq. (L5) for every factor ``t - h`` of one factorisation."""
    angles = []
    for axis in factorization.dq_axes:
        coefficients = np.asarray(axis.array(), dtype=float)
        angles.append(2.0 * np.arctan2(-np.linalg.norm(coefficients[1:4]), t - coefficients[0]))
    return np.array(angles)


def factor_joint_angles(mechanism: Any, t: float) -> NDArray[np.float64]:
    """Joint rotations from home of the loop :func:`loop_from_mechanism` at curve parameter ``t``."""
    first, second = mechanism.factorizations
    return np.concatenate([_factor_angles(first, t), -_factor_angles(second, t)[::-1]])


#: Curve parameters tried, in order, for a regular start pose (:func:`regular_start`).
START_PARAMETERS = (0.0, 1.0, -1.0, 0.5, -0.5, 2.0, -2.0)


def regular_start(mechanism: Any, loop: SingleLoop) -> NDArray[np.float64]:
    """Joint rotations at the first curve parameter of :data:`START_PARAMETERS` where ``loop`` (the mechanism's,
    :func:`loop_from_mechanism`) is regular, first-order mobility 1: home (``t`` infinite) and some poses of a
    mechanism that folds flat are singular, and a motion traced from a singular pose may switch branches."""
    for t in START_PARAMETERS:
        phi = factor_joint_angles(mechanism, t)
        if loop.mobility(phi) == 1:
            return phi
    raise ValueError(f"no regular pose of the mechanism at t in {START_PARAMETERS}; give the start pose yourself")


def attach_points(mechanism: Any, scale: float = 1.0) -> NDArray[np.float64]:
    """Where the mechanism's design attaches its links to each joint axis, ``(n, 2, 3)`` (times ``scale``).

    Row ``i`` holds the points of link ``i`` and link ``i + 1`` on joint ``i`` of :func:`loop_from_mechanism`:
    Rational Linkages gives every joint two connection points, ``points[0]`` and ``points[1]``, a link of a
    factorisation running from ``points[1]`` of one joint to ``points[0]`` of the next (``MotionFactorization.link``)
    and the base joining the two factorisations' first ``points[0]``; the second factorisation is read reversed.
    Its collision-free designs (``collisions_free_6r``) choose these points to keep the links apart.
    """
    first, second = mechanism.factorizations
    m, n = len(first.linkage), len(first.linkage) + len(second.linkage)

    def point(joint: Any, k: int) -> NDArray[np.float64]:
        return scale * np.asarray(joint.points[k].normalized_euclidean(), dtype=float)

    rows = [[point(first.linkage[i], 0), point(first.linkage[i], 1)] for i in range(m)]
    rows += [[point(second.linkage[n - 1 - i], 1), point(second.linkage[n - 1 - i], 0)] for i in range(m, n)]
    return np.array(rows)
