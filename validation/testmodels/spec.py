r"""What a TestModel twin is and how it is judged.

A :class:`TestModel` names one of Exudyn's regression models (``main/pythonDev/TestModels/<name>.py``
at commit e44aca1b), the number it stores (:class:`StoredValue`) and two runs of the same model:
:func:`TestModel.ours` (our solver, Newton to ``tolerance``) and :func:`TestModel.exudyn` (Exudyn's
own items, rebuilt from the script, at the script's solver settings or with tightened Newton
tolerances). Each run returns the TestModel's ``result`` (the number the script computes from its
sensor) and the sensor's rows (:class:`ModelRun`).

Judgement (:func:`judge`): ours passes if it is within :data:`STORED_TOLERANCE` (relative) of the stored
value. A stored value is Exudyn's run at its default Newton tolerances (relative 1e-8, absolute 1e-10,
modified Newton) and so carries that run's Newton error. Where that error is larger than
:data:`STORED_TOLERANCE` (Exudyn's run at the script's settings reproduces the stored value to
:data:`REPRODUCED_TOLERANCE`, its converged run with tightened tolerances misses it by more than
:data:`STORED_TOLERANCE`), ours passes if it is within :data:`CONVERGED_TOLERANCE` of that converged run
(NGsolveCMStest: both 1.24e-9 from the stored value). A wrong stored value is not explained so: Exudyn's
run at the script's settings would not reproduce it.

An :class:`Example` is one of Exudyn's examples (``main/pythonDev/Examples/<name>.py``): it stores no
value, so ours is judged against Exudyn's run of the same model (:func:`judge_example`): its sensor rows
within ``converged_tolerance`` (:data:`CONVERGED_TOLERANCE` unless the example states why its round-off
floor is higher) of Exudyn's converged run.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "EXUDYN_COMMIT",
    "STORED_TOLERANCE",
    "CONVERGED_TOLERANCE",
    "REPRODUCED_TOLERANCE",
    "TIGHT_RELATIVE",
    "TIGHT_ABSOLUTE",
    "TIGHT_RELATIVE_FALLBACK",
    "OUR_TOLERANCE",
    "FREQUENCY_TOLERANCE",
    "StoredValue",
    "ModelRun",
    "TestModel",
    "Example",
    "Verdict",
    "relative",
    "judge",
    "judge_example",
    "exudyn_settings",
    "exudyn_label",
    "solve",
    "add_with_user_functions",
]

#: Exudyn's commit the models and their stored values are read from.
EXUDYN_COMMIT = "e44aca1b4fe3e5f4d820ff407fb3fd30b6581c1c"
#: Ours against the stored value (relative).
STORED_TOLERANCE = 1e-9
#: Ours against Exudyn's converged run, both with tightened tolerances (relative).
CONVERGED_TOLERANCE = 1e-11
#: Exudyn's run at the script's settings reproduces the stored value (relative): the eigensolver's
#: basis (another one of the same span each run) moves it by up to 1e-12 (objectFFRFreducedOrderTest).
REPRODUCED_TOLERANCE = 1e-11
#: Exudyn's tightened Newton tolerances, full Newton (:func:`solve`). Relative 1e-10 is not enough for
#: superElementRigidJointTest (it moves by 4e-13); at relative 1e-12, 2 of 12 runs of
#: objectFFRFreducedOrderTest stopped (each run's eigensolver returns another basis of the same span,
#: and Newton's residual is measured in it), so :func:`solve` falls back to relative 1e-10 there
#: (12 of 12 finished). Exudyn's converged results scatter by up to 5e-12 from run to run.
TIGHT_RELATIVE = 1e-12
TIGHT_RELATIVE_FALLBACK = 1e-10
TIGHT_ABSOLUTE = 1e-12
#: Our Newton tolerance (``generalized_alpha``'s ``tolerance``, modified Newton) unless a model sets its own.
OUR_TOLERANCE = 1e-12


@dataclass(frozen=True)
class StoredValue:
    """The number a TestModel is checked against, in the units of the script's ``result``.

    ``value`` is what Exudyn's test suite compares with today: ``runTestSuiteRefSol.py``'s reference
    for ``testResult``, converted to ``result`` by the script's own ``testResult = ...`` line.
    ``in_script`` is the number in the script's ``exudynTestGlobals.testError = ... (result - X)`` line;
    the two differ where the script's line was not updated when the reference was (``note``).
    """

    value: float
    in_script: float
    suite_reference: str
    note: str = ""


@dataclass
class ModelRun:
    """One run of a TestModel: its ``result``, the sensor rows it was computed from (time first) and
    the wall time (s) of the whole run (model building, reduction and integration).

    Not a :class:`~ffrf.output.result.Result`: it holds what an Exudyn TestModel script computes, its scalar
    ``result`` and the one sensor file that scalar is computed from (Exudyn's layout), filled the same way by
    Exudyn's run and by ours (each model's ``ours`` and ``exudyn``), so that both are judged against Exudyn's stored
    value in the script's own terms."""

    result: float
    sensor: NDArray[np.float64]
    seconds: float
    settings: str


