r"""Tolerance analysis of bore errors to first and second order: a study's prints in a second
(``docs/formulation.md``, (D3), (D11)).

A study whose parameters are bore errors (twist, offset, axial, tilt, shift of
:class:`~ffrf.scenes.linkage_description.BoreError` in the misfit model) varies a linkage whose quasi-static path
responds smoothly to them. To first order the coupler's deviation from the ideal path at pose :math:`i` of a print
with errors :math:`e` is

.. math:: d_i(e) \approx d_i(0) + S_i\,e,

with :math:`d_i(0)` the base's own deviation (its gravity sag, its own bore errors) and :math:`S_i` the exact
derivatives of Eq. (D1) at the base's equilibria (:func:`ffrf.scenes.path_sensitivity.bore_sensitivity`): one run
and one sensitivity solve per pose, then any number of prints by a matrix product (:meth:`LinearPath.max_deviation`,
the largest :math:`|d_i(e)|` over the poses, the study's ``max_coupler_deviation_m``). Percentiles come with their
95 % confidence interval from the order statistics of the sample (:func:`percentiles`). The model holds while the
errors are small against what bends the path; :func:`check_with_full_runs` compares it with full runs of some of the
study's own prints and says where they disagree.

Where the first order is not enough (the driving torque: the misfit's strain energy is of second order in the
errors), :func:`second_order` adds each output's second derivatives by every pair of parameters, Eq. (D11),

.. math:: d_i(e) \approx d_i(0) + S_i\,e + \tfrac12\,e^T H_i\,e,

from central second differences of full runs of the base (:func:`second_differences`): the same sampling, checks
and percentiles then hold to second order.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import SensitivityError
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.path_sensitivity import bore_sensitivity
from ffrf.studies.sampling import study_design, values_from_unit
from ffrf.studies.spec import Study
from ffrf.studies.statistics import exceedance, percentile_interval
from ffrf.studies.variant import BORE_FIELDS, build_variant, run_variant, variant_options

__all__ = [
    "CHECK_TOLERANCE",
    "LinearPath",
    "check_linear",
    "check_first_differences",
    "check_with_full_runs",
    "second_differences",
    "second_order",
    "first_order_stability",
    "linear_path",
    "allocate",
    "linear_report",
    "percentiles",
    "sample_values",
]

#: Largest relative difference between the linear model's and a full run's largest deviation before a check warns.
CHECK_TOLERANCE = 0.05
#: Largest difference, relative to the largest exact slope of a parameter, between the exact slopes and the first
#: differences of the second order's full runs (their third-order term: a few percent at a spread's step).
SLOPE_AGREEMENT = 0.2
#: Prints per block of :meth:`LinearPath.max_deviation` (memory: poses x 3 x block doubles, and with curvature the
#: block's k (k + 1) / 2 monomials).
_BLOCK = 20_000


@dataclass(frozen=True)
class LinearPath:
    """The coupler's deviation along a study's base path to first order in its parameters (module docstring):
    ``nominal`` ``(poses, 3)`` (m) at the base, ``slopes`` ``(poses, 3, k)`` (m per unit of each parameter, in the
    study's units: deg, mm), at the ``drive_angle`` (rad) of the base run's outputs; ``seconds``: the base run's and
    the sensitivities' wall time; the driving torque likewise, ``torque`` ``(poses,)`` (N m) and ``torque_slopes``
    ``(poses, k)``, where given; and for a study that monitors stability the lowest squared frequency of Eq. (B1),
    ``frequency`` ``(poses,)`` (rad^2/s^2) and ``frequency_slopes`` ``(poses, k)``; to second order (Eq. (D11),
    :func:`second_order`) the deviation's second derivatives ``curvature`` ``(poses, 3, k, k)`` and the torque's
    ``torque_curvature`` ``(poses, k, k)`` (per unit of each pair of parameters), which every print then includes."""

    parameters: tuple[str, ...]
    drive_angle: NDArray[np.float64]
    nominal: NDArray[np.float64]
    slopes: NDArray[np.float64]
    seconds: dict[str, float]
    torque: NDArray[np.float64] | None = None
    torque_slopes: NDArray[np.float64] | None = None
    frequency: NDArray[np.float64] | None = None
    frequency_slopes: NDArray[np.float64] | None = None
    curvature: NDArray[np.float64] | None = None
    torque_curvature: NDArray[np.float64] | None = None

    @property
    def order(self) -> int:
        """1 for the first-order model, 2 where its second derivatives are given."""
        return 1 if self.curvature is None else 2

    def min_squared_frequency(self, values: NDArray) -> NDArray[np.float64]:
        """``(n,)``: each print's lowest squared frequency of Eq. (B1) over the poses (rad^2/s^2); zero or below
        where the first order says the print reaches a fold (snaps), beyond which it does not hold."""
        if self.frequency is None or self.frequency_slopes is None:
            raise ValueError("this linear model has no stability: the study does not monitor it")
        nominal, slopes = self.frequency, self.frequency_slopes
        return _blockwise(values, lambda block: (nominal[:, None] + slopes @ block.T).min(axis=0))

    def max_torque(self, values: NDArray) -> NDArray[np.float64]:
        """``(n,)``: each print's largest driving torque magnitude over the poses (N m)."""
        if self.torque is None or self.torque_slopes is None:
            raise ValueError("this linear model has no driving torque")
        nominal, slopes, curvature = self.torque, self.torque_slopes, self.torque_curvature

        def largest(block: NDArray) -> NDArray[np.float64]:
            torque = nominal[:, None] + slopes @ block.T
            if curvature is not None:
                torque += _half_quadratic(curvature, block)
            return np.abs(torque).max(axis=0)

        return _blockwise(values, largest)

    def deviations(self, values: NDArray) -> NDArray[np.float64]:
        """``(n, poses, 3)``: the deviation at every pose of each print ``values`` ``(n, k)``."""
        values = np.atleast_2d(np.asarray(values, dtype=float))
        moved = self.nominal[None] + np.einsum("pck,nk->npc", self.slopes, values)
        if self.curvature is not None:
            poses, k = self.nominal.shape[0], len(self.parameters)
            moved += _half_quadratic(self.curvature.reshape(poses * 3, k, k), values).T.reshape(-1, poses, 3)
        return moved

    def max_deviation(self, values: NDArray) -> NDArray[np.float64]:
        """``(n,)``: each print's largest deviation over the poses (m)."""
        poses, k = self.nominal.shape[0], len(self.parameters)
        flat = self.slopes.reshape(poses * 3, -1)
        curvature = None if self.curvature is None else self.curvature.reshape(poses * 3, k, k)

        def largest(block: NDArray) -> NDArray[np.float64]:
            moved = flat @ block.T
            if curvature is not None:
                moved += _half_quadratic(curvature, block)
            moved = moved.reshape(poses, 3, -1) + self.nominal[:, :, None]
            return np.sqrt(np.einsum("pcn,pcn->pn", moved, moved)).max(axis=0)

        return _blockwise(values, largest)


def _half_quadratic(curvature: NDArray, values: NDArray) -> NDArray[np.float64]:
    """``(rows, n)``: e^T H_r e / 2 for every row's second derivatives ``curvature`` ``(rows, k, k)`` and every print
    e of ``values`` ``(n, k)`` (Eq. (D11)'s last term), as one matrix product over the k (k + 1) / 2 monomials
    e_i e_j (i <= j) with the coefficients H_ii / 2 and H_ij: half the products of H e, all of them in BLAS."""
    i, j = np.triu_indices(curvature.shape[1])
    coefficients = curvature[:, i, j] * np.where(i == j, 0.5, 1.0)
    return coefficients @ (values[:, i] * values[:, j]).T


def _blockwise(values: NDArray, per_block: Callable[[NDArray], NDArray]) -> NDArray[np.float64]:
    """``per_block`` of the prints ``values`` ``(n, k)`` in blocks of :data:`_BLOCK` (memory: poses x 3 x block
    doubles), one value per print."""
    values = np.atleast_2d(np.asarray(values, dtype=float))
    out = np.empty(len(values))
    for start in range(0, len(values), _BLOCK):
        out[start : start + _BLOCK] = per_block(values[start : start + _BLOCK])
    return out


def check_linear(study: Study) -> None:
    """Refuse (``ValueError``) a study the linear model cannot take, naming what to change: parameters other than
    bore errors, bore errors not in the misfit model, runs that are dynamic."""
    others = [f"{p.name} ({p.target})" for p in study.parameters if p.target not in BORE_FIELDS]
    if others:
        raise ValueError(
            f"study {study.name!r}: the linear tolerance analysis takes bore errors ({', '.join(BORE_FIELDS)}); "
            f"{', '.join(others)} are not: run the study in full (without --linear)"
        )
    if study.base.bore_error_model != "misfit":
        raise ValueError(
            f"study {study.name!r}: the linear tolerance analysis differentiates the misfit model's joints; set "
            'bore_error_model = "misfit" in [base]'
        )
    if study.base.overrides.get("mode") == "dynamic":
        raise ValueError(
            f"study {study.name!r}: the linear tolerance analysis differentiates quasi-static equilibria; its runs are "
            'dynamic: set mode = "quasi_static" in [base]'
        )


def linear_path(study: Study) -> LinearPath:
    """The study's base (every parameter 0: the base's own bore errors kept) run quasi-statically at the study's
    outputs, and the exact derivatives of its deviation by each parameter (module docstring)."""
    check_linear(study)
    zeros = {p.name: 0.0 for p in study.parameters}
    started = time.perf_counter()
    scene, run = build_variant(study, zeros)
    _, options, _ = variant_options(study, zeros)
    result = run_linkage(scene, mode="quasi_static", n_outputs=int(run["outputs"]), sensors="path")
    ran = time.perf_counter()
    bores = tuple(sorted({(int(p.joint or 0), int(p.link or 0)) for p in study.parameters}))
    assert result.multipliers is not None  # a quasi-static run keeps its equilibria's multipliers
    fields = tuple(dict.fromkeys(BORE_FIELDS[p.target][0] for p in study.parameters))
    exact = bore_sensitivity(
        scene,
        scene.loop,
        options,
        result.time,
        result.q,
        result.multipliers,
        bores,
        stability=study.stability,
        fields=fields,
    )
    columns, torques, frequencies = [], [], []
    for p in study.parameters:
        field, factor = BORE_FIELDS[p.target]
        index = exact.parameters.index(f"{field} joint{int(p.joint or 0)} link{int(p.link or 0)}")
        columns.append(factor * exact.coupler_point[:, :, index])
        torques.append(factor * exact.driving_torque[:, index])
        if exact.lowest_squared_frequency is not None:
            frequencies.append(factor * exact.lowest_squared_frequency[:, index])
    return LinearPath(
        tuple(p.name for p in study.parameters),
        exact.drive_angle,
        np.asarray(result.sensors["coupler_deviation"], dtype=float),
        np.stack(columns, axis=2),
        {"base_run": ran - started, "sensitivities": time.perf_counter() - ran},
        np.asarray(result.sensors["driving_torque"], dtype=float),
        np.stack(torques, axis=1),
        exact.squared_frequency,
        np.stack(frequencies, axis=1) if frequencies else None,
    )


def second_differences(
    outputs: Callable[[NDArray], NDArray],
    steps: NDArray,
    at_zero: NDArray,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Second derivatives ``(rows, k, k)`` at e = 0 of the vector ``outputs(e)`` ``(rows,)`` (``at_zero`` its value
    there) by central second differences with ``steps`` ``(k,)`` (Eq. (D11)): from f(+-h_i u_i) the diagonal,
    (f(h_i u_i) + f(-h_i u_i) - 2 f(0)) / h_i^2, and from f(+-(h_i u_i + h_j u_j)) each pair's mixed derivative,
    the rest once the diagonal's part is taken away: k (k + 1) evaluations, exact for polynomials up to the third
    degree (the odd terms cancel in each +- pair). Also the first derivatives ``(rows, k)`` the same evaluations give,
    (f(h_i u_i) - f(-h_i u_i)) / (2 h_i), to check the exact ones against. ``progress(done, total)`` after each."""
    steps = np.asarray(steps, dtype=float)
    k, f0 = steps.size, np.asarray(at_zero, dtype=float)
    total, done = k * (k + 1), 0

    def symmetric_sum(direction: NDArray) -> tuple[NDArray, NDArray]:
        nonlocal done
        plus, minus = np.asarray(outputs(direction), dtype=float), np.asarray(outputs(-direction), dtype=float)
        done += 2
        if progress is not None:
            progress(done, total)
        return plus + minus - 2.0 * f0, plus - minus

    hessian = np.empty((f0.size, k, k))
    slopes = np.empty((f0.size, k))
    for i in range(k):
        even, odd = symmetric_sum(steps[i] * np.eye(k)[i])
        hessian[:, i, i] = even / steps[i] ** 2
        slopes[:, i] = odd / (2.0 * steps[i])
    for i in range(k):
        for j in range(i + 1, k):
            even, _ = symmetric_sum(steps[i] * np.eye(k)[i] + steps[j] * np.eye(k)[j])
            mixed = (even - steps[i] ** 2 * hessian[:, i, i] - steps[j] ** 2 * hessian[:, j, j]) / (
                2.0 * steps[i] * steps[j]
            )
            hessian[:, i, j] = hessian[:, j, i] = mixed
    return hessian, slopes


def second_order(
    study: Study, model: LinearPath, steps: NDArray | None = None, progress: Callable[[int, int], None] | None = None
) -> LinearPath:
    """``model`` (:func:`linear_path` of ``study``) with the second derivatives of the coupler's deviation and of the
    driving torque at every pose by each pair of parameters (Eq. (D11)): :func:`second_differences` of full
    quasi-static runs of the study's base with the parameters at +-``steps`` (study units; default each parameter's
    spread, the standard deviation of 10^4 of its prints), k (k + 1) runs. The first differences of the deviation
    from the same runs must agree with its exact slopes (:func:`check_first_differences`; a run that left the base's
    branch would not): else :class:`~ffrf.errors.SensitivityError` naming the parameter."""
    if model.torque is None or model.torque_slopes is None:
        raise ValueError("this linear model has no driving torque to take to second order")
    if steps is None:
        steps = sample_values(study, 10_000, study.seed).std(axis=0)
    steps = np.asarray(steps, dtype=float)
    poses = model.nominal.shape[0]

    def outputs(values: NDArray) -> NDArray[np.float64]:
        named = dict(zip(model.parameters, (float(v) for v in values), strict=True))
        scene, run = build_variant(study, named)
        result = run_linkage(scene, mode="quasi_static", n_outputs=int(run["outputs"]), sensors="path")
        deviation = np.asarray(result.sensors["coupler_deviation"], dtype=float)
        return np.concatenate([deviation.ravel(), np.asarray(result.sensors["driving_torque"], dtype=float)])

    base = np.concatenate([model.nominal.ravel(), model.torque])
    hessian, slopes = second_differences(outputs, steps, base, progress)
    # the deviation's rows only: a snap or jump moves the coupler, while the torque's small first derivative is
    # easily outgrown by its third-order term (measured 29 % at 0.4 mm steps on a smooth path)
    rows = poses * 3
    check_first_differences(model.parameters, steps, slopes[:rows], model.slopes.reshape(rows, -1))
    k = len(model.parameters)
    return replace(
        model,
        curvature=hessian[: poses * 3].reshape(poses, 3, k, k),
        torque_curvature=hessian[poses * 3 :],
    )


def check_first_differences(parameters: tuple[str, ...], steps: NDArray, differences: NDArray, exact: NDArray) -> None:
    """Raise :class:`~ffrf.errors.SensitivityError` where a parameter's first differences ``(rows, k)`` from the
    runs at +-``steps`` differ from the exact slopes ``(rows, k)`` by more than :data:`SLOPE_AGREEMENT` of its
    largest exact slope: the path is not smooth over the step (a snap or a jump between the runs)."""
    scale = np.abs(exact).max(axis=0)
    off = np.abs(differences - exact).max(axis=0) / np.where(scale > 0.0, scale, 1.0)
    if off.max() > SLOPE_AGREEMENT:
        worst = int(np.argmax(off))
        raise SensitivityError(
            f"{parameters[worst]}: the full runs at +-{steps[worst]:g} give a first derivative "
            f"{100 * off[worst]:.3g} % off the exact one: the path is not smooth over that step (a snap, a jump); "
            "give smaller steps or run the study in full"
        )


def sample_values(study: Study, n: int, seed: int) -> NDArray[np.float64]:
    """``(n, k)`` independent random prints of the study's parameter distributions (seeded)."""
    unit = np.random.default_rng(seed).random((n, len(study.parameters)))
    return np.column_stack([values_from_unit(p, unit[:, i]) for i, p in enumerate(study.parameters)])


def percentiles(sample: NDArray, levels: tuple[float, ...] = (50.0, 95.0, 99.0)) -> dict[str, dict[str, float | None]]:
    """Each percentile of ``sample`` with its 95 % interval (:func:`ffrf.studies.statistics.percentile_interval`;
    ``None`` for an end the sample cannot bound)."""
    ordered = np.sort(np.asarray(sample, dtype=float))
    out = {}
    for level in levels:
        low, high = (x if np.isfinite(x) else None for x in percentile_interval(ordered, level))
        out[f"p{level:g}"] = {"value": float(np.percentile(ordered, level)), "low": low, "high": high}
    return out


def check_with_full_runs(study: Study, model: LinearPath, count: int) -> list[dict]:
    """The first ``count`` prints of the study's own design run in full (:func:`ffrf.studies.variant.run_variant`)
    against the linear model: per print its largest deviation both ways (m) and their relative difference, and
    ``agrees`` when that is within :data:`CHECK_TOLERANCE`; the same of the largest driving torque (N m) where the
    model has it (``torque_difference``)."""
    rows = []
    for variant in study_design(study)[:count]:
        full = run_variant(study, variant)
        values = np.array([variant.values[name] for name in model.parameters])[None]
        linear = float(model.max_deviation(values)[0])
        measured = float(full.get("max_coupler_deviation_m", math.nan))
        difference = abs(linear - measured) / measured if measured > 0.0 else math.inf
        row = {
            "id": variant.id,
            "full_m": measured,
            "linear_m": linear,
            "relative_difference": difference,
            "status": full.get("status"),
        }
        if model.torque is not None:
            torque = float(model.max_torque(values)[0])
            full_torque = float(full.get("max_abs_driving_torque_Nm", math.nan))
            torque_difference = abs(torque - full_torque) / full_torque if full_torque > 0.0 else math.inf
            row |= {"full_torque_Nm": full_torque, "linear_torque_Nm": torque, "torque_difference": torque_difference}
        if model.frequency is not None and math.isfinite(full.get("min_frequency_hz", math.nan)):
            hertz = float(_hertz(model.min_squared_frequency(values))[0])
            full_hertz = float(full["min_frequency_hz"])
            row |= {
                "full_min_frequency_hz": full_hertz,
                "linear_min_frequency_hz": hertz,
                "frequency_difference": abs(hertz - full_hertz) / full_hertz,
            }
        rows.append(row | {"agrees": bool(difference <= CHECK_TOLERANCE)})
    return rows


def _largest_factor(level_of: Callable[[float], float], target: float, top: float = 64.0) -> float:
    """The largest ``f`` in [0, ``top``] with ``level_of(f) <= target`` by bisection (``level_of`` grows with ``f``
    where it matters: a spread times ``f``), to 1e-3 relative; 0 when even ``f = 0`` misses the target."""
    if level_of(0.0) > target:
        return 0.0
    if level_of(top) <= target:
        return top
    low, high = 0.0, top
    while high - low > 1e-3 * high:
        middle = 0.5 * (low + high)
        low, high = (middle, high) if level_of(middle) <= target else (low, middle)
    return low


def allocate(model: LinearPath, values: NDArray, target: float, level: float = 95.0) -> dict:
    """Tolerances that keep the ``level``-th percentile of the largest deviation at most ``target`` (m), from the
    prints ``values`` ``(n, k)`` of the study's distributions (the same prints throughout, their spreads scaled about
    their means): ``common_factor``, the largest factor on every given spread at once; and an equal-effect
    allocation, a print shop's table: each parameter's spread (standard deviation, study units) such that one
    standard deviation of it moves the coupler at most the same distance along the path (``equal_move_m``, the
    largest that keeps the target), tight where the path is sensitive, loose where it is not. A target the nominal
    linkage already misses allows nothing (factors 0)."""
    values = np.asarray(values, dtype=float)
    mean = values.mean(axis=0)
    centred = values - mean
    spreads = centred.std(axis=0)
    standard = centred / np.where(spreads > 0.0, spreads, 1.0)  # the distributions' shapes, unit spread
    unit_moves = np.linalg.norm(model.slopes, axis=1).max(axis=0)  # largest move per unit of each parameter (m)

    def percentile(scaled: NDArray) -> float:
        return float(np.percentile(model.max_deviation(scaled), level))

    common = _largest_factor(lambda f: percentile(mean + f * centred), target)
    reference = float(np.median(unit_moves * spreads))  # the equal move's scale for the bisection
    equal = reference * _largest_factor(lambda f: percentile(mean + standard * (f * reference / unit_moves)), target)
    return {
        "target_m": target,
        "level": level,
        "common_factor": common,
        "equal_move_m": equal,
        "per_parameter": {
            name: {"given_std": float(spread), "equal_effect_std": float(equal / move)}
            for name, spread, move in zip(model.parameters, spreads, unit_moves, strict=True)
        },
    }


def _torque_percentiles(model: LinearPath, values: NDArray, rows: list[dict]) -> dict:
    """The largest driving torque's percentiles where the prints run in full agree with the model within
    :data:`CHECK_TOLERANCE`; else only how far they differ (a torque from misfit is of second order in the errors:
    its first order can miss it by tens of percent where the deviation's holds)."""
    worst = max((row["torque_difference"] for row in rows if "torque_difference" in row), default=math.inf)
    if worst <= CHECK_TOLERANCE:
        return percentiles(model.max_torque(values))
    order = "first" if model.order == 1 else "second"
    return {"refused": f"prints run in full differ from the {order} order by up to {100 * worst:.3g} %"}


def _hertz(squared: NDArray) -> NDArray[np.float64]:
    """Frequencies (Hz) of squared angular frequencies (rad^2/s^2); a fold's (zero or below) is 0."""
    return np.sqrt(np.maximum(np.asarray(squared, dtype=float), 0.0)) / (2.0 * np.pi)


def first_order_stability(model: LinearPath, values: NDArray) -> dict:
    """The prints' lowest vibration frequency to first order (Hz, percentiles) and the prints that the first order
    says reach a fold (their share with its interval, and the poses where the first of them folds): the first order
    holds only away from folds, so where there are such prints the study must run in full."""
    lowest = model.min_squared_frequency(values)
    folding = exceedance(-lowest, 0.0)  # the prints whose lowest squared frequency is below zero
    out: dict = {"min_frequency_hz": percentiles(_hertz(lowest), (0.0, 1.0, 5.0, 50.0, 95.0)), "folds": folding}
    if folding["exceeding"]:
        assert model.frequency is not None and model.frequency_slopes is not None
        first = values[int(np.argmin(lowest))]
        pose = int(np.argmin(model.frequency + model.frequency_slopes @ first))
        out["warning"] = (
            f"{folding['exceeding']} of {folding['n']} prints reach a fold to first order (the lowest squared "
            "frequency of Eq. (B1) falls below zero, first near drive angle "
            f"{np.degrees(model.drive_angle[pose]):.4g} deg): they snap, and the first order does not hold for them; "
            "run the study in full"
        )
    return out


def linear_report(
    study: Study,
    prints: int,
    checks: int,
    target: float | None = None,
    level: float = 95.0,
    second: bool = False,
    progress: Callable[[int, int], None] | None = None,
    model: LinearPath | None = None,
) -> dict:
    """The study to first order (to second with ``second``: :func:`second_order`, its full runs reported to
    ``progress(done, total)``; or by a ``model`` of the same base built before, as for several tolerance levels of one
    study) as plain data (``linear.json`` of ``python -m ffrf study --linear``): ``prints``
    random prints of its distributions (seeded by the study's seed), the percentiles of their largest deviation (m)
    with 95 % intervals, per parameter the largest move of the coupler along the path for one standard deviation of
    it (``one_std_moves``, m: which bores matter), the first ``checks`` prints of its design run in full against the
    model, ``verified`` when all of those agree (:data:`CHECK_TOLERANCE`) and, for a study that monitors stability,
    no print reaches a fold to first order (``stability``: :func:`first_order_stability`), and the seconds each part
    took; with a ``target`` (m), the tolerances that keep the ``level``-th percentile within it (:func:`allocate`, on
    10^5 of the prints)."""
    if model is None:
        model = linear_path(study)
    if second and model.order == 1:
        started = time.perf_counter()
        model = second_order(study, model, progress=progress)
        model = replace(model, seconds=dict(model.seconds, second_order=time.perf_counter() - started))
    values = sample_values(study, prints, study.seed)
    started = time.perf_counter()
    largest = model.max_deviation(values)
    sampled = time.perf_counter() - started
    spread = values.std(axis=0)
    moves = np.linalg.norm(model.slopes, axis=1).max(axis=0) * spread
    started = time.perf_counter()
    rows = check_with_full_runs(study, model, checks)
    checked = time.perf_counter() - started
    stability = None if model.frequency is None else first_order_stability(model, values)
    folds = 0 if stability is None else stability["folds"]["exceeding"]
    return {
        "study": study.name,
        "order": model.order,
        "prints": prints,
        "nominal_max_deviation_m": float(np.linalg.norm(model.nominal, axis=1).max()),
        "max_coupler_deviation_m": percentiles(largest),
        "mean_m": float(largest.mean()),
        "one_std_moves": {
            name: {"move_m": float(move)}
            for name, move in sorted(zip(model.parameters, moves, strict=True), key=lambda kv: -kv[1])
        },
        "max_abs_driving_torque_Nm": _torque_percentiles(model, values, rows),
        "limits": {
            output: exceedance(largest, above) for output, above in study.limits if output == "max_coupler_deviation_m"
        },
        "checks": rows,
        "verified": bool(rows) and all(row["agrees"] for row in rows) and not folds,
        "check_tolerance": CHECK_TOLERANCE,
        "seconds": dict(model.seconds, prints=sampled, checks=checked),
    } | (
        ({} if stability is None else {"stability": stability})
        | ({} if target is None else {"allocation": allocate(model, values[:100_000], target, level)})
    )
