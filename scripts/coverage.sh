#!/usr/bin/env bash
# Statement coverage of kinematics/, ffrf/, identification/ and validation/ by the default test
# suite, with numba's JIT off so that the kernels count as Python (far slower than the suite):
# measured once in a while, not in CI. From a clean tree the summary (total and per package, the
# tests' outcome, commit) is recorded in docs/results/coverage.json. Extra arguments go to pytest,
# e.g. a subset of tests/ (the result file keeps them). Exits with pytest's status.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
exec .venv/bin/python scripts/record_tests.py docs/results/coverage.json --coverage -- -p no:cacheprovider "$@"
