"""What stability monitoring, a study's default (issue #37), costs per print and what it buys: the first prints of
the 2000-print study (``examples/study_bennett_pla_2000.toml``, 16 bore errors, default discretisation, 121 poses),
each run in one process with and without monitoring (:func:`ffrf.studies.variant.run_variant`, the scene cache
warm): how their runs ended (:data:`ffrf.studies.outputs.ENDS`), the share of stops no cause explains with its 95 %
interval, and the wall time per print (median and mean), with and without.

Usage::

    .venv/bin/python -m bench study_stability --variants 60 --json out/study_stability.json
"""

from __future__ import annotations

import argparse
import statistics
import time
import tomllib
from pathlib import Path

import numpy as np

from bench.report import write_report

EXAMPLE = Path(__file__).parents[1] / "examples" / "study_bennett_pla_2000.toml"


def _rows(document: dict, stability: bool, count: int) -> list[dict]:
    from ffrf.paper.bennett_scene import STUDY_BASES
    from ffrf.studies.sampling import study_design
    from ffrf.studies.spec import study_from_document
    from ffrf.studies.variant import run_variant

    base = dict(document["base"], stability=stability)
    study = study_from_document(dict(document, base=base), EXAMPLE.parent, EXAMPLE.name, STUDY_BASES)
    variants = sorted(study_design(study), key=lambda v: v.sample)[:count]
    run_variant(study, variants[0])  # the scene cache and the kernels, not timed
    rows = []
    for k, variant in enumerate(variants):
        rows.append(run_variant(study, variant))
        if (k + 1) % 20 == 0:
            print(f"  stability {stability}: {k + 1} of {count} prints", flush=True)
    return rows


def summary(rows: list[dict]) -> dict:
    """How the rows' runs ended, the unclassified stops with their interval, and the time per print."""
    from ffrf.studies.outputs import ENDS
    from ffrf.studies.statistics import exceedance

    ends = {end: sum(r["end"] == end for r in rows) for end in ENDS}
    unclassified = exceedance(np.array([float(r["end"] == "stopped (unclassified)") for r in rows]), 0.5)
    times = [r["wall_time_s"] for r in rows]
    return {
        "prints": len(rows),
        "ends": ends,
        "unclassified": unclassified,
        "median_s": statistics.median(times),
        "mean_s": statistics.fmean(times),
        "stopped_at_deg": [r["last_drive_angle_deg"] for r in rows if r["status"] != "ok"],
    }


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=60, help="the first prints of the study's design")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    document = tomllib.loads(EXAMPLE.read_text())
    started = time.perf_counter()
    report: dict = {"study": EXAMPLE.name, "variants": args.variants}
    for name, stability in (("with_stability", True), ("without_stability", False)):
        report[name] = summary(_rows(document, stability, args.variants))
        r = report[name]
        print(
            f"{name}: {r['ends']}; median {r['median_s']:.3f} s, mean {r['mean_s']:.3f} s per print",
            flush=True,
        )
    report["cost_ratio_median"] = report["with_stability"]["median_s"] / report["without_stability"]["median_s"]
    report["cost_ratio_mean"] = report["with_stability"]["mean_s"] / report["without_stability"]["mean_s"]
    report["wall_time_s"] = time.perf_counter() - started
    if args.json:
        write_report(report, args.json, echo=False)
    return report


if __name__ == "__main__":
    main()
