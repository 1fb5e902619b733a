"""A tiny Bennett study (coarse links: h = 12 mm, P1, 2 modes, 9 quasi-static outputs) through a Dask
LocalCluster of two worker processes, written to Parquet: every variant is a row, a variant with bad parameters is
a row with its reason, a rerun skips what is finished, and the rows equal standalone runs of the same scenes."""

import json
import math
import os
import threading
import time
from dataclasses import replace

import numpy as np
import pytest
from dask.distributed import Client, LocalCluster

from ffrf import load
from ffrf.paper.bennett_scene import STUDY_BASES, bennett_options, build_bennett_from_options
from ffrf.scenes.linkage_description import BoreError
from ffrf.studies.report import write_report
from ffrf.studies.runner import read_rows, run_study
from ffrf.studies.spec import study_from_document
from ffrf.studies.variant import OUTPUTS

BASE = {"bennett": "pla", "h": 0.012, "order": 1, "modes": 2, "mode": "quasi_static", "outputs": 9}


def _study(twists: list[float], h: list[float], limits: tuple[tuple[str, float], ...] = ()):
    """A grid over the base's joint-3 bore twist on link 0 (deg) and the element edge (m)."""
    return study_from_document(
        {
            "study": {"name": "tiny", "method": "grid"},
            "base": BASE,
            "parameters": [
                {"name": "twist", "target": "bore_twist_deg", "joint": 3, "link": 0, "values": twists},
                {"name": "edge", "target": "h", "values": h},
            ],
            "limits": [{"output": output, "above": above} for output, above in limits],
        },
        bases=STUDY_BASES,
    )


@pytest.fixture(scope="module")
def client():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as c:
            yield c


def _standalone(twist_deg: float) -> dict:
    """The same scene built and run without the study: the paper's PLA Bennett, the bore twist as a misfit."""
    options = replace(
        bennett_options("pla", h=0.012, order=1, n_modes=2),
        bore_errors=(BoreError(joint=3, link=0, twist=math.radians(twist_deg)),),
        bore_error_model="misfit",
    )
    return load(build_bennett_from_options(options)).run(mode="quasi_static", outputs=9).summary()


def test_a_tiny_study_runs_on_two_workers_resumes_and_equals_standalone_runs(client, tmp_path):
    """Four variants, two of them with an element edge of 1 m (refused by the scene's checks: rows with the
    reason), then a rerun with one more twist runs only the new variants; the ok rows equal standalone runs to
    1e-12 (relative), the same code path on another process."""
    study = _study([0.0, 0.5], [0.012, 1.0])
    run = run_study(study, tmp_path, client=client, progress=False)
    assert (run.design, run.skipped, run.ok, run.failed, run.lost) == (4, 0, 2, 2, 0)
    table = read_rows(tmp_path).to_pylist()
    assert len(table) == 4 and len({r["id"] for r in table}) == 4
    failed = [r for r in table if r["status"] == "failed"]
    assert all(r["edge"] == 1.0 and r["reason"].startswith("bad input") and "h" in r["reason"] for r in failed)
    assert all(math.isnan(r["max_coupler_deviation_m"]) for r in failed)
    for row in (r for r in table if r["status"] == "ok"):
        assert row["assembles"] is True
        reference = _standalone(row["twist"])
        for name in OUTPUTS[:3]:
            assert row[name] == pytest.approx(reference[name], rel=1e-12, abs=0.0), name
    twisted = next(r for r in table if r["status"] == "ok" and r["twist"] == 0.5)
    nominal = next(r for r in table if r["status"] == "ok" and r["twist"] == 0.0)
    assert twisted["assembly_strain_energy_J"] > 10 * nominal["assembly_strain_energy_J"]

    limit = 1.01 * nominal["max_coupler_deviation_m"]  # a specification the twisted prints miss
    again = run_study(
        _study([0.0, 0.5, 1.0], [0.012, 1.0], (("max_coupler_deviation_m", limit),)), tmp_path, client=client,
        progress=False,
    )  # fmt: skip
    assert (again.design, again.skipped, again.ok + again.failed) == (6, 4, 2)
    rows = read_rows(tmp_path).to_pylist()
    assert len(rows) == 6
    report = write_report(tmp_path).read_text()
    assert "max_coupler_deviation_m" in report and "contour" in report
    analysis = json.loads((tmp_path / "analysis.json").read_text())
    beyond = sum(r["status"] == "ok" and r["max_coupler_deviation_m"] > limit for r in rows)
    yield_ = analysis["limits"]["max_coupler_deviation_m"]
    assert (yield_["n"], yield_["exceeding"]) == (3, beyond) and beyond >= 1  # failed prints are not counted
    assert yield_["yield_low"] <= yield_["yield"] <= yield_["yield_high"]
    assert f"{beyond} of 3 ok prints exceed it" in report


