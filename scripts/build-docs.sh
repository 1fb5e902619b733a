#!/usr/bin/env bash
# The documentation site: the Markdown pages of docs/, the API reference from the docstrings and the examples
# run as a gallery -> docs/_build/html. Fails on any Sphinx warning and on an example that fails.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
rm -rf docs/api/generated  # autosummary writes it afresh: a module renamed since the last build must not linger
exec .venv/bin/python -m sphinx -b html -W --keep-going -q docs docs/_build/html "$@"
