"""Stability along a quasi-static run (``--stability``, Eq. (B1)): the paper's nominal PLA Bennett linkage has no
unstable pose over a revolution, and its smallest squared frequency is the lowest vibration of the linkage."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from ffrf.cli import main
from ffrf.scenes.linkage_description import LinkageOptions
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage
from kinematics.rational_mechanism import load_model, loop_from_mechanism, regular_start


def test_the_nominal_pla_bennett_is_stable_over_a_revolution(tmp_path, capsys):
    """Coarse links (12 mm, P1, 2 modes), 25 quasi-static poses: every equilibrium's smallest squared frequency is
    positive (a linkage that moves smoothly, as the paper's prints do), the run says where the margin is smallest,
    and stability.json and stability.png are written."""
    code = main(
        ["bennett", "--variant", "pla", "--h", "0.012", "--order", "1", "--modes", "2", "--outputs", "25",
         "--quasi-static", "--stability", "--out", str(tmp_path)]
    )  # fmt: skip
    assert code == 0
    table = json.loads((tmp_path / "stability.json").read_text())
    values = np.array(table["squared_frequencies_rad2_per_s2"])
    assert values.shape == (25, 3) and np.all(values[:, 0] > 0.0)
    summary = table["summary"]
    assert summary["unstable_poses"] == 0 and summary["min_squared_frequency"] == values[:, 0].min()
    assert (tmp_path / "stability.png").is_file()
    assert "stability: smallest squared frequency" in capsys.readouterr().out
    assert summary["sign_changes"] == [] and summary["snaps"] == []
    critical = summary["critical"]
    assert critical["where"] == "least stable output"
    assert critical["squared_frequency"] == pytest.approx(values[:, 0].min(), rel=1e-9)
    assert sum(critical["link_shares"].values()) == pytest.approx(1.0, rel=1e-12)
    mode = meshio.read(tmp_path / "stability_critical.vtu").point_data["critical_mode"]
    assert np.linalg.norm(mode, axis=1).max() == pytest.approx(1.0, rel=1e-12)


@pytest.mark.slow
def test_a_coarse_plane_fold_6r_snaps_at_a_fold_where_its_critical_mode_loses_its_stiffness():
    """Eq. (S6) on a linkage: the coarse printed plane_fold_6r (12 mm P1 links, 2 modes) folds just before its flat
    pose. Two independent views of the fold agree: continuation finds the turn of the drive angle (-0.71 deg), and
    Eq. (B1) there has a squared frequency near zero (measured 15 rad^2/s^2, against 1.7e4 for the same mode 2 deg
    earlier). The landing is stable, releases energy (1.1 mJ) and the run goes on past the fold."""
    model = load_model("plane_fold_6r")
    loop = loop_from_mechanism(model, 0.1)
    origin = regular_start(model, loop)
    options = LinkageOptions(h=12e-3, order=1, n_modes=2, start_angle=float(origin[0]), origin=origin, tool_link=3)
    scene = build_linkage(loop, options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=51, t_end=26.0, stability=True)
    (snap,) = result.metadata["stability"]["snaps"]
    assert snap["landed"] and snap["energy_released_J"] > 0.0
    assert -3.0 < snap["drive_angle_deg"] < 1.0  # within a few degrees of the rigid loop's flat fold at 0
    earlier = result.sensors["stability_squared_frequencies"]
    angles = np.degrees(result.sensors["drive_angle"])
    before = earlier[(angles < snap["drive_angle_deg"] - 1.5) & (angles > snap["drive_angle_deg"] - 4.0)]
    assert abs(snap["squared_frequency_at_fold"]) < 1e-2 * before[:, 1].max()
    assert result.time[-1] == pytest.approx(26.0)
    assert result.metadata["stability"]["critical"]["where"] == "fold"


def test_stability_of_a_dynamic_run_is_refused(tmp_path, capsys):
    code = main(["bennett", "--h", "0.012", "--order", "1", "--modes", "2", "--dynamic", "--stability",
                 "--out", str(tmp_path)])  # fmt: skip
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "stability is judged at equilibria" in err
