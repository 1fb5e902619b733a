"""Stability along a quasi-static run (``--stability``, Eq. (B1)): the paper's nominal PLA Bennett linkage has no
unstable pose over a revolution, and its smallest squared frequency is the lowest vibration of the linkage."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from ffrf import load
from ffrf.cli import main
from ffrf.scenes.linkage_description import LinkageOptions
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
    result = load(scene).run(mode="quasi_static", outputs=51, t_end=26.0, stability=True)
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


#: One print of the paper's PLA Bennett with every bore off (joint, link, twist deg, offset mm), drawn by the
#: 2000-print study (examples/study_bennett_pla_2000.toml): near the pose where all four joints pass 180 deg (t = 16 s)
#: its equilibrium path turns within one quasi-static step.
SHARP_PRINT = (
    (0, 0, 0.4342, -0.0363),
    (0, 1, 0.0822, 0.0057),
    (1, 1, 1.2655, -0.0748),
    (1, 2, 0.0821, 0.1031),
    (2, 2, 0.5452, 0.0104),
    (2, 3, 0.0705, -0.1099),
    (3, 0, -0.148, -0.1165),
    (3, 3, -0.5407, 0.0244),
)


def test_a_sharp_turn_of_the_path_without_a_fold_is_followed_onto_the_branch_the_dynamics_follow(monkeypatch):
    """Plain quasi-static steps follow the sharp turn along the path's tangent (Eq. (S4)); steps that may not be
    halved stop at it, and a ``stability`` run then bridges the stretch by continuation (Eq. (S5)) and completes
    with no snap. Both reach the equilibrium Newton finds from the state of a dynamic run of the same print at that
    time (an independent path to it: the linkage at 1 rpm stays near equilibrium)."""
    from dataclasses import replace

    from ffrf.errors import StaticDivergence
    from ffrf.paper.bennett_scene import bennett_options, build_bennett_from_options
    from ffrf.scenes.linkage_description import BoreError
    from ffrf.solvers import static_solver
    from ffrf.solvers.static_solver import static_equilibrium

    errors = tuple(BoreError(j, k, np.radians(twist), 1e-3 * offset) for j, k, twist, offset in SHARP_PRINT)
    scene = build_bennett_from_options(
        replace(bennett_options("pla", collision_free=False), bore_errors=errors, bore_error_model="misfit")
    )
    followed = load(scene).run("quasi_static", outputs=121)
    assert followed.time[-1] == pytest.approx(scene.t_end)
    monkeypatch.setattr(static_solver, "MAX_HALVINGS", 0)
    with pytest.raises(StaticDivergence) as stopped:
        load(scene).run("quasi_static", outputs=121)
    t_stop = float(stopped.value.partial.time[-1])
    bridged = load(scene).run("quasi_static", outputs=121, stability=True)
    assert bridged.metadata["stability"]["snaps"] == [] and bridged.time[-1] == pytest.approx(scene.t_end)
    row = int(np.searchsorted(bridged.time, t_stop)) + 1  # the first output after the stop: bridged
    dynamic = load(scene).run("dynamic", outputs=121, step=5e-3, t_end=float(bridged.time[row]))
    from_dynamics = static_equilibrium(scene.system, dynamic.q[-1], float(bridged.time[row]))
    assert np.max(np.abs(from_dynamics.q - bridged.q[row])) < 1e-8
    assert np.max(np.abs(from_dynamics.q - followed.q[row])) < 1e-8
