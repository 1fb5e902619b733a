"""Sizes beyond which a run or a study is a typing mistake, not a plan: one table for scene files, linkage files,
study files and command-line flags (``docs/bad_input.md``, "Limits").

A request above a limit is refused before anything is built, with the estimate of its time or memory and the key
(or flag) that lifts the limit; the estimates use the measured costs below, so they are rough (a factor of a few)
but tell minutes from months. Plausibility ranges (link lengths) only warn: a linkage of 0.5 mm links may be meant.
"""

from __future__ import annotations

import math

from ffrf.scenes.step_sizes import DRIVE_ANGLE_PER_STEP, MAX_DRIVE_STEP, MAX_DYNAMIC_STEP

__all__ = [
    "LINK_LENGTH_RANGE",
    "MAX_OUTPUTS",
    "MAX_TIME_STEPS",
    "MAX_VARIANTS",
    "SECONDS_PER_STEP",
    "SECONDS_PER_VARIANT",
    "duration",
    "length_unit_problem",
    "linkage_run_steps",
    "memory",
    "steps_problem",
    "variants_problem",
]

#: Time steps (dynamic) or equilibria (quasi-static) of one run; override: ``[scene] max_steps`` / ``--max-steps``.
MAX_TIME_STEPS = 10_000_000
#: Output times of one run (each keeps every coordinate and sensor); not overridable.
MAX_OUTPUTS = 1_000_000
#: Variants of one study; override: ``[study] max_variants``.
MAX_VARIANTS = 100_000
#: Wall time of one dynamic step of the default Bennett scene, 0.44 ms (docs/speed_vs_error.md, full_revolution.json).
SECONDS_PER_STEP = 0.44e-3
#: Wall time of one variant of a small study (build from the cache, assemble, a quasi-static revolution): about 1 s
#: at best (docs/studies.md), so the estimate is a lower bound.
SECONDS_PER_VARIANT = 1.0
#: Link lengths (m) a linkage of this solver plausibly has; outside, a unit mistake (mm for m) is likelier.
LINK_LENGTH_RANGE = (1e-3, 10.0)


def duration(seconds: float) -> str:
    """``seconds`` as a rough human duration (``"3.2 h"``, ``"190 years"``)."""
    for unit, size in (("years", 3.156e7), ("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


def memory(n_bytes: float) -> str:
    """``n_bytes`` in binary units (``"7.28 TiB"``)."""
    for unit, size in (("PiB", 2.0**50), ("TiB", 2.0**40), ("GiB", 2.0**30), ("MiB", 2.0**20), ("KiB", 2.0**10)):
        if n_bytes >= size:
            return f"{n_bytes / size:.3g} {unit}"
    return f"{n_bytes:.0f} B"


def steps_problem(steps: float, limit: int | None, override: str, why: str = "") -> str | None:
    """The refusal of a run of ``steps`` time steps (or equilibria) above ``limit`` (default
    :data:`MAX_TIME_STEPS`), with its estimated time and ``override`` (the key or flag that lifts the limit)."""
    limit = MAX_TIME_STEPS if limit is None else limit
    if not math.isfinite(steps):
        return f"the run would take an unbounded number of time steps{why}"
    if steps <= limit:
        return None
    return (
        f"{steps:.3g} time steps{why} (more than {limit:.3g}; at least {duration(steps * SECONDS_PER_STEP)} at "
        f"{1e3 * SECONDS_PER_STEP:g} ms per step); check the units (seconds, revolutions) or the step, or set "
        f"{override} to run it anyway"
    )


def linkage_run_steps(
    omega: float, ramp_time: float, revolutions: float, mode: str = "auto", step: float | None = None
) -> float:
    """Estimated time steps (dynamic) or equilibria (quasi-static) of a linkage run: the cosine ramp of ``ramp_time``
    (s) to the drive speed ``omega`` (rad/s), then ``revolutions``; its end ``t_end = ramp_time + 2 pi revolutions /
    omega`` (the ramp turns ``omega ramp_time / 2``, :mod:`ffrf.scenes.linkage_description`). Dynamic: ``t_end /
    step`` (default step :func:`ffrf.scenes.assembly.dynamic_step`); quasi-static: the turn over
    :data:`ffrf.scenes.step_sizes.MAX_DRIVE_STEP`; ``auto``: the dynamic count when a ``step`` is given (it is there to
    be used), else the smaller, the count of either mode."""
    speed = abs(omega)
    turn = 0.5 * speed * ramp_time + 2.0 * math.pi * revolutions
    t_end = ramp_time + 2.0 * math.pi * revolutions / speed
    given = step is not None
    if step is None:
        step = min(MAX_DYNAMIC_STEP, DRIVE_ANGLE_PER_STEP / speed)
    dynamic, quasi_static = t_end / step, turn / MAX_DRIVE_STEP
    auto = dynamic if given else min(dynamic, quasi_static)
    return {"dynamic": dynamic, "quasi_static": quasi_static}.get(mode, auto)


def variants_problem(variants: int, parameters: int, limit: int | None) -> str | None:
    """The refusal of a study of ``variants`` rows of ``parameters`` values above ``limit`` (default
    :data:`MAX_VARIANTS`): its count, the memory of its design and its time at :data:`SECONDS_PER_VARIANT`."""
    limit = MAX_VARIANTS if limit is None else limit
    if variants <= limit:
        return None
    return (
        f"the design has {variants:.3g} variants (more than {limit:.3g}; its unit samples alone take "
        f"{memory(8.0 * variants * max(parameters, 1))}, and at {SECONDS_PER_VARIANT:g} s per variant it runs "
        f"{duration(variants * SECONDS_PER_VARIANT)} of worker time); use fewer samples or values, or set "
        f"max_variants = {variants} in [study] to run it anyway"
    )


def length_unit_problem(lengths_m: list[float], given: str) -> str | None:
    """Why link lengths ``lengths_m`` (m, zeros ignored: intersecting axes) look like a unit mistake, with the
    likely fix; ``given`` names where the unit was chosen (``unit = "mm"``, ``--unit mm``). ``None`` if plausible."""
    sizes = [abs(v) for v in lengths_m if v != 0.0 and math.isfinite(v)]
    if not sizes:
        return None
    low, high = LINK_LENGTH_RANGE
    longest = max(sizes)
    if longest < low:
        return (
            f"the longest link is {1e3 * longest:.3g} mm, below {1e3 * low:g} mm: lengths in metres read as "
            f"millimetres? check {given}"
        )
    if longest > high:
        return (
            f"the longest link is {longest:.4g} m, above {high:g} m: lengths in millimetres read as metres? "
            f"check {given}"
        )
    return None
