"""The 2000-print tolerance study of the PLA Bennett to first and second order, against its full Monte Carlo (#35).

    .venv/bin/python -m bench record linear_tolerance                  # docs/results/linear_tolerance.json
    .venv/bin/python -m bench linear_tolerance --json out/linear.json   # the rows alone

``examples/study_bennett_pla_2000.toml`` (every bore twisted, std 0.5 deg, and moved along its link's normal, std
0.1 mm; misfit model, 121 poses) by ``ffrf.studies.linear_tolerance.linear_report``: 10^6 random prints of the
linear model, the percentiles of their largest coupler deviation with 95 % intervals, against the full study's
recorded percentiles (``docs/results/study_pla_2000.json``, 2000 prints run in full), the prints' lowest vibration
frequency to first order (Eq. (D7)) against the full study's and the prints that reach a fold; and at tolerances of
0.5, 1, 2 and 4 times the study's, ``--check`` prints of the study's own design run in full against the model: where
the first order holds and where it breaks; and the tolerances that keep the 95th percentile within 1 mm. Then the
same to second order (Eq. (D11): the base's second derivatives by central second differences of k (k + 1) full runs
at the study's spreads, once for every level): the same prints run in full against both models, the driving torque
(of second order in the errors) among them.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

from bench.report import write_report
from ffrf.paper.bennett_scene import STUDY_BASES
from ffrf.studies.linear_tolerance import linear_path, linear_report, second_order
from ffrf.studies.spec import Study, load_study

STUDY = Path("examples/study_bennett_pla_2000.toml")
FULL = Path("docs/results/study_pla_2000.json")
LEVELS = (0.5, 1.0, 2.0, 4.0)
#: The allocation's target: the 95th percentile of the largest coupler deviation within 1 mm (m).
TARGET = 1e-3


def scaled(study: Study, factor: float) -> Study:
    """The study with every parameter's spread (a normal's std) times ``factor``."""
    parameters = tuple(replace(p, arguments=(p.arguments[0], factor * p.arguments[1])) for p in study.parameters)
    return replace(study, parameters=parameters)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    parser.add_argument("--prints", type=int, default=10**6)
    parser.add_argument("--check", type=int, default=16, help="prints run in full per tolerance level")
    args = parser.parse_args()
    study = load_study(STUDY, STUDY_BASES)
    if any(p.distribution != "normal" for p in study.parameters):
        raise SystemExit(f"{STUDY}: every parameter must be normal to scale its std")
    outputs = json.loads(FULL.read_text())["results"]["outputs"]
    full = outputs["max_coupler_deviation_m"]["percentiles"]
    frequency = outputs["min_frequency_hz"]["percentiles"]
    first = linear_path(study)
    print(f"first order: {first.seconds}", flush=True)
    started = time.perf_counter()
    second = second_order(study, first, progress=lambda done, total: print(f"second order: {done}/{total} runs"))
    second_order_s = time.perf_counter() - started
    levels = []
    for factor in LEVELS:
        level = scaled(study, factor)
        report = linear_report(level, args.prints, args.check, TARGET, model=first)
        quadratic = linear_report(level, args.prints, args.check, TARGET, model=second)
        print(f"x{factor}: {report['max_coupler_deviation_m']}, verified {report['verified']}", flush=True)
        print(f"   second order: {quadratic['max_coupler_deviation_m']}, verified {quadratic['verified']}", flush=True)
        levels.append(dict(report, level=factor, second_order=quadratic))
    write_report(
        {
            "study": str(STUDY),
            "full_study": {key: full[key] for key in ("n", "mean", "p50", "p95", "p99")},
            "full_study_min_frequency_hz": {key: frequency[key] for key in ("n", "p0", "p1", "p5", "p50", "p95")},
            "second_order_runs_s": second_order_s,
            "rows": levels,
        },
        args.json,
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
