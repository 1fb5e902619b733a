"""Command line: ``python -m identification (--vicon CSV ... | --result DIR ...) [--json]``.

Identifies the DH parameters of the Bennett loop from motion-capture exports or simulation
results (one per run; several runs give mean and standard deviation) and prints the
table in the paper's layout, or JSON (metres and radians) with ``--json``. Bad input (a missing,
binary or broken file, a non-finite twist, a zero window) is one line ``error: ...`` on stderr
and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from kinematics import PAPER_ALPHA

from .circle_fit import IdentificationError
from .records import read_simulation_result, read_vicon_csv
from .report import dh_table_csv, dh_table_markdown, plot_axis_fits
from .runs import identify_record, run_statistics


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m identification", description=__doc__.splitlines()[0])
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--vicon", type=Path, nargs="+", help="Vicon segment CSV export(s), one per run")
    source.add_argument("--result", type=Path, nargs="+", help="simulation result folder(s) with results.npz")
    parser.add_argument("--unit", default="mm", choices=["mm", "m"], help="length unit of the Vicon export")
    parser.add_argument(
        "--window",
        type=int,
        default=None,
        help="moving-average window in frames (default: 10 for --vicon as in the paper, 1 for noise-free --result)",
    )
    parser.add_argument(
        "--alpha-deg",
        type=float,
        nargs=4,
        default=list(np.degrees(PAPER_ALPHA)),
        help="nominal twists, used only to orient the fitted axes",
    )
    parser.add_argument("--json", action="store_true", help="print JSON instead of the table")
    parser.add_argument("--out", type=Path, help="also write dh_table.md, dh_table.csv and axis_fits.png here")
    args = parser.parse_args(argv)
    if not np.all(np.isfinite(args.alpha_deg)):  # argparse accepts "nan" and "inf" as floats
        print(
            f"error: --alpha-deg {args.alpha_deg} must be 4 finite twists in degrees, e.g. the paper's "
            f"{np.degrees(PAPER_ALPHA).round(3).tolist()}",
            file=sys.stderr,
        )
        return 2

    try:
        records = (
            [read_vicon_csv(p, unit=args.unit) for p in args.vicon]
            if args.vicon
            else [read_simulation_result(p) for p in args.result]
        )
        window = args.window if args.window is not None else (10 if args.vicon else 1)
        results = [identify_record(r, window, np.radians(args.alpha_deg)) for r in records]
    except (IdentificationError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    stats = run_statistics([r.loop for r in results])
    if args.json:
        payload = {
            "runs": [dict(r.loop.as_dict(), source=r.source, revolutions=r.revolutions) for r in results],
            "mean": {k: v.tolist() for k, v in stats.mean.items()},
            "std": {k: v.tolist() for k, v in stats.std.items()},
            "units": "metres and radians",
        }
        print(json.dumps(payload, indent=2))
    else:
        for r in results:
            print(f"{r.source}: {r.frames_used} frames, {r.revolutions:.2f} revolutions of link 3")
        print(dh_table_markdown(stats))
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "dh_table.md").write_text(dh_table_markdown(stats) + "\n")
        (args.out / "dh_table.csv").write_text(dh_table_csv(stats))
        fig, _ = plot_axis_fits(records[0].points, results[0].loop.fits)
        fig.savefig(args.out / "axis_fits.png", dpi=130, bbox_inches="tight")
    return 0


if __name__ == "__main__":
    sys.exit(main())
