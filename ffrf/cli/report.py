"""A linkage run on the command line (``bennett``, ``linkage``, ``run`` of a linkage file): the facade's run
(:meth:`ffrf.model.Model.run`) with a progress bar, its :class:`~ffrf.output.result.Result` saved, and what it found
in a few lines; and the verdict of a run's checks as the exit status."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ffrf.cli.stop import STOP, progress_printer
from ffrf.errors import Interrupted, NewtonDivergence, StaticDivergence
from ffrf.model import Model
from ffrf.output.result import Result
from ffrf.paper.figures import VARIANT_COLORS
from ffrf.scenes.linkage_scene import LinkageScene
from ffrf.solvers.stability import check_judged_at_equilibria

__all__ = ["run_and_report", "report_verification"]


def run_and_report(
    model: Model,
    out: Path,
    label: str,
    started: float,
    options: dict,
    paper: str = "",
    then: Callable[[Result], None] | None = None,
) -> int:
    """Run a linkage and save what ``bennett`` and ``linkage`` write (:meth:`ffrf.output.result.Result.save`).

    ``options``: ``mode`` (``auto``, ``quasi_static``, ``dynamic``), ``outputs``, ``step`` (s), ``vtk_every``,
    ``stability``, ``clearance_margin`` (m; default the scene's, else 1 mm); ``then(result)``: more to do with a run
    that did not stop (``linkage --reach``)."""
    scene = model.scene
    if not isinstance(scene, LinkageScene):
        raise TypeError(f"{model.name!r} is no linkage: its run is reported by python -m ffrf run")
    stability = options.get("stability", False)
    check_judged_at_equilibria(options["mode"], stability, "run quasi-statically (drop --dynamic / mode)")
    auto = options["mode"] == "auto"
    mode, ratio = model.choose_mode(options["mode"], stability)
    print(
        f"Running {mode.replace('_', '-')} over {scene.t_end:.1f} s of drive"
        + (f" (drive time scale / longest link period = {ratio:.0f})" if auto else ""),
        file=sys.stderr,
    )
    try:
        with STOP.deferred():
            result = model.run(
                mode,
                outputs=options["outputs"],
                step=options["step"],
                progress=progress_printer(),
                stability=stability,
                blas_threads=None,
            )
        stopped = None
    except (StaticDivergence, NewtonDivergence, Interrupted) as error:  # write what was computed, then say so
        if not isinstance(error, Interrupted):  # (the progress bar ended its line)
            print(file=sys.stderr)  # end the progress bar's line
        if error.partial is None:
            raise
        result, stopped = error.partial, error
    clearance = result.add_clearance(options.get("clearance_margin"))
    with STOP.deferred():
        result.save(out, views=False)
    if isinstance(stopped, Interrupted):  # the user asked to stop: the results so far, no figures
        end = result.time[-1]
        raise Interrupted(
            f"{stopped}: the results up to t = {end:.6g} s (drive angle {np.degrees(scene.drive_angle(end)):.4g} deg) "
            f"are in {out} (metadata.json: stopped)"
        )
    STOP.check(f" after the run: its complete results are in {out}, without figures")
    written = result.write_views(out, vtk_every=options["vtk_every"], label=label, colors=VARIANT_COLORS)
    if options["vtk_every"] > 0:
        print(f"ParaView series: {written[0]}", file=sys.stderr)
    if "stability" in result.metadata:
        _print_stability(result, out)
    summary = result.summary()
    print(
        f"{label}: max coupler deviation from the ideal path "
        f"{1e3 * summary['max_coupler_deviation_m']:.4f} mm at the same drive angle, "
        f"{1e3 * summary['max_coupler_distance_to_path_m']:.4f} mm to the closest point"
        + (f" (paper: below {paper} mm)" if paper else "")
        + f"; max driving torque {1e3 * summary['max_abs_driving_torque_Nm']:.3f} N mm; "
        f"largest constraint residual {summary['max_constraint_residual']:.1e}; energy balance closed to "
        f"{summary['energy_balance_relative']:.1e} of its energy scale (Eq. (C2)); wall time "
        f"{time.perf_counter() - started:.1f} s -> {out}"
    )
    estimate = result.metadata.get("step_error_estimate")
    if estimate is not None:
        print(
            f"time steps of {1e3 * result.metadata['step']:g} ms"
            + (
                f" ({estimate['steps']} steps, down to {1e3 * estimate['shortest_step_s']:.3g} ms where a joint turns "
                "fast, Eq. (G7))"
                if "steps" in estimate and estimate["shortest_step_s"] < 0.999 * result.metadata["step"]
                else ""
            )
            + "; local error estimate of the bodies' positions per "
            f"step (Eq. (G5)): median {estimate['median_m']:.1e} m, largest {estimate['largest_m']:.1e} m "
            f"at t = {estimate['largest_at_s']:.3g} s"
        )
    for pose in result.metadata.get("near_dead_poses", []):
        print(
            f"near-dead pose at drive angle {pose['drive_angle_deg']:.4g} deg: joint {pose['joint']} turns "
            f"{pose['ratio']:.3g} times faster than the driver; the coupler leaves the rigid motion by "
            f"{1e3 * pose['max_coupler_deviation_near_m']:.3g} mm within 2 deg of it "
            f"({1e3 * pose['max_coupler_deviation_elsewhere_m']:.3g} mm elsewhere): the rigid motion is "
            "ill-conditioned there (docs/hard_cases.md)"
        )
    if clearance is not None:
        print(f"clearance of the links along the rigid motion: {clearance['summary']}")
    misfit = scene.misfit_degrees > 0.0
    print("assembled state (gravity" + (", misfit" if misfit else "") + f"; {out / 'assembly.vtu'}):")
    assert result.assembly is not None  # a linkage's run always records the assembled state
    for link in result.assembly.links:
        print("  " + link.line())
    if stopped is not None:
        end = result.time[-1]
        print(
            f"error: the run stopped: {stopped} (the results up to t = {end:.6g} s, drive angle "
            f"{np.degrees(scene.drive_angle(end)):.4g} deg, are in {out})",
            file=sys.stderr,
        )
        return 1
    if then is not None:
        then(result)
    return report_verification(result.metadata.get("verification"))


def report_verification(verification: dict | None) -> int:
    """Print the run's warnings and, as the last line, its verdict (``verification`` of ``metadata.json``,
    :mod:`ffrf.output.verification`); exit status 0 when the run verified itself, 3 when a check failed (the
    results are written all the same, and ``verification.reasons`` names what failed)."""
    if verification is None:
        return 0
    for warning in verification["warnings"]:
        print(f"warning: {warning}")
    print(verification["verdict"])
    return 0 if verification["verified"] else 3


def _print_stability(result: Result, out: Path) -> None:
    """What the stability monitor found (``stability.json``, ``stability.png``): the least stable pose, each snap,
    and the critical pose with its mode (``stability_critical.vtu``)."""
    s = result.metadata["stability"]
    print(
        f"stability: smallest squared frequency {s['min_squared_frequency']:.4g} rad^2/s^2 "
        f"({s['min_frequency_hz']:.3g} Hz) at drive angle {s['at_drive_angle_deg']:.4g} deg; "
        f"{s['unstable_poses']} unstable pose(s) -> {out / 'stability.json'}"
    )
    for snap in s.get("snaps", []):
        links = sorted(snap["critical_mode_body_shares"].items(), key=lambda item: -item[1])[:2]
        jump = (
            f"the linkage jumps to another branch, coupler point {1e3 * snap['coupler_jump_m']:.4g} mm away, "
            f"releasing {1e3 * snap['energy_released_J']:.4g} mJ (landing found by the {snap['landed_by']})"
            if snap["landed"]
            else "no stable equilibrium to land on was found along the traced path nor by a dynamic passage from the "
            "fold (run it dynamically)"
        )
        print(
            f"snap: the equilibrium path folds at drive angle {snap['drive_angle_deg']:.4g} deg "
            f"(driving torque {1e3 * snap['driving_torque_Nm']:.4g} N mm); {jump}; critical mode mostly in "
            + ", ".join(f"{name} ({100 * share:.0f} %)" for name, share in links)
        )
    critical = result.critical
    if critical is not None:
        print(
            f"critical pose ({critical.where}, drive angle {np.degrees(result.scene.drive_angle(critical.t)):.4g} deg, "
            f"squared frequency {critical.squared_frequency:.4g} rad^2/s^2) with its mode: "
            f"{out / 'stability_critical.vtu'}"
        )
