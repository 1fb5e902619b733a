"""``python -m ffrf run SCENE.toml``: a scene file (or a linkage file, reported as the built-in linkages are) through
the facade (:func:`ffrf.load`), its :class:`~ffrf.output.result.Result` saved into ``--out``."""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

from ffrf.cli.arguments import output_folder
from ffrf.cli.report import report_verification, run_and_report
from ffrf.cli.stop import STOP, progress_printer
from ffrf.errors import Interrupted, NewtonDivergence, StaticDivergence
from ffrf.model import Model, load
from ffrf.solvers.stability import check_judged_at_equilibria

__all__ = ["HELP", "configure", "run"]

HELP = "run a scene file (TOML) built from your own meshes"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", type=Path, help="scene file (TOML), see ffrf.scenes.scene_file")
    parser.add_argument("--out", type=Path, required=True, help="output directory (results.npz, metadata.json)")
    parser.add_argument(
        "--stability",
        action="store_true",
        help="as stability = true in the scene: judge every equilibrium of a quasi-static run (Eq. (B1)) and go on "
        "past folds (Eq. (S6)); writes stability.json and stability_critical.vtu",
    )


def run(args: argparse.Namespace) -> int:
    started = time.perf_counter()
    model = load(args.scene)
    if args.stability:
        mode = model.settings().get("mode", "dynamic")
        check_judged_at_equilibria(mode, True, 'set mode = "quasi_static" in the scene file (--stability)')
        model = Model(replace(model.scene, settings={**model.scene.settings, "stability": True}))
    out = output_folder(args.out)  # after the scene's checks: a refused scene leaves no folder behind
    if model.kind == "linkage":  # a linkage file: reported as the built-in linkages are
        options = model.settings() | {"vtk_every": 0}
        return run_and_report(model, out, model.name, started, options)
    scene = model.scene
    print(
        f"Scene {scene.name!r}: {len(scene.bodies)} bodies, {len(scene.system.constraints)} joints, "
        f"{scene.system.n_coordinates} coordinates",
        file=sys.stderr,
    )
    with STOP.deferred():
        try:
            result = model.run(progress=progress_printer(), blas_threads=None)  # --blas-threads holds
        except (StaticDivergence, NewtonDivergence, Interrupted) as error:  # write what was computed, then say so
            if error.partial is None:
                raise
            error.partial.save(out)
            error.args = (f"{error} (the results up to t = {error.partial.time[-1]:.6g} s are in {out})",)
            raise
        result.save(out)
    STOP.check(f" after the run: its complete results are in {out}")
    for snap in result.metadata.get("stability", {}).get("snaps", []):
        released = snap["energy_released_J"]
        print(
            f"snap: the equilibrium path folds at t = {snap['time_s']:.6g} s; "
            + (
                f"it lands on another branch ({snap['landed_by']}), releasing {released:.4g} J"
                if snap["landed"]
                else "no landing found"
            )
        )
    print(f"{scene.name}: wall time {result.metadata['wall_time_s']:.1f} s -> {args.out}")
    return report_verification(result.metadata.get("verification"))
