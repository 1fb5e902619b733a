"""Exceptions raised by the finite-element link models.

All are subclasses of :class:`ValueError`, so callers that only care about
"bad input" can catch that; the message always names the object, the bad value
and a remedy.
"""

from __future__ import annotations

__all__ = ["FEInputError", "MeshError", "InterfaceError", "MaterialError", "GeometryError", "SceneError"]


class FEInputError(ValueError):
    """Base class of every input error of :mod:`ffrf`."""


class MeshError(FEInputError):
    """Inverted, degenerate or disconnected elements, suspicious units, unreadable files."""


class InterfaceError(FEInputError):
    """Empty, collinear or otherwise unusable interface node sets."""


class MaterialError(FEInputError):
    """Non-physical elastic or inertial material data."""


class GeometryError(FEInputError):
    """Impossible parametric link geometry (parallel axes, overlapping housings, ...)."""


class SceneError(FEInputError):
    """A scene file that cannot be built; the message names the entry and the fix."""
