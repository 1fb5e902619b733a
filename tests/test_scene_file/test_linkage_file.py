"""Linkage files (ffrf.scenes.linkage_file): a whole linkage from a DH table, axes or a model, in a few lines.

Checked against the paper's Bennett scenes run the built-in way (same discretisation: the same coupler path),
and, for a Rational Linkages model run from the command line with stiff links, against the ideal motion.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ffrf import load
from ffrf.cli import main
from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.scene_file import load_scene
from kinematics import BennettLinkage

COARSE = "h = 0.012\norder = 1\nmodes = 2\n"
DH_FILE = (
    """[linkage]
dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90]}
unit = "mm"
driver = 3
tool_link = 2
start_angle_deg = -90.0
bore_errors = [{joint = 3, link = 0, twist_deg = 1.0}]
"""
    + COARSE
)


#: The default collision-free stacking of the paper's Bennett (``COLLISION_FREE_STACKING``), in mm, as a file says it.
STACKING = (
    "[linkage.stacking]\n"
    "offsets = [-27.7, -32.4, -38.3, -26.8]\nspacers = [3.9, 10.1, 6.9, 4.1]\norders = [1, -1, 1, -1]\n"
)


def _axes_file() -> str:
    lines = []
    for axis in BennettLinkage.paper().axes:
        point = ", ".join(f"{1e3 * x:.17g}" for x in axis.point)
        direction = ", ".join(f"{x:.17g}" for x in axis.direction)
        lines.append(f"{{point = [{point}], direction = [{direction}]}}")
    return DH_FILE.replace(
        "dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90]}", "axes = [" + ", ".join(lines) + "]"
    )


@pytest.fixture(scope="module")
def paper_pla1():
    scene = build_bennett("pla1", h=0.012, order=1, n_modes=2)
    return load(scene).run(mode="quasi_static", outputs=9)


@pytest.mark.parametrize("source", ["dh", "axes"])
def test_the_papers_misaligned_bennett_from_a_linkage_file_runs_as_the_built_in_scene(tmp_path, paper_pla1, source):
    """The paper's DH table (or its axes h0..h3), in mm, with the base's 1 deg bore error and the collision-free
    stacking of :data:`~ffrf.paper.bennett_scene.COLLISION_FREE_STACKING`: the same coupler path and driving torque as
    build_bennett('pla1') (measured 0 m: the same description)."""
    path = tmp_path / "bennett.toml"
    path.write_text((DH_FILE if source == "dh" else _axes_file()) + STACKING)
    ours = load(load_scene(path)).run(mode="quasi_static", outputs=9)
    assert np.max(np.abs(ours.sensors["coupler_point"] - paper_pla1.sensors["coupler_point"])) < 1e-10
    assert np.max(np.abs(ours.sensors["driving_torque"] - paper_pla1.sensors["driving_torque"])) < 1e-10
    assert ours.summary()["max_coupler_deviation_m"] > 5e-4  # a real misfit, not a closable loop


def test_a_stiff_rational_linkages_4r_from_the_command_line_follows_its_ideal_motion(tmp_path, capsys):
    """bennett_ark24 at a quarter of its unit size, rigid: the run follows the ideal motion and writes everything, but
    its default links pass through each other along the motion (the nominal stacking: every link's housings at
    the joint points), so the run is not verified: it exits 3 and its verdict names the clearance."""
    code = main(
        ["linkage", "--model", "bennett_ark24", "--scale", "0.25", "--variant", "rigid", "--h", "0.012", "--order", "1",
         "--modes", "2", "--outputs", "13", "--quasi-static", "--out", str(tmp_path)]
    )  # fmt: skip
    assert code == 3
    metadata = json.loads((tmp_path / "metadata.json").read_text())
    assert metadata["summary"]["max_coupler_deviation_m"] < 1e-8  # E = 1e15 Pa under gravity
    assert metadata["summary"]["max_constraint_residual"] < 1e-10
    written = json.loads((tmp_path / "linkage.json").read_text())
    assert written["linkage"]["model"] == "bennett_ark24"  # the linkage file the options stand for
    for name in ("results.npz", "results.csv", "assembly.vtu", "coupler_deviation.png", "driving_torque.png"):
        assert (tmp_path / name).is_file()
    verification = metadata["verification"]
    assert not metadata["clearance"]["margin_met"] and not verification["verified"]
    assert [reason.split()[0] for reason in verification["reasons"]] == ["clearance"]
    clearance = next(c for c in verification["checks"] if c["name"] == "clearance")
    smallest = min(p["between_poses_m"] for p in metadata["clearance"]["pairs"])
    assert clearance["value"] == 1e-3 and clearance["tolerance"] == smallest < 0.0  # they overlap
    out = capsys.readouterr().out
    assert "max coupler deviation" in out and out.splitlines()[-1].startswith("verified: false: clearance")


def test_a_linkage_file_that_keeps_no_clearance_is_verified_without_it(tmp_path, capsys):
    """``check_clearance = false`` (a model not to be printed): the same linkage as above exits 0, with a note
    instead of the check and no clearance computed."""
    path = tmp_path / "ark.toml"
    path.write_text(
        '[linkage]\nmodel = "bennett_ark24"\nscale = 0.25\ncheck_clearance = false\n'
        "material = {E = 1e15, nu = 0.3, rho = 1e3}\n" + COARSE + '[scene]\noutputs = 13\nmode = "quasi_static"\n'
    )
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    metadata = json.loads((tmp_path / "out" / "metadata.json").read_text())
    assert "clearance" not in metadata
    verification = metadata["verification"]
    assert verification["verified"] and "clearance" not in [c["name"] for c in verification["checks"]]
    assert any("check_clearance = false" in note for note in verification["notes"])
    assert "clearance of the links" not in capsys.readouterr().out


@pytest.mark.slow  # 95 s; collision-free links stay covered by the Goldberg example and plane_fold_6r
def test_collision_free_links_of_a_rational_linkages_4r_from_the_command_line(tmp_path):
    """``--collision-free``: the stacking is designed for the model at the scale asked (half of bennett_ark24's unit
    size, links 121 and 209 mm), and the run's own check on the meshed solids proves every pair of links keeping the
    default 1 mm along the motion (its links at the joint points overlap by 10.8 mm, docs/usage.md), so it exits 0.
    Designed links get an axial gap of the margin + 0.5 mm: beside a joint, an arm trimmed one gap from the other
    link's housing stays that far from it as the joint turns (Eq. (CL3)), which the check between poses could not
    prove to keep a margin equal to the gap; links that share a joint come closest at that gap."""
    code = main(
        ["linkage", "--model", "bennett_ark24", "--scale", "0.5", "--variant", "rigid", "--collision-free",
         "--h", "0.012", "--order", "1", "--modes", "2", "--outputs", "31", "--quasi-static", "--out", str(tmp_path)]
    )  # fmt: skip
    assert code == 0
    written = json.loads((tmp_path / "linkage.json").read_text())
    assert written["linkage"]["collision_free"] is True and "clearance_margin" not in written["linkage"]
    metadata = json.loads((tmp_path / "metadata.json").read_text())
    clearance = metadata["clearance"]
    assert clearance["margin_met"] and clearance["margin_m"] == 1e-3, clearance
    adjacent = [p["clearance_m"] for p in clearance["pairs"] if (p["links"][1] - p["links"][0]) % 2 == 1]
    assert min(adjacent) == pytest.approx(1.5e-3, abs=0.02e-3)  # the widened gap (mesh facets: 0.001 mm off)
    assert metadata["verification"]["verified"]


def test_a_measured_bore_axis_is_the_same_as_built_as_its_twist(tmp_path):
    """The base's joint-3 bore given as the line it is on (the paper's alpha_3 = 91 deg axis h3, in mm) builds the
    same description as the 1 deg twist error: bores, joints and start poses agree to round-off (measured 1.1e-16)."""
    from ffrf.paper.axes import bennett_axes

    h3 = bennett_axes(91.0)[3]
    point = ", ".join(f"{1e3 * x:.17g}" for x in h3.point)
    direction = ", ".join(f"{x:.17g}" for x in h3.direction)
    measured = DH_FILE.replace(
        "bore_errors = [{joint = 3, link = 0, twist_deg = 1.0}]",
        f"bore_errors = [{{joint = 3, link = 0, point = [{point}], direction = [{direction}]}}]",
    )
    (tmp_path / "twist.toml").write_text(DH_FILE)
    (tmp_path / "measured.toml").write_text(measured)
    twist, axis = load_scene(tmp_path / "twist.toml"), load_scene(tmp_path / "measured.toml")
    for a, b in zip(twist.joints, axis.joints, strict=True):
        assert np.max(np.abs(np.subtract(a.axes, b.axes))) < 1e-12
        assert np.max(np.abs(np.subtract(a.points, b.points))) < 1e-12
    np.testing.assert_allclose(axis.q_initial, twist.q_initial, atol=1e-12)


def test_a_run_whose_path_ends_writes_what_it_computed_and_says_where(tmp_path, capsys):
    """plane_fold_6r in PLA under gravity: its quasi-static path ends just past the flat-folded home pose, where
    the rigid loop has first-order mobility 3 (docs/formulation.md, Eq. (S4)). The command exits 1 with one error
    line naming where, and the results up to there are written, the last of them past the fold."""
    path = tmp_path / "plane_fold.toml"
    path.write_text('[linkage]\nmodel = "plane_fold_6r"\n' + COARSE + '[scene]\noutputs = 121\nmode = "quasi_static"\n')
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 1
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "the run stopped" in errors[0] and "are in" in errors[0]
    metadata = json.loads((tmp_path / "out" / "metadata.json").read_text())
    stopped = metadata["stopped"]
    results = np.load(tmp_path / "out" / "results.npz")
    assert results["time"][-1] == pytest.approx(stopped["time_s"]) and 10 < len(results["time"]) < 121
    assert np.degrees(results["drive_angle"][-1]) == pytest.approx(stopped["drive_angle_deg"])
    assert -3.0 < stopped["drive_angle_deg"] < 5.0  # home, the fold, is at 0 deg
    for name in ("results.csv", "assembly.vtu", "coupler_deviation.png", "driving_torque.png"):
        assert (tmp_path / "out" / name).is_file()


@pytest.mark.slow
def test_the_plane_fold_6r_stops_where_its_path_ends_whatever_the_outputs():
    """Issue #32: the quasi-static path is solved on its own steps (docs/formulation.md, Eq. (S10)) and the outputs
    from it, so where the coarse PLA plane_fold_6r's path ends near its flat-folded home pose is the same for 61,
    241 and 961 outputs (it was 0.27, 1.80 and 2.94 deg for the default links when the path was solved at the
    outputs), to the path's own halving resolution of 3 deg / 2^8 (the same path: the same float)."""
    from ffrf.errors import StaticDivergence
    from ffrf.scenes.linkage_file import load_linkage

    document = {"linkage": {"name": "plane_fold_6r pla", "model": "plane_fold_6r", "h": 0.012, "order": 1, "modes": 2}}
    scene = load_linkage(document)
    stops = []
    for outputs in (61, 241, 961):
        with pytest.raises(StaticDivergence) as stopped:
            load(scene).run(mode="quasi_static", outputs=outputs, t_end=30.0, sensors="path")
        stops.append(stopped.value.partial.metadata["stopped"]["drive_angle_deg"])
    assert -3.0 < stops[0] < 5.0  # home, the fold, is at 0 deg
    assert stops[1] == pytest.approx(stops[0], abs=3.0 / 2**8) and stops[2] == pytest.approx(stops[0], abs=3.0 / 2**8)


