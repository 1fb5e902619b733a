"""The benchmarks: each module measures one thing and writes it as JSON; ``bench/registry.py`` lists them.

Run from the repository root as a package (``python -m bench --help``): ``python -m bench NAME [ARGS]`` runs one,
``python -m bench record RESULT`` keeps its output as ``docs/results/RESULT.json`` with provenance, and
``python -m bench stale`` lists the result files older than the code they measure (``docs/architecture.md``,
"Figures in the docs").
"""

from pathlib import Path

#: The repository's root: the working directory of the benchmarks' child processes.
ROOT = Path(__file__).resolve().parents[1]
