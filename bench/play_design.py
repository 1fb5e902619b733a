"""The largest play of the PLA Bennett's passive joints that keeps its coupler within 1 mm of the ideal path
(``examples/design_bennett_play.toml``, ``docs/formulation.md`` Eq. (P8); issue #36): every play run, the answer and
the first play that misses, and the designed linkage's own run at 145 poses.

    .venv/bin/python -m bench record play_design                       # docs/results/play_design.json
    .venv/bin/python -m bench play_design --json out/play_design.json   # the same, written elsewhere
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from bench.report import write_report

EXAMPLE = Path(__file__).parents[1] / "examples" / "design_bennett_play.toml"


def main(argv=None) -> dict:
    from ffrf.cli import main as ffrf

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--design", type=Path, default=EXAMPLE, help="a design file with a [play] table")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        status = ffrf(["design", str(args.design), "--out", str(out)])
        design = json.loads((out / "design.json").read_text())
        check = json.loads((out / "check" / "metadata.json").read_text())
    report = {
        "design_file": args.design.name,
        "exit_status": status,
        **design,
        "check": {
            "outputs": check["n_outputs"],
            "max_coupler_deviation_mm": 1e3 * check["summary"]["max_coupler_deviation_m"],
            "verified": check["verification"]["verified"],
            "wall_time_s": check["timings_s"],
        },
    }
    if args.json:
        write_report(report, args.json, echo=False)
    return report


if __name__ == "__main__":
    main()
