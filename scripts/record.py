"""Run a measuring command and keep what it measured as a result file of the docs.

    .venv/bin/python scripts/record.py docs/results/NAME.json --json out/x.json -- CMD ARGS...

runs ``CMD ARGS...`` (``python`` is this interpreter), reads the JSON the command wrote to
each ``--json`` (one file: its content; several: ``{file stem: content}``) and writes
``{"meta": ..., "results": ...}`` to the result file: the command, the UTC date, the machine (CPU,
cores, load averages at start and end), the versions of the installed packages and the git commit
(``ffrf/output/provenance.py``). ``--select KEY`` keeps only those top-level keys of the results;
``--rows-by FIELD`` turns every list of dicts named ``rows`` into a dict keyed by ``FIELD``, so that
a figure's JSON pointer names it (``/variants/pla/...`` instead of ``/rows/1/...``).

The numbers in ``README.md`` and ``docs/*.md`` are links into these files; ``scripts/update_docs.py``
rewrites them from the files.

The command runs with a disk cache of built scenes of its own (``FFRF_CACHE_DIR``, a fresh temporary folder), so
what it measures does not depend on an earlier run's cache; a benchmark that measures the cache sets it itself.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ffrf.output.provenance import load_average, provenance  # noqa: E402


def _rows_by(value, field: str, name: str):
    """``value`` with every list of dicts under a key ``rows`` keyed by ``field`` and renamed ``name``."""
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            if key == "rows" and isinstance(item, list) and all(isinstance(r, dict) and field in r for r in item):
                out[name] = {str(r[field]): _rows_by(r, field, name) for r in item}
            else:
                out[key] = _rows_by(item, field, name)
        return out
    if isinstance(value, list):
        return [_rows_by(v, field, name) for v in value]
    return value


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result", type=Path, help="the result file to write, docs/results/NAME.json")
    parser.add_argument(
        "--json", type=Path, action="append", required=True, help="a JSON file the command writes (repeatable)"
    )
    parser.add_argument("--select", nargs="*", help="keep only these top-level keys of the command's JSON")
    parser.add_argument("--rows-by", help="key lists of rows by this field (see the module's docstring)")
    parser.add_argument("--rows-name", default="rows", help="name of the keyed rows (default: rows)")
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--" not in argv:
        parser.error("no command given: ... -- CMD ARGS...")
    split = argv.index("--")
    args, command = parser.parse_args(argv[:split]), argv[split + 1 :]
    shown = ["python" if c == sys.executable else c for c in command]
    run = [sys.executable if c == "python" else c for c in command]

    load = load_average()
    started = time.perf_counter()
    for path in args.json:
        path.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory(prefix="ffrf-cache-") as cache:
        status = subprocess.run(run, cwd=ROOT, env=dict(os.environ, FFRF_CACHE_DIR=cache)).returncode
    wall = time.perf_counter() - started
    missing = [str(path) for path in args.json if not path.exists()]
    if missing:
        print(f"record: {' '.join(shown)} wrote no {', '.join(missing)} (exit status {status}); nothing recorded")
        return 1
    results = {path.stem: json.loads(path.read_text()) for path in args.json}
    if len(results) == 1:
        results = next(iter(results.values()))
    if args.select:
        results = {k: results[k] for k in args.select if k in results}
    if args.rows_by:
        results = _rows_by(results, args.rows_by, args.rows_name)
    meta = provenance(" ".join(shown), load_at_start=load, wall_time_s=wall)
    meta["exit_status"] = status
    args.result.parent.mkdir(parents=True, exist_ok=True)
    args.result.write_text(json.dumps({"meta": meta, "results": results}, indent=1) + "\n")
    print(f"record: {args.result} ({wall:.0f} s, exit status {status})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
