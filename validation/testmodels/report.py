r"""``python -m validation testmodels``: run the TestModel twins, print stored value, Exudyn's runs and
ours with their differences, optionally write them as JSON, and say whether every model passed.

For each model (:data:`validation.testmodels.TESTMODELS`): ours (Newton to the model's tolerance), and
unless ``exudyn=False`` Exudyn's rebuild of the script at the script's settings and with tightened
tolerances (:func:`validation.testmodels.spec.exudyn_settings`); the verdict is
:func:`validation.testmodels.spec.judge`. Differences are relative; ``*_without_time`` divides by the
stored value less the sum of the time column (for results that sum it: the sensor's own columns
alone); ``trajectory`` compares the sensor rows, largest difference over the largest value.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from . import EXUDYN_COMMIT, TESTMODELS
from .spec import (
    CONVERGED_TOLERANCE,
    REPRODUCED_TOLERANCE,
    STORED_TOLERANCE,
    TIGHT_ABSOLUTE,
    TIGHT_RELATIVE,
    ModelRun,
    TestModel,
    judge,
    relative,
)

__all__ = ["evaluate", "run_testmodels", "format_table", "main"]


def _run(run: ModelRun) -> dict[str, Any]:
    return {"result": run.result, "seconds": run.seconds, "settings": run.settings, "rows": int(run.sensor.shape[0])}


def _trajectory(a: ModelRun, b: ModelRun) -> float:
    """max |a - b| over the sensor's own columns, relative to max |b|; the time columns must agree."""
    if a.sensor.shape != b.sensor.shape or np.abs(a.sensor[:, 0] - b.sensor[:, 0]).max() > 1e-12:
        raise RuntimeError(f"sensor rows differ: {a.sensor.shape} at other times than {b.sensor.shape}")
    return float(np.abs(a.sensor[:, 1:] - b.sensor[:, 1:]).max() / np.abs(b.sensor[:, 1:]).max())


def evaluate(model: TestModel, exudyn: bool = True) -> dict[str, Any]:
    """One model: its runs, differences and verdict, as plain data (the JSON's ``models/<name>``)."""
    out: dict[str, Any] = {
        "description": model.description,
        "result_formula": model.result_formula,
        "stored": asdict(model.stored),
        "slow": model.slow,
    }
    if model.missing:
        return out | {"passed": False, "reason": f"not expressible yet: {model.missing}"}
    stored = model.stored.value
    ours = model.ours(model.tolerance)
    diffs: dict[str, Any] = {"ours_vs_stored": relative(ours.result, stored)}
    if model.time_in_result:
        own = abs(stored - float(np.abs(ours.sensor[:, 0]).sum()))
        diffs["ours_vs_stored_without_time"] = abs(ours.result - stored) / own
    out["ours"] = _run(ours)
    default_result = tight_result = None
    if exudyn:
        default, tight = model.exudyn(False), model.exudyn(True)
        default_result, tight_result = default.result, tight.result
        out["exudyn"], out["exudyn_tight"] = _run(default), _run(tight)
        diffs |= {
            "exudyn_vs_stored": relative(default.result, stored),
            "exudyn_tight_vs_stored": relative(tight.result, stored),
            "ours_vs_exudyn": relative(ours.result, default.result),
            "ours_vs_exudyn_tight": relative(ours.result, tight.result),
            "trajectory": {
                "ours_vs_exudyn": _trajectory(ours, default),
                "ours_vs_exudyn_tight": _trajectory(ours, tight),
            },
        }
        if model.time_in_result:
            own = abs(tight.result - float(np.abs(tight.sensor[:, 0]).sum()))
            diffs["ours_vs_exudyn_tight_without_time"] = abs(ours.result - tight.result) / own
            stored_own = abs(stored - float(np.abs(tight.sensor[:, 0]).sum()))
            diffs["exudyn_tight_vs_stored_without_time"] = abs(tight.result - stored) / stored_own
    if model.stored.in_script != stored:
        diffs["in_script_vs_stored"] = relative(model.stored.in_script, stored)
        diffs["ours_vs_in_script"] = relative(ours.result, model.stored.in_script)
    verdict = judge(stored, ours.result, default_result, tight_result)
    return out | {"differences": diffs, "passed": verdict.passed, "reason": verdict.reason}


