r"""The lightest section that keeps a linkage's coupler on its ideal path: gradient-based design on exact
sensitivities (``docs/formulation.md``, Eq. (D6); issue #35).

The links' section dimensions :math:`p` (fields of :class:`~ffrf.geometry.link_geometry.LinkDesign` that leave the
bores in place, every link alike) solve

.. math:: \min_p\ m(p) \quad\text{s.t.}\quad |d_i(p)| \le \bar d,\ \ \mu_i(p) \ge (2\pi \underline f)^2,
          \ \ v_{ik}(p) \le \bar v \ \text{at every pose } i \text{ and link } k,\qquad p_{lo} \le p \le p_{hi},

with :math:`m` the links' mass, :math:`d_i` the coupler's deviation from the ideal path at pose :math:`i` of a
quasi-static revolution under the linkage's load (its weight, its bore errors) and, where a lowest frequency
:math:`\underline f` is asked for, :math:`\mu_i` the lowest squared frequency of Eq. (B1) there (its gradient by
Eq. (D7)); where a stress bound :math:`\bar v` is asked for, :math:`v_{ik}` the p-norm of link :math:`k`'s von
Mises stresses there (Eq. (D10): smooth where the peak of Eq. (D9) is not, and never below it), of the strains
averaged over balls of the problem's radius around each vertex (Eq. (D14): finite where the corner strains are
singular). Each design is
meshed and run afresh; the gradients are exact for the meshed model (Eq. (D1) with the section's morph, Eq. (D5),
:func:`~ffrf.scenes.path_sensitivity.section_sensitivity`): :math:`\partial|d_i|/\partial p = d_i^T
(\partial d_i/\partial p)/|d_i|`. scipy's SLSQP works in dimensions relative to the start, mass relative to the
start's and deviations relative to the bound. At its end the first-order optimality (KKT) residual is measured
independently of SLSQP: the objective's gradient against the non-negative combination (``scipy.optimize.nnls``) of
the active constraints' and bounds' gradients.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize, nnls

from ffrf.errors import GeometryError, SceneError
from ffrf.geometry.design_velocity import SECTION_PARAMETERS
from ffrf.scenes.linkage_description import LinkageOptions
from ffrf.scenes.linkage_file import LINKAGE_SCHEMA, linkage_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.scenes.path_sensitivity import MORPH_STEP, section_sensitivity, section_velocities
from ffrf.scenes.scene_schema import Key, check_table
from ffrf.scenes.schema_keys import positive
from kinematics.single_loop import SingleLoop

__all__ = [
    "ACTIVE",
    "DESIGN",
    "FEASIBLE",
    "FTOL",
    "KKT_TOLERANCE",
    "DesignPoint",
    "DesignProblem",
    "SectionDesign",
    "designed_document",
    "evaluate",
    "load_design",
    "optimise_section",
]

#: A design file's ``[design]`` table (lengths in the linkage's ``unit``): the section dimensions every link shares,
#: their bounds, the bound on the coupler's deviation, the poses it is checked at and SLSQP's iteration limit.
DESIGN = {
    "parameters": Key("strings", True),
    "lower": Key("numbers", True),
    "upper": Key("numbers", True),
    "max_deviation": Key("number", True, positive),
    "min_frequency_hz": Key("number", False, positive),
    "max_stress_mpa": Key("number", False, positive),
    "stress_radius": Key("number", False, positive),
    "min_clearance": Key("number", False, positive),
    "outputs": Key("integer", False, positive),
    "max_iterations": Key("integer", False, positive),
}

#: SLSQP's tolerance on the objective (the mass relative to the start's): each design is meshed afresh, so its mass
#: and deviations carry the meshes' own differences (about 1e-4 and 3e-3 of a change by a millimetre, measured), and
#: on the bound SLSQP wanders within them at a tighter tolerance (measured on the PLA Bennett: 3e-4 of the mass).
FTOL = 1e-3
#: Poses of the rigid revolution at which a clearance bound is checked (and bounded between them, Eq. (CL4)).
CLEARANCE_POSES = 72
#: A design meets the bound when its largest deviation exceeds it by at most this fraction.
FEASIBLE = 1e-3
#: An optimum is accepted when its KKT residual (relative to the objective's gradient) is below this.
KKT_TOLERANCE = 2e-2

#: A constraint or bound within this fraction of its scale counts as active in the KKT residual: ten times FTOL, as
#: SLSQP stops within about FTOL of a bound (at FTOL itself a constraint 0.99e-3 from its bound counted on one BLAS
#: kernel and not on another).
ACTIVE = 1e-2


@dataclass(frozen=True)
class DesignProblem:
    """The section ``parameters`` with their ``lower`` and ``upper`` bounds (m), the bound on the coupler's
    deviation ``max_deviation`` (m) at each of ``outputs`` poses of a revolution, SLSQP's ``max_iterations`` and,
    optionally, the least lowest vibration frequency ``min_frequency_hz`` (Hz, Eq. (B1)) at each pose and the
    largest von Mises stress of any link ``max_stress`` (Pa) at each pose, averaged over balls of ``stress_radius``
    (m, Eq. (D14): the corner stress of Eq. (D9) is singular where an arm meets its housing), and the least clearance
    of every pair of links along a revolution of the rigid motion ``min_clearance`` (m, Eqs. (CL1)-(CL5))."""

    parameters: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    max_deviation: float
    outputs: int = 25
    max_iterations: int = 20
    min_frequency_hz: float | None = None
    max_stress: float | None = None
    min_clearance: float | None = None
    stress_radius: float | None = None

    @property
    def min_squared_frequency(self) -> float | None:
        """The frequency bound as a squared angular frequency (rad^2/s^2), Eq. (B1)'s unit."""
        return None if self.min_frequency_hz is None else (2.0 * np.pi * self.min_frequency_hz) ** 2

    def __post_init__(self) -> None:
        unknown = [p for p in self.parameters if p not in SECTION_PARAMETERS]
        if unknown or not self.parameters:
            raise SceneError(f"design parameters {list(self.parameters)}: choose from {list(SECTION_PARAMETERS)}")
        if not len(self.lower) == len(self.upper) == len(self.parameters):
            raise SceneError("design: give one lower and one upper bound per parameter")
        if any(not 0.0 < lo < hi for lo, hi in zip(self.lower, self.upper, strict=True)):
            raise SceneError(f"design: every bound needs 0 < lower < upper, got {self.lower} and {self.upper}")
        if not self.max_deviation > 0.0:
            raise SceneError(f"design: max_deviation must be > 0, got {self.max_deviation!r}")
        if self.outputs < 3:
            raise SceneError(f"design: outputs must be at least 3 poses, got {self.outputs}")
        if self.min_frequency_hz is not None and not self.min_frequency_hz > 0.0:
            raise SceneError(f"design: min_frequency_hz must be > 0, got {self.min_frequency_hz!r}")
        if self.max_stress is not None and not self.max_stress > 0.0:
            raise SceneError(f"design: max_stress_mpa must be > 0, got {self.max_stress!r} Pa")
        if (self.max_stress is None) != (self.stress_radius is None):
            raise SceneError(
                "design: give max_stress_mpa and stress_radius together: the links' stress is singular where an arm "
                "meets its housing, so the bound holds the stress averaged over balls of stress_radius (the "
                "material's critical distance, in the linkage's unit; Eq. (D14))"
            )
        if self.stress_radius is not None and not self.stress_radius > 0.0:
            raise SceneError(f"design: stress_radius must be > 0, got {self.stress_radius!r} m")
        if self.min_clearance is not None and not self.min_clearance > 0.0:
            raise SceneError(f"design: min_clearance must be > 0, got {self.min_clearance!r} m")


