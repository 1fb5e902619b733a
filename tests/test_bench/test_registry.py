"""The benchmarks' registry (``bench/registry.py``) covers the suite: every result file of the docs has a recording,
every module of ``bench/`` is a benchmark or one of the runner's own pieces, and every path a benchmark is said to
measure exists (a renamed package would otherwise never make its results stale)."""

from __future__ import annotations

from bench import ROOT
from bench.__main__ import main
from bench.registry import BENCHMARKS, recordings

#: Modules of bench/ that are the runner or shared by benchmarks, not benchmarks.
RUNNER = {"__init__", "__main__", "registry", "record", "staleness", "report", "memory_probe"}


def test_every_result_file_has_exactly_one_recording_and_every_recording_its_file() -> None:
    files = {path.stem for path in (ROOT / "docs" / "results").glob("*.json")}
    stems = [record.result for entry in BENCHMARKS for record in entry.records]
    assert len(stems) == len(set(stems)), "a result file recorded twice"
    assert set(stems) == files, {"unrecorded": files - set(stems), "no file": set(stems) - files}


def test_every_module_of_bench_is_a_registered_benchmark_or_part_of_the_runner() -> None:
    modules = {path.stem for path in (ROOT / "bench").glob("*.py")}
    registered = {entry.name for entry in BENCHMARKS if entry.in_bench}
    assert modules - RUNNER == registered


def test_measured_paths_exist() -> None:
    for entry in BENCHMARKS:
        for source in entry.sources():
            assert (ROOT / source).exists(), f"{entry.name} measures {source}, which does not exist"


def test_a_recording_reads_what_its_command_writes_into_its_folder() -> None:
    for stem, (_, record) in recordings().items():
        if record.recipe_missing:
            continue
        assert record.outputs, stem
        folder_given = "{out}" in record.args
        for output in record.outputs:
            assert f"{{out}}/{output}" in record.args or folder_given, (stem, output)


def test_the_runner_lists_every_result_file(capsys) -> None:
    assert main(["--list"]) == 0
    listed = capsys.readouterr().out
    for stem in recordings():
        assert f"docs/results/{stem}.json" in listed


def test_a_benchmark_name_records_all_its_files_and_a_result_file_itself() -> None:
    """``full_revolution`` names a benchmark and its first file: the name records both of its files;
    ``full_revolution.json`` that file alone, as does a result stem that is no benchmark."""
    from bench.__main__ import _recordings

    def stems(names):
        return [rec.result for _, rec in _recordings(names)]

    assert stems(["full_revolution"]) == ["full_revolution", "full_revolution_paper"]
    assert stems(["full_revolution.json"]) == ["full_revolution"]
    assert stems(["full_revolution_paper"]) == ["full_revolution_paper"]
