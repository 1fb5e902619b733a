"""Ctrl-C (SIGINT) and SIGTERM stop a run at its next step and keep what it computed (issue #32): the command exits
with 130 and one line, no traceback, and its folder holds the results up to the interruption, complete by their
manifest, with ``stopped.reason == "interrupted"`` in the metadata. Before, Ctrl-C printed a traceback and wrote
nothing.

The run is ``python -m ffrf run`` of the bar pendulum of ``scene_fixtures`` (dynamic, 20 s at 1 ms steps; about
7 s when uninterrupted with warm numba kernels), in a process of its own so that the signal is real."""

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scene_fixtures import PENDULUM, driven_link_scene, write_bar

from ffrf.errors import Interrupted
from ffrf.output.tables import read_results
from ffrf.scenes.scene_file import load_scene, start_state
from ffrf.solvers.generalized_alpha import generalized_alpha

ROOT = Path(__file__).parents[2]
LONG = PENDULUM.replace("t_end = 0.1", "t_end = 20.0").replace("outputs = 101", "outputs = 2001")


def _run_until_progress(tmp_path: Path, number: signal.Signals) -> tuple[int, str]:
    """Start the run, send ``number`` once its progress bar shows 2 %, and return its exit status and stderr."""
    write_bar(tmp_path)
    (tmp_path / "scene.toml").write_text(LONG)
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    command = [sys.executable, "-m", "ffrf", "run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out")]
    process = subprocess.Popen(command, stderr=subprocess.PIPE, cwd=tmp_path, env=environment)
    assert process.stderr is not None
    seen = b""
    try:
        while not re.search(rb"\s([2-9]|\d\d+) %", seen):  # the bar's line is rewritten with \r: read bytes
            byte = process.stderr.read(1)
            assert byte, f"the run ended before its progress reached 2 %: {seen.decode()}"
            seen += byte
        process.send_signal(number)
        rest = process.stderr.read()
        status = process.wait(timeout=120)
    finally:
        process.kill()
    return status, (seen + rest).decode()


@pytest.mark.parametrize("number", [signal.SIGINT, signal.SIGTERM], ids=lambda number: number.name)
def test_a_signal_stops_the_run_with_130_one_line_and_its_results_so_far(tmp_path, number):
    status, stderr = _run_until_progress(tmp_path, number)
    assert status == 130, stderr
    assert "Traceback" not in stderr
    last = stderr.strip().splitlines()[-1]
    assert last.startswith(f"interrupted by {number.name}") and "results up to t = " in last, last
    arrays, metadata = read_results(tmp_path / "out")  # whole: the manifest matches every file
    assert metadata["stopped"]["reason"] == "interrupted"
    end = metadata["stopped"]["time_s"]
    time = arrays["time"]
    assert 0.2 <= end < 20.0 and time[-1] == end and len(time) == round(end / 0.01) + 1
    # what was written is what the uninterrupted run computes up to there (same steps, same outputs)
    scene = load_scene(tmp_path / "scene.toml")
    q0 = scene.q_initial
    reference = generalized_alpha(scene.system, q0, np.zeros_like(q0), end, 1e-3, rho_inf=0.8, output_every=10)
    np.testing.assert_allclose(arrays["q"], reference.q, rtol=0.0, atol=1e-9)


STUDY = """
[study]
name = "interrupted"
method = "grid"
[base]
bennett = "pla"
h = 0.012
order = 1
modes = 2
mode = "quasi_static"
outputs = 9
[[parameters]]
name = "twist"
target = "bore_twist_deg"
joint = 3
link = 0
values = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5]
"""