@pytest.mark.slow
def test_a_killed_worker_loses_no_row(client, tmp_path):
    """A worker process killed while the study runs (its nanny restarts it; the scheduler reruns its variant):
    the study ends with every row, and a rerun finds nothing to do."""
    study = _study([0.0, 0.25, 0.5, 0.75], [0.012])

    killed: list[str] = []

    def kill_one_worker() -> None:
        for _ in range(600):  # as soon as a worker runs a variant (within a minute)
            busy = [w for w, keys in client.processing().items() if keys]
            if busy:
                time.sleep(0.5)
                try:
                    client.run(os._exit, 1, workers=busy[:1])
                except Exception:  # noqa: BLE001 -- the worker dies before it answers, as intended
                    pass
                killed.append(busy[0])
                return
            time.sleep(0.1)

    killer = threading.Thread(target=kill_one_worker)
    killer.start()
    run = run_study(study, tmp_path, client=client, progress=False)
    killer.join()
    assert killed, "no worker was busy to be killed"
    rows = read_rows(tmp_path).to_pylist()
    assert run.lost == 0 and len(rows) == 4 and len({r["id"] for r in rows}) == 4
    assert all(r["status"] == "ok" for r in rows)
    rerun = run_study(study, tmp_path, client=client, progress=False)
    assert (rerun.skipped, rerun.ok + rerun.failed) == (4, 0)
    assert np.all(np.isfinite([r["max_coupler_deviation_m"] for r in rows]))


@pytest.mark.slow
def test_twenty_random_variants_equal_standalone_runs_of_their_scenes(client, tmp_path):
    """Issue #19's check: 20 Monte-Carlo variants (seeded) of the base with a twisted bore on link 0 (normal, std
    0.5 deg) and a shifted bore on link 2 (normal, std 0.1 mm), run by the study on two worker processes, equal
    standalone runs of the same scenes built through the public API to 1e-12 (relative): no hidden difference."""
    study = study_from_document(
        {
            "study": {"name": "twenty", "method": "monte_carlo", "samples": 20, "seed": 7},
            "base": BASE,
            "parameters": [
                {
                    "name": "twist",
                    "target": "bore_twist_deg",
                    "joint": 3,
                    "link": 0,
                    "normal": {"mean": 0.0, "std": 0.5},
                },
                {
                    "name": "shift",
                    "target": "bore_offset_mm",
                    "joint": 1,
                    "link": 2,
                    "normal": {"mean": 0.0, "std": 0.1},
                },
            ],
        },
        bases=STUDY_BASES,
    )
    run = run_study(study, tmp_path, client=client, progress=False)
    assert (run.design, run.ok) == (20, 20)
    for row in read_rows(tmp_path).to_pylist():
        options = replace(
            bennett_options("pla", h=0.012, order=1, n_modes=2),
            bore_errors=(
                BoreError(joint=3, link=0, twist=math.radians(row["twist"])),
                BoreError(joint=1, link=2, offset=1e-3 * row["shift"]),
            ),
            bore_error_model="misfit",
        )
        reference = load(build_bennett_from_options(options)).run(mode="quasi_static", outputs=9).summary()
        for name in OUTPUTS[:3]:
            assert row[name] == pytest.approx(reference[name], rel=1e-12, abs=0.0), (name, row["id"])


def test_dh_offset_and_section_parameters_set_the_bore_and_the_links_design():
    """``bore_axial_mm`` adds to the bore's seat shift along its axis (m, DH offset d), ``arm_width_mm`` and
    ``arm_thickness_mm`` set every link's arm section (m); the bore's other errors stay."""
    from ffrf.studies.variant import variant_options

    study = study_from_document(
        {
            "study": {"name": "section", "method": "grid"},
            "base": BASE,
            "parameters": [
                {"name": "d3", "target": "bore_axial_mm", "joint": 3, "link": 0, "values": [0.2]},
                {"name": "twist", "target": "bore_twist_deg", "joint": 3, "link": 0, "values": [1.0]},
                {"name": "width", "target": "arm_width_mm", "values": [20.0]},
                {"name": "thickness", "target": "arm_thickness_mm", "values": [9.0]},
            ],
        },
        bases=STUDY_BASES,
    )
    _, options, _ = variant_options(study, {"d3": 0.2, "twist": 1.0, "width": 20.0, "thickness": 9.0})
    (bore,) = options.bore_errors
    assert (bore.joint, bore.link) == (3, 0)
    assert bore.axial == pytest.approx(2e-4, rel=1e-15) and bore.twist == pytest.approx(math.radians(1.0))
    assert options.design.arm_width == pytest.approx(0.020) and options.design.arm_thickness == pytest.approx(0.009)
    assert options.design.housing_length == bennett_options("pla").design.housing_length


