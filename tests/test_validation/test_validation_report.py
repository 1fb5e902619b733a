"""``python -m validation`` end to end on a coarse PLA scene (the CI guard of issue 7), and the
mode-comparison measures on known cases.

Coarse scene: h = 6 mm, 2 fixed-interface modes per link, 25 quasi-static rows over the ramp
and revolution, 0.1 s dynamic window. Measured on 2026-11-24: coupler and tracked nodes 3e-9 m
(6e-5 of the coupler's elastic deviation), torque 6e-8 relative (quasi-static); frequencies
equal to 4e-13, MAC 1 - 2e-15. The tests hold their own thresholds; they never read the
``TARGETS`` that ``validation`` uses for its verdict.
"""

from __future__ import annotations

import json
from functools import cache

import numpy as np
import pytest

from kinematics import PAPER_A, PAPER_ALPHA
from validation.__main__ import main
from validation.modes import frequency_clusters, mass_mac

ARGS = ["--h", "6e-3", "--order", "1", "--modes", "2", "--outputs", "25", "--dynamic-window", "0.1", "--step", "1e-3"]
REQUIRED_KEYS = (
    "modes",
    "trajectories",
    "torque",
    "coupler_deviation_from_ideal_m",
    "timing_s",
    "versions",
    "settings",
    "checks",
    "passed",
)


@cache
def summary_folder():
    import tempfile
    from pathlib import Path

    folder = Path(tempfile.mkdtemp(prefix="validation-"))
    code = main(["summary", "--variants", "pla", *ARGS, "--out", str(folder)])
    assert code in (0, 1), f"the validation run failed (exit {code})"
    # Exit 2 is a failed run; 0 or 1 is validation's own verdict (its TARGETS), which these tests do not
    # adopt: they hold their own thresholds and only check that the exit code states the verdict.
    passed = json.loads((folder / "pla" / "metrics.json").read_text())["passed"]
    assert code == (0 if passed else 1), code
    return folder


def metrics() -> dict:
    return json.loads((summary_folder() / "pla" / "metrics.json").read_text())


def test_metrics_have_the_documented_keys():
    m = metrics()
    for key in REQUIRED_KEYS:
        assert key in m, key
    assert set(m["modes"]) == {"link0", "link1", "link2", "link3"}
    for body in m["modes"].values():
        assert {"max_rel_freq_diff", "min_mac_diag"} <= set(body)
    assert {"coupler_point", "link1_node0", "link3_node2"} <= set(m["trajectories"])
    assert set(m["coupler_deviation_from_ideal_m"]) >= {"inhouse", "exudyn"}
    for solver in ("inhouse", "exudyn"):
        assert set(m["timing_s"][solver]) >= {"setup", "integration", "total"}
        assert m["timing_s"][solver]["total"] > 0
    assert m["versions"]["exudyn"].startswith("1.13")


def test_coarse_pla_scene_agrees_with_exudyn():
    """The CI guard: fails if the agreement of the two solvers degrades. Thresholds are this test's own,
    about 100x the values measured on 2026-11-24 (AMD EPYC), except the trajectories: there the
    difference is the two marker Jacobians' modelling difference (see the next test), so 10x."""
    m = metrics()
    for link, modes in m["modes"].items():
        assert modes["max_rel_freq_diff"] < 4e-11, link  # measured 4.0e-13 (link2)
        assert 1.0 - modes["min_mac_diag"] < 2e-13, link  # measured 2.0e-15
    assert m["torque"]["max_rel_diff"] < 6e-6  # measured 6.0e-8
    assert m["dynamic"]["torque"]["max_rel_diff"] < 5e-5  # measured 5.3e-7
    for run in (m, m["dynamic"]):
        worst = max(t["relative_to_elastic_deviation"] for t in run["trajectories"].values())
        assert worst < 6e-4  # measured 5.6e-5 (quasi-static), 4.1e-5 (dynamic)
    assert m["passed"] == all(c["value"] < c["target"] for c in m["checks"])  # the verdict states its checks
    assert len(m["checks"]) == 2 * 4 + 2 * 2  # modes per link, quasi-static and dynamic


