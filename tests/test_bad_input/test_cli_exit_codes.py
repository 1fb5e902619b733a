"""Command lines fail loudly and briefly: one ``error:`` line and exit status 2 on bad input, no
traceback; ``python -m validation`` exits 1 when a target is missed, so scripts and CI can rely on it."""

import os
from types import SimpleNamespace

import pytest
from scene_fixtures import PENDULUM, write_bar


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    return err


def test_ffrf_run_refuses_a_bad_scene_with_exit_2(tmp_path, capsys):
    from ffrf.cli import main

    write_bar(tmp_path)
    (tmp_path / "scene.toml").write_text(PENDULUM.replace("gravity =", "gravty ="))
    assert main(["run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out")]) == 2
    assert "did you mean 'gravity'" in one_line_error(capsys)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "content, words",
    [
        (
            "Segments\n100\n,,Bennett:Link1\nFrame,Sub Frame,RX,RY,RZ,TX,TY,TZ\n,,deg,deg,deg,mm,mm,mm\n"
            "1,0,0,0,0,a,2,3\n",
            "line 6: could not convert string to float: 'a'",
        ),
        ("Segments\n100\n,,Bennett:Link1\nFrame,Sub Frame,RX,RY,RZ,TX,TY,TZ\n,,deg,deg,deg,mm,mm,mm\n", "no data rows"),
        ("just,some,numbers\n1,2,3\n", "no 'Frame, Sub Frame, ...' header row"),
    ],
)
def test_identification_refuses_a_broken_vicon_file_with_exit_2(tmp_path, capsys, content, words):
    from identification.__main__ import main

    (tmp_path / "run.csv").write_text(content)
    assert main(["--vicon", str(tmp_path / "run.csv")]) == 2
    assert words in one_line_error(capsys)


def test_identification_names_a_missing_result_with_exit_2(tmp_path, capsys):
    from identification.__main__ import main

    assert main(["--result", str(tmp_path)]) == 2
    assert "results.npz not found: run a simulation first" in one_line_error(capsys)


@pytest.mark.parametrize("passed, status", [(True, 0), (False, 1)])
def test_validation_exit_status_says_whether_every_target_was_met(tmp_path, monkeypatch, passed, status):
    import validation.__main__ as cli

    fake = SimpleNamespace(
        metrics={
            "passed": passed,
            "trajectories": {"coupler_point": {"max_abs_diff_m": 0.0}},
            "torque": {"max_rel_diff": 0.0},
        }
    )
    monkeypatch.setattr(cli, "validate_bennett", lambda settings: fake)
    monkeypatch.setattr(cli, "write_report", lambda validation, folder: folder / "report.md")
    monkeypatch.setattr(cli, "write_summary", lambda validations, folder: folder / "summary.md")
    assert cli.main(["report", "--variant", "pla", "--out", str(tmp_path)]) == status
    assert cli.main(["summary", "--variants", "pla", "rigid", "--out", str(tmp_path)]) == status


def test_validation_exit_status_2_when_a_run_fails(tmp_path, monkeypatch, capsys):
    import validation.__main__ as cli

    def fail(settings):
        raise RuntimeError("Newton diverged")

    monkeypatch.setattr(cli, "validate_bennett", fail)
    assert cli.main(["report", "--variant", "pla", "--out", str(tmp_path)]) == 2
    assert "validation failed: RuntimeError: Newton diverged" in one_line_error(capsys)


def test_blas_threads_are_set_for_the_run_and_zero_is_refused(monkeypatch, capsys):
    """``python -m ffrf --blas-threads N`` runs the command with N BLAS threads (1 by default); 0 is refused."""
    from threadpoolctl import threadpool_info

    from ffrf import cli

    seen: list[list[int]] = []

    def probe(args):
        seen.append([pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"])
        return 0

    monkeypatch.setitem(cli.SUBCOMMANDS, "run", (cli.SUBCOMMANDS["run"][0], cli.SUBCOMMANDS["run"][1], probe))
    assert cli.main(["run", "x.toml", "--out", "o"]) == 0
    assert cli.main(["--blas-threads", "2", "run", "x.toml", "--out", "o"]) == 0
    default = [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]
    assert seen[0] and seen[0] == [1] * len(default)
    assert seen[1] == [min(2, os.cpu_count() or 1)] * len(default)  # OpenBLAS runs at most one thread per core
    with pytest.raises(SystemExit) as refused:
        cli.main(["--blas-threads", "0", "run", "x.toml", "--out", "o"])
    assert refused.value.code == 2
    assert "argument --blas-threads: must be a whole number >= 1" in capsys.readouterr().err
