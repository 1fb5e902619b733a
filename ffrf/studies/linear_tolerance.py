r"""Tolerance analysis of bore errors to first order: a study's prints in a second (``docs/formulation.md``, (D3)).

A study whose parameters are bore errors (twist, offset, axial of :class:`~ffrf.scenes.linkage_description.BoreError`
in the misfit model) varies a linkage whose quasi-static path responds smoothly to them. To first order the coupler's
deviation from the ideal path at pose :math:`i` of a print with errors :math:`e` is

.. math:: d_i(e) \approx d_i(0) + S_i\,e,

with :math:`d_i(0)` the base's own deviation (its gravity sag, its own bore errors) and :math:`S_i` the exact
derivatives of Eq. (D1) at the base's equilibria (:func:`ffrf.scenes.path_sensitivity.bore_sensitivity`): one run
and one sensitivity solve per pose, then any number of prints by a matrix product (:meth:`LinearPath.max_deviation`,
the largest :math:`|d_i(e)|` over the poses, the study's ``max_coupler_deviation_m``). Percentiles come with their
95 % confidence interval from the order statistics of the sample (:func:`percentiles`). The model holds while the
errors are small against what bends the path; :func:`check_with_full_runs` compares it with full runs of some of the
study's own prints and says where they disagree.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

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
    "check_with_full_runs",
    "first_order_stability",
    "linear_path",
    "allocate",
    "linear_report",
    "percentiles",
    "sample_values",
]

#: Largest relative difference between the linear model's and a full run's largest deviation before a check warns.
CHECK_TOLERANCE = 0.05
#: Prints per block of :meth:`LinearPath.max_deviation` (memory: poses x 3 x block doubles).
_BLOCK = 20_000


@dataclass(frozen=True)
class LinearPath:
    """The coupler's deviation along a study's base path to first order in its parameters (module docstring):
    ``nominal`` ``(poses, 3)`` (m) at the base, ``slopes`` ``(poses, 3, k)`` (m per unit of each parameter, in the
    study's units: deg, mm), at the ``drive_angle`` (rad) of the base run's outputs; ``seconds``: the base run's and
    the sensitivities' wall time; the driving torque likewise, ``torque`` ``(poses,)`` (N m) and ``torque_slopes``
    ``(poses, k)``, where given; and for a study that monitors stability the lowest squared frequency of Eq. (B1),
    ``frequency`` ``(poses,)`` (rad^2/s^2) and ``frequency_slopes`` ``(poses, k)``."""

    parameters: tuple[str, ...]
    drive_angle: NDArray[np.float64]
    nominal: NDArray[np.float64]
    slopes: NDArray[np.float64]
    seconds: dict[str, float]
    torque: NDArray[np.float64] | None = None
    torque_slopes: NDArray[np.float64] | None = None
    frequency: NDArray[np.float64] | None = None
    frequency_slopes: NDArray[np.float64] | None = None

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
        nominal, slopes = self.torque, self.torque_slopes
        return _blockwise(values, lambda block: np.abs(nominal[:, None] + slopes @ block.T).max(axis=0))

    def deviations(self, values: NDArray) -> NDArray[np.float64]:
        """``(n, poses, 3)``: the deviation at every pose of each print ``values`` ``(n, k)``."""
        values = np.atleast_2d(np.asarray(values, dtype=float))
        return self.nominal[None] + np.einsum("pck,nk->npc", self.slopes, values)

    def max_deviation(self, values: NDArray) -> NDArray[np.float64]:
        """``(n,)``: each print's largest deviation over the poses (m)."""
        poses = self.nominal.shape[0]
        flat = self.slopes.reshape(poses * 3, -1)

        def largest(block: NDArray) -> NDArray[np.float64]:
            moved = (flat @ block.T).reshape(poses, 3, -1) + self.nominal[:, :, None]
            return np.sqrt(np.einsum("pcn,pcn->pn", moved, moved)).max(axis=0)

        return _blockwise(values, largest)


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
    exact = bore_sensitivity(
        scene, scene.loop, options, result.time, result.q, result.multipliers, bores, stability=study.stability
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
    return {"refused": f"prints run in full differ from the first order by up to {100 * worst:.3g} %"}


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


def linear_report(study: Study, prints: int, checks: int, target: float | None = None, level: float = 95.0) -> dict:
    """The study to first order as plain data (``linear.json`` of ``python -m ffrf study --linear``): ``prints``
    random prints of its distributions (seeded by the study's seed), the percentiles of their largest deviation (m)
    with 95 % intervals, per parameter the largest move of the coupler along the path for one standard deviation of
    it (``one_std_moves``, m: which bores matter), the first ``checks`` prints of its design run in full against the
    model, ``verified`` when all of those agree (:data:`CHECK_TOLERANCE`) and, for a study that monitors stability,
    no print reaches a fold to first order (``stability``: :func:`first_order_stability`), and the seconds each part
    took; with a ``target`` (m), the tolerances that keep the ``level``-th percentile within it (:func:`allocate`, on
    10^5 of the prints)."""
    model = linear_path(study)
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
