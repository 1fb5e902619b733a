r"""The largest play a linkage's passive joints may have: the radial clearance of its pins in their bores up to
which its coupler stays within a bound of the ideal path (``docs/formulation.md``, Eq. (P8); issue #36).

A pin that may move in its bore makes the path non-smooth in the play :math:`c`: contacts open and close, pins cross
their bores in jumps (Eq. (P6)), and the derivatives of Eq. (D1) do not exist there. So the play is designed by
full runs, not gradients: the largest deviation :math:`D(c) = \max_i |d_i(c)|` of a quasi-static revolution is
evaluated on an even grid :math:`0 = c_0 < \dots < c_g = \bar c`, then the first bracket where the bound
:math:`D \le \bar d` stops holding (the run verified itself and its deviation within the bound) is bisected to a
width of at most the resolution. The answer is the largest play :math:`c^*` such that every play evaluated up to
it met the bound, with :math:`c^+`, the smallest evaluated play above it that did not. Nothing guarantees that
:math:`D` grows with :math:`c` between the plays evaluated; where the grid shows the bound met again above a play
that missed it the design says so (``monotone`` false) and keeps the first bracket, the conservative answer.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ffrf.errors import SceneError, StaticDivergence
from ffrf.scenes.linkage_description import LinkageOptions, with_radial_play
from ffrf.scenes.linkage_file import LINKAGE_SCHEMA, linkage_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.scenes.scene_schema import Key, check_table
from ffrf.scenes.schema_keys import positive
from kinematics.single_loop import SingleLoop

__all__ = [
    "PLAY",
    "PlayDesign",
    "PlayPoint",
    "PlayProblem",
    "evaluate_play",
    "largest_play",
    "load_play_design",
    "played_document",
]

#: A design file's ``[play]`` table: the bound on the coupler's deviation (in the linkage's ``unit``), the largest
#: radial play considered and the resolution of the answer (mm, as a ``clearance`` table's), the number of even
#: intervals of the first scan, and the poses of each revolution (default the linkage's own ``outputs``: a run
#: keeps its energy books at its outputs, and the drive's work across a pin's jump needs them dense to close).
PLAY = {
    "max_deviation": Key("number", True, positive),
    "largest_mm": Key("number", True, positive),
    "resolution_mm": Key("number", False, positive),
    "grid": Key("integer", False, positive),
    "outputs": Key("integer", False, positive),
}

#: A deviation within this fraction above its bound meets it (as :data:`~ffrf.scenes.section_design.FEASIBLE`).
FEASIBLE = 1e-3


@dataclass(frozen=True)
class PlayProblem:
    """The bound ``max_deviation`` (m) on the coupler's deviation at each of ``outputs`` poses of a revolution, the
    largest radial play considered ``largest`` (m), the answer's ``resolution`` (m) and the first scan's ``grid``
    intervals."""

    max_deviation: float
    largest: float
    resolution: float
    grid: int = 4
    outputs: int = 37

    def __post_init__(self) -> None:
        if not self.max_deviation > 0.0:
            raise SceneError(f"play: max_deviation must be > 0, got {self.max_deviation!r}")
        if not 0.0 < self.resolution < self.largest:
            raise SceneError(
                f"play: resolution_mm ({1e3 * self.resolution:g}) must be > 0 and below largest_mm "
                f"({1e3 * self.largest:g}); lower it or raise largest_mm"
            )
        if self.grid < 1:
            raise SceneError(f"play: grid must be at least 1 interval, got {self.grid}")
        if self.outputs < 3:
            raise SceneError(f"play: outputs must be at least 3 poses, got {self.outputs}")


@dataclass(frozen=True)
class PlayPoint:
    """One play ``radial`` (m), run: the coupler's largest deviation (m; over the poses reached), the assembly's
    largest von Mises stress (Pa), the pins' largest eccentricity in their bores (m), whether the run ``verified``
    itself (and the ``reasons`` where not), where it ``stopped`` (``None``: at its end) and its ``seconds``."""

    radial: float
    max_deviation: float
    assembly_stress: float
    max_eccentricity: float
    verified: bool
    stopped: str | None
    seconds: float
    reasons: tuple[str, ...] = ()

    def meets(self, problem: PlayProblem) -> bool:
        """Whether the run went to its end, verified itself and kept the coupler within the bound."""
        within = self.max_deviation <= problem.max_deviation * (1.0 + FEASIBLE)
        return self.verified and self.stopped is None and within


@dataclass(frozen=True)
class PlayDesign:
    """Every play evaluated (``points``, by play), the answer ``largest`` (the largest play up to which every play
    evaluated met the bound; ``None`` when ideal joints do not), ``failing`` (the smallest evaluated play above it
    that did not; ``None`` when ``largest`` is the problem's own) and whether the evaluated plays met the bound in
    one stretch from zero (``monotone``)."""

    problem: PlayProblem
    points: tuple[PlayPoint, ...]
    largest: PlayPoint | None
    failing: PlayPoint | None
    monotone: bool


def evaluate_play(loop: SingleLoop, options: LinkageOptions, problem: PlayProblem, radial: float) -> PlayPoint:
    """Build the linkage with ``radial`` (m) of play in its passive joints and run it quasi-statically over the
    problem's poses; a path that stops is a point that misses the bound (its deviation up to the stop)."""
    started = time.perf_counter()
    scene = build_linkage(loop, with_radial_play(options, 1e3 * radial), where=f"play {1e3 * radial:g} mm")
    stopped = None
    try:
        result = run_linkage(scene, mode="quasi_static", n_outputs=problem.outputs)
    except StaticDivergence as error:
        if error.partial is None:
            raise
        result, stopped = error.partial, str(error.partial.metadata["stopped"]["message"])
    deviation = np.linalg.norm(np.asarray(result.sensors["coupler_deviation"], dtype=float), axis=1)
    eccentricity = [float(np.max(result.sensors[f"{j.name}_eccentricity"])) for j in scene.loose_joints]
    assembly = result.assembly.as_dict() if result.assembly is not None else {"max_von_mises_pa": float("nan")}
    return PlayPoint(
        radial,
        float(deviation.max()),
        float(assembly["max_von_mises_pa"]),
        max(eccentricity, default=0.0),
        result.verification is not None and bool(result.verification.verified),
        stopped,
        time.perf_counter() - started,
        () if result.verification is None else tuple(result.verification.reasons),
    )


def largest_play(
    problem: PlayProblem,
    evaluate: Callable[[float], PlayPoint],
    progress: Callable[[PlayPoint], None] | None = None,
) -> PlayDesign:
    """The module docstring's search: ``evaluate(radial)`` runs one play (m); ``progress(point)`` after each."""
    points: dict[float, PlayPoint] = {}

    def at(radial: float) -> PlayPoint:
        if radial not in points:
            points[radial] = evaluate(radial)
            if progress is not None:
                progress(points[radial])
        return points[radial]

    scan = [at(float(c)) for c in np.linspace(0.0, problem.largest, problem.grid + 1)]
    met = [p.meets(problem) for p in scan]
    first_miss = met.index(False) if False in met else None
    monotone = first_miss is None or not any(met[first_miss:])
    if first_miss is None:
        return PlayDesign(problem, tuple(scan), scan[-1], None, monotone)
    if first_miss == 0:
        return PlayDesign(problem, tuple(scan), None, scan[0], monotone)
    low, high = scan[first_miss - 1], scan[first_miss]
    while high.radial - low.radial > problem.resolution:
        middle = at(0.5 * (low.radial + high.radial))
        low, high = (middle, high) if middle.meets(problem) else (low, middle)
    return PlayDesign(problem, tuple(sorted(points.values(), key=lambda p: p.radial)), low, high, monotone)


def load_play_design(document: dict, where: str = "design") -> tuple[SingleLoop, LinkageOptions, PlayProblem]:
    """A play design file (already parsed): a linkage file (:mod:`ffrf.scenes.linkage_file`) with a ``[play]`` table
    (:data:`PLAY`). Returns the loop, the options it builds the linkage with (its own ``clearance`` table, if any,
    gives the pins' length and contact law) and the problem in SI units."""
    check_table(document, dict(LINKAGE_SCHEMA, play=Key("table", True, keys=PLAY)), where)
    loop, options, _ = linkage_options({k: v for k, v in document.items() if k != "play"}, where)
    spec = document["play"]
    length = 1e-3 if document["linkage"].get("unit") == "mm" else 1.0
    largest = 1e-3 * float(spec["largest_mm"])
    try:
        problem = PlayProblem(
            length * float(spec["max_deviation"]),
            largest,
            1e-3 * float(spec.get("resolution_mm", 1e3 * largest / 32.0)),
            int(spec.get("grid", 4)),
            int(spec.get("outputs", options.outputs)),
        )
    except SceneError as error:
        raise SceneError(f"{where}, {error}") from error
    return loop, options, problem


def played_document(document: dict, design: PlayDesign, options: LinkageOptions) -> dict:
    """The design file's linkage (without ``[play]``) with the answer's play in its ``[scene] clearance`` (the rest
    of the table as :func:`~ffrf.scenes.linkage_description.with_radial_play` makes it from ``options``; ideal joints
    where the answer is none or zero): a linkage file of the designed linkage."""
    radial_mm = 0.0 if design.largest is None else 1e3 * design.largest.radial
    play = with_radial_play(options, radial_mm).joint_play
    scene = {k: v for k, v in document.get("scene", {}).items() if k != "clearance"}
    scene |= {} if play is None else {"clearance": play}
    return {k: v for k, v in dict(document, scene=scene).items() if k != "play"}
