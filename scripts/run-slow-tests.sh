#!/usr/bin/env bash
# The tests marked `slow` (long studies, together far beyond the CI budget), which the default
# suite and CI leave out: run them before a release and weekly. From a clean tree the outcome is
# recorded in docs/results/slow_tests.json (counts per outcome, failing tests, duration, commit).
# Extra arguments go to pytest. Exits with pytest's status.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
exec .venv/bin/python scripts/record_tests.py docs/results/slow_tests.json -- -m slow -p no:cacheprovider "$@"
