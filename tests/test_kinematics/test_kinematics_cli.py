"""The main job of this stage: `python -m kinematics bennett` prints the linkage and writes the path."""

import json

import numpy as np

from kinematics.__main__ import main


def test_bennett_command_writes_path_and_summary(tmp_path, capsys):
    assert main(["bennett", "--out", str(tmp_path), "--points", "90"]) == 0
    text = capsys.readouterr().out
    assert "Bennett conditions hold" in text
    assert "h3 = -1j + eps(+0.22k)" in text  # the paper's h_3 = -j + 11/50 eps k
    path = np.loadtxt(tmp_path / "coupler_path.csv", delimiter=",", skiprows=1)
    assert path.shape == (90, 3)
    assert (tmp_path / "coupler_path.png").stat().st_size > 10_000
    summary = json.loads((tmp_path / "kinematics.json").read_text())
    np.testing.assert_allclose(summary["configuration_ratios"], [1, np.sqrt(3), -1, -np.sqrt(3)], atol=1e-12)


def test_misaligned_variant_is_reported_not_mobile(capsys):
    assert main(["bennett", "--alpha3-deg", "92", "--points", "96"]) == 0
    text = capsys.readouterr().out
    assert "Not a Bennett linkage" in text and "NOT mobile" in text
