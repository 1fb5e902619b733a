"""Readers (Vicon CSV, simulation results) and the command line."""

import json

import numpy as np
import pytest
from identification_fixtures import ideal_record, write_vicon_csv

from identification import read_simulation_result, read_vicon_csv
from identification.__main__ import main
from kinematics import BennettLinkage

LINKAGE = BennettLinkage.paper()


@pytest.fixture
def trajectories(rng):
    return ideal_record(LINKAGE, np.linspace(0, 2 * np.pi, 500, endpoint=False), 1, rng)


def test_vicon_reader_scales_and_keeps_missing_frames_as_nan(tmp_path, trajectories):
    path = tmp_path / "run1.csv"
    base = {0: np.zeros_like(trajectories[1])}
    write_vicon_csv(path, {**base, **trajectories}, rate=100.0, missing_frames={7, 8})
    record = read_vicon_csv(path)
    assert sorted(record.points) == [1, 2, 3]  # the base segment (link 0) is not needed
    np.testing.assert_allclose(record.time[:3], [0.01, 0.02, 0.03])
    assert np.isnan(record.points[2][7]).all() and np.isnan(record.points[2][8]).all()
    np.testing.assert_allclose(record.points[3][100], trajectories[3][100], atol=1e-11)


def test_cli_on_vicon_runs_prints_table_and_json(tmp_path, trajectories, capsys, rng):
    paths = []
    for run in range(3):
        noisy = {k: v + 2e-5 * rng.normal(size=v.shape) for k, v in trajectories.items()}
        paths.append(tmp_path / f"run{run}.csv")
        write_vicon_csv(paths[-1], noisy, missing_frames={40})
    assert main(["--vicon", *map(str, paths), "--window", "1", "--out", str(tmp_path / "report")]) == 0
    text = capsys.readouterr().out
    assert "| 1 | 220.000 |" in text and "| 3 | 220.000 |" in text
    assert (tmp_path / "report" / "dh_table.csv").exists() and (tmp_path / "report" / "axis_fits.png").exists()
    assert main(["--vicon", *map(str, paths), "--window", "1", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(payload["mean"]["a"], LINKAGE.a, atol=2e-5)
    np.testing.assert_allclose(payload["mean"]["alpha"], LINKAGE.alpha, atol=2e-4)
    assert len(payload["runs"]) == 3 and payload["runs"][0]["revolutions"] == pytest.approx(1.0, abs=0.01)


def test_simulation_result_reader_and_cli(tmp_path, rng, capsys):
    points = ideal_record(LINKAGE, np.linspace(0, 2 * np.pi, 400, endpoint=False), 3, rng)
    arrays = {"time": np.linspace(0, 60, 400)}
    for link, p in points.items():
        for j in range(3):
            arrays[f"link{link}_node{j}"] = p[:, j]
    np.savez(tmp_path / "results.npz", **arrays)
    record = read_simulation_result(tmp_path)
    assert record.points[2].shape == (400, 3, 3)
    assert main(["--result", str(tmp_path), "--window", "1", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(payload["mean"]["a"], LINKAGE.a, atol=1e-10)
    np.testing.assert_allclose(payload["mean"]["d"], 0.0, atol=1e-10)
    assert main(["--result", str(tmp_path / "missing")]) == 2
    assert "results.npz not found" in capsys.readouterr().err


def test_cli_reports_errors_clearly(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("not,a,vicon,file\n1,2,3,4\n")
    assert main(["--vicon", str(bad)]) == 2
    assert "no 'Frame, Sub Frame" in capsys.readouterr().err