def test_a_study_runs_on_a_separate_scheduler_given_by_its_address(tmp_path):
    """``--scheduler tcp://...`` and nothing else: a scheduler and a worker started as their own processes (as on a
    cluster, from the same environment), the study's rows equal a local run's outputs."""
    import json
    import subprocess
    import sys

    from ffrf.cli import main

    scheduler_file = tmp_path / "scheduler.json"
    dask = [sys.executable, "-m", "dask"]
    scheduler = subprocess.Popen([*dask, "scheduler", "--port", "0", "--scheduler-file", str(scheduler_file)])
    worker = None
    try:
        for _ in range(600):
            if scheduler_file.exists() and scheduler_file.stat().st_size:
                break
            time.sleep(0.1)
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://")
        worker = subprocess.Popen(
            [*dask, "worker", address, "--nthreads", "1", "--nworkers", "1", "--no-dashboard"],
            env=dict(os.environ, OPENBLAS_NUM_THREADS="1"),
        )
        path = tmp_path / "study.toml"
        path.write_text(
            "[study]\nname = 'remote'\nmethod = 'grid'\n[base]\nbennett = 'pla'\nh = 0.012\norder = 1\nmodes = 2\n"
            "mode = 'quasi_static'\noutputs = 9\n[[parameters]]\nname = 'twist'\ntarget = 'bore_twist_deg'\n"
            "joint = 3\nlink = 0\nvalues = [0.0, 1.0]\n"
        )
        assert main(["study", str(path), "--out", str(tmp_path / "out"), "--scheduler", address, "--no-report"]) == 0
    finally:
        for process in (worker, scheduler):
            if process is not None:
                process.terminate()
                process.wait(timeout=60)
    rows = sorted(read_rows(tmp_path / "out").to_pylist(), key=lambda row: row["twist"])
    assert [row["status"] for row in rows] == ["ok", "ok"]
    assert len({row["worker"] for row in rows}) == 1  # the one remote worker ran both
    for row in rows:
        expected = _standalone(row["twist"])
        assert abs(row["max_coupler_deviation_m"] - expected["max_coupler_deviation_m"]) < 1e-12


def test_a_study_with_stability_monitoring_reports_what_a_standalone_stability_run_finds(tmp_path):
    """``stability = true`` in the base: each row's snaps, released energy and lowest frequency are those of the same
    scene run alone with stability monitoring (the nominal and a 1 deg print of the coarse Bennett: stable, no snap)."""
    study = study_from_document(
        {
            "study": {"name": "stable", "method": "grid"},
            "base": dict(BASE, stability=True),
            "parameters": [{"name": "twist", "target": "bore_twist_deg", "joint": 3, "link": 0, "values": [0.0, 1.0]}],
        },
        bases=STUDY_BASES,
    )
    run_study(study, tmp_path / "out", workers=1, progress=False)
    for row in read_rows(tmp_path / "out").to_pylist():
        options = replace(
            bennett_options("pla", h=0.012, order=1, n_modes=2),
            bore_errors=(BoreError(joint=3, link=0, twist=math.radians(row["twist"])),),
            bore_error_model="misfit",
        )
        alone = load(build_bennett_from_options(options)).run(mode="quasi_static", outputs=9, stability=True)
        assert row["status"] == "ok" and row["snaps"] == 0 and row["snap_energy_released_J"] == 0
        assert row["min_frequency_hz"] > 1.0
        assert abs(row["min_frequency_hz"] - alone.metadata["stability"]["min_frequency_hz"]) < 1e-9