@dataclass(frozen=True)
class DesignPoint:
    """One design, meshed and run: its parameter ``values`` (m), the links' ``mass`` (kg) and the coupler's
    ``deviation`` (m) at each pose, with their gradients by the parameters (``(k,)`` and ``(poses, k)``); for a
    problem with a frequency bound the lowest squared frequency of Eq. (B1) at each pose (rad^2/s^2) and its
    gradients likewise, and for one with a stress bound every link's peak von Mises stress at each pose
    ``(poses, links)`` (Pa, Eq. (D9), of the strains averaged over the problem's balls, Eq. (D14)) and the norm of
    those stresses that the bound holds, ``stress_norm`` (Pa, Eq. (D10)), with the norm's gradients
    ``(poses, links, k)``; for one with a clearance bound the smallest clearance of each pair of links along the
    revolution ``clearance`` ``(pairs,)`` (m, Eq. (CL1)) and its gradients ``(pairs, k)`` (Eq. (CL5)), the pairs
    ``clearance_pairs`` ``(pairs, 2)``."""

    values: NDArray[np.float64]
    mass: float
    deviation: NDArray[np.float64]
    mass_gradient: NDArray[np.float64]
    deviation_gradient: NDArray[np.float64]
    seconds: float
    frequency: NDArray[np.float64] | None = None
    frequency_gradient: NDArray[np.float64] | None = None
    stress: NDArray[np.float64] | None = None
    stress_gradient: NDArray[np.float64] | None = None
    stress_norm: NDArray[np.float64] | None = None
    clearance: NDArray[np.float64] | None = None
    clearance_gradient: NDArray[np.float64] | None = None
    clearance_pairs: NDArray[np.int64] | None = None

    @property
    def max_deviation(self) -> float:
        return float(self.deviation.max())

    @property
    def max_stress(self) -> float | None:
        """The largest von Mises stress of any link over the poses (Pa), where computed."""
        return None if self.stress is None else float(np.nanmax(self.stress))

    @property
    def max_stress_norm(self) -> float | None:
        """The largest norm of Eq. (D10) of any link over the poses (Pa): what the stress bound holds."""
        return None if self.stress_norm is None else float(np.nanmax(self.stress_norm))

    @property
    def min_frequency_hz(self) -> float | None:
        """The lowest vibration frequency over the poses (Hz), where computed."""
        return None if self.frequency is None else float(np.sqrt(max(self.frequency.min(), 0.0)) / (2.0 * np.pi))

    def margins(self, problem: DesignProblem) -> NDArray[np.float64]:
        """Every constraint's margin, non-negative where met: the deviations' relative to their bound, then the
        squared frequencies' relative to theirs."""
        out = [1.0 - self.deviation / problem.max_deviation]
        if problem.min_squared_frequency is not None and self.frequency is not None:
            out.append(self.frequency / problem.min_squared_frequency - 1.0)
        if problem.max_stress is not None and self.stress_norm is not None:  # a link without elements: no bound
            out.append(np.nan_to_num(1.0 - self.stress_norm / problem.max_stress, nan=1.0).ravel())
        if problem.min_clearance is not None and self.clearance is not None:
            out.append(self.clearance / problem.min_clearance - 1.0)
        return np.concatenate(out)

    def margin_gradients(self, problem: DesignProblem) -> NDArray[np.float64]:
        """The margins' gradients by the parameters (m^-1), ``(constraints, k)``."""
        out = [-self.deviation_gradient / problem.max_deviation]
        if problem.min_squared_frequency is not None and self.frequency_gradient is not None:
            out.append(self.frequency_gradient / problem.min_squared_frequency)
        if problem.max_stress is not None and self.stress_gradient is not None:
            slopes = self.stress_gradient.reshape(-1, self.stress_gradient.shape[-1])
            out.append(np.nan_to_num(-slopes / problem.max_stress, nan=0.0))
        if problem.min_clearance is not None and self.clearance_gradient is not None:
            out.append(self.clearance_gradient / problem.min_clearance)
        return np.vstack(out)

    def constraint_names(self, problem: DesignProblem) -> list[str]:
        """What each of :meth:`margins` bounds, in order."""
        poses = len(self.deviation)
        names = [f"deviation at pose {i}" for i in range(poses)]
        if problem.min_squared_frequency is not None and self.frequency is not None:
            names += [f"frequency at pose {i}" for i in range(poses)]
        if problem.max_stress is not None and self.stress_norm is not None:
            links = self.stress_norm.shape[1]
            names += [f"stress of link {k} at pose {i}" for i in range(poses) for k in range(links)]
        if problem.min_clearance is not None and self.clearance_pairs is not None:
            names += [f"clearance of links {a}-{b}" for a, b in self.clearance_pairs]
        return names

    def feasible(self, problem: DesignProblem) -> bool:
        """Whether every constraint is met to :data:`FEASIBLE`."""
        return bool(self.margins(problem).min() >= -FEASIBLE)


