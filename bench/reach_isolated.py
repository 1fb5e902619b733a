"""Can the printed collisions_free_6r reach its isolated assemblies? The energy barrier from its motion to each
(issue #20; docs/stability.md, docs/formulation.md Eqs. (S7)-(S9)).

Runs ``python -m ffrf linkage --model MODEL --reach`` at the default discretisation (PLA, 6 mm P2 links, 4
fixed-interface modes per link, a quasi-static revolution at 1 rpm with gravity) and keeps, per isolated assembly of
the rigid loop: its distance from the motion, the barrier of the minimum-energy path (string method, 21 images) and
the straight joint-space path's, the largest von Mises stress on the way against PLA's strength, the barrier against
the drive's work over the revolution (where it drives; also against 2 pi times its largest |driving torque|), the
string's iterations and the wall times.

Usage::

    .venv/bin/python -m bench reach_isolated --json out/reach.json

Timings are wall-clock on a shared 2-core machine: compare them only within a run.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

from bench.report import write_report
from ffrf.cli import main as ffrf

KEPT = (
    "barrier_J",
    "straight_path_barrier_J",
    "motion_end_energy_J",
    "assembly_energy_J",
    "peak_image",
    "images",
    "peak_max_von_mises_pa",
    "stress_ratio",
    "work_ratio",
    "verdict",
    "iterations",
    "converged",
    "residual_Nm",
    "seconds",
)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="collisions_free_6r")
    parser.add_argument("--images", type=int, default=21, help="images of the string, both ends included")
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        started = time.perf_counter()
        status = ffrf(
            ["linkage", "--model", args.model, "--reach", "--reach-images", str(args.images), "--out", str(out)]
        )
        wall = time.perf_counter() - started
        if status != 0:
            print(f"python -m ffrf linkage --reach exited with {status}; nothing recorded", file=sys.stderr)
            return status
        reach = json.loads((out / "reach.json").read_text())
        metadata = json.loads((out / "metadata.json").read_text())
    drive = reach["drive"]
    assemblies = []
    for entry in reach["assemblies"]:
        row = {key: entry[key] for key in KEPT}
        row["distance_rms_rad"] = entry["assembly"]["distance_rms_rad"]
        row["distance_max_rad"] = entry["assembly"]["distance_max_rad"]
        row["gap_translation_m"] = entry["assembly"]["gap_translation_m"]
        row["straight_over_barrier"] = entry["straight_path_barrier_J"] / entry["barrier_J"]
        row["max_torque_work_ratio"] = entry["barrier_J"] / drive["max_torque_work_J"]
        assemblies.append(row)
    summary = {
        "model": args.model,
        "h_m": metadata["h"],
        "order": metadata["order"],
        "modes_per_link": metadata["n_modes"],
        "run_mode": metadata["mode"],
        "run_outputs": metadata["n_outputs"],
        "drive": drive,
        "strength_pa": reach["strength_pa"],
        "strength_source": reach["strength_source"],
        "nearby": reach["nearby"],
        "assemblies": assemblies,
        "reach_s": reach["seconds"],
        "wall_time_s": wall,
    }
    write_report(summary, args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
