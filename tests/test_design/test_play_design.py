"""The largest play of a linkage's passive joints that keeps its coupler within a bound (Eq. (P8)): the search
against closed-form deviation laws (where the bound's root is known), what it does when the bound is met everywhere,
nowhere or in two stretches, and ``python -m ffrf design`` with a ``[play]`` table on the coarse loose Bennett."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest
from scene_fixtures import LOOSE_BENNETT_FILE

from ffrf.errors import SceneError
from ffrf.scenes.play_design import PlayPoint, PlayProblem, largest_play, load_play_design


def _law(deviation, verified=lambda c: True, stopped=lambda c: None):
    """An evaluator whose largest deviation is ``deviation(c)`` (m), with the play ``c`` in m."""
    calls: list[float] = []

    def evaluate(radial: float) -> PlayPoint:
        calls.append(radial)
        return PlayPoint(radial, float(deviation(radial)), 0.0, radial, verified(radial), stopped(radial), 0.0)

    return evaluate, calls


@pytest.mark.parametrize(("d0", "slope"), [(0.168e-3, 10.6), (1.03e-3, 5.8), (0.0, 1.0)])
def test_the_largest_play_brackets_the_root_of_a_linear_deviation_law_within_the_resolution(d0, slope):
    """D(c) = d0 + s c (the coarse loose Bennett measures s = 10.6: pins tilting by 2c/L in their bores): the answer
    c* and the first failing play c+ bracket the root (bound - d0)/s, c+ - c* <= the resolution, and the runs are
    the grid's plus the bisection's, log2 of the bracket over the resolution."""
    problem = PlayProblem(max_deviation=2e-3, largest=0.3e-3, resolution=0.01e-3, grid=3)
    evaluate, calls = _law(lambda c: d0 + slope * c)
    design = largest_play(problem, evaluate)
    root = (problem.max_deviation - d0) / slope
    assert design.largest is not None and design.monotone
    if root >= problem.largest:
        assert design.largest.radial == problem.largest and design.failing is None
        assert len(calls) == problem.grid + 1
        return
    assert design.failing is not None
    assert design.largest.radial <= root < design.failing.radial
    assert design.failing.radial - design.largest.radial <= problem.resolution
    assert len(calls) == problem.grid + 1 + int(np.ceil(np.log2(problem.largest / problem.grid / problem.resolution)))
    assert [p.radial for p in design.points] == sorted(calls)


def test_a_run_that_stops_or_does_not_verify_itself_misses_the_bound_whatever_its_deviation():
    problem = PlayProblem(max_deviation=1.0, largest=0.4e-3, resolution=0.05e-3, grid=4)
    evaluate, _ = _law(lambda c: 0.0, stopped=lambda c: "no equilibrium" if c > 0.25e-3 else None)
    stopped = largest_play(problem, evaluate)
    assert stopped.largest is not None and stopped.failing is not None
    assert stopped.largest.radial <= 0.25e-3 < stopped.failing.radial
    evaluate, _ = _law(lambda c: 0.0, verified=lambda c: c < 0.15e-3)
    unverified = largest_play(problem, evaluate)
    assert unverified.largest is not None and unverified.failing is not None
    assert unverified.largest.radial < 0.15e-3 <= unverified.failing.radial


def test_a_bound_met_again_above_a_miss_is_reported_and_the_first_bracket_kept():
    """D dips below the bound again between 0.2 and 0.3 mm: the answer stays in the first bracket (the conservative
    one) and the design says the plays met the bound in two stretches."""
    problem = PlayProblem(max_deviation=1e-3, largest=0.3e-3, resolution=0.01e-3, grid=3)
    evaluate, _ = _law(lambda c: 0.5e-3 + 5.0 * c if c < 0.25e-3 else 0.0)
    design = largest_play(problem, evaluate)
    assert not design.monotone
    assert design.largest is not None and design.failing is not None
    assert design.largest.radial <= 0.1e-3 < design.failing.radial <= 0.1e-3 + problem.resolution


def test_when_ideal_joints_miss_the_bound_there_is_no_answer():
    problem = PlayProblem(max_deviation=1e-3, largest=0.3e-3, resolution=0.01e-3, grid=2)
    design = largest_play(problem, _law(lambda c: 2e-3 + c)[0])
    assert design.largest is None and design.failing is not None and design.failing.radial == 0.0


PLAY_FILE = (
    LOOSE_BENNETT_FILE
    + """
