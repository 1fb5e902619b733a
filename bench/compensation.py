"""Bore corrections that compensate the deviation from the ideal path: the PLA Bennett and a 6R (issue #35).

    .venv/bin/python -m bench record compensation                  # docs/results/compensation.json
    .venv/bin/python -m bench compensation --json out/comp.json     # the rows alone

For the PLA Bennett and its 1 deg variant (default discretisation, 121 quasi-static poses over the ramp and a
revolution) and Rational Linkages' collisions_free_6r in PLA (``examples/collisions_free_6r.toml``, the same poses):
``ffrf.scenes.compensation.compensate`` (corrections within 0.5 deg and 0.2 mm), and the corrected print run in full
twice: with the corrections as joint misfits (the model the first order is of) and remeshed on the corrected bores
(the parts as printed), then the drive's correction along the motion of the print as printed
(``ffrf.scenes.drive_correction.correct_drive``: the part of what remains along the path, where the task is a path).
Per variant the largest deviation before, predicted, after both runs and after the drive's correction (against the
print's distance to the ideal curve, which no drive removes), the corrections and the times.
"""

from __future__ import annotations

import argparse
import time
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from bench.report import write_report
from ffrf.paper.bennett_scene import _paper_loop, bennett_options
from ffrf.scenes.compensation import compensate, with_corrections
from ffrf.scenes.drive_correction import correct_drive
from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage

OUTPUTS = 121
ROOT = Path(__file__).resolve().parents[1]


def _forward(loop, options, model: str, drive: bool = False) -> dict:
    started = time.perf_counter()
    scene = build_linkage(loop, replace(options, bore_error_model=model))
    result = run_linkage(scene, mode="quasi_static", n_outputs=OUTPUTS, sensors="path")
    deviation = np.linalg.norm(result.sensors["coupler_deviation"], axis=1)
    out: dict[str, Any] = {"max_coupler_deviation_m": float(deviation.max()), "seconds": time.perf_counter() - started}
    if drive:
        assert result.multipliers is not None
        corrected = correct_drive(scene, result.time, result.q, result.multipliers)
        out["drive"] = {
            "max_coupler_deviation_m": corrected.after_m,
            "max_distance_to_path_m": float(result.sensors["coupler_distance_to_path"].max()),
            "max_correction_deg": float(np.degrees(np.abs(corrected.corrected_angle - corrected.drive_angle)).max()),
            "clipped": corrected.clipped,
            "seconds": corrected.seconds,
        }
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    document = tomllib.loads((ROOT / "examples" / "collisions_free_6r.toml").read_text())
    six_r = linkage_options(document, "collisions_free_6r")[:2]
    cases = [("pla", _paper_loop(), bennett_options("pla")), ("pla1", _paper_loop(), bennett_options("pla1"))]
    rows = []
    for variant, loop, options in [*cases, ("collisions_free_6r", *six_r)]:
        compensation = compensate(loop, options, outputs=OUTPUTS)
        corrected = with_corrections(options, compensation.corrections)
        printed = _forward(loop, corrected, "remesh", drive=True)
        row: dict = {
            "variant": variant,
            "before_m": compensation.before_m,
            "predicted_m": compensation.predicted_m,
            "design_s": compensation.seconds,
            "corrections": [
                {
                    "joint": c.joint,
                    "link": c.link,
                    "twist_deg": float(np.degrees(c.twist)),
                    "offset_m": c.offset,
                    "axial_m": c.axial,
                }
                for c in compensation.corrections
            ],  # fmt: skip
            "misfit": _forward(loop, corrected, "misfit"),
            "remesh": printed,
            "reduction": compensation.before_m / printed["max_coupler_deviation_m"],
            "reduction_with_drive": compensation.before_m / printed["drive"]["max_coupler_deviation_m"],
        }
        print(variant, {k: row[k] for k in ("before_m", "predicted_m", "reduction")}, flush=True)
        rows.append(row)
    write_report({"outputs": OUTPUTS, "rows": rows}, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
