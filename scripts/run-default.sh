#!/usr/bin/env bash
# Main job on the built-in default scene: the paper's flexible Bennett linkage (PLA), written to out/.
#   out/kinematics      ideal linkage: axes, motion polynomial, coupler path
#   out/pla             flexible simulation: results.npz, metadata.json
#   out/pla/identified  DH parameters identified from the simulated link trajectories
#   out/pla/validation  cross-validation against Exudyn: report.md (verdict first), metrics.json, figures
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
.venv/bin/python -m ffrf warmup  # compiles the kernels once after install (cached afterwards)
.venv/bin/python -m kinematics bennett --out out/kinematics
.venv/bin/python -m ffrf bennett --variant pla --out out/pla "$@"
.venv/bin/python -m identification --result out/pla --out out/pla/identified
.venv/bin/python -m validation report --variant pla --out out/pla/validation