def run_testmodels(names: Sequence[str] | None = None, exudyn: bool = True, progress=None) -> dict[str, Any]:
    """Every model of ``names`` (default: all, in :data:`TESTMODELS` order); ``progress(name, entry)``
    is called after each."""
    chosen = [m for m in TESTMODELS if names is None or m.name in names]
    unknown = set(names or ()) - {m.name for m in TESTMODELS}
    if unknown:
        raise KeyError(f"unknown TestModels {sorted(unknown)}; known: {', '.join(m.name for m in TESTMODELS)}")
    models = {}
    for model in chosen:
        models[model.name] = evaluate(model, exudyn)
        if progress is not None:
            progress(model.name, models[model.name])
    return {
        "exudyn_commit": EXUDYN_COMMIT,
        "tolerances": {
            "stored": STORED_TOLERANCE,
            "converged": CONVERGED_TOLERANCE,
            "reproduced": REPRODUCED_TOLERANCE,
            "exudyn_tight_relative": TIGHT_RELATIVE,
            "exudyn_tight_absolute": TIGHT_ABSOLUTE,
        },
        "exudyn_version": _exudyn_version() if exudyn else None,
        "models": models,
        "passed": all(entry["passed"] for entry in models.values()),
    }


def _exudyn_version() -> str:
    import exudyn

    return str(exudyn.__version__)


def _entry_lines(name: str, entry: dict[str, Any]) -> list[str]:
    stored = entry["stored"]
    lines = [f"{name}: {'PASS' if entry['passed'] else 'FAIL'} - {entry['reason']}"]
    if "ours" not in entry:
        return lines
    lines.append(f"  stored           {stored['value']:.16g}   ({stored['suite_reference']})")
    if stored["in_script"] != stored["value"]:
        lines.append(f"  in the script    {stored['in_script']:.16g}   ({stored['note']})")
    d = entry["differences"]
    for key, label in (("exudyn", "exudyn"), ("exudyn_tight", "exudyn tight")):
        if key in entry:
            run = entry[key]
            lines.append(
                f"  {label:<16} {run['result']:.16g}   vs stored {d[key + '_vs_stored']:.1e}   {run['seconds']:6.2f} s"
            )
    ours = entry["ours"]
    lines.append(
        f"  ours             {ours['result']:.16g}   vs stored {d['ours_vs_stored']:.1e}   {ours['seconds']:6.2f} s"
    )
    if "ours_vs_exudyn" in d:
        t = d["trajectory"]
        lines.append(
            f"  ours vs exudyn {d['ours_vs_exudyn']:.1e}, vs exudyn tight {d['ours_vs_exudyn_tight']:.1e}; "
            f"sensor rows {t['ours_vs_exudyn']:.1e} and {t['ours_vs_exudyn_tight']:.1e}"
        )
    if "ours_vs_stored_without_time" in d:
        extra = d.get("ours_vs_exudyn_tight_without_time")
        lines.append(
            f"  sensor columns alone (time column left out): ours vs stored {d['ours_vs_stored_without_time']:.1e}"
            + (
                ""
                if extra is None
                else f", vs exudyn tight {extra:.1e} (exudyn tight vs stored "
                f"{d['exudyn_tight_vs_stored_without_time']:.1e})"
            )
        )
    return lines


def _header(exudyn_version: str | None) -> str:
    return (
        f"Exudyn TestModels (commit {EXUDYN_COMMIT[:8]}), exudyn {exudyn_version or 'not run'}; pass: ours within "
        f"{STORED_TOLERANCE:g} of the stored value, or within {CONVERGED_TOLERANCE:g} of Exudyn's converged run where "
        "that misses the stored value by Exudyn's own Newton error"
    )


def format_table(results: dict[str, Any]) -> str:
    """The printed report of :func:`run_testmodels`."""
    lines = [_header(results["exudyn_version"])]
    for name, entry in results["models"].items():
        lines += _entry_lines(name, entry)
    passed = sum(entry["passed"] for entry in results["models"].values())
    lines.append(f"{passed} of {len(results['models'])} models passed")
    return "\n".join(lines)


def main(names: Sequence[str] | None, exudyn: bool, json_path: Path | None) -> int:
    """The subcommand: 0 if every model passed, 1 if one did not, 2 if a run failed."""
    print(_header(_exudyn_version() if exudyn else None), flush=True)
    try:
        results = run_testmodels(
            names, exudyn, lambda name, entry: print("\n".join(_entry_lines(name, entry)), flush=True)
        )
    except Exception as error:  # noqa: BLE001 - command-line boundary: any failure is reported, exit code 2
        print(f"testmodels failed: {type(error).__name__}: {error}", file=sys.stderr)
        return 2
    passed = sum(entry["passed"] for entry in results["models"].values())
    print(f"{passed} of {len(results['models'])} models passed")
    if json_path is not None:
        json_path.parent.mkdir(parents=True, exist_ok=True)
        json_path.write_text(json.dumps(results, indent=1) + "\n")
    return 0 if results["passed"] else 1
