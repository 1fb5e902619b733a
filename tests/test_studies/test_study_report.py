"""What a study's report says of its own numbers (issue #37): every sensitivity with its interval, and warnings
where a reader would otherwise take noise for a result. The rows are written here (a Saltelli design of the
Ishigami function, Saltelli et al., Global Sensitivity Analysis: The Primer, 2008), so nothing is built or run."""

import json

import numpy as np
import pytest

from ffrf.paper.bennett_scene import STUDY_BASES
from ffrf.studies.report import analyse, write_report
from ffrf.studies.runner import _description, _write_batch, row_schema
from ffrf.studies.sampling import study_design
from ffrf.studies.spec import study_from_document
from ffrf.studies.variant import print_end

OUTPUT = "max_coupler_deviation_m"


def _ishigami(x: np.ndarray) -> np.ndarray:
    return np.sin(x[:, 0]) + 7.0 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])


def _folder(tmp_path, method: str, samples: int, share: float = 1.0):
    """A study folder of three uniform parameters on [-pi, pi] whose rows carry the Ishigami function as their
    largest coupler deviation, for the first ``share`` of the design's variants."""
    parameters = [
        {"name": name, "target": target, "uniform": {"low": -np.pi, "high": np.pi}}
        for name, target in (("x1", "E"), ("x2", "rho"), ("x3", "rpm"))
    ]
    study = study_from_document(
        {
            "study": {"method": method, "samples": samples, "seed": 1},
            "base": {"bennett": "pla"},
            "parameters": parameters,
        },
        bases=STUDY_BASES,
    )
    design = study_design(study)[: int(share * len(study_design(study)))]
    x = np.array([[v.values[n] for n in ("x1", "x2", "x3")] for v in design])
    rows = [
        {"id": v.id, "block": v.block, "sample": v.sample, "status": "ok", "reason": "", "assembles": True,
         "wall_time_s": 1.0, OUTPUT: float(y)} | v.values
        for v, y in zip(design, _ishigami(x), strict=True)
    ]  # fmt: skip
    (tmp_path / "study.json").write_text(json.dumps(_description(study)))
    _write_batch(rows, row_schema(study), tmp_path)
    return tmp_path


def test_few_samples_give_wide_sobol_intervals_and_the_report_says_they_rank_nothing(tmp_path):
    """N = 16 (80 variants, as the shipped Saltelli example): the indices come with intervals of several tenths, the
    report warns that they do not rank the parameters, and that a linear model explains little of the output."""
    analysis = analyse(_folder(tmp_path, "saltelli", 16))
    entry = analysis["outputs"][OUTPUT]
    assert max(entry["sobol_total_conf"].values()) > 0.2
    assert entry["sobol_rows_used"] == 16
    warnings = "\n".join(analysis["warnings"])
    assert "Sobol indices are uncertain" in warnings and "raise samples" in warnings
    assert "R^2" in warnings and entry["src_r2"] < 0.5
    report = write_report(tmp_path).read_text()
    assert "## Warnings" in report and "+-" in report


def test_many_samples_give_tight_intervals_around_the_closed_form_and_no_warning_on_them(tmp_path):
    """N = 4096: every index's interval is narrow (below 0.1) and contains the closed form (first order 0.314,
    0.442, 0; total 0.558, 0.442, 0.244); no warning about the indices."""
    analysis = analyse(_folder(tmp_path, "saltelli", 4096))
    entry = analysis["outputs"][OUTPUT]
    first = dict(zip(("x1", "x2", "x3"), (0.3139, 0.4424, 0.0), strict=True))
    total = dict(zip(("x1", "x2", "x3"), (0.5576, 0.4424, 0.2437), strict=True))
    for name in first:
        assert abs(entry["sobol_first"][name] - first[name]) <= entry["sobol_first_conf"][name] < 0.1, name
        assert abs(entry["sobol_total"][name] - total[name]) <= entry["sobol_total_conf"][name] < 0.1, name
    assert not any("Sobol" in warning for warning in analysis["warnings"])


def test_an_unfinished_study_says_so_and_a_random_design_gets_given_data_indices(tmp_path):
    """Half of a Latin hypercube's 2048 rows: the report warns that the study is unfinished (its numbers are of the
    rows there), and gives each parameter's first-order index from the rows as given, with its interval, near the
    closed form (within the interval plus 0.05)."""
    analysis = analyse(_folder(tmp_path, "lhs", 2048, share=0.5))
    assert any("the study is unfinished: 1024 of its 2048 variants" in w for w in analysis["warnings"])
    entry = analysis["outputs"][OUTPUT]
    for name, exact in zip(("x1", "x2", "x3"), (0.3139, 0.4424, 0.0), strict=True):
        value, half = entry["given_data_first"][name], entry["given_data_first_conf"][name]
        assert abs(value - exact) <= half + 0.05, (name, value, half)


