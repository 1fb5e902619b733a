#!/usr/bin/env bash
# Default test suite (what CI runs). Extra arguments go to pytest, e.g. -m slow.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
# pytest exits 5 when it collected no test: that is a failure here, as any non-zero code.
# One worker per core, each test file on one worker (its module fixtures built once); -n 0 runs in this process.
exec .venv/bin/python -m pytest -n auto --dist loadfile "$@"
