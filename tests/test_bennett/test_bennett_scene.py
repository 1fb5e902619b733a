"""The paper's flexible Bennett linkage on a coarse discretisation (the default run uses 4 mm
tetrahedra and 8 modes; the paper 2 mm and 32): against the motion polynomial (rigid),
misalignment trend (PLA, 1 and 2 deg), constraint satisfaction, the drive and the outputs."""

import json

import numpy as np
import pytest

from ffrf import load
from ffrf.paper.bennett_scene import PAPER_MAX_COUPLER_DEVIATION_MM, build_bennett, paper_max_coupler_deviation

COARSE = dict(h=6e-3, order=1, n_modes=2)


@pytest.fixture(scope="module")
def runs():
    return {
        variant: load(build_bennett(variant, **COARSE)).run(mode="quasi_static", outputs=13)
        for variant in ("rigid", "pla", "pla2")
    }


def test_start_state_is_the_ideal_linkage():
    scene = build_bennett("pla", **COARSE)
    assert np.abs(scene.system.constraint_values(scene.q_start, 0.0)).max() < 1e-12
    assert scene.t_end == pytest.approx(61.0)  # 1 s ramp + one revolution at 1 rpm


def test_rigid_links_follow_the_motion_polynomial(runs):
    """Paper: the ideally stiff variant deviates less than 0.001 mm from the motion curve."""
    summary = runs["rigid"].summary()
    assert summary["max_coupler_deviation_m"] < 1e-9
    torque = runs["rigid"].sensors["driving_torque"]
    assert np.abs(torque).max() > 1e-3  # the drive lifts the links against gravity


def test_misalignment_increases_deviation_and_constraints_hold(runs):
    deviation = {v: r.summary()["max_coupler_deviation_m"] for v, r in runs.items()}
    assert deviation["rigid"] < 1e-3 * deviation["pla"]
    assert deviation["pla2"] > 5 * deviation["pla"]
    for result in runs.values():
        assert result.summary()["max_constraint_residual"] < 1e-10
        angles = result.sensors["drive_angle"]
        assert angles[-1] - angles[0] == pytest.approx(2 * np.pi + 0.5 * 2 * np.pi / 60, rel=1e-12)


def test_results_are_written_with_metadata(runs, tmp_path):
    runs["pla"].write_tables(tmp_path)
    data = np.load(tmp_path / "results.npz")
    assert data["time"].shape == (13,) and data["coupler_point"].shape == (13, 3)
    assert data["link2_node1"].shape == (13, 3) and data["joint_angles"].shape == (13, 4)
    metadata = json.loads((tmp_path / "metadata.json").read_text())
    assert metadata["variant"] == "pla" and metadata["mode"] == "quasi_static"
    assert metadata["summary"]["max_coupler_deviation_m"] > 0
    table = np.genfromtxt(tmp_path / "results.csv", delimiter=",", names=True)
    np.testing.assert_array_equal(table["time"], data["time"])
    np.testing.assert_array_equal(table["coupler_point_z"], data["coupler_point"][:, 2])
    np.testing.assert_array_equal(table["joint_reactions_4_5"], data["joint_reactions"][:, 4, 5])


def test_energy_balance_closes_quasi_statically():
    """Drive work = change of gravity + strain energy (no inertia, no damping) over the revolution.
    The work is a Simpson integral over the outputs (fourth order): measured 2.4e-6 with 241
    outputs, 1.2e-7 with 481."""
    result = load(build_bennett("pla", **COARSE)).run(mode="quasi_static", outputs=481)
    assert result.summary()["energy_balance_relative"] < 1e-6
    assert result.summary()["max_constraint_residual"] < 1e-10


def test_paraview_series(runs, tmp_path):
    from ffrf.output.paraview import write_time_series

    scene = build_bennett("pla", **COARSE)
    result = runs["pla"]
    pvd = write_time_series(
        tmp_path,
        [(link.fe, link.reduction.basis) for link in scene.links],
        [scene.system.block(k) for k in range(4)],
        result.time,
        result.q,
        every=4,
        name="b",
    )
    text = pvd.read_text()
    assert text.count("<DataSet") == 4 and f'timestep="{result.time[4]:.9g}"' in text
    import meshio

    frame = meshio.read(tmp_path / "vtk" / "b_00004.vtu")
    assert frame.points.shape[0] == sum(len(link.fe.mesh.points) for link in scene.links)
    # The base is clamped: it only deflects elastically (tens of micrometres); the coupler moves by centimetres.
    body = frame.point_data["body"]
    assert np.abs(frame.point_data["displacement"][body == 0]).max() < 1e-3
    assert np.abs(frame.point_data["displacement"][body == 2]).max() > 1e-2


def test_paper_deviation_table():
    """The paper's maximum coupler deviations (Sect. "Results"), one per variant, as its table states
    them: the rigid one is a bound."""
    assert PAPER_MAX_COUPLER_DEVIATION_MM == {"rigid": 0.001, "pla": 0.211, "pla1": 1.215, "pla2": 2.305}
    assert [paper_max_coupler_deviation(v) for v in ("rigid", "pla", "pla1", "pla2")] == [
        "< 0.001",
        "0.211",
        "1.215",
        "2.305",
    ]
    assert paper_max_coupler_deviation("scene.toml") == ""


def test_a_dynamic_run_steps_by_drive_angle_and_reports_its_local_error_estimate():
    """Without a step of its own a dynamic run turns the drive 0.06 deg per step, at most 10 ms: 10 ms at 1 rpm and
    at 0.5 rpm, 5 ms at 2 rpm. The run reports the local error estimate of Eq. (G5), which is O(h^3): half the step
    divides its median over the run by about eight."""
    from ffrf.scenes.assembly import dynamic_step
    from ffrf.system.drives import rpm

    scenes = {speed: build_bennett("pla", omega=rpm(speed), **COARSE) for speed in (0.5, 1.0, 2.0)}
    assert dynamic_step(scenes[1.0]) == pytest.approx(0.01, rel=1e-12)
    assert dynamic_step(scenes[0.5]) == 0.01
    assert dynamic_step(scenes[2.0]) == pytest.approx(0.005, rel=1e-12)
    default = load(scenes[2.0]).run(mode="dynamic", outputs=7, t_end=1.5)
    assert default.metadata["step"] == pytest.approx(0.005, rel=1e-12)
    halved = load(scenes[2.0]).run(mode="dynamic", outputs=7, t_end=1.5, step=0.0025)
    estimate, finer = default.metadata["step_error_estimate"], halved.metadata["step_error_estimate"]
    assert 5.0 < estimate["median_m"] / finer["median_m"] < 11.0
    assert estimate["largest_m"] >= estimate["median_m"] > 0.0
