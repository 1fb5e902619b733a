"""``python -m ffrf design DESIGN.toml --out DIR``: with a ``[design]`` table, the lightest section of a linkage's
links that keeps its coupler within a bound of the ideal path (:mod:`ffrf.scenes.section_design`); with a ``[play]``
table, the largest play of its passive joints that does (:mod:`ffrf.scenes.play_design`); then the designed linkage
run and verified as ``python -m ffrf run`` does.

Writes ``progress.json`` after every SLSQP iteration or play run (what is kept if the design stops), ``design.json``
(the problem, every design evaluated, the answer and, for a section, SLSQP's end and the KKT residual),
``designed.toml`` (the linkage file of the answer) and, in ``check/``, the designed linkage's own run; the exit status
is that run's (0 only when it verified itself), or 1 when there is no accepted answer (no design met the bound, or a
section's KKT residual is above :data:`~ffrf.scenes.section_design.KKT_TOLERANCE`).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tomllib
from pathlib import Path

from ffrf.cli.arguments import output_folder
from ffrf.cli.report import run_and_report
from ffrf.errors import SceneError
from ffrf.model import load
from ffrf.scenes.play_design import (
    PlayPoint,
    PlayProblem,
    evaluate_play,
    largest_play,
    load_play_design,
    played_document,
)
from ffrf.scenes.scene_toml import scene_toml
from ffrf.scenes.section_design import DesignPoint, SectionDesign, designed_document, load_design, optimise_section

__all__ = ["HELP", "configure", "run"]

HELP = (
    "find the lightest link section that keeps the coupler on its path (a linkage file + [design]), or the largest "
    "play of its joints that does (+ [play])"
)


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("design", type=Path, help="design file (TOML): a linkage file with a [design] or [play] table")
    parser.add_argument("--out", type=Path, required=True, help="output directory")


def run(args: argparse.Namespace) -> int:
    started = time.perf_counter()
    if not args.design.is_file():
        raise SceneError(f"design file {args.design} not found")
    document = tomllib.loads(args.design.read_text())
    if ("design" in document) == ("play" in document):
        raise SceneError(f"{args.design}: give either a [design] table (a section) or a [play] table (joint play)")
    if "play" in document:
        return _design_play(document, args, started)
    loop, options, problem = load_design(document, str(args.design))
    out = output_folder(args.out)
    print(f"Designing {options.name}: {', '.join(problem.parameters)} for the least mass", file=sys.stderr)

    iterations: list[dict] = []

    def progress(iteration: int, point: DesignPoint) -> None:
        iterations.append({"iteration": iteration, **_point(point, problem.parameters)})
        (out / "progress.json").write_text(json.dumps(iterations, indent=2) + "\n")  # kept if the design stops
        values = ", ".join(f"{p} {1e3 * v:.3f} mm" for p, v in zip(problem.parameters, point.values, strict=True))
        lowest, largest = point.min_frequency_hz, point.max_stress
        frequency = (
            "" if lowest is None else f", lowest frequency {lowest:.3f} Hz (bound {problem.min_frequency_hz} Hz)"
        )
        if largest is not None and problem.max_stress is not None:
            frequency += (
                f", peak stress {1e-6 * largest:.4g} MPa over {1e3 * (problem.stress_radius or 0.0):.3g} mm balls, "
                f"its norm (D10) {1e-6 * (point.max_stress_norm or 0.0):.4g} MPa "
                f"(bound {1e-6 * problem.max_stress:.4g} MPa)"
            )
        if point.clearance is not None and problem.min_clearance is not None:
            frequency += (
                f", smallest clearance {1e3 * float(point.clearance.min()):.3f} mm "
                f"(bound {1e3 * problem.min_clearance:.3f} mm)"
            )
        print(
            f"iteration {iteration}: {values}: mass {1e3 * point.mass:.2f} g, largest deviation "
            f"{1e3 * point.max_deviation:.4f} mm (bound {1e3 * problem.max_deviation:.4f} mm){frequency}",
            file=sys.stderr,
        )

    design = optimise_section(loop, options, problem, progress)
    (out / "design.json").write_text(json.dumps(_summary(design, time.perf_counter() - started), indent=2) + "\n")
    designed = out / "designed.toml"
    designed.write_text(scene_toml(designed_document(document, design)))
    print(
        f"{options.name}: mass {1e3 * design.start.mass:.2f} -> {1e3 * design.optimum.mass:.2f} g, largest "
        f"deviation {1e3 * design.start.max_deviation:.4f} -> {1e3 * design.optimum.max_deviation:.4f} mm in "
        f"{design.iterations} iterations ({design.message}; KKT residual {design.kkt_residual:.2g}) -> {designed}",
        file=sys.stderr,
    )
    print(
        f"the designed linkage against its Exudyn twin: python -m validation report --scene {designed} "
        f"--out {out / 'exudyn'}",
        file=sys.stderr,
    )
    status = _check(designed, out)
    if not design.success:
        print(
            f"error: the design is not accepted (KKT residual {design.kkt_residual:.2g}; SLSQP: {design.message})",
            file=sys.stderr,
        )
        return max(status, 1)
    return status


def _check(designed: Path, out: Path) -> int:
    """Run the designed linkage file as ``python -m ffrf run`` does, into ``out/check``; its exit status."""
    model = load(designed)
    return run_and_report(model, out / "check", model.name, time.perf_counter(), model.settings() | {"vtk_every": 0})


def _design_play(document: dict, args: argparse.Namespace, started: float) -> int:
    loop, options, problem = load_play_design(document, str(args.design))
    out = output_folder(args.out)
    print(
        f"Designing {options.name}: the largest radial play of its passive joints (0..{1e3 * problem.largest:g} mm) "
        f"with the coupler within {1e3 * problem.max_deviation:g} mm",
        file=sys.stderr,
    )
    evaluated: list[dict] = []

    def progress(point: PlayPoint) -> None:
        evaluated.append(_play_point(point, problem))
        (out / "progress.json").write_text(json.dumps(evaluated, indent=2) + "\n")  # kept if the design stops
        end = "" if point.stopped is None else f", stopped: {point.stopped}"
        end += "" if point.verified or not point.reasons else f" ({point.reasons[0]})"
        print(
            f"play {1e3 * point.radial:.4g} mm: largest deviation {1e3 * point.max_deviation:.4f} mm (bound "
            f"{1e3 * problem.max_deviation:.4g} mm), verified {point.verified}{end} -> "
            f"{'meets' if point.meets(problem) else 'misses'} ({point.seconds:.0f} s)",
            file=sys.stderr,
        )

    design = largest_play(problem, lambda radial: evaluate_play(loop, options, problem, radial), progress)
    summary = {
        "problem": {
            "max_deviation_mm": 1e3 * problem.max_deviation,
            "largest_mm": 1e3 * problem.largest,
            "resolution_mm": 1e3 * problem.resolution,
            "grid": problem.grid,
            "outputs": problem.outputs,
        },
        "largest": None if design.largest is None else _play_point(design.largest, problem),
        "failing": None if design.failing is None else _play_point(design.failing, problem),
        "monotone": design.monotone,
        "evaluated": [_play_point(p, problem) for p in design.points],
        "seconds": time.perf_counter() - started,
    }
    (out / "design.json").write_text(json.dumps(summary, indent=2) + "\n")
    designed = out / "designed.toml"
    designed.write_text(scene_toml(played_document(document, design, options)))
    if not design.monotone:
        print(
            "warning: the bound is met again above a play that misses it; the answer is the largest play below the "
            "first that misses (see design.json's evaluated plays)",
            file=sys.stderr,
        )
    if design.largest is None:
        print(f"error: even ideal joints miss the bound ({_miss(design.failing)}); nothing designed", file=sys.stderr)
        return 1
    above = (
        f"the largest considered; {1e3 * problem.largest:g} mm meets it"
        if design.failing is None
        else f"{1e3 * design.failing.radial:.4g} mm misses it: {_miss(design.failing)}"
    )
    print(
        f"{options.name}: the coupler stays within {1e3 * problem.max_deviation:g} mm up to a play of "
        f"{1e3 * design.largest.radial:.4g} mm ({above}) -> {designed}",
        file=sys.stderr,
    )
    return _check(designed, out)


def _miss(point: PlayPoint | None) -> str:
    """Why a play's run missed the bound, in a few words."""
    if point is None:
        return ""
    if point.stopped is not None:
        return f"its path stopped: {point.stopped}"
    if not point.verified:
        return "its run did not verify itself" + (f": {point.reasons[0]}" if point.reasons else "")
    return f"largest deviation {1e3 * point.max_deviation:.4f} mm"


