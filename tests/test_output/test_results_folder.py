"""A results folder cannot lie (``ffrf.output.tables.write_results``, issue #32): it holds the run before or the new
one, whole, never a mix; its manifest tells a reader which; an earlier run's other outputs do not stay next to a new
run's results; a damaged or incomplete set is a one-line error."""

import json
import os
import time

import numpy as np
import pytest

from ffrf.errors import ResultsError
from ffrf.output import tables
from ffrf.output.tables import MANIFEST, check_results, read_arrays, read_results, write_results


def _arrays(rows: int, offset: float) -> dict:
    time_ = np.linspace(0.0, 1.0, rows)
    return {"time": time_, "x": np.column_stack([time_ + offset, 2 * time_, -time_])}


def _snapshot(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_a_written_folder_reads_back_and_its_manifest_lists_every_file(tmp_path):
    arrays = _arrays(5, 0.0)
    write_results(tmp_path, arrays, {"run": 1}, coordinates=np.ones((5, 2)))
    read, metadata = read_results(tmp_path)
    np.testing.assert_array_equal(read["x"], arrays["x"])
    np.testing.assert_array_equal(read["q"], np.ones((5, 2)))
    assert metadata == {"run": 1}
    manifest = json.loads((tmp_path / MANIFEST).read_text())
    assert sorted(manifest["files"]) == ["metadata.json", "results.csv", "results.npz"]
    assert manifest["files"]["results.csv"]["bytes"] == (tmp_path / "results.csv").stat().st_size
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary file left


@pytest.mark.parametrize("fail_at", [1, 2, 3])
def test_a_write_that_fails_midway_leaves_the_earlier_run_as_it_was(tmp_path, monkeypatch, fail_at):
    """The failure after the first (second, third) staged file: the folder is byte for byte the earlier run's."""
    write_results(tmp_path, _arrays(5, 0.0), {"run": 1})
    before = _snapshot(tmp_path)
    calls = []
    digest = tables._digest

    def failing(path):  # called once per staged file, after all three are written: fail at the n-th
        calls.append(path)
        if len(calls) == fail_at:
            raise OSError(28, "No space left on device")
        return digest(path)

    real_csv = tables.write_csv

    def csv_then_fail(path, arrays):  # also fail between the first and the second file, once
        out = real_csv(path, arrays)
        if fail_at == 1:
            raise KeyboardInterrupt
        return out

    monkeypatch.setattr(tables, "_digest", failing)
    monkeypatch.setattr(tables, "write_csv", csv_then_fail)
    with pytest.raises((OSError, KeyboardInterrupt)):
        write_results(tmp_path, _arrays(7, 1.0), {"run": 2})
    monkeypatch.undo()
    assert _snapshot(tmp_path) == before
    check_results(tmp_path)


def test_a_mixed_set_is_refused_by_its_manifest(tmp_path):
    """What a kill between the renames (or a file copied in) leaves: the manifest names the file that differs."""
    write_results(tmp_path, _arrays(5, 0.0), {"run": 1})
    other = tmp_path / "other"
    write_results(other, _arrays(7, 1.0), {"run": 2})
    os.replace(other / "results.csv", tmp_path / "results.csv")
    with pytest.raises(ResultsError, match=r"results\.csv is not the file the run wrote .*the write was cut short"):
        read_results(tmp_path)
    with pytest.raises(ResultsError, match="results.csv is not the file"):
        read_arrays(tmp_path)  # the npz is whole, but its folder is not one run's


@pytest.mark.parametrize("damage", ["empty npz", "missing metadata", "bad manifest"])
def test_a_damaged_folder_is_one_line_error(tmp_path, damage):
    write_results(tmp_path, _arrays(5, 0.0), {"run": 1})
    if damage == "empty npz":
        (tmp_path / "results.npz").write_bytes(b"")
        (tmp_path / MANIFEST).unlink()  # as a folder written before manifests: the read itself must not crash
        words = "EOFError"
    elif damage == "missing metadata":
        (tmp_path / "metadata.json").unlink()
        words = "metadata.json is missing"
    else:
        (tmp_path / MANIFEST).write_text("{")
        words = "manifest.json cannot be read"
    with pytest.raises(ResultsError, match=words) as error:
        read_results(tmp_path)
    assert "\n" not in str(error.value) and "again" in str(error.value)


def test_a_new_run_removes_an_earlier_runs_other_outputs_and_keeps_its_own_and_the_users(tmp_path):
    """The earlier run wrote a ParaView series and stability files; the new run (started after them) writes none:
    they go; what the new run wrote before its results (assembly.vtu) and files of other names stay."""
    write_results(tmp_path, _arrays(5, 0.0), {"run": 1})
    old = ["stability.json", "coupler_deviation.png", "linkage.pvd", "vtk/linkage_00000.vtu", "assembly.vtu"]
    (tmp_path / "vtk").mkdir()
    for name in [*old, "my_notes.txt", "my_own.pvd"]:
        (tmp_path / name).write_text('<DataSet file="vtk/linkage_00000.vtu"/>' if name == "linkage.pvd" else "earlier")
        os.utime(tmp_path / name, (1e9, 1e9))
    started = time.time() - 1.0
    (tmp_path / "assembly.vtu").write_text("this run's")  # written by the new run before its results
    write_results(tmp_path, _arrays(7, 1.0), {"run": 2}, since=started)
    left = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file())
    expected = ["assembly.vtu", "manifest.json", "metadata.json", "my_notes.txt", "my_own.pvd", "results.csv"]
    expected += ["results.npz"]
    assert left == expected
    assert (tmp_path / "assembly.vtu").read_text() == "this run's"
    listed = json.loads((tmp_path / MANIFEST).read_text())["files"]
    assert sorted(listed) == ["assembly.vtu", "metadata.json", "results.csv", "results.npz"]