@dataclass(frozen=True)
class TestModel:
    """One of Exudyn's TestModels and its twin.

    ``ours`` takes our Newton tolerance (``tolerance``: :data:`OUR_TOLERANCE`, or 1e-13 where that stops
    short of the converged result), ``exudyn`` ``tight`` (False: the script's settings). ``time_in_result``:
    the result sums the sensor's time column too. ``missing`` names what our solver lacks for a model
    it cannot express (then ``ours`` is not called); ``slow``: ours takes more than 20 s."""

    name: str
    description: str
    result_formula: str
    stored: StoredValue
    ours: Callable[[float], ModelRun]
    exudyn: Callable[[bool], ModelRun]
    time_in_result: bool = False
    tolerance: float = OUR_TOLERANCE
    missing: str = ""
    slow: bool = False

    __test__ = False  # not a pytest class


@dataclass(frozen=True)
class Example:
    """One of Exudyn's examples and its twin; no stored value (see the module docstring).

    ``source_blob``: the script's git blob id at :data:`EXUDYN_COMMIT`. ``converged_tolerance``: ours
    against Exudyn's converged run, sensor rows (largest difference over largest value); above
    :data:`CONVERGED_TOLERANCE` only with ``floor_reason``. ``frequencies``: named eigenfrequency
    sets (Hz) to report, ``"ours"`` and ``"exudyn"`` (same mesh) judged to ``FREQUENCY_TOLERANCE``."""

    name: str
    source_blob: str
    description: str
    result_formula: str
    ours: Callable[[float], ModelRun]
    exudyn: Callable[[bool], ModelRun]
    tolerance: float = OUR_TOLERANCE
    converged_tolerance: float = CONVERGED_TOLERANCE
    floor_reason: str = ""
    frequencies: Callable[[], dict[str, NDArray[np.float64]]] | None = None
    slow: bool = True

    __test__ = False

    def __post_init__(self) -> None:
        if self.converged_tolerance > CONVERGED_TOLERANCE and not self.floor_reason:
            raise ValueError(f"example {self.name}: a tolerance above {CONVERGED_TOLERANCE:g} needs its reason")


#: Our fixed-interface eigenfrequencies against Exudyn's on the same mesh (relative).
FREQUENCY_TOLERANCE = 1e-9


def relative(a: float, b: float) -> float:
    """``|a - b|`` / ``|b|``."""
    return abs(a - b) / abs(b)


@dataclass
class Verdict:
    """``passed`` and how: against the stored value, or against Exudyn's converged run where the stored
    value carries Exudyn's Newton error (``reason`` says which and by how much)."""

    passed: bool
    reason: str
    checks: dict[str, float] = field(default_factory=dict)


def judge(stored: float, ours: float, exudyn: float | None = None, exudyn_tight: float | None = None) -> Verdict:
    """The rule of the module docstring; ``exudyn`` and ``exudyn_tight``: the results of Exudyn's runs at
    the script's settings and with tightened tolerances (None: not run)."""
    off = relative(ours, stored)
    checks = {"ours_vs_stored": off}
    if off <= STORED_TOLERANCE:
        return Verdict(True, f"ours - stored = {off:.1e} <= {STORED_TOLERANCE:g}", checks)
    if exudyn is None or exudyn_tight is None:
        return Verdict(False, f"ours - stored = {off:.1e} > {STORED_TOLERANCE:g} (Exudyn not run)", checks)
    reproduced = relative(exudyn, stored)
    newton_error = relative(exudyn_tight, stored)
    to_converged = relative(ours, exudyn_tight)
    checks |= {
        "exudyn_vs_stored": reproduced,
        "exudyn_converged_vs_stored": newton_error,
        "ours_vs_exudyn_converged": to_converged,
    }
    explained = reproduced <= REPRODUCED_TOLERANCE and newton_error > STORED_TOLERANCE
    if explained and to_converged <= CONVERGED_TOLERANCE:
        return Verdict(
            True,
            f"ours - stored = {off:.1e} > {STORED_TOLERANCE:g}, but Exudyn's converged run is {newton_error:.1e} "
            f"from the stored value too (its run at the script's settings {reproduced:.0e}: the stored value's "
            f"Newton error), and ours is {to_converged:.1e} from the converged run",
            checks,
        )
    return Verdict(
        False,
        f"ours - stored = {off:.1e} > {STORED_TOLERANCE:g}; Exudyn at the script's settings - stored = "
        f"{reproduced:.1e}, Exudyn converged - stored = {newton_error:.1e}, "
        f"ours - Exudyn converged = {to_converged:.1e}",
        checks,
    )


