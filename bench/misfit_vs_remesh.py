"""The cheap-variant rule of studies (issue #19): a bore error modelled as a joint-frame misfit on the nominal meshes
(``LinkageOptions.bore_error_model = "misfit"``) against the remeshed, misaligned link ("remesh"), for the paper's
PLA Bennett with its base bore's twist 1 and 2 deg off (variants pla1, pla2).

For each variant and model a quasi-static revolution; recorded per variant: the deviation the bore error causes
(largest distance of the coupler point from the nominal linkage's at the same drive angle, remeshed model), the
misfit model's largest distance from the remeshed one, and their ratio (the issue asks for below 5 %).

Usage::

    .venv/bin/python -m bench misfit_vs_remesh --json out/misfit_vs_remesh.json [--h 0.006]
"""

from __future__ import annotations

import argparse
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf.paper.bennett_scene import bennett_options, build_bennett_from_options
from ffrf.scenes.linkage_run import run_linkage


def coupler_path(variant: str, model: str, h: float, order: int, modes: int, outputs: int) -> tuple[np.ndarray, float]:
    """The coupler point over a quasi-static revolution of ``variant`` with bore errors modelled by ``model``."""
    started = time.perf_counter()
    options = replace(bennett_options(variant, h=h, order=order, n_modes=modes), bore_error_model=model)
    result = run_linkage(build_bennett_from_options(options, variant), "quasi_static", outputs)
    return result.sensors["coupler_point"], time.perf_counter() - started


def compare(h: float, order: int, modes: int, outputs: int) -> dict:
    """Per variant: the deviation its bore error causes, the misfit model's error, their ratio (module docstring)."""
    nominal, _ = coupler_path("pla", "remesh", h, order, modes, outputs)
    rows = {}
    for variant in ("pla1", "pla2"):
        remeshed, remesh_s = coupler_path(variant, "remesh", h, order, modes, outputs)
        misfit, misfit_s = coupler_path(variant, "misfit", h, order, modes, outputs)
        caused = float(np.linalg.norm(remeshed - nominal, axis=1).max())
        error = float(np.linalg.norm(misfit - remeshed, axis=1).max())
        rows[variant] = {
            "deviation_caused_m": caused,
            "misfit_error_m": error,
            "error_over_deviation": error / caused,
            "remesh_run_s": remesh_s,
            "misfit_run_s": misfit_s,
        }
    return {"h_m": h, "order": order, "modes_per_link": modes, "outputs": outputs, "variants": rows}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, default=6e-3)
    parser.add_argument("--order", type=int, default=2)
    parser.add_argument("--modes", type=int, default=4)
    parser.add_argument("--outputs", type=int, default=121)
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    report = compare(args.h, args.order, args.modes, args.outputs)
    write_report(report, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
