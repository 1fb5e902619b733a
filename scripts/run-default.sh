#!/usr/bin/env bash
# Main job on the built-in default scene: the paper's Bennett linkage, written to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
exec .venv/bin/python -m kinematics bennett --out out "$@"
