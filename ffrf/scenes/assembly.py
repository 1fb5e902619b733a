r"""The static assembly of a scene, the state its run starts from, and how far its quasi-static steps go.

:func:`assemble` closes the joints of a built scene (:mod:`ffrf.scenes.builder`) by
continuation: gravity in two load steps on the closable system (every joint's side 0 takes side
1's frame and point), then each misfit joint's side 0 turned and moved to its own frame and point
in ``steps`` increments (``Scene.with_misfit(fraction)``), one static equilibrium each; the
assembly stress stays in the bodies.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import AssemblyDivergence, StaticDivergence
from ffrf.scenes.builder import Scene
from ffrf.scenes.step_sizes import DRIVE_ANGLE_PER_STEP, MAX_DRIVE_STEP, MAX_DYNAMIC_STEP, PATH_STEPS_WITHOUT_DRIVE
from ffrf.solvers.pseudo_transient import settle
from ffrf.solvers.static_solver import StaticSolution, static_equilibrium
from ffrf.system.clearance_joint import ClearanceJoint
from ffrf.system.multibody import MultibodySystem

__all__ = [
    "assemble",
    "dynamic_step",
    "quasi_static_path_step",
    "quasi_static_step",
    "start_state",
    "starts_static",
    "DRIVE_ANGLE_PER_STEP",
    "MAX_DRIVE_STEP",
    "MAX_DYNAMIC_STEP",
    "PATH_STEPS_WITHOUT_DRIVE",
    "STEPS_PER_DEGREE",
]

#: Continuation steps of :func:`assemble` per degree of the largest axis misfit.
STEPS_PER_DEGREE = 4


def _fastest_drive_speed(scene: Scene) -> float | None:
    """The largest full speed (rad/s) of ``scene``'s drives; ``None`` without a drive."""
    speeds = [abs(j.angle.ramp.omega) for j in scene.joints if j.angle is not None]
    return max(speeds) if speeds else None


def quasi_static_step(scene: Scene) -> float | None:
    """Time (s) in which the fastest drive of ``scene`` turns :data:`MAX_DRIVE_STEP` at full speed; ``None``
    without a drive. Quasi-static runs insert equilibria so that no step is longer."""
    speed = _fastest_drive_speed(scene)
    return None if speed is None else MAX_DRIVE_STEP / speed


def quasi_static_path_step(scene: Scene, t_end: float) -> Callable[[float], float]:
    """The path step of a quasi-static run of ``scene`` over [0, ``t_end``] (Eq. (S10), constant): the time in which
    its fastest drive turns :data:`MAX_DRIVE_STEP` at full speed (:func:`quasi_static_step`), or without a drive
    ``t_end`` / :data:`PATH_STEPS_WITHOUT_DRIVE`. It depends on the scene alone, not on its outputs, so neither
    do the equilibria at a given time (to Newton's tolerance) nor where the path stops or snaps."""
    if not t_end > 0.0:
        raise ValueError(f"t_end must be > 0 s for a quasi-static run, got {t_end}")
    drive = quasi_static_step(scene)
    step = t_end / PATH_STEPS_WITHOUT_DRIVE if drive is None else drive
    return lambda t: step


def dynamic_step(scene: Scene) -> float:
    """The generalized-alpha step (s) of a dynamic run of ``scene`` that names none: the time in which its fastest
    drive turns :data:`DRIVE_ANGLE_PER_STEP` at full speed, at most :data:`MAX_DYNAMIC_STEP` (which a scene without a
    drive takes)."""
    speed = _fastest_drive_speed(scene)
    return MAX_DYNAMIC_STEP if speed is None else min(MAX_DYNAMIC_STEP, DRIVE_ANGLE_PER_STEP / speed)


