"""Smoke test of ``bench/speed_vs_error.py --quick`` (issue 9): the pipeline runs, every point
has the documented keys with finite numbers, and the coupler error shrinks from the 10 mm to the
8 mm mesh against the 6 mm reference (convergence: an independent check, not stored values)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from bench import speed_vs_error

KEYS = {
    "solver",
    "sweep",
    "mode",
    "order",
    "h",
    "modes",
    "step",
    "rho_inf",
    "t_end",
    "setup_s",
    "integration_s",
    "assembly_s",
    "peak_mem_mb",
    "peak_rss_mb",
    "coupler_error_m",
    "torque_error_rel",
}
NUMBERS = (
    "setup_s",
    "integration_s",
    "assembly_s",
    "peak_mem_mb",
    "peak_rss_mb",
    "coupler_error_m",
    "torque_error_rel",
)


def test_quick_sweep_writes_complete_points_that_converge(tmp_path: Path) -> None:
    speed_vs_error.main(["--quick", "--out", str(tmp_path)])
    points = json.loads((tmp_path / "results.json").read_text())
    assert {p["sweep"] for p in points} == {"quasi_static", "dynamic_window"}
    for p in points:
        assert KEYS <= p.keys()
        assert p["solver"] == "ffrf"
        assert all(math.isfinite(p[k]) for k in NUMBERS), p
        assert p["setup_s"] > 0 and p["integration_s"] > 0 and p["peak_rss_mb"] > 0
        assert 0 < p["coupler_error_m"] < 1e-3  # coarse meshes: tens of micrometres
    for sweep in ("quasi_static", "dynamic_window"):
        by_h = {p["h"]: p["coupler_error_m"] for p in points if p["sweep"] == sweep}
        assert by_h[0.008] < by_h[0.01], (sweep, by_h)
    reference = json.loads((tmp_path / "reference.json").read_text())
    # halving the reference's step changes it far less than the meshes' errors
    assert reference["dynamic_reference"]["twice_the_step_coupler_m"] < 1e-2 * min(by_h.values())
    assert (tmp_path / "cheapest.md").read_text().count("| 1 mm |") == 2
    assert (tmp_path / "pareto_quasi_static.png").exists() and (tmp_path / "pareto_dynamic_window.png").exists()
