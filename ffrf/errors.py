"""Every exception class of :mod:`ffrf`, below every layer so that any module can raise them.

Bad input (:class:`FEInputError` and its subclasses) derives from :class:`ValueError`, so callers
that only care about "bad input" can catch that; solver failures (:class:`StaticDivergence`,
:class:`NewtonDivergence`) derive from :class:`RuntimeError`; a run stopped on request (:class:`Interrupted`) from
:class:`BaseException`. Every message names the object, the bad value and a remedy.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "FEInputError",
    "MeshError",
    "InterfaceError",
    "MaterialError",
    "GeometryError",
    "SceneError",
    "ReductionError",
    "ExternalFEError",
    "ResultsError",
    "StaticDivergence",
    "AssemblyDivergence",
    "NewtonDivergence",
    "SingularIterationMatrix",
    "SensitivityError",
    "Interrupted",
]


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


class ReductionError(FEInputError):
    """A model, an interface set or a request that the HCB reduction cannot handle."""


class ExternalFEError(FEInputError):
    """Nodes and matrices given from outside (Abaqus, Matrix Market or .npz files, or arrays) that
    cannot be read or do not make one solid FE model."""


class ResultsError(FEInputError):
    """A results folder that cannot be read: a file missing, damaged, or not the one its manifest lists
    (:func:`ffrf.output.tables.check_results`)."""


# Solver failures: not bad input, so not FEInputError.


class StaticDivergence(RuntimeError):
    """Newton found no static equilibrium; ``partial``, where given, holds the equilibria found before, and
    ``snaps`` the folds a run went through or stopped at (:mod:`ffrf.solvers.snap_through`)."""

    def __init__(self, message: str, partial: Any = None, snaps: tuple = ()):
        super().__init__(message)
        self.partial = partial
        self.snaps = snaps


class AssemblyDivergence(StaticDivergence):
    """The static assembly (gravity, then closing the joint misfits) found no equilibrium: the linkage as built
    does not assemble from its start pose (:func:`ffrf.scenes.assembly.assemble`)."""


class NewtonDivergence(RuntimeError):
    """Newton did not converge; ``partial`` holds the results up to the last converged step."""

    def __init__(self, message: str, partial: Any):
        super().__init__(message)
        self.partial = partial


class SingularIterationMatrix(NewtonDivergence):
    """The iteration matrix (G3) has zero singular values by the rank rule (R1): no step can be solved."""


class SensitivityError(RuntimeError):
    """A derivative that does not exist where it was asked for: an equilibrium at a fold (Eq. (D1))."""


class Interrupted(BaseException):
    """The run was asked to stop (SIGINT, SIGTERM: :mod:`ffrf.cli`) and stopped between two steps. A progress callback
    raises it; the solver it interrupts sets ``partial`` (as :class:`NewtonDivergence` does: what was computed up to
    the last output) and ``snaps`` (as :class:`StaticDivergence`), so that callers can write what was computed.
    Neither bad input nor a solver failure: like :class:`KeyboardInterrupt` a :class:`BaseException`, so that no
    ``except Exception`` on the way (a cache file's read, a worker pool) takes it for a failure of its own."""

    def __init__(self, message: str = "interrupted", partial: Any = None, snaps: tuple = ()):
        super().__init__(message)
        self.partial = partial
        self.snaps = snaps