def test_the_print_shop_report_lists_every_unfinished_print_the_worst_and_where_their_maxima_occur(tmp_path):
    """A Monte Carlo design of 200 prints whose rows are written here: every 25th print did not assemble (8), every
    other 10th stopped on its path after assembling (16, their assembly energy kept). The report lists the 24
    unfinished prints in the design's order with their parameters and reasons (all in unfinished.csv), shows outputs
    in mm, counts the stopped prints' assembly energy, names the five worst prints by deviation with the drive angle
    of their maximum, and the percentiles' convergence ends at the percentiles of all ok prints."""
    parameters = [{"name": "twist", "target": "E", "uniform": {"low": 0.0, "high": 1.0}}]
    study = study_from_document(
        {
            "study": {"method": "monte_carlo", "samples": 200, "seed": 3},
            "base": {"bennett": "pla"},
            "parameters": parameters,
        },
        bases=STUDY_BASES,
    )
    design = study_design(study)
    rows, stopped, unassembled = [], [], []
    for v in design:
        x = v.values["twist"]
        row = {
            "id": v.id,
            "block": v.block,
            "sample": v.sample,
            "wall_time_s": 1.0,
            "status": "ok",
            "reason": "",
            "assembles": True,
            "assembly_strain_energy_J": 1e-3 * x,
            "last_drive_angle_deg": 270.0,
        } | v.values
        if v.sample % 25 == 0:
            row |= {
                "status": "failed",
                "reason": "no assembly: diverged",
                "assembles": False,
                "assembly_strain_energy_J": None,
                "last_drive_angle_deg": None,
            }
            unassembled.append(v.id)
        elif v.sample % 10 == 0:
            row |= {"status": "failed", "reason": "the run stopped: no equilibrium", "last_drive_angle_deg": 16.0 * x}
            stopped.append(v.id)
        else:
            row |= {OUTPUT: 2e-3 * x, "max_coupler_deviation_at_deg": 90.0 + x}
        rows.append(row | {"end": print_end(row)})
    (tmp_path / "study.json").write_text(json.dumps(_description(study)))
    _write_batch(rows, row_schema(study), tmp_path)
    analysis = analyse(tmp_path)
    unfinished = analysis["unfinished"]
    by_sample = sorted(design, key=lambda v: v.sample)
    assert [p["id"] for p in unfinished] == [v.id for v in by_sample if v.id in stopped or v.id in unassembled]
    assert len(unfinished) == 8 + 16 and len(stopped) == 16
    first = next(p for p in unfinished if p["id"] in stopped)
    twist = first["parameters"]["twist"]
    assert first["assembles"] is True and first["last_drive_angle_deg"] == pytest.approx(16.0 * twist)
    assert "no equilibrium" in first["reason"]
    assert analysis["outputs"]["assembly_strain_energy_J"]["percentiles"]["n"] == 200 - 8
    ends = analysis["ends"]
    assert (ends["completed"], ends["no assembly"], ends["stopped (unclassified)"]) == (176, 8, 16)
    assert analysis["unclassified"]["exceeding"] == 16 and analysis["unclassified"]["n"] == 200
    assert any("16 of 200 prints stopped for a reason the solver does not classify" in w for w in analysis["warnings"])
    ok = np.array([v.values["twist"] for v in design if v.id not in stopped and v.id not in unassembled])
    worst = analysis["worst"]["max_coupler_deviation_m"]
    np.testing.assert_allclose([p["value"] for p in worst], 2.0 * np.sort(ok)[::-1][:5], rtol=1e-12)  # mm
    np.testing.assert_allclose([p["at_deg"] for p in worst], 90.0 + np.sort(ok)[::-1][:5], rtol=1e-12)
    final = analysis["outputs"][OUTPUT]["convergence"][-1]
    assert final["n"] == ok.size
    np.testing.assert_allclose([final["p50"], final["p95"]], np.percentile(2e-3 * ok, [50, 95]), rtol=1e-12)
    report = write_report(tmp_path).read_text()
    assert "## Prints that did not finish" in report and "24 prints" in report
    assert f"| max_coupler_deviation | mm | {ok.size} |" in report
    assert f"{2.0 * ok.max():.4g}" in report  # the worst print in mm
    lines = (tmp_path / "unfinished.csv").read_text().strip().splitlines()
    assert len(lines) == 1 + 24 and lines[0].startswith("id,assembles,last_drive_angle_deg,twist,reason")
    assert (tmp_path / "figures" / f"{OUTPUT}_convergence.png").is_file()


def test_every_end_of_a_print_is_named_from_its_row():
    """Each way a print's run ends (ffrf.studies.outputs.ENDS) is told from its row: the snaps it went through, and
    the reason of a stop as the solver words it (a fold whose traced path finds no landing, a near-dead pose)."""
    from ffrf.solvers.snap_through import NO_LANDING
    from ffrf.studies.outputs import ENDS

    stopped = {"status": "failed", "assembles": True}
    rows = {
        "completed": {"status": "ok", "snaps": 0},
        "completed through snaps": {"status": "ok", "snaps": 2},
        "no assembly": {"status": "failed", "reason": "no assembly: Newton diverged"},
        "stopped at a near-dead pose": stopped
        | {"reason": "the run stopped: near-dead point of the rigid loop at drive angle 16 deg: joint 2 turns fast"},
        "stopped at a fold without landing": stopped
        | {"reason": f"the run stopped: quasi-static path step 9 at t = 3 s: {NO_LANDING.format(t=2.9)}"},
        "stopped (unclassified)": stopped | {"reason": "the run stopped: static Newton did not converge"},
        "bad input": {"status": "failed", "reason": "bad input: the mesh is empty"},
        "error": {"status": "failed", "reason": "ValueError: something else"},
    }
    assert set(rows) == set(ENDS)
    for end, row in rows.items():
        assert print_end(row) == end