@dataclass(frozen=True)
class SectionDesign:
    """An optimisation's ``start`` and ``optimum`` (the lightest design evaluated that meets the bound), every design
    evaluated (``history``), SLSQP's ``iterations`` and ``message``, ``success`` (:func:`optimise_section`), and
    the KKT residual (relative to the objective's gradient) with the multipliers of the active constraints (poses)
    and bounds."""

    problem: DesignProblem
    start: DesignPoint
    optimum: DesignPoint
    history: tuple[DesignPoint, ...]
    iterations: int
    success: bool
    message: str
    kkt_residual: float
    active: dict[str, float] = field(default_factory=dict)


def evaluate(loop: SingleLoop, options: LinkageOptions, problem: DesignProblem, values: NDArray) -> DesignPoint:
    """Mesh and run the linkage with the section ``values`` (m) and differentiate its mass and deviations (every link
    alike: the derivative by a common dimension is the sum of the links')."""
    started = time.perf_counter()
    design = replace(options.design, **dict(zip(problem.parameters, map(float, values), strict=True)))
    scene = build_linkage(loop, replace(options, design=design))
    result = run_linkage(scene, mode="quasi_static", n_outputs=problem.outputs, sensors="path")
    assert result.multipliers is not None  # a quasi-static run keeps its equilibria's multipliers
    try:
        velocities = section_velocities(scene, problem.parameters)
        exact = section_sensitivity(
            scene,
            result.time,
            result.q,
            result.multipliers,
            problem.parameters,
            velocities=velocities,
            stability=problem.min_frequency_hz is not None,
            stress=problem.max_stress is not None,
            stress_radius=problem.stress_radius,
        )
    except GeometryError as error:
        section = ", ".join(f"{p} {1e3 * v:.4g} mm" for p, v in zip(problem.parameters, values, strict=True))
        raise SceneError(f"design at {section}: {error}; keep the bounds away from that section") from error
    assert exact.mass is not None
    k = len(problem.parameters)
    coupler = exact.coupler_point.reshape(len(result.time), 3, -1, k).sum(axis=2)
    deviation = np.asarray(result.sensors["coupler_deviation"], dtype=float)
    size = np.linalg.norm(deviation, axis=1)
    direction = deviation / np.maximum(size, np.finfo(float).tiny)[:, None]
    frequency_gradient = (
        None
        if exact.lowest_squared_frequency is None
        else exact.lowest_squared_frequency.reshape(len(result.time), -1, k).sum(axis=1)
    )
    stress_gradient = (
        None
        if exact.stress_norm_slopes is None
        else exact.stress_norm_slopes.reshape(len(result.time), len(scene.bodies), -1, k).sum(axis=2)
    )
    clearance = gradient = pairs = None
    if problem.min_clearance is not None:  # every link alike: each velocity moves all links, so both of a pair
        found = scene.clearance(CLEARANCE_POSES, problem.min_clearance)
        steps = MORPH_STEP * np.asarray(values, dtype=float)
        clearance, pairs = found.distance, found.pairs
        gradient = scene.clearance_slopes(found, velocities, problem.parameters, steps, CLEARANCE_POSES)
    return DesignPoint(
        np.asarray(values, dtype=float),
        float(sum(body.moments.mass for body in scene.system.bodies)),
        size,
        exact.mass.reshape(-1, k).sum(axis=0),
        np.einsum("pa,pak->pk", direction, coupler),
        time.perf_counter() - started,
        exact.squared_frequency,
        frequency_gradient,
        exact.peak_stress,
        stress_gradient,
        exact.stress_norm,
        clearance,
        gradient,
        pairs,
    )