def assemble(
    scene: Scene,
    steps: int | None = None,
    t: float = 0.0,
    q0: NDArray | None = None,
    convert: Callable[[MultibodySystem], MultibodySystem] | None = None,
) -> StaticSolution:
    """Static assembly at time ``t`` from ``q0`` (default the bodies' poses): gravity in two load
    steps on the closable system, then the misfit in ``steps`` increments (default
    :data:`STEPS_PER_DEGREE` per degree of the largest axis misfit, at least 1). ``convert`` maps
    each intermediate system (e.g. to other joint conventions)."""
    if scene.loose_joints:
        return _assemble_loose(scene, steps, t, q0, convert)
    if steps is None:
        steps = max(1, math.ceil(STEPS_PER_DEGREE * scene.misfit_degrees - 1e-6))
    convert = (lambda system: system) if convert is None else convert
    q = scene.q_initial if q0 is None else q0
    k = 0
    try:
        solution = static_equilibrium(convert(scene.with_misfit(0.0)), q, t=t, load_steps=2)
        for k in range(1, steps + 1):
            solution = static_equilibrium(convert(scene.with_misfit(k / steps)), solution.q, t=t)
    except StaticDivergence as error:
        # Name the scene and the continuation step: the solver's own message knows neither.
        gap = float(np.abs(scene.system.constraint_values(q, t)).max())
        raise AssemblyDivergence(
            f"static assembly of scene {scene.name!r} ({scene.misfit_degrees:.3g} deg of axis misfit) failed at "
            f"continuation step {k}/{steps} (gravity and a joint gap of {gap:.3g} at the start): {error}. The bodies "
            "must absorb the misfit elastically from the start pose; check the joints' axes (axis0, axis1), or "
            "for a large misfit assemble in more steps (assemble(scene, steps=...))"
        ) from error
    return solution


def _assemble_loose(
    scene: Scene,
    steps: int | None,
    t: float,
    q0: NDArray | None,
    convert: Callable[[MultibodySystem], MultibodySystem] | None,
) -> StaticSolution:
    """A scene whose joints have play: assembled with ideal joints first (the pins centred in their bores), then
    settled into its bores by pseudo-transient continuation (Eq. (P6)); where that stalls, the play is opened in
    :data:`PLAY_STEPS` steps from zero (bushings, which hold the pins where the ideal joints did), each settled from
    the last."""
    ideal = assemble(scene.with_ideal_joints(), steps, t, q0, convert)
    system = scene.system if convert is None else convert(scene.system)
    try:
        return settle(system, ideal.q, t)
    except StaticDivergence as error:
        stalled = error
    q = ideal.q
    try:
        for fraction in np.linspace(0.0, 1.0, PLAY_STEPS + 1):
            q = settle(_with_play_fraction(system, fraction), q, t).q
        return settle(system, q, t)
    except StaticDivergence as error:
        raise AssemblyDivergence(
            f"static assembly of scene {scene.name!r}: the pins of its joints with play "
            f"({', '.join(j.name for j in scene.loose_joints)}) did not settle into their bores, neither at once "
            f"({stalled}) nor with the play opened in {PLAY_STEPS} steps ({error})"
        ) from error


#: Steps in which the assembly of a linkage with play opens the play, where settling at once stalls.
PLAY_STEPS = 10


def _with_play_fraction(system: MultibodySystem, fraction: float) -> MultibodySystem:
    """``system`` with every joint's play (radial and axial) scaled by ``fraction``."""
    forces = tuple(
        replace(e, radial=fraction * e.radial, axial=fraction * e.axial) if isinstance(e, ClearanceJoint) else e
        for e in system.forces
    )
    return replace(system, forces=forces)


def starts_static(scene: Scene) -> bool:
    """Whether a run starts from :func:`assemble`: ``static_start`` if given, else for quasi-static
    runs and whenever a joint has a misfit."""
    s = scene.settings
    return bool(s.get("static_start", s.get("mode", "dynamic") != "dynamic" or scene.misfit_degrees > 0.0))


def start_state(scene: Scene) -> NDArray[np.float64]:
    """The state a run starts from: the bodies' poses, assembled statically (:func:`assemble`) when
    :func:`starts_static`."""
    return assemble(scene).q if starts_static(scene) else scene.q_initial.copy()
