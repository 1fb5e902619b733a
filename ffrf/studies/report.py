"""The analysis of a finished (or partly finished) study: percentiles, distributions, sensitivities, report.md.

:func:`write_report` reads ``DIR/study.json`` and the rows (:func:`ffrf.studies.runner.read_rows`) and writes
``DIR/report.md`` with ``DIR/figures/*.png`` and the numbers in ``DIR/analysis.json``: per output the
percentile table of its ok variants, a histogram with the empirical CDF, the standardised regression
coefficients on all ok rows, the first-order and total Sobol indices of a Saltelli design
(:mod:`ffrf.studies.sensitivity`), scatter plots of the output against the most influential parameters, and for a
grid of two or more parameters a contour plot over the first two (the mean over the others).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

from ffrf.studies.runner import read_rows
from ffrf.studies.sensitivity import given_data_indices, sobol_indices, standardised_regression
from ffrf.studies.statistics import exceedance, percentile_interval

__all__ = ["PERCENTILES", "percentile_table", "saltelli_outputs", "analyse", "write_report"]

PERCENTILES = (0, 1, 5, 25, 50, 75, 95, 99, 100)
#: Scatter plots per output: the parameters with the largest total index (or given-data index, or ``|SRC|``).
TOP_PARAMETERS = 3
#: Below this R^2 a linear model does not rank the parameters: the report says so.
LOW_R2 = 0.5
#: A Sobol index whose 95 % interval is wider than this either way is too uncertain to rank by: the report says so.
WIDE_INDEX = 0.2
#: Designs of random rows, whose first-order indices come from the rows as given (RBD-FAST).
RANDOM_DESIGNS = ("monte_carlo", "lhs", "sobol")


def percentile_table(values: NDArray) -> dict:
    """Count, mean, standard deviation and :data:`PERCENTILES` of the finite ``values``, and ``intervals``: the
    95 % interval of each percentile between the extremes
    (:func:`~ffrf.studies.statistics.percentile_interval`, distribution-free; ``None`` for an end the sample
    cannot bound)."""
    v = np.sort(np.asarray(values, dtype=float))
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {"n": 0}
    table = {"n": int(v.size), "mean": float(v.mean()), "std": float(v.std(ddof=1)) if v.size > 1 else 0.0}
    table |= {f"p{p}": float(q) for p, q in zip(PERCENTILES, np.percentile(v, PERCENTILES), strict=True)}
    intervals = {f"p{p}": [x if np.isfinite(x) else None for x in percentile_interval(v, p)] for p in PERCENTILES[1:-1]}
    return table | {"intervals": intervals}


def saltelli_outputs(columns: dict[str, NDArray], output: NDArray, d: int, n: int) -> tuple[NDArray, NDArray, NDArray]:
    """``f_A``, ``f_B`` (``n``) and ``f_AB`` (``n x d``) of a Saltelli design from the rows' ``block`` and
    ``sample`` columns; NaN where a variant has no row yet or failed."""
    blocks = ["A", "B"] + [f"AB{i}" for i in range(d)]
    f = {name: np.full(n, np.nan) for name in blocks}
    for block, sample, value in zip(columns["block"], columns["sample"], output, strict=True):
        if block in f and 0 <= sample < n:
            f[block][sample] = value
    return f["A"], f["B"], np.column_stack([f[f"AB{i}"] for i in range(d)])


def _columns(directory: Path) -> dict[str, NDArray]:
    table = read_rows(directory)
    if table is None:
        raise FileNotFoundError(f"{directory}: no rows yet (run the study first: python -m ffrf study ...)")
    return {name: np.asarray(table.column(name).to_pylist()) for name in table.column_names}


def analyse(directory: str | Path) -> dict:
    """The numbers of the report (module docstring) as plain data."""
    directory = Path(directory)
    study = json.loads((directory / "study.json").read_text())
    columns = _columns(directory)
    names = [p["name"] for p in study["parameters"]]
    ok = columns["status"] == "ok"
    failures: dict[str, int] = {}
    for reason in columns["reason"][~ok]:
        key = str(reason).split(":")[0]
        failures[key] = failures.get(key, 0) + 1
    x = np.column_stack([columns[name].astype(float) for name in names])
    outputs = {}
    warnings = []
    variants = study.get("variants")
    if variants is not None and len(ok) < variants:
        warnings.append(
            f"the study is unfinished: {len(ok)} of its {variants} variants have a row, and every number here is of "
            "those (a Saltelli design's indices of its complete sample rows only)"
        )
    for output in study["outputs"]:
        y = np.where(ok, columns[output].astype(float), np.nan)
        regression = standardised_regression(x, y)
        entry = {
            "percentiles": percentile_table(y),
            "src": dict(zip(names, regression.beta.tolist(), strict=True)),
            "src_interval": {
                n: [lo, hi] for n, lo, hi in zip(names, regression.low.tolist(), regression.high.tolist(), strict=True)
            },
            "src_r2": regression.r2,
        }
        if np.isfinite(regression.r2) and regression.r2 < LOW_R2:
            warnings.append(
                f"{output}: a linear model explains R^2 = {regression.r2:.2g} of it, so its regression coefficients "
                "do not rank the parameters"
            )
        if study["method"] == "saltelli":
            indices = sobol_indices(*saltelli_outputs(columns, y, len(names), study["samples"]))
            entry |= {
                "sobol_first": dict(zip(names, indices.first.tolist(), strict=True)),
                "sobol_total": dict(zip(names, indices.total.tolist(), strict=True)),
                "sobol_first_conf": dict(zip(names, indices.first_conf.tolist(), strict=True)),
                "sobol_total_conf": dict(zip(names, indices.total_conf.tolist(), strict=True)),
                "sobol_rows_used": indices.used,
            }
            warnings += _index_warnings(output, names, indices.first, indices.first_conf, "first-order")
            warnings += _index_warnings(output, names, indices.total, indices.total_conf, "total")
        elif study["method"] in RANDOM_DESIGNS:
            given = given_data_indices(x, y)
            entry |= {
                "given_data_first": dict(zip(names, given.first.tolist(), strict=True)),
                "given_data_first_conf": dict(zip(names, given.first_conf.tolist(), strict=True)),
            }
        outputs[output] = entry
    limits = {
        output: exceedance(np.where(ok, columns[output].astype(float), np.nan), above)
        for output, above in study.get("limits", [])
    }
    return {
        "study": study,
        "warnings": warnings,
        "limits": limits,
        "rows": int(len(ok)),
        "ok": int(ok.sum()),
        "failed": failures,
        "assembles": int(np.sum(columns["assembles"] == True)),  # noqa: E712 -- an object array with None
        "wall_time_s": percentile_table(columns["wall_time_s"].astype(float)),
        "outputs": outputs,
    }


def _index_warnings(output: str, names: list[str], index: NDArray, conf: NDArray, kind: str) -> list[str]:
    """What a reader must know of one output's Sobol indices: an index outside [0, 1] beyond its interval (the
    estimator's sampling error, not a property of the linkage), and intervals too wide to rank by."""
    out = []
    for name, value, half in zip(names, index, conf, strict=True):
        if np.isfinite(value) and (value - half > 1.0 or value + half < 0.0):
            out.append(
                f"{output}: the {kind} index of {name} is {value:.3g} +- {half:.2g}, outside [0, 1] beyond its "
                "interval: too few samples for this estimator; raise samples"
            )
    widest = float(np.nanmax(conf)) if np.any(np.isfinite(conf)) else 0.0
    if widest > WIDE_INDEX:
        out.append(
            f"{output}: its {kind} Sobol indices are uncertain (95 % intervals up to +-{widest:.2g}): they do not rank "
            "the parameters; raise samples"
        )
    return out