@pytest.mark.slow
def test_near_rigid_interp_4poses_6r_without_load_follows_rational_linkages_through_its_near_dead_pose():
    """Issue #32: Rational Linkages' interp_4poses_6r passes a near-dead pose at drive angle -16.45 deg where joint 5
    turns 41.6 times faster than the driver. Without gravity nothing strains links of E = 1e15 Pa, so the quasi-static
    path on its own steps (docs/formulation.md, Eq. (S10): at most 6 deg of the fastest joint per step) must follow
    the rigid motion of the nominal loop (traced from Rational Linkages' axes) to round-off through that pose; the
    run names the pose (metadata ``near_dead_poses``). With gravity the same links leave the motion there by
    millimetres (docs/hard_cases.md): the near-bifurcation amplifies their strain."""
    from ffrf.fe.materials import RIGID
    from ffrf.scenes.linkage_file import load_linkage

    material = {"E": RIGID.E, "nu": RIGID.nu, "rho": RIGID.rho, "name": RIGID.name}
    document = {
        "linkage": {"name": "interp_4poses_6r rigid", "model": "interp_4poses_6r", "material": material},
        "scene": {"gravity": [0.0, 0.0, 0.0]},
    }
    result = load(load_linkage(document)).run(mode="quasi_static", outputs=31, t_end=9.0, sensors="path")
    angles = np.degrees(result.sensors["drive_angle"])
    assert angles.min() < -16.45 < angles.max()
    assert np.max(np.linalg.norm(result.sensors["coupler_deviation"], axis=1)) < 1e-10
    (pose,) = result.metadata["near_dead_poses"]
    assert pose["joint"] == 5 and pose["ratio"] == pytest.approx(41.6, abs=0.05)
    assert pose["drive_angle_deg"] == pytest.approx(-16.45, abs=0.05)


def test_a_bore_s_tilt_and_shift_are_read_in_degrees_and_the_file_s_unit():
    """``tilt_deg`` and ``shift`` of a linkage file's bore error reach the BoreError in rad and m (the file in mm)."""
    import tomllib

    from ffrf.scenes.linkage_file import linkage_options

    text = DH_FILE.replace("twist_deg = 1.0}", "twist_deg = 1.0, tilt_deg = 0.5, shift = 0.2}")
    assert text != DH_FILE
    _, options, _ = linkage_options(tomllib.loads(text))
    (error,) = options.bore_errors
    assert error.tilt == pytest.approx(np.radians(0.5), rel=1e-15) and error.shift == pytest.approx(2e-4, rel=1e-15)
    assert error.twist == pytest.approx(np.radians(1.0), rel=1e-15)