def optimise_section(
    loop: SingleLoop,
    options: LinkageOptions,
    problem: DesignProblem,
    progress: Callable[[int, DesignPoint], None] | None = None,
) -> SectionDesign:
    """Solve the module docstring's problem from the linkage's own section (clipped to the bounds) with SLSQP;
    ``progress(iteration, design)`` after each iteration. The optimum is accepted (``success``) when it meets the
    bound to :data:`FEASIBLE` and its KKT residual is below :data:`KKT_TOLERANCE`, whatever SLSQP's own message."""
    lower, upper = np.asarray(problem.lower), np.asarray(problem.upper)
    scale = np.clip([getattr(options.design, p) for p in problem.parameters], lower, upper)
    evaluated: dict[bytes, DesignPoint] = {}
    history: list[DesignPoint] = []

    def at(x: NDArray) -> DesignPoint:
        key = np.asarray(x, dtype=float).tobytes()
        if key not in evaluated:
            evaluated[key] = evaluate(loop, options, problem, np.asarray(x) * scale)
            history.append(evaluated[key])
        return evaluated[key]

    mass0 = at(np.ones(len(scale))).mass

    def objective(x: NDArray) -> tuple[float, NDArray]:
        point = at(x)
        return point.mass / mass0, point.mass_gradient * scale / mass0

    def margins(x: NDArray) -> NDArray:
        return at(x).margins(problem)

    def margin_gradients(x: NDArray) -> NDArray:
        return at(x).margin_gradients(problem) * scale

    iteration = 0

    def callback(x: NDArray) -> None:
        nonlocal iteration
        iteration += 1
        if progress is not None:
            progress(iteration, at(x))

    solution = minimize(
        objective,
        np.ones(len(scale)),
        jac=True,
        method="SLSQP",
        bounds=list(zip(lower / scale, upper / scale, strict=True)),
        constraints=[{"type": "ineq", "fun": margins, "jac": margin_gradients}],
        callback=callback,
        options={"maxiter": problem.max_iterations, "ftol": FTOL},
    )
    # SLSQP returns its last iterate; take the lightest design that meets the bound among those it ran
    feasible = [p for p in history if p.feasible(problem)]
    optimum = min(feasible, key=lambda p: p.mass) if feasible else at(solution.x)
    residual, active = _kkt(problem, optimum, optimum.values / scale, scale, mass0)
    success = bool(feasible) and residual < KKT_TOLERANCE
    return SectionDesign(
        problem,
        history[0],
        optimum,
        tuple(history),
        int(solution.nit),
        success,
        str(solution.message),
        residual,
        active,
    )