def _distribution_figure(values: NDArray, name: str, path: Path) -> None:
    """Histogram and empirical CDF of one output's finite values."""
    v = np.sort(values[np.isfinite(values)])
    figure = Figure(figsize=(9, 3.5))
    hist, ecdf = figure.subplots(1, 2)
    hist.hist(v, bins=max(5, min(50, int(np.sqrt(v.size)) + 1)))
    hist.set_xlabel(name)
    hist.set_ylabel("variants")
    ecdf.step(v, np.arange(1, v.size + 1) / v.size, where="post")
    ecdf.set_xlabel(name)
    ecdf.set_ylabel("empirical CDF")
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def _scatter_figure(x: dict[str, NDArray], y: NDArray, name: str, path: Path) -> None:
    """The output against each of the given parameters."""
    figure = Figure(figsize=(4 * len(x), 3.5))
    axes = np.atleast_1d(figure.subplots(1, len(x)))
    for ax, (parameter, values) in zip(axes, x.items(), strict=True):
        ax.plot(values, y, ".", markersize=3)
        ax.set_xlabel(parameter)
        ax.set_ylabel(name)
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def _contour_figure(x1: NDArray, x2: NDArray, y: NDArray, labels: tuple[str, str, str], path: Path) -> None:
    """Contours of the mean of ``y`` over the grid of ``x1`` and ``x2`` (other parameters averaged)."""
    u1, u2 = np.unique(x1), np.unique(x2)
    grid = np.full((len(u2), len(u1)), np.nan)
    for i, a in enumerate(u1):
        for j, b in enumerate(u2):
            chosen = y[(x1 == a) & (x2 == b)]
            chosen = chosen[np.isfinite(chosen)]
            grid[j, i] = chosen.mean() if chosen.size else np.nan
    figure = Figure(figsize=(5, 4))
    ax = figure.subplots()
    filled = ax.contourf(u1, u2, grid, levels=12)
    figure.colorbar(filled, ax=ax, label=labels[2])
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def _influence(entry: dict, names: list[str]) -> list[str]:
    """Parameters by influence: total Sobol index where there is one, else the given-data first-order index, else
    ``|SRC|``."""
    score = entry.get("sobol_total", entry.get("given_data_first", {n: abs(entry["src"][n]) for n in names}))
    return sorted(names, key=lambda n: -np.nan_to_num(score[n], nan=-1.0))


