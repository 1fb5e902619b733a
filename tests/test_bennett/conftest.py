"""Puts ``bench/`` on ``sys.path`` for this folder: ``test_hard_cases`` runs a fast subset of the
hard cases of ``bench/hard_cases.py``, a script folder that is not a package."""

import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / "bench"
if str(BENCH) not in sys.path:
    sys.path.insert(0, str(BENCH))