def judge_example(example: Example, ours_vs_converged: float, frequency_error: float | None = None) -> Verdict:
    """Ours passes if its sensor rows are within ``example.converged_tolerance`` of Exudyn's converged
    run and, where compared, its eigenfrequencies within :data:`FREQUENCY_TOLERANCE` of Exudyn's."""
    checks = {"ours_vs_exudyn_converged": ours_vs_converged}
    bound = example.converged_tolerance
    passed = ours_vs_converged <= bound
    reason = f"sensor rows: ours - Exudyn converged = {ours_vs_converged:.1e} {'<=' if passed else '>'} {bound:g}"
    if bound > CONVERGED_TOLERANCE:
        reason += f" ({example.floor_reason})"
    if frequency_error is not None:
        checks["frequencies_ours_vs_exudyn"] = frequency_error
        fine = frequency_error <= FREQUENCY_TOLERANCE
        passed = passed and fine
        reason += f"; eigenfrequencies {frequency_error:.1e} {'<=' if fine else '>'} {FREQUENCY_TOLERANCE:g}"
    return Verdict(passed, reason, checks)


def exudyn_settings(step: float, t_end: float, rho_inf: float, relative_tolerance: float | None = None):
    """A TestModel's ``SimulationSettings``: ``int(tEnd/h)`` steps, sensors every step, modified Newton,
    spectral radius ``rho_inf``, no solution file, everything else Exudyn's default; with
    ``relative_tolerance``: full Newton to it and :data:`TIGHT_ABSOLUTE`, no step-size reduction."""
    import exudyn as exu

    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.numberOfSteps = int(t_end / step)
    ti.endTime = t_end
    ti.verboseMode = 0
    ti.generalizedAlpha.spectralRadius = rho_inf
    if relative_tolerance is not None:
        ti.newton.useModifiedNewton = False
        ti.newton.relativeTolerance = relative_tolerance
        ti.newton.absoluteTolerance = TIGHT_ABSOLUTE
        ti.adaptiveStep = False  # a step Newton cannot finish fails the run instead of being cut
    else:
        ti.newton.useModifiedNewton = True
    s.solution.sensors.writePeriod = step
    s.solution.file.write = False
    return s


def solve(mbs, step: float, t_end: float, rho_inf: float, tight: bool) -> float | None:
    """``mbs.SolveDynamic`` at the script's settings, or with tightened tolerances: relative
    :data:`TIGHT_RELATIVE`, and if Exudyn's Newton cannot get there (its residual's round-off; about one
    run in six of objectFFRFreducedOrderTest) :data:`TIGHT_RELATIVE_FALLBACK`. Returns the relative
    tolerance used (None: the script's)."""
    import exudyn as exu

    if not tight:
        mbs.SolveDynamic(exudyn_settings(step, t_end, rho_inf))
        return None
    try:
        mbs.SolveDynamic(exudyn_settings(step, t_end, rho_inf, TIGHT_RELATIVE))
        return TIGHT_RELATIVE
    except exu.SolverError:
        mbs.SolveDynamic(exudyn_settings(step, t_end, rho_inf, TIGHT_RELATIVE_FALLBACK))
        return TIGHT_RELATIVE_FALLBACK


def exudyn_label(relative_tolerance: float | None) -> str:
    """The settings of an Exudyn run (:func:`solve`'s return value), for the report."""
    if relative_tolerance is None:
        return "exudyn, the script's settings (modified Newton, relative 1e-8, absolute 1e-10)"
    return f"exudyn, full Newton, relative {relative_tolerance:g}, absolute {TIGHT_ABSOLUTE:g}"


def add_with_user_functions(cms, exu, mbs, **arguments) -> dict:
    """``cms.AddObjectFFRFreducedOrderWithUserFunctions(exu, mbs, **arguments)`` as the scripts call it,
    with ``eulerParametersRef`` (deprecated since Exudyn 1.11; kept: it makes the Euler-parameter node
    the stored values were computed with), its deprecation warning silenced."""
    with warnings.catch_warnings():
        warnings.filterwarnings(
            "ignore", "the argument FEM.AddObjectFFRFreducedOrderWithUserFunctions", DeprecationWarning
        )
        return cms.AddObjectFFRFreducedOrderWithUserFunctions(exu, mbs, **arguments)