def _kkt(
    problem: DesignProblem, point: DesignPoint, x: NDArray, scale: NDArray, mass0: float
) -> tuple[float, dict[str, float]]:
    """The first-order optimality residual at ``point`` (relative to the objective's gradient, in SLSQP's scaled
    variables ``x``) and the non-negative multipliers of the active constraints and bounds that minimise it."""
    gradient = point.mass_gradient * scale / mass0
    columns, names = [], []
    margins, gradients = point.margins(problem), point.margin_gradients(problem)
    labels = point.constraint_names(problem)
    for i in np.flatnonzero(margins < ACTIVE):
        columns.append(gradients[i] * scale)
        names.append(labels[i])
    for j, name in enumerate(problem.parameters):
        unit = np.zeros(len(scale))
        unit[j] = 1.0
        if x[j] * scale[j] <= problem.lower[j] * (1.0 + ACTIVE):
            columns.append(unit)
            names.append(f"{name} at its lower bound")
        if x[j] * scale[j] >= problem.upper[j] * (1.0 - ACTIVE):
            columns.append(-unit)
            names.append(f"{name} at its upper bound")
    if not columns:
        return float(np.linalg.norm(gradient) / np.linalg.norm(gradient)), {}
    multipliers, residual = nnls(np.column_stack(columns), gradient)
    return float(residual / np.linalg.norm(gradient)), dict(zip(names, map(float, multipliers), strict=True))


def load_design(document: dict, where: str = "design") -> tuple[SingleLoop, LinkageOptions, DesignProblem]:
    """A design file (already parsed): a linkage file (:mod:`ffrf.scenes.linkage_file`) with a ``[design]`` table
    (:data:`DESIGN`), lengths in the linkage's ``unit``. Returns the loop, the options it builds the linkage with and
    the problem in SI units."""
    check_table(document, dict(LINKAGE_SCHEMA, design=Key("table", True, keys=DESIGN)), where)
    loop, options, _ = linkage_options({k: v for k, v in document.items() if k != "design"}, where)
    spec = document["design"]
    length = 1e-3 if document["linkage"].get("unit") == "mm" else 1.0
    try:
        problem = DesignProblem(
            tuple(spec["parameters"]),
            tuple(length * float(v) for v in spec["lower"]),
            tuple(length * float(v) for v in spec["upper"]),
            length * float(spec["max_deviation"]),
            int(spec.get("outputs", 25)),
            int(spec.get("max_iterations", 20)),
            float(spec["min_frequency_hz"]) if "min_frequency_hz" in spec else None,
            1e6 * float(spec["max_stress_mpa"]) if "max_stress_mpa" in spec else None,
            length * float(spec["min_clearance"]) if "min_clearance" in spec else None,
            length * float(spec["stress_radius"]) if "stress_radius" in spec else None,
        )
    except SceneError as error:
        raise SceneError(f"{where}, {error}") from error
    return loop, options, problem


def designed_document(document: dict, design: SectionDesign) -> dict:
    """The design file's linkage (without ``[design]``) with the optimum's section in its ``link_design``, in the
    file's unit: a linkage file of the designed linkage."""
    length = 1e-3 if document["linkage"].get("unit") == "mm" else 1.0
    chosen = {p: float(v) / length for p, v in zip(design.problem.parameters, design.optimum.values, strict=True)}
    linkage = dict(document["linkage"], link_design=dict(document["linkage"].get("link_design", {}), **chosen))
    return {k: v for k, v in dict(document, linkage=linkage).items() if k != "design"}