def test_the_comparison_is_not_vacuous():
    """The coupler sags (tens of micrometres) far above the differences, and the runs really differ
    where the models differ: exact vs Exudyn's gravity, exact vs Exudyn's marker Jacobian."""
    m = metrics()
    deviation = m["coupler_deviation_from_ideal_m"]["exudyn"]
    assert 1e-5 < deviation < 1e-3
    assert deviation == pytest.approx(m["coupler_deviation_from_ideal_m"]["inhouse"], rel=0.05)
    differences = m["modelling_differences"]
    assert differences["with_exudyn_jacobian_vs_exudyn"]["max_abs_diff_m"] < 1e-11  # measured 6.5e-14 m
    assert (
        differences["exact_vs_exudyn_marker_jacobian"]["max_abs_diff_m"]
        > 1e3 * differences["with_exudyn_jacobian_vs_exudyn"]["max_abs_diff_m"]
    )
    assert differences["exact_vs_exudyn_gravity"]["max_abs_diff_m"] > 1e-10
    assert m["constraint_residual"]["inhouse"] < 3e-11  # measured 2.5e-13
    assert m["constraint_residual"]["exudyn"] < 1e-11  # measured 7.9e-14


def test_report_states_the_verdict_first_and_links_its_figures():
    folder = summary_folder() / "pla"
    text = (folder / "report.md").read_text()
    first_screen = "\n".join(text.splitlines()[:12])
    m = metrics()
    missed = sum(not c["passed"] for c in m["checks"])
    state = "all targets met" if not missed else f"{missed} of {len(m['checks'])} targets missed"
    assert f"**Verdict: {state}.**" in first_screen  # the report states the metrics' verdict, whatever it is
    assert "Exudyn 1.13" in first_screen
    for figure in (
        "coupler_deviation.png",
        "driving_torque.png",
        "difference_quasi_static.png",
        "mac.png",
        "difference_dynamic.png",
        "coupler_path.png",
    ):
        assert (folder / figure).stat().st_size > 10_000, figure
        assert f"({figure})" in text


def test_summary_identifies_the_paper_linkage_from_both_solvers():
    """DH parameters identified (paper's method) from our and Exudyn's simulated link trajectories:
    the PLA links sag by tens of micrometres, so a_i and alpha_i land near the paper's table (measured
    0.011 mm and 0.024 deg away on this coarse scene, thresholds well below the paper's 0.134 mm effect),
    and the two solvers' trajectories give the same parameters (measured 2e-6 mm and 1.4e-6 deg apart)."""
    data = json.loads((summary_folder() / "summary.json").read_text())
    identified = data["pla"]["identified"]
    for solver in ("inhouse", "exudyn"):
        dh = identified[solver]
        assert np.allclose(dh["a_mm"], 1e3 * np.asarray(PAPER_A), atol=0.03)
        assert np.allclose(np.abs(dh["alpha_deg"]), np.abs(np.degrees(PAPER_ALPHA)), atol=0.05)
    for key in ("a_mm", "d_mm", "alpha_deg"):
        assert np.allclose(identified["inhouse"][key], identified["exudyn"][key], atol=1e-4), key
    text = (summary_folder() / "summary.md").read_text()
    assert "| pla |" in text and "0.211" in text


def test_mass_mac_is_one_on_matching_modes_and_sees_a_rotation():
    rng = np.random.default_rng(1)
    n = 12
    mass = np.diag(rng.uniform(1.0, 2.0, n))
    modes = np.linalg.qr(rng.normal(size=(n, 3)))[0]
    mac = mass_mac(modes, -2.0 * modes, mass)  # scale and sign do not matter
    assert np.allclose(np.diag(mac), 1.0, atol=1e-14)
    turn = np.cos(0.1) * modes[:, 0] + np.sin(0.1) * modes[:, 1]
    value = mass_mac(modes[:, :1], turn[:, None], mass)[0, 0]
    assert 0.9 < value < 1.0 - 1e-4


def test_frequency_clusters_group_repeated_values():
    groups = frequency_clusters(np.array([1.0, 2.0, 2.0 * (1 + 1e-9), 3.0]))
    assert [list(g) for g in groups] == [[0], [1, 2], [3]]
