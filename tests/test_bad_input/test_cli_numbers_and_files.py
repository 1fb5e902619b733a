"""Bad numbers and unreadable files on the command lines: one ``error:`` line naming the fix, exit
status 2, no traceback, and (for a run) nothing computed before the output folder is known to work."""

import io

import numpy as np
import pytest
from scene_fixtures import PENDULUM, write_bar

SEGMENT_NAMES = ",,Bennett:Link1,,,,,,Bennett:Link2,,,,,,Bennett:Link3,,,,,\n"


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    return err


def tiny_vicon_csv(frames: int = 8) -> str:
    """A Vicon segment export of links 1-3 with ``frames`` frames of made-up (finite) positions."""
    rows = [
        "Segments",
        "100",
        SEGMENT_NAMES.strip(),
        "Frame,Sub Frame" + ",RX,RY,RZ,TX,TY,TZ" * 3,
        ",," + ",".join(["deg,deg,deg,mm,mm,mm"] * 3),
    ]
    rng = np.random.default_rng(1)
    for frame in range(1, frames + 1):
        rows.append(f"{frame},0," + ",".join(f"{v:.3f}" for v in rng.normal(size=18)))
    return "\n".join(rows) + "\n"


def test_tiny_vicon_file_is_read(tmp_path):
    """The helper's file is a valid export, so the failures below come from the one bad argument."""
    from identification.records import read_vicon_csv

    (tmp_path / "run.csv").write_text(tiny_vicon_csv())
    record = read_vicon_csv(tmp_path / "run.csv")
    assert sorted(record.points) == [1, 2, 3] and record.n_frames == 8


@pytest.mark.parametrize(
    "arguments, words",
    [
        (["--window", "0"], "moving-average window must be >= 1 frame, got 0; give --window 1"),
        (["--alpha-deg", "nan", "90", "150", "90"], "--alpha-deg [nan, 90.0, 150.0, 90.0] must be 4 finite twists"),
    ],
)
def test_identification_refuses_bad_numbers_with_exit_2(tmp_path, capsys, arguments, words):
    from identification.__main__ import main

    (tmp_path / "run.csv").write_text(tiny_vicon_csv())
    assert main(["--vicon", str(tmp_path / "run.csv"), *arguments]) == 2
    assert words in one_line_error(capsys)


def test_identification_refuses_a_binary_file_with_exit_2(tmp_path, capsys):
    from identification.__main__ import main

    (tmp_path / "run.c3d").write_bytes(b"\xff\xfe\x00\x01binary motion capture")
    assert main(["--vicon", str(tmp_path / "run.c3d")]) == 2
    assert "run.c3d: not a text file" in one_line_error(capsys)


def _npy_bytes() -> bytes:
    """A bare ``.npy`` array (what ``np.save`` writes), not an archive of named arrays."""
    buffer = io.BytesIO()
    np.save(buffer, np.arange(3.0))
    return buffer.getvalue()


def _zip_cut_in_half(path):
    np.savez(path.with_name("whole.npz"), time=np.arange(100.0), link1_node0=np.zeros((100, 3)))
    whole = path.with_name("whole.npz").read_bytes()
    path.write_bytes(whole[: len(whole) // 2])


@pytest.mark.parametrize(
    "damage, words",
    [
        (lambda path: path.write_text("time,x\n0,1\n"), "ValueError"),
        (_zip_cut_in_half, "BadZipFile"),
        (lambda path: path.write_bytes(_npy_bytes()), "one array"),
        (lambda path: path.write_bytes(b""), "EOFError"),  # a zero-byte file: was a traceback (issue #32)
    ],
)
def test_identification_refuses_a_damaged_result_with_exit_2(tmp_path, capsys, damage, words):
    from identification.__main__ import main

    damage(tmp_path / "results.npz")
    assert main(["--result", str(tmp_path)]) == 2
    message = one_line_error(capsys)
    assert "results.npz cannot be read as a results archive" in message and words in message
    assert "write it again with python -m ffrf bennett" in message


@pytest.mark.parametrize(
    "arguments, words",
    [
        (["--alpha3-deg", "nan"], "--alpha3-deg nan is not a finite angle"),
        (["--points", "0"], "--points 0: sample the coupler path at 4 points or more"),
    ],
)
def test_kinematics_refuses_bad_numbers_with_exit_2(tmp_path, capsys, arguments, words):
    from kinematics.__main__ import main

    assert main(["bennett", *arguments, "--out", str(tmp_path / "out")]) == 2
    assert words in one_line_error(capsys)
    assert not (tmp_path / "out").exists()


def test_kinematics_names_an_unwritable_output_folder_with_exit_2(tmp_path, capsys):
    from kinematics.__main__ import main

    (tmp_path / "out").write_text("a file, not a folder")
    assert main(["bennett", "--points", "8", "--out", str(tmp_path / "out")]) == 2
    assert "cannot write to --out" in one_line_error(capsys)


def test_ffrf_refuses_a_non_finite_twist_with_exit_2(tmp_path, capsys):
    from ffrf.cli import main

    assert main(["mesh", "--link", "1", "--alpha3-deg", "inf", "--out", str(tmp_path / "out")]) == 2
    assert "alpha3_deg=inf is not a finite angle" in one_line_error(capsys)


@pytest.mark.parametrize("command", [["bennett"], ["run", "scene.toml"]])
def test_ffrf_checks_the_output_folder_before_the_run(tmp_path, capsys, monkeypatch, command):
    """An unwritable ``--out`` is refused before any simulation, so no run is lost to it."""
    from ffrf.cli import main
    from ffrf.model import Model

    def must_not_run(*args, **kwargs):
        raise AssertionError("the run started before --out was checked")

    monkeypatch.setattr(Model, "run", must_not_run)
    write_bar(tmp_path)
    (tmp_path / "scene.toml").write_text(PENDULUM)
    (tmp_path / "out").write_text("a file, not a folder")
    command = [str(tmp_path / c) if c.endswith(".toml") else c for c in command]
    assert main([*command, "--out", str(tmp_path / "out")]) == 2
    assert "cannot write to --out" in one_line_error(capsys)


@pytest.mark.parametrize(
    ("flag", "value"),
    [
        ("--step", "-1"),
        ("--step", "inf"),
        ("--rho-inf", "1.5"),
        ("--modes", "0"),
        ("--outputs", "1"),
        ("--h", "nan"),
        ("--dynamic-window", "-0.5"),
    ],
)
def test_validation_flags_are_checked_like_the_runs_flags(tmp_path, capsys, flag, value):
    """``python -m validation report`` refuses what ``python -m ffrf bennett`` refuses, before anything is built:
    a usage error naming the flag, exit status 2, nothing written."""
    from validation.__main__ import main

    with pytest.raises(SystemExit) as stop:
        main(["report", "--variant", "pla", flag, value, "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    assert flag in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
