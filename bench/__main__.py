"""The benchmarks' runner (run from the repository root).

    python -m bench --list                 every benchmark, the result files it records and the code it measures
    python -m bench NAME [ARGS...]         run bench/NAME.py with its own arguments (NAME --help lists them)
    python -m bench record NAME...         record every file of a benchmark NAME, or docs/results/RESULT.json
                                           alone (RESULT or RESULT.json), from a clean tree: provenance and the
                                           commit in its meta
    python -m bench stale                  list the result files older than the code they measure, and why;
                                           exit status 1 if any

The benchmarks, their recordings' arguments and the paths each one measures are listed in bench/registry.py.
"""

from __future__ import annotations

import runpy
import sys

from bench.registry import BENCHMARKS, Benchmark, Recording, benchmark, recording


def _list() -> int:
    """Print every benchmark, how it runs, what it measures and its recordings."""
    for entry in BENCHMARKS:
        print(f"{entry.name}: {entry.summary}\n    run: {entry.command}\n    measures: {', '.join(entry.sources())}")
        for rec in entry.records:
            if rec.recipe_missing:
                args = f"(not by the runner: {rec.recipe_missing})"
            else:
                args = " ".join([*rec.env, *rec.args])
            print(f"    docs/results/{rec.result}.json  {args}")
    return 0


def _recordings(names: list[str]) -> list[tuple[Benchmark, Recording]]:
    """The recordings named: benchmark names (all their recordings; a benchmark's first file may have its name),
    or result stems (``RESULT`` or ``RESULT.json``, that file alone)."""
    chosen = []
    for name in names:
        stem = name.removesuffix(".json")
        if name == stem:
            try:
                entry = benchmark(name)
                chosen += [(entry, rec) for rec in entry.records]
                continue
            except KeyError:
                pass
        try:
            chosen.append(recording(stem))
        except KeyError:
            raise KeyError(f"no result file or benchmark {name!r} (python -m bench --list)") from None
    return chosen


def _record(names: list[str]) -> int:
    """Record the result files named (stems or benchmark names); stops at the first that cannot be."""
    from bench.record import DirtyTree, record  # imports ffrf (provenance): not needed by --list or stale

    if not names:
        print("bench record: name a result file (docs/results/RESULT.json) or a benchmark; see --list")
        return 2
    try:
        chosen = _recordings(names)
    except KeyError as error:
        print(f"bench record: {error.args[0]}")
        return 2
    for entry, rec in chosen:
        try:
            path = record(entry, rec)
        except (DirtyTree, ValueError) as error:
            print(f"bench record: {error}")
            return 1
        print(f"bench record: {path}")
    return 0


def _stale() -> int:
    """Print the stale result files with the reason; exit status 1 if any."""
    from bench.staleness import stale_results

    found = stale_results()
    for item in found:
        print(item)
    print(f"{len(found)} stale result files (python -m bench record RESULT re-records one from a clean tree)")
    return 1 if found else 0


def _run(name: str, args: list[str]) -> int:
    """Run ``bench/NAME.py`` as ``__main__`` with ``args`` as its command line."""
    try:
        entry = benchmark(name)
    except KeyError as error:
        print(f"bench: {error.args[0]}")
        return 2
    if not entry.in_bench:
        print(f"bench: {name} is run as {entry.command}, not by this runner")
        return 2
    sys.argv = [f"bench/{name}.py", *args]
    runpy.run_module(entry.runnable, run_name="__main__", alter_sys=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    """The runner's command line (the module's docstring); its exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else 2
    command, rest = argv[0], argv[1:]
    if command in ("--list", "list"):
        return _list()
    if command == "record":
        return _record(rest)
    if command == "stale":
        return _stale()
    return _run(command, rest)


if __name__ == "__main__":
    sys.exit(main())
