r"""``python -m validation testmodels``: run the TestModel twins, print stored value, Exudyn's runs and
ours with their differences, optionally write them as JSON, and say whether every model passed.

For each model (:data:`validation.testmodels.TESTMODELS`): ours (Newton to the model's tolerance), and
unless ``exudyn=False`` Exudyn's rebuild of the script at the script's settings and with tightened
tolerances (:func:`validation.testmodels.spec.exudyn_settings`); the verdict is
:func:`validation.testmodels.spec.judge`. Differences are relative; ``*_without_time`` divides by the
stored value less the sum of the time column (for results that sum it: the sensor's own columns
alone); ``trajectory`` compares the sensor rows, largest difference over the largest value.

Then Exudyn's examples (:data:`validation.testmodels.EXAMPLES`, :func:`evaluate_example`): no stored
value, so they run only with Exudyn (whose ``FEMinterface`` also imports their Netgen meshes) and are
judged by :func:`validation.testmodels.spec.judge_example`; with ``exudyn=False`` they are listed as skipped.

Exudyn's runs (and its eigenfrequencies of an example) run inside :func:`validation.modes.deterministic_eigsh`: its
``FEM`` module's sparse eigensolver would start from a random vector, and move their results from run to run.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from ..modes import deterministic_eigsh
from . import EXAMPLES, EXUDYN_COMMIT, TESTMODELS
from .spec import (
    CONVERGED_TOLERANCE,
    FREQUENCY_TOLERANCE,
    REPRODUCED_TOLERANCE,
    STORED_TOLERANCE,
    TIGHT_ABSOLUTE,
    TIGHT_RELATIVE,
    Example,
    ModelRun,
    TestModel,
    judge,
    judge_example,
    relative,
)

__all__ = ["evaluate", "evaluate_example", "run_testmodels", "format_table", "main"]


def _run(run: ModelRun) -> dict[str, Any]:
    return {"result": run.result, "seconds": run.seconds, "settings": run.settings, "rows": int(run.sensor.shape[0])}


def _trajectory(a: ModelRun, b: ModelRun) -> float:
    """max |a - b| over the sensor's own columns, relative to max |b|; the time columns must agree (to
    1e-12 of the end time: Exudyn sums its steps, 1.1e-12 s off after 4000 steps of 5 ms)."""
    end = max(1.0, float(np.abs(b.sensor[:, 0]).max()))
    if a.sensor.shape != b.sensor.shape or np.abs(a.sensor[:, 0] - b.sensor[:, 0]).max() > 1e-12 * end:
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
        with deterministic_eigsh():
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


def evaluate_example(example: Example, exudyn: bool = True) -> dict[str, Any]:
    """One example: ours and Exudyn's two runs, differences of the sensor rows, eigenfrequencies, verdict."""
    out: dict[str, Any] = {
        "description": example.description,
        "result_formula": example.result_formula,
        "source": f"main/pythonDev/Examples/{example.name}.py, git blob {example.source_blob}",
        "slow": example.slow,
    }
    if not exudyn:
        return out | {"skipped": "no stored value: judged against Exudyn's run, which was not asked for"}
    ours = example.ours(example.tolerance)
    with deterministic_eigsh():
        default, tight = example.exudyn(False), example.exudyn(True)
    out["ours"], out["exudyn"], out["exudyn_tight"] = _run(ours), _run(default), _run(tight)
    diffs: dict[str, Any] = {
        "ours_vs_exudyn": relative(ours.result, default.result),
        "ours_vs_exudyn_tight": relative(ours.result, tight.result),
        "trajectory": {
            "ours_vs_exudyn": _trajectory(ours, default),
            "ours_vs_exudyn_tight": _trajectory(ours, tight),
            "exudyn_vs_exudyn_tight": _trajectory(default, tight),
        },
    }
    frequency_error = None
    if example.frequencies is not None:
        with deterministic_eigsh():
            sets = example.frequencies()
        out["frequencies_hz"] = {name: [float(f) for f in values] for name, values in sets.items()}
        frequency_error = float(np.max(np.abs(sets["ours"] / sets["exudyn"] - 1.0)))
        diffs["frequencies"] = {
            f"{name}_vs_exudyn{suffix}": float(np.max(np.abs(sets[name] / sets["exudyn" + suffix] - 1.0)))
            for name, suffix in (("ours", ""), ("ours_feet_only", "_feet_only"))
            if name in sets
        }
        if "stated" in sets:
            stated = sets["stated"]
            diffs["frequencies"] |= {
                "ours_feet_only_vs_stated_hz": float(np.max(np.abs(sets["ours_feet_only"] - stated))),
                "ours_feet_only_vs_stated": float(np.max(np.abs(sets["ours_feet_only"] / stated - 1.0))),
            }
    verdict = judge_example(example, diffs["trajectory"]["ours_vs_exudyn_tight"], frequency_error)
    return out | {"differences": diffs, "passed": verdict.passed, "reason": verdict.reason}