def _play_point(point: PlayPoint, problem: PlayProblem) -> dict:
    return {
        "radial_mm": 1e3 * point.radial,
        "max_deviation_mm": 1e3 * point.max_deviation,
        "assembly_max_von_mises_mpa": 1e-6 * point.assembly_stress,
        "max_pin_eccentricity_mm": 1e3 * point.max_eccentricity,
        "verified": point.verified,
        "not_verified_because": list(point.reasons),
        "stopped": point.stopped,
        "meets": point.meets(problem),
        "seconds": point.seconds,
    }


def _point(point: DesignPoint, parameters: tuple[str, ...]) -> dict:
    return {
        "section_mm": {p: 1e3 * float(v) for p, v in zip(parameters, point.values, strict=True)},
        "mass_g": 1e3 * point.mass,
        "max_deviation_mm": 1e3 * point.max_deviation,
        "seconds": point.seconds,
    } | (
        ({} if point.min_frequency_hz is None else {"min_frequency_hz": point.min_frequency_hz})
        | ({} if point.max_stress is None else {"max_stress_mpa": 1e-6 * point.max_stress})
        | ({} if point.max_stress_norm is None else {"max_stress_norm_mpa": 1e-6 * point.max_stress_norm})
        | ({} if point.clearance is None else {"min_clearance_mm": 1e3 * float(point.clearance.min())})
    )


def _summary(design: SectionDesign, seconds: float) -> dict:
    problem = design.problem
    return {
        "problem": {
            "parameters": list(problem.parameters),
            "lower_mm": [1e3 * v for v in problem.lower],
            "upper_mm": [1e3 * v for v in problem.upper],
            "max_deviation_mm": 1e3 * problem.max_deviation,
            "min_frequency_hz": problem.min_frequency_hz,
            "max_stress_mpa": None if problem.max_stress is None else 1e-6 * problem.max_stress,
            "stress_radius_mm": None if problem.stress_radius is None else 1e3 * problem.stress_radius,
            "min_clearance_mm": None if problem.min_clearance is None else 1e3 * problem.min_clearance,
            "outputs": problem.outputs,
        },
        "start": _point(design.start, problem.parameters),
        "optimum": _point(design.optimum, problem.parameters),
        "iterations": design.iterations,
        "evaluations": len(design.history),
        "success": design.success,
        "message": design.message,
        "kkt_residual": design.kkt_residual,
        "active_multipliers": design.active,
        "history": [_point(p, problem.parameters) for p in design.history],
        "seconds": seconds,
    }
