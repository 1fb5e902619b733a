#!/usr/bin/env bash
# Lint, format check and type check (configured in pyproject.toml), with the pinned tools of
# the project's .venv. Runs every check and fails if any of them failed.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
status=0
.venv/bin/ruff check . || status=1
.venv/bin/ruff format --check . || status=1
.venv/bin/mypy || status=1
exit $status
