#!/usr/bin/env bash
# The tests marked `slow` (long studies, 20-40 min on a loaded 2-core machine), which the default
# suite and CI leave out: run them before a release and weekly. From a clean tree the outcome is
# recorded in docs/results/slow_tests.json (counts per outcome, failing tests, duration, commit);
# from a tree with uncommitted changes the tests run but nothing is recorded. Extra arguments go
# to pytest. Exits with pytest's status.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
if [ -n "$(git status --porcelain --untracked-files=no)" ]; then
    echo "run-slow-tests: uncommitted changes: running the slow tests without recording them" >&2
    exec .venv/bin/python -m pytest -m slow "$@"
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
result=docs/results/slow_tests.json
.venv/bin/python scripts/record.py "$result" --json "$out/slow_tests.json" -- \
    python scripts/pytest_summary.py "$out/slow_tests.json" -- -m slow -p no:cacheprovider "$@"
.venv/bin/python -c 'import json, sys; sys.exit(json.load(open(sys.argv[1]))["results"]["exit_status"])' "$result"
