# Sourced by the other scripts: create .venv and install the project with its test, validation,
# studies and docs extras, once (and again whenever pyproject.toml changes).
set -euo pipefail
PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PYTHON" -m venv .venv
fi
stamp=.venv/.installed-$(sha1sum pyproject.toml | cut -c1-12)
if [ ! -f "$stamp" ]; then
    .venv/bin/python -m pip install --quiet --upgrade pip
    .venv/bin/python -m pip install --quiet -e ".[test,validation,studies,docs]"
    rm -f .venv/.installed-*
    touch "$stamp"
fi
