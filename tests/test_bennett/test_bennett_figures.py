"""Paper-style figures (ffrf.output.linkage_figures): files are written and the plotted data are the inputs
(angles from the start in degrees, deviations in mm, torques in N mm), including extra series; the paper's
colours (ffrf.paper.figures) are the given labels' only."""

import numpy as np
import pytest

from ffrf import cli
from ffrf.output.linkage_figures import (
    coupler_deviation_series,
    driving_torque_series,
    plot_coupler_deviation,
    plot_driving_torque,
    plot_over_drive_angle,
)
from ffrf.output.result import Result


def synthetic_result(scale: float, rng) -> Result:
    angle = np.radians(90.0) + np.linspace(0.0, 2 * np.pi + 0.05, 50)
    sensors = {
        "drive_angle": angle,
        "coupler_deviation": scale * rng.normal(size=(50, 3)),
        "driving_torque": scale * np.sin(angle),
    }
    return Result(np.linspace(0.0, 61.0, 50), sensors, np.zeros((50, 1)))


def lines_by_label(ax) -> dict:
    return {line.get_label(): (line.get_xdata(), line.get_ydata(), line.get_linestyle()) for line in ax.lines}


def test_deviation_plot_shows_the_inputs(tmp_path, rng):
    runs = {"pla": synthetic_result(1e-4, rng), "pla2": synthetic_result(2e-3, rng)}
    np.savez(tmp_path / "results.npz", time=runs["pla"].time, **runs["pla"].sensors)
    twin = (np.linspace(0.0, 2 * np.pi, 7), np.arange(7.0))
    fig, ax = plot_coupler_deviation({**runs, "from file": tmp_path}, tmp_path / "dev.png", extra={"Exudyn": twin})
    assert (tmp_path / "dev.png").stat().st_size > 1000
    lines = lines_by_label(ax)
    for label, run in runs.items():
        sensors = run.sensors
        assert np.array_equal(lines[label][0], np.degrees(sensors["drive_angle"] - sensors["drive_angle"][0]))
        assert np.allclose(lines[label][1], 1e3 * np.linalg.norm(sensors["coupler_deviation"], axis=1), rtol=1e-15)
    assert np.array_equal(lines["from file"][1], lines["pla"][1])  # the npz path gives the same curve
    assert np.array_equal(lines["Exudyn"][0], np.degrees(twin[0])) and np.array_equal(lines["Exudyn"][1], twin[1])
    assert lines["Exudyn"][2] == "--" and lines["pla"][2] == "-"


def test_torque_plot_magnitude_and_signed(tmp_path, rng):
    run = synthetic_result(0.02, rng)
    _, ax = plot_driving_torque({"rigid": run}, tmp_path / "torque.png")
    assert (tmp_path / "torque.png").exists()
    assert np.allclose(lines_by_label(ax)["rigid"][1], 1e3 * np.abs(run.sensors["driving_torque"]), rtol=1e-15)
    _, ax = plot_driving_torque({"rigid": run}, magnitude=False)
    assert np.allclose(lines_by_label(ax)["rigid"][1], 20.0 * np.sin(run.sensors["drive_angle"]), rtol=1e-12)
    angle, values = driving_torque_series(run, magnitude=False)
    assert angle[0] == 0.0 and angle[-1] == pytest.approx(2 * np.pi + 0.05)


def test_given_colours_colour_their_labels_only(rng):
    from matplotlib.colors import to_hex

    from ffrf.paper.figures import VARIANT_COLORS

    runs = {"rigid": synthetic_result(1e-4, rng), "mine": synthetic_result(1e-4, rng)}
    _, ax = plot_coupler_deviation(runs, colors=VARIANT_COLORS)
    colours = {line.get_label(): to_hex(line.get_color()) for line in ax.lines}
    assert colours["rigid"] == to_hex("tab:orange")
    assert colours["mine"] == to_hex("tab:blue")  # the colour cycle's first: no colour of its own
    _, ax = plot_driving_torque(runs)
    assert to_hex(ax.lines[0].get_color()) == to_hex("tab:blue")  # without colours, the cycle's


def test_generic_plot_and_series(rng):
    run = synthetic_result(1e-3, rng)
    angle, deviation = coupler_deviation_series(run)
    _, ax = plot_over_drive_angle({"a": (angle, deviation), "b": ([0.0, np.pi], [1.0, 2.0])}, "mm")
    assert ax.get_ylabel() == "mm" and ax.get_xlabel().startswith("drive angle")
    assert np.array_equal(lines_by_label(ax)["b"][0], [0.0, 180.0])


def test_bennett_command_writes_figures_and_assembly(tmp_path, monkeypatch, capsys):
    """The bennett subcommand on a short run (t_end shortened to 2 s; its other options unchanged)."""
    from ffrf.model import Model

    full_run = Model.run
    monkeypatch.setattr(Model, "run", lambda model, *args, **kw: full_run(model, *args, **kw, t_end=2.0))
    code = cli.main(
        [
            "bennett",
            "--variant",
            "pla1",
            "--h",
            "6e-3",
            "--order",
            "1",
            "--modes",
            "2",
            "--outputs",
            "5",
            "--quasi-static",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    for name in ("results.npz", "metadata.json", "assembly.vtu", "coupler_deviation.png", "driving_torque.png"):
        assert (tmp_path / name).exists(), name
    out = capsys.readouterr().out
    assert "misfit" in out and sum(line.strip().startswith("link ") for line in out.splitlines()) == 4