def test_a_run_that_stops_before_its_results_cannot_pass_for_the_earlier_one(tmp_path):
    """A run wrote linkage.json, then stopped before writing results: the folder's manifest, the earlier run's, lists
    the earlier linkage.json, so the folder is refused rather than read as one run."""
    (tmp_path / "linkage.json").write_text("linkage A")
    write_results(tmp_path, _arrays(5, 0.0), {"linkage": "A"}, since=time.time() - 10.0)
    check_results(tmp_path)
    (tmp_path / "linkage.json").write_text("linkage B")  # the next run's first file; then it was killed
    with pytest.raises(ResultsError, match="linkage.json is not the file the run wrote"):
        check_results(tmp_path)


def test_a_folder_without_results_keeps_files_of_those_names(tmp_path):
    """Only a folder that held results is cleaned: a first run into a folder of the user's own files deletes none."""
    (tmp_path / "linkage.json").write_text("the user's own")
    os.utime(tmp_path / "linkage.json", (1e9, 1e9))
    write_results(tmp_path, _arrays(3, 0.0), {}, since=time.time())
    assert (tmp_path / "linkage.json").read_text() == "the user's own"


def test_the_process_start_is_before_now_and_after_boot():
    started = tables.process_started()
    assert time.time() - 3600 * 24 * 365 < started <= time.time()


def test_identification_refuses_a_mixed_result_folder_with_one_line_and_exit_2(tmp_path, capsys):
    """``python -m identification --result DIR`` on a folder whose results.npz is not the one its manifest lists."""
    from identification.__main__ import main

    def nodes(rows: int) -> dict:
        return {"time": np.arange(float(rows))} | {
            f"link{k}_node{j}": np.zeros((rows, 3)) for k in (1, 2, 3) for j in (0, 1)
        }

    write_results(tmp_path, nodes(5), {})
    write_results(tmp_path / "later", nodes(6), {})
    os.replace(tmp_path / "later" / "results.npz", tmp_path / "results.npz")
    assert main(["--result", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    assert "results.npz is not the file the run wrote" in err