def test_workers_of_another_solver_version_are_refused(tmp_path):
    """A scheduler without workers is reported after the wait, not waited on forever. A worker whose solver differs
    from the client's (here: a copy of the sources with one comment added, first on the path of a `dask worker`
    started as its own process) would compute rows of another version: the study refuses before submitting any
    variant, naming the worker, and writes no row."""
    import shutil
    import subprocess
    import sys

    import ffrf
    from ffrf.errors import SceneError
    from ffrf.scenes.scene_cache import code_version

    copy = tmp_path / "other"
    shutil.copytree(os.path.dirname(ffrf.__file__), copy / "ffrf")
    (copy / "ffrf" / "errors.py").write_text((copy / "ffrf" / "errors.py").read_text() + "\n# another version\n")
    environment = dict(os.environ, PYTHONPATH=os.pathsep.join([str(copy), os.environ.get("PYTHONPATH", "")]))
    with LocalCluster(n_workers=0, dashboard_address=None) as cluster, Client(cluster) as other:
        # a scheduler without a worker is named, not waited on forever
        with pytest.raises(SceneError, match="has no worker after 1 s: start workers on it"):
            run_study(_study([0.0], [0.012]), tmp_path / "out", client=other, progress=False, worker_wait=1.0)
        command = [sys.executable, "-m", "distributed.cli.dask_worker", cluster.scheduler_address, "--nthreads", "1"]
        worker = subprocess.Popen(  # not in the repository: python -m puts its folder first on the path
            command, env=environment, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        try:
            other.wait_for_workers(1, timeout=120)
            (theirs,) = other.run(code_version).values()
            assert theirs != code_version()  # the worker does run the copy
            with pytest.raises(SceneError, match="run another version of the solver than this client"):
                run_study(_study([0.0], [0.012]), tmp_path / "out", client=other, progress=False)
        finally:
            worker.terminate()
            worker.wait(timeout=60)
    assert read_rows(tmp_path / "out") is None


def test_a_study_runs_on_a_scheduler_started_with_a_file_and_its_workers_warm_their_kernels(tmp_path):
    """As a batch system starts them: `dask scheduler --scheduler-file F` and `dask worker --scheduler-file F` as
    processes of their own, and the study given only F. Its row equals the standalone run's, and the worker ran the
    kernel warm-up plugin when the study registered it."""
    import subprocess
    import sys

    from ffrf.studies.runner import KernelWarmup

    file = tmp_path / "scheduler.json"
    quiet = {"cwd": tmp_path, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    processes = [
        subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--scheduler-file", str(file), "--port", "0",
             "--dashboard-address", ":0"], **quiet
        ),
    ]  # fmt: skip
    try:
        deadline = time.monotonic() + 120
        while not file.is_file() and time.monotonic() < deadline:
            time.sleep(0.2)
        worker = [sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(file), "--nthreads", "1"]
        processes.append(subprocess.Popen(worker, **quiet))
        run = run_study(_study([0.5], [0.012]), tmp_path / "out", scheduler_file=str(file), progress=False)
        assert (run.design, run.ok, run.failed, run.lost) == (1, 1, 0, 0)
        (row,) = read_rows(tmp_path / "out").to_pylist()
        assert row["max_coupler_deviation_m"] == pytest.approx(_standalone(0.5)["max_coupler_deviation_m"], rel=1e-12)
        with Client(scheduler_file=str(file)) as client:
            plugins = client.run(lambda dask_worker: sorted(dask_worker.plugins))
        assert all(KernelWarmup.name in names for names in plugins.values()) and plugins
    finally:
        for process in reversed(processes):
            process.terminate()
            process.wait(timeout=60)


def test_radial_clearance_is_a_study_parameter_and_its_rows_equal_standalone_runs_with_play(tmp_path):
    """``radial_clearance_mm`` loosens every passive joint (pins as long as the housings; 0: ideal joints): each row of
    a grid over it equals the same linkage run alone with that play (18 deg of drive of the coarse Bennett), and the
    play moves the coupler."""
    study = study_from_document(
        {
            "study": {"name": "play", "method": "grid"},
            "base": dict(BASE, revolutions=0.05, outputs=3),
            "parameters": [{"name": "play", "target": "radial_clearance_mm", "values": [0.0, 0.1]}],
        },
        bases=STUDY_BASES,
    )
    run_study(study, tmp_path / "out", workers=1, progress=False)
    rows = {row["play"]: row for row in read_rows(tmp_path / "out").to_pylist()}
    assert sorted(rows) == [0.0, 0.1] and all(row["status"] == "ok" for row in rows.values())
    for play, row in rows.items():
        options = replace(
            bennett_options("pla", h=0.012, order=1, n_modes=2, revolutions=0.05), bore_error_model="misfit"
        )
        if play > 0.0:
            pin_length_mm = 1e3 * options.design.housing_length
            options = replace(options, joint_play={"radial_mm": play, "pin_length_mm": pin_length_mm})
        scene = build_bennett_from_options(options)
        assert len(scene.loose_joints) == (3 if play > 0.0 else 0)
        reference = load(scene).run(mode="quasi_static", outputs=3).summary()
        for name in OUTPUTS[:3]:
            assert row[name] == pytest.approx(reference[name], rel=1e-12, abs=0.0), (name, play)
    change = abs(rows[0.1]["max_coupler_deviation_m"] - rows[0.0]["max_coupler_deviation_m"])
    assert change > 1e-5  # a tenth of the 0.1 mm play at least: the pins move in their bores