def run_testmodels(names: Sequence[str] | None = None, exudyn: bool = True, progress=None) -> dict[str, Any]:
    """Every model and example of ``names`` (default: all, :data:`TESTMODELS` then :data:`EXAMPLES`);
    ``progress(name, entry)`` is called after each."""
    every = TESTMODELS + EXAMPLES
    unknown = set(names or ()) - {m.name for m in every}
    if unknown:
        raise KeyError(f"unknown TestModels {sorted(unknown)}; known: {', '.join(m.name for m in every)}")
    models = {}
    for model in every:
        if names is not None and model.name not in names:
            continue
        entry = evaluate(model, exudyn) if isinstance(model, TestModel) else evaluate_example(model, exudyn)
        models[model.name] = entry
        if progress is not None:
            progress(model.name, entry)
    return {
        "exudyn_commit": EXUDYN_COMMIT,
        "tolerances": {
            "stored": STORED_TOLERANCE,
            "converged": CONVERGED_TOLERANCE,
            "reproduced": REPRODUCED_TOLERANCE,
            "exudyn_tight_relative": TIGHT_RELATIVE,
            "exudyn_tight_absolute": TIGHT_ABSOLUTE,
            "frequencies": FREQUENCY_TOLERANCE,
        },
        "exudyn_version": _exudyn_version() if exudyn else None,
        "models": models,
        "passed": all(entry["passed"] for entry in models.values() if "skipped" not in entry),
    }


def _exudyn_version() -> str:
    import exudyn

    return str(exudyn.__version__)


def _example_lines(name: str, entry: dict[str, Any]) -> list[str]:
    if "skipped" in entry:
        return [f"{name}: skipped - {entry['skipped']}"]
    lines = [f"{name}: {'PASS' if entry['passed'] else 'FAIL'} - {entry['reason']}"]
    d = entry["differences"]
    for key, label in (("exudyn", "exudyn"), ("exudyn_tight", "exudyn tight"), ("ours", "ours")):
        run = entry[key]
        lines.append(f"  {label:<16} {run['result']:.16g}   {run['rows']} rows   {run['seconds']:6.2f} s")
    t = d["trajectory"]
    lines.append(
        f"  sensor rows: ours vs exudyn {t['ours_vs_exudyn']:.1e}, vs exudyn tight {t['ours_vs_exudyn_tight']:.1e} "
        f"(exudyn vs exudyn tight {t['exudyn_vs_exudyn_tight']:.1e})"
    )
    if "frequencies_hz" in entry:
        for label, values in entry["frequencies_hz"].items():
            lines.append(f"  {label + ' (Hz)':<24} " + " ".join(f"{v:.4f}" for v in values))
        lines.append("  eigenfrequencies: " + ", ".join(f"{k} {v:.1e}" for k, v in d["frequencies"].items()))
    return lines


def _entry_lines(name: str, entry: dict[str, Any]) -> list[str]:
    if "stored" not in entry:
        return _example_lines(name, entry)
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
    lines.append(_count(results["models"]))
    return "\n".join(lines)


def _count(models: dict[str, Any]) -> str:
    judged = [entry for entry in models.values() if "skipped" not in entry]
    skipped = len(models) - len(judged)
    return f"{sum(e['passed'] for e in judged)} of {len(judged)} models passed" + (
        f" ({skipped} skipped)" if skipped else ""
    )


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
    print(_count(results["models"]))
    if json_path is not None:
        json_path.parent.mkdir(parents=True, exist_ok=True)
        json_path.write_text(json.dumps(results, indent=1) + "\n")
    return 0 if results["passed"] else 1
