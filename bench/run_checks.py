"""How far the default runs are from failing their own checks (ffrf.output.verification), and the exact distance to
the ideal path against the polyline it replaced (issue #32).

    .venv/bin/python -m bench record run_checks                     # docs/results/run_checks.json
    .venv/bin/python -m bench run_checks --json out/run_checks.json  # the rows alone

Runs, at the command line's defaults (961 outputs, 6 mm P2, 4 modes): the PLA and rigid Bennett linkages
quasi-statically, PLA dynamically (10 ms steps), collisions_free_6r in PLA and rigid, and the stiff Bennett and
collisions_free_6r without gravity (241 outputs). Per run: every check's value, tolerance and margin (tolerance /
value), the warnings; for the unloaded stiff runs the largest distance to the path, exact and by the polyline
through the samples the old metric used (4000 for the Bennett, 720 for any loop), and the distance's time.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf.output.path_distance import distance_to_curve
from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.linkage_file import load_linkage
from ffrf.scenes.linkage_run import run_linkage

OUTPUTS = 961


def polyline_distance(points: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """Distance to the closed polyline through ``curve`` (the metric before issue #32)."""
    chord = np.roll(curve, -1, axis=0) - curve
    chord2 = np.einsum("ij,ij->i", chord, chord)
    out = np.empty(len(points))
    for k in range(0, len(points), 32):
        rel = points[k : k + 32, None, :] - curve[None]
        s = np.clip(np.einsum("cij,ij->ci", rel, chord) / chord2, 0.0, 1.0)
        gap = rel - s[..., None] * chord
        out[k : k + 32] = np.sqrt(np.min(np.einsum("cij,cij->ci", gap, gap), axis=1))
    return out


def six_r(
    material: dict,
    gravity: tuple[float, float, float],
    h: float = 6e-3,
    order: int = 2,
    modes: int = 4,
    model: str = "collisions_free_6r",
):
    return load_linkage(
        {
            "linkage": {
                "name": model,
                "model": model,
                "scale": 0.1,
                "material": material,
                "h": h,
                "order": order,
                "modes": modes,
            },
            "scene": {"gravity": list(gravity)},
        },
        where=model,
    )


def measure(name: str, scene, mode: str, outputs: int, distances: bool = False) -> dict:
    began = time.perf_counter()
    result = run_linkage(scene, mode=mode, n_outputs=outputs)
    row = {
        "name": name,
        "mode": mode,
        "outputs": outputs,
        "run_s": time.perf_counter() - began,
        "verified": result.metadata["verification"]["verified"],
        "checks": {c["name"]: c for c in result.metadata["verification"]["checks"]},
        "warnings": result.metadata["verification"]["warnings"],
        "summary": result.summary(),
    }
    if distances:
        points = result.sensors["coupler_point"]
        curve = scene.ideal_coupler_exact()
        distance_to_curve(points, curve)  # once before timing: the samples are traced and kept
        began = time.perf_counter()
        exact = distance_to_curve(points, curve).distance
        row["distance_s"] = time.perf_counter() - began
        row["max_distance_exact_m"] = float(np.max(exact))
        row["max_distance_polyline_m"] = float(np.max(polyline_distance(points, scene.ideal_coupler_curve())))
        row["max_deviation_m"] = float(np.max(np.linalg.norm(result.sensors["coupler_deviation"], axis=1)))
    print(name, {k: (c["value"], c["tolerance"], c["margin"]) for k, c in row["checks"].items()}, flush=True)
    return row


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    rigid = {"E": 1e15, "nu": 0.33, "rho": 1250.0, "name": "ideally rigid"}
    pla = {"E": 1.2e9, "nu": 0.33, "rho": 450.0, "name": "PLA", "strength": 53e6}
    rows = [
        measure("bennett_pla", build_bennett("pla"), "quasi_static", OUTPUTS, distances=True),
        measure("bennett_rigid", build_bennett("rigid"), "quasi_static", OUTPUTS),
        measure("collisions_free_6r_pla", six_r(pla, (0.0, 0.0, -9.81)), "quasi_static", OUTPUTS, distances=True),
        measure("collisions_free_6r_rigid", six_r(rigid, (0.0, 0.0, -9.81)), "quasi_static", OUTPUTS),
        measure("bennett_pla_dynamic", build_bennett("pla"), "dynamic", OUTPUTS),
        measure(
            "bennett_rigid_unloaded",
            build_bennett("rigid", gravity=(0.0, 0.0, 0.0)),
            "quasi_static",
            241,
            distances=True,
        ),
        measure(
            "collisions_free_6r_rigid_unloaded",
            six_r(rigid, (0.0, 0.0, 0.0), h=12e-3, order=1, modes=2),
            "quasi_static",
            241,
            distances=True,
        ),
    ]
    write_report({"rows": rows}, args.json, echo=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