[play]
max_deviation = 5.0
largest_mm = 0.1
grid = 1
resolution_mm = 0.05
outputs = 5
"""
)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d["play"].update(resolution_mm=0.2), "resolution_mm"),
        (lambda d: d["play"].update(largest_mm=-0.1), "largest_mm"),
        (lambda d: d["play"].update(grid=0), "grid"),
        (lambda d: d["play"].update(radial_mm=0.1), "radial_mm"),
        (lambda d: d["play"].pop("max_deviation"), "max_deviation"),
    ],
)
def test_a_bad_play_table_is_refused_in_one_line(change, message):
    document = tomllib.loads(PLAY_FILE)
    change(document)
    with pytest.raises(SceneError, match=message) as error:
        load_play_design(document, "play.toml")
    assert "\n" not in str(error.value)


def test_a_design_file_with_both_a_section_and_a_play_is_refused(tmp_path):
    from ffrf.cli import main

    path = tmp_path / "both.toml"
    path.write_text(
        PLAY_FILE + '\n[design]\nparameters = ["arm_width"]\nlower = [8]\nupper = [20]\nmax_deviation = 1\n'
    )
    assert main(["design", str(path), "--out", str(tmp_path / "out")]) == 2


def _design(tmp_path, text: str) -> tuple[int, dict, dict]:
    from ffrf.cli import main

    path = tmp_path / "play.toml"
    path.write_text(text)
    status = main(["design", str(path), "--out", str(tmp_path / "out")])
    summary = json.loads((tmp_path / "out" / "design.json").read_text())
    return status, summary, tomllib.loads((tmp_path / "out" / "designed.toml").read_text())


def test_a_play_design_whose_bound_holds_up_to_the_largest_play_writes_that_play_and_checks_it(tmp_path, capsys):
    """The coarse loose Bennett over 18 deg with a generous bound (5 mm; its pins tilt by about 2c/L = 0.017 rad):
    both plays of the grid meet it, so the designed file carries the largest, 0.1 mm, with the file's 12 mm pins,
    and its own run verifies itself within the bound."""
    status, summary, designed = _design(tmp_path, PLAY_FILE)
    assert status == 0
    assert [p["radial_mm"] for p in summary["evaluated"]] == [0.0, 0.1]
    assert all(p["meets"] and p["verified"] for p in summary["evaluated"])
    assert summary["largest"]["radial_mm"] == 0.1 and summary["failing"] is None
    assert designed["scene"]["clearance"] == {"radial_mm": 0.1, "pin_length_mm": 12.0}
    assert "play" not in designed
    check = json.loads((tmp_path / "out" / "check" / "metadata.json").read_text())
    assert check["verification"]["verified"]
    assert 1e3 * check["summary"]["max_coupler_deviation_m"] <= summary["problem"]["max_deviation_mm"]
    assert "up to a play of 0.1 mm" in capsys.readouterr().err


@pytest.mark.slow
def test_a_play_design_bisects_to_the_play_where_the_coupler_leaves_its_bound(tmp_path):
    """The same linkage with the coupler held within 1 mm: the ideal joints meet it, 0.1 mm of play does not
    (pins tilting by 2c/L over 18 deg of drive), the bisection ends at 0.05 mm, whose designed file's own run
    meets the bound, while the failing play's deviation exceeds it. Measured 70 s on the 2-core machine."""
    status, summary, designed = _design(tmp_path, PLAY_FILE.replace("max_deviation = 5.0", "max_deviation = 1.0"))
    assert status == 0
    failing, largest = summary["failing"], summary["largest"]
    assert failing["max_deviation_mm"] > 1.0 >= largest["max_deviation_mm"]
    assert failing["radial_mm"] - largest["radial_mm"] <= 0.05
    assert designed["scene"]["clearance"]["radial_mm"] == largest["radial_mm"]
    check = json.loads((tmp_path / "out" / "check" / "metadata.json").read_text())
    assert check["verification"]["verified"] and 1e3 * check["summary"]["max_coupler_deviation_m"] <= 1.0