def _interval(table: dict, level: int) -> str:
    """A percentile's 95 % interval as ``[low, high]`` (empty where the table has none)."""
    interval = table.get("intervals", {}).get(f"p{level}")
    if interval is None:
        return ""
    low, high = (
        "-inf" if interval[0] is None else f"{interval[0]:.4g}",
        "inf" if interval[1] is None else f"{interval[1]:.4g}",
    )
    return f"[{low}, {high}]"


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)] + [
        "| " + " | ".join(r) + " |" for r in rows
    ]


def write_report(directory: str | Path) -> Path:
    """Write ``report.md``, ``analysis.json`` and ``figures/`` into the study folder (module docstring)."""
    directory = Path(directory)
    analysis = analyse(directory)
    (directory / "analysis.json").write_text(json.dumps(analysis, indent=2))
    figures = directory / "figures"
    figures.mkdir(exist_ok=True)
    columns = _columns(directory)
    study = analysis["study"]
    names = [p["name"] for p in study["parameters"]]
    ok = columns["status"] == "ok"
    lines = [
        f"# Study {study['name']!r}",
        "",
        f"Method {study['method']}, {analysis['rows']} variants with a row, {analysis['ok']} ok, "
        f"{analysis['assembles']} assembled; failures by reason: {analysis['failed'] or 'none'}. "
        "Outputs in SI units (`docs/studies.md`).",
        "",
    ]
    if analysis["warnings"]:
        lines += ["## Warnings", ""] + [f"- {warning}" for warning in analysis["warnings"]] + [""]
    lines += ["## Percentiles of the ok variants", ""]
    header = ["output", "n"] + [f"p{p}" for p in PERCENTILES] + ["p50, 95 % interval", "p95, 95 % interval"]
    rows = [
        [o, str(e["percentiles"].get("n", 0))]
        + [f"{e['percentiles'].get(f'p{p}', float('nan')):.4g}" for p in PERCENTILES]
        + [_interval(e["percentiles"], level) for level in (50, 95)]
        for o, e in analysis["outputs"].items()
    ]
    lines += _table(header, rows) + [""]
    for output, limit in analysis.get("limits", {}).items():
        if limit["n"] == 0:
            continue
        lines.append(
            f"Limit {output} <= {limit['above']:.4g}: {limit['exceeding']} of {limit['n']} ok prints exceed it; yield "
            f"{100 * limit['yield']:.4g} % (95 % interval {100 * limit['yield_low']:.4g} to "
            f"{100 * limit['yield_high']:.4g} %); failed prints are not counted."
        )
    lines += ["", "## Sensitivities", ""]
    for output, entry in analysis["outputs"].items():
        lines += [
            f"### {output}",
            "",
            f"Linear regression: R^2 = {entry['src_r2']:.3g}. Each value with its 95 % interval.",
            "",
        ]
        sobol, given = "sobol_first" in entry, "given_data_first" in entry
        header = ["parameter", "SRC"] + (["S_i", "S_Ti"] if sobol else []) + (["S_i (given data)"] if given else [])
        rows = [
            [n, f"{entry['src'][n]:.3g} [{entry['src_interval'][n][0]:.3g}, {entry['src_interval'][n][1]:.3g}]"]
            + (
                [
                    f"{entry['sobol_first'][n]:.3g} +- {entry['sobol_first_conf'][n]:.2g}",
                    f"{entry['sobol_total'][n]:.3g} +- {entry['sobol_total_conf'][n]:.2g}",
                ]
                if sobol
                else []
            )
            + ([f"{entry['given_data_first'][n]:.3g} +- {entry['given_data_first_conf'][n]:.2g}"] if given else [])
            for n in names
        ]
        lines += _table(header, rows) + [""]
        y = np.where(ok, columns[output].astype(float), np.nan)
        if np.isfinite(y).sum() < 2:
            continue
        _distribution_figure(y, output, figures / f"{output}_distribution.png")
        top = _influence(entry, names)[:TOP_PARAMETERS]
        _scatter_figure({n: columns[n].astype(float) for n in top}, y, output, figures / f"{output}_scatter.png")
        lines += [f"![{output}](figures/{output}_distribution.png)", f"![{output}](figures/{output}_scatter.png)"]
        if study["method"] == "grid" and len(names) >= 2:
            x1, x2 = columns[names[0]].astype(float), columns[names[1]].astype(float)
            _contour_figure(x1, x2, y, (names[0], names[1], output), figures / f"{output}_contour.png")
            lines.append(f"![{output}](figures/{output}_contour.png)")
        lines.append("")
    path = directory / "report.md"
    path.write_text("\n".join(lines) + "\n")
    return path
