"""The staleness check of result files (``bench/staleness.py``) and the recording's refusal of a dirty tree
(``bench/record.py``), on a throw-away git repository: a result is stale when code it measures changed after the
commit in its meta, or when that commit did not hold the code it measured."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from bench.record import DirtyTree, keyed_rows, record, require_clean_tree
from bench.registry import Benchmark, Recording
from bench.staleness import stale_results, why_stale


def _git(root: Path, *args: str) -> str:
    command = ["git", "-c", "user.name=bench", "-c", "user.email=bench@example.org", *args]
    return subprocess.run(command, cwd=root, check=True, capture_output=True, text=True).stdout.strip()


def _commit(root: Path, files: dict[str, str]) -> str:
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    _git(root, "add", "-A")
    _git(root, "commit", "-q", "-m", "change")
    return _git(root, "rev-parse", "HEAD")


def _result(folder: Path, stem: str, git: object) -> Path:
    path = folder / f"{stem}.json"
    path.write_text(json.dumps({"meta": {"git": git}, "results": {}}))
    return path


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    root = tmp_path / "repo"
    root.mkdir()
    _git(root, "init", "-q")
    return root


def test_a_result_goes_stale_when_the_code_it_measures_changes_and_only_then(repo: Path, tmp_path: Path) -> None:
    recorded = _commit(repo, {"solver/core.py": "x = 1\n", "docs/notes.md": "a\n"})
    results = tmp_path / "results"
    results.mkdir()
    _result(results, "speed", {"commit": recorded, "dirty": False})
    sources = {"speed": ("solver", "bench/speed.py")}
    assert stale_results(results, sources, repo) == []

    _commit(repo, {"docs/notes.md": "b\n"})  # not measured
    assert stale_results(results, sources, repo) == []

    _commit(repo, {"solver/core.py": "x = 2\n"})
    (stale,) = stale_results(results, sources, repo)
    assert stale.path.name == "speed.json"
    assert "solver/core.py" in stale.reason and recorded[:10] in stale.reason

    _commit(repo, {"solver/core.py": "x = 1\n"})  # back to the code it measured
    assert stale_results(results, sources, repo) == []


def test_a_result_from_a_dirty_or_unknown_tree_is_stale(repo: Path, tmp_path: Path) -> None:
    recorded = _commit(repo, {"solver/core.py": "x = 1\n"})
    sources = ("solver",)
    cases = {
        "dirty": ({"commit": recorded, "dirty": True}, "dirty tree"),
        "unknown_state": ({"commit": recorded, "dirty": None}, "not known to be clean"),
        "foreign": ({"commit": "0123456789" * 4, "dirty": False}, "not in this repository"),
        "no_commit": (None, "names no commit"),
    }
    for stem, (git, reason) in cases.items():
        found = why_stale(_result(tmp_path, stem, git), sources, repo)
        assert found is not None and reason in found, (stem, found)
    clean = _result(tmp_path, "clean", {"commit": recorded, "dirty": False})
    assert why_stale(clean, sources, repo) is None
    assert "no benchmark" in str(why_stale(clean, None, repo))


def test_recording_refuses_a_dirty_tree_before_running_anything(repo: Path, tmp_path: Path) -> None:
    recorded = _commit(repo, {"solver/core.py": "x = 1\n"})
    assert require_clean_tree(repo) == {"commit": recorded, "dirty": False}
    (repo / "solver" / "core.py").write_text("x = 3\n")
    with pytest.raises(DirtyTree, match="commit or stash"):
        require_clean_tree(repo)
    # a command that would write its output if it ran
    entry = Benchmark("probe", "writes a file", module="json.tool")
    recording = Recording("probe", ("--help",), ("report.json",))
    with pytest.raises(DirtyTree):
        record(entry, recording, tmp_path / "results", root=repo)
    assert not (tmp_path / "results").exists()


def test_recorded_result_files_leave_the_tree_clean_for_the_next_recording(repo: Path) -> None:
    """The result files of one commit are recorded one after another: a changed ``docs/results/`` file is what a
    recording wrote, not code it ran; a changed file anywhere else still makes the tree dirty."""
    recorded = _commit(repo, {"solver/core.py": "x = 1\n", "docs/results/speed.json": "{}\n"})
    (repo / "docs" / "results" / "speed.json").write_text('{"meta": {}}\n')
    assert require_clean_tree(repo) == {"commit": recorded, "dirty": False}
    (repo / "docs" / "results.md").write_text("a page beside the results\n")
    _git(repo, "add", "docs/results.md")
    with pytest.raises(DirtyTree):
        require_clean_tree(repo)


def test_a_recording_warms_up_first_and_keeps_what_the_command_wrote(repo: Path, tmp_path: Path) -> None:
    """The warm-up (``python -m ffrf warmup`` by default) runs before the timed command, in its environment; the
    meta names the commit of the tree that ran, not of the one this process imports ``ffrf`` from (a clone sharing
    another tree's environment once recorded that tree's commit)."""
    probe = "import json, os, sys; json.dump({'warmed': os.path.exists('warmed')}, open(sys.argv[1], 'w'))\n"
    head = _commit(repo, {"probe_bench.py": probe, ".gitignore": "warmed\n"})
    entry = Benchmark(
        "probe_bench", "writes whether the warm-up ran", measures=("probe_bench.py",), module="probe_bench"
    )
    recording = Recording("probe", ("{out}/report.json",))
    warm_up = ("-c", "open('warmed', 'w').close()")
    path = record(entry, recording, tmp_path / "results", root=repo, warm_up=warm_up)
    written = json.loads(path.read_text())
    assert written["results"] == {"warmed": True}
    assert written["meta"]["exit_status"] == 0 and "probe_bench OUT/report.json" in written["meta"]["command"]
    assert written["meta"]["git"] == {"commit": head, "dirty": False}


def test_rows_are_keyed_by_a_field_for_json_pointers() -> None:
    report = {"scene": "s", "rows": [{"variant": "rigid", "x": 1}, {"variant": "pla", "x": 2}]}
    assert keyed_rows(report, "variant", "variants") == {
        "scene": "s",
        "variants": {"rigid": {"variant": "rigid", "x": 1}, "pla": {"variant": "pla", "x": 2}},
    }