@pytest.mark.slow
def test_ctrl_c_in_a_study_keeps_the_finished_rows_and_a_rerun_runs_the_rest(tmp_path):
    """SIGINT once two variants of 16 are done: exit 130, one line, no traceback; the rows written are the variants
    that finished, and the same command then runs exactly the others (each id once in the end)."""
    from ffrf.studies.runner import read_rows

    (tmp_path / "study.toml").write_text(STUDY)
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    command = [sys.executable, "-m", "ffrf", "study", str(tmp_path / "study.toml"), "--out", str(tmp_path / "out")]
    command += ["--workers", "2", "--no-report"]
    process = subprocess.Popen(command, stderr=subprocess.PIPE, cwd=tmp_path, env=environment)
    assert process.stderr is not None
    seen = b""
    try:
        while not re.search(rb"\b([2-9]|1[0-5])/16\b", seen):
            byte = process.stderr.read(1)
            assert byte, f"the study ended before two variants were done: {seen.decode()}"
            seen += byte
        process.send_signal(signal.SIGINT)
        stderr = (seen + process.stderr.read()).decode()
        status = process.wait(timeout=120)
    finally:
        process.kill()
    assert status == 130 and "Traceback" not in stderr, stderr
    last = stderr.strip().splitlines()[-1]
    assert last.startswith("interrupted by SIGINT") and "the same command runs the rest" in last, last
    first = read_rows(tmp_path / "out")
    assert first is not None and 2 <= first.num_rows < 16
    rerun = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path, env=environment, timeout=600)
    assert rerun.returncode == 0, rerun.stderr
    assert f"{first.num_rows} finished before, {16 - first.num_rows} ok" in rerun.stdout
    rows = read_rows(tmp_path / "out")
    assert rows is not None and sorted(rows.column("twist").to_pylist()) == pytest.approx([0.1 * k for k in range(16)])


def _stop_at(call: int):
    """A progress callback that asks to stop at its ``call``-th call, as the CLI's does after a signal."""
    calls = []

    def progress(t: float, t_end: float) -> None:
        calls.append(t)
        if len(calls) == call:
            raise Interrupted("interrupted by SIGINT")

    return progress


@pytest.mark.parametrize(
    "mode",
    ["dynamic", "quasi_static", "quasi_static through snaps", "quasi_static own steps", "quasi_static snaps own steps"],
)
def test_an_interrupted_solver_hands_over_the_outputs_it_computed(tmp_path, mode):
    """The solver a progress callback interrupts raises :class:`Interrupted` with ``partial``: the outputs before the
    stop, equal to the first outputs of the same run left alone (same steps, same code: to the bit)."""
    from ffrf.solvers.simulate import simulate

    if mode == "dynamic":
        write_bar(tmp_path)
        (tmp_path / "scene.toml").write_text(PENDULUM)
        arguments = {"mode": "dynamic", "t_end": 0.1, "outputs": 11, "step": 1e-3, "rho_inf": 0.8}
        call, rows = 35, 4  # outputs every 10 steps: the 35th step is past the 4th output (t = 0, 10, 20, 30 ms)
    else:
        (tmp_path / "scene.toml").write_text(driven_link_scene("[0.0, 1.0, 0.0]", t_end=5.0, outputs=11, modes=2))
        arguments = {"mode": "quasi_static", "t_end": 5.0, "outputs": 11, "through_snaps": "snaps" in mode}
        call, rows = 4, 4
        if mode.endswith("own steps"):  # the path on steps of 0.3 s (Eq. (S10)): the 4th step ends at 1.2 s
            arguments["static_path_step"] = lambda t: 0.3
            rows = 3  # the outputs at 0, 0.5 and 1 s are solved from the path by then
    scene = load_scene(tmp_path / "scene.toml")
    q0 = start_state(scene)
    whole = simulate(scene.system, q0, **arguments)
    with pytest.raises(Interrupted) as stop:
        simulate(scene.system, q0, **arguments, progress=_stop_at(call))
    part = stop.value.partial
    assert len(part.time) == rows and part.q.shape == (rows, whole.q.shape[1])
    np.testing.assert_array_equal(part.time, whole.time[:rows])
    np.testing.assert_array_equal(part.q, whole.q[:rows])
    np.testing.assert_array_equal(part.multipliers, whole.multipliers[:rows])


def test_the_first_signal_in_a_run_is_noted_and_a_second_one_or_one_outside_stops_at_once():
    """``ffrf.cli``'s handling of SIGINT in-process (a signal to this process runs its handler before the next line):
    outside a run a signal raises at once; inside one the first is
    noted (the next step's check raises) and a second raises at once; the handlers before are restored after."""
    from ffrf.cli.stop import StopRequest

    stop = StopRequest()
    before = signal.getsignal(signal.SIGINT)
    with stop.installed():
        with pytest.raises(Interrupted, match="interrupted by SIGINT"):
            os.kill(os.getpid(), signal.SIGINT)
        stop.signal = None
        with stop.deferred():
            os.kill(os.getpid(), signal.SIGTERM)
            assert stop.signal == "SIGTERM"  # noted, the run goes on to its next step
            with pytest.raises(Interrupted, match="interrupted by SIGTERM after"):
                stop.check(" after")
            with pytest.raises(Interrupted):
                os.kill(os.getpid(), signal.SIGINT)
    assert signal.getsignal(signal.SIGINT) is before
