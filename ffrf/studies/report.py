"""The analysis of a finished (or partly finished) study: percentiles, distributions, sensitivities, report.md.

:func:`write_report` reads ``DIR/study.json`` and the rows (:func:`ffrf.studies.runner.read_rows`) and writes
``DIR/report.md`` with ``DIR/figures/*.png`` and the numbers in ``DIR/analysis.json`` (SI units; the report shows
mm, MPa, N mm and mJ): per output the percentile table of its ok variants (of every assembled variant for the
assembly's outputs, whose path may have stopped later), how its p50 and p95 settle as variants are added, a
histogram with the empirical CDF, the standardised regression coefficients on all ok rows, the first-order and
total Sobol indices of a Saltelli design (:mod:`ffrf.studies.sensitivity`), the parameters' contributions, scatter
plots of the output against the most influential parameters, and for a grid of two or more parameters a contour
plot over the first two (the mean over the others); for the print shop (:mod:`ffrf.studies.prints`) the prints
that did not finish with their parameters and reasons (also ``DIR/unfinished.csv``), the worst prints, and the
drive angles where the maxima occur.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

from ffrf.studies.outputs import ENDS, WHERE, is_assembly_output
from ffrf.studies.prints import CONVERGING, convergence, display, unfinished_prints, worst_prints
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
#: A print's run that stopped for no classified reason (:data:`~ffrf.studies.outputs.ENDS`).
UNCLASSIFIED = "stopped (unclassified)"
#: Above this share of unclassified stops the report warns (issue #37's bound for the 2000-print example).
UNCLASSIFIED_SHARE = 0.005
#: The report lists this many unfinished prints (``unfinished.csv`` all of them).
UNFINISHED_SHOWN = 20
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
    assembled = columns["assembles"] == True  # noqa: E712 -- an object array with None
    for output in study["outputs"]:
        y = np.where(assembled if is_assembly_output(output) else ok, columns[output].astype(float), np.nan)
        regression = standardised_regression(x, y)
        entry = {
            "percentiles": percentile_table(y),
            "convergence": convergence(columns, y),
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
    ends = {end: int(np.sum(columns["end"] == end)) for end in ENDS} if "end" in columns else {}
    unclassified = exceedance(np.array([float(e == UNCLASSIFIED) for e in columns.get("end", [])]), 0.5)
    if unclassified["n"] and unclassified["fraction"] > UNCLASSIFIED_SHARE:
        warnings.append(
            f"{unclassified['exceeding']} of {unclassified['n']} prints stopped for a reason the solver does not "
            f"classify ({100 * unclassified['fraction']:.2g} %, above {100 * UNCLASSIFIED_SHARE:g} %): they are the "
            "solver's failures, not the prints'; run with stability = true, or see unfinished.csv"
        )
    worst = {o: worst_prints(columns, names, o) for o in ("max_coupler_deviation_m", "max_abs_driving_torque_Nm")}
    where = {w: percentile_table(np.where(ok, columns[w].astype(float), np.nan)) for w in WHERE if w in columns}
    return {
        "study": study,
        "warnings": warnings,
        "limits": limits,
        "ends": ends,
        "unclassified": unclassified,
        "unfinished": unfinished_prints(columns, names),
        "worst": worst,
        "where": where,
        "rows": int(len(ok)),
        "ok": int(ok.sum()),
        "failed": failures,
        "assembles": int(np.sum(assembled)),
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
    score = _contributions(entry, names)[1]
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


def _scaled(table: dict, factor: float) -> dict:
    """A percentile table in the report's unit (``factor`` from SI)."""
    out = {k: factor * v if isinstance(v, float) and k != "n" else v for k, v in table.items()}
    if "intervals" in table:
        out["intervals"] = {
            k: [None if x is None else factor * x for x in pair] for k, pair in table["intervals"].items()
        }
    return out


def _print_shop(analysis: dict, names: list[str]) -> list[str]:
    """The report's lines on the prints one by one (:mod:`ffrf.studies.prints`)."""
    lines = ["## Prints that did not finish", ""]
    unfinished = analysis["unfinished"]
    if not unfinished:
        lines += ["Every print ran to the end of its path.", ""]
    else:
        lines += [
            f"{len(unfinished)} prints (all in `unfinished.csv`; parameters in the study's units):",
            "",
        ]
        rows = [
            [
                p["id"],
                {True: "yes", False: "no", None: "-"}[p["assembles"]],
                "-" if p["last_drive_angle_deg"] is None else f"{p['last_drive_angle_deg']:.1f}",
                p["reason"][:120].replace("|", "/"),
            ]
            + [f"{p['parameters'][n]:.4g}" for n in names]
            for p in unfinished[:UNFINISHED_SHOWN]
        ]
        lines += _table(["id", "assembled", "path ended at (deg)", "reason", *names], rows)
        more = len(unfinished) - UNFINISHED_SHOWN
        lines += ([f"... and {more} more in `unfinished.csv`."] if more > 0 else []) + [""]
    lines += ["## The worst prints and where their maxima occur", ""]
    where = analysis.get("where", {})
    for output, worst in analysis["worst"].items():
        if not worst:
            continue
        label, unit, _ = display(output)
        angles = where.get(f"{label}_at_deg", {})
        if angles.get("n"):
            lines.append(
                f"{label}: over the ok prints its maximum occurs between {angles['p5']:.1f} and "
                f"{angles['p95']:.1f} deg of drive (p5 to p95; median {angles['p50']:.1f} deg)."
            )
        rows = [
            [p["id"], f"{p['value']:.4g}", "-" if p["at_deg"] is None else f"{p['at_deg']:.1f}"]
            + [f"{p['parameters'][n]:.4g}" for n in names]
            for p in worst
        ]
        lines += [""] + _table(["id", f"{label} ({unit})", "at (deg)", *names], rows) + [""]
    return lines


def _write_unfinished(unfinished: list[dict], names: list[str], path: Path) -> None:
    """Every print that did not finish, one line each: id, assembled, drive angle where it ended, parameters,
    reason."""
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["id", "assembles", "last_drive_angle_deg", *names, "reason"])
        for p in unfinished:
            writer.writerow(
                [p["id"], p["assembles"], p["last_drive_angle_deg"], *(p["parameters"][n] for n in names), p["reason"]]
            )


def _convergence_figure(points: list[dict], name: str, path: Path) -> None:
    """The output's p50 and p95 with their 95 % intervals against the number of variants they are of."""
    label, unit, factor = display(name)
    figure = Figure(figsize=(5, 3.5))
    ax = figure.subplots()
    n = np.array([p["n"] for p in points])
    for level in CONVERGING:
        value = factor * np.array([p[f"p{level}"] for p in points])
        bounds = np.array([[np.nan if x is None else factor * x for x in p[f"p{level}_interval"]] for p in points])
        ax.plot(n, value, "o-", label=f"p{level}")
        ax.fill_between(n, bounds[:, 0], bounds[:, 1], alpha=0.2)
    ax.set_xlabel("variants")
    ax.set_ylabel(f"{label} ({unit})" if unit else label)
    ax.legend()
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def _contributions_figure(entry: dict, names: list[str], name: str, path: Path) -> None:
    """The parameters by contribution (:func:`_influence`'s measure, its 95 % interval as error bars), largest on
    top: a tornado chart."""
    kind, values, half = _contributions(entry, names)
    ranked = _influence(entry, names)[::-1]
    figure = Figure(figsize=(5, 0.4 * len(names) + 1.2))
    ax = figure.subplots()
    ax.barh(ranked, [values[n] for n in ranked], xerr=[half.get(n, 0.0) for n in ranked])
    ax.set_xlabel(f"{kind} of {display(name)[0]}")
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def _contributions(entry: dict, names: list[str]) -> tuple[str, dict[str, float], dict[str, float]]:
    """What ranks the parameters (total Sobol index, given-data first-order index, or |SRC|) and its intervals'
    half widths."""
    if "sobol_total" in entry:
        return "total Sobol index", entry["sobol_total"], entry["sobol_total_conf"]
    if "given_data_first" in entry:
        return "first-order index (given data)", entry["given_data_first"], entry["given_data_first_conf"]
    src = {n: abs(entry["src"][n]) for n in names}
    half = {n: 0.5 * (entry["src_interval"][n][1] - entry["src_interval"][n][0]) for n in names}
    return "|standardised regression coefficient|", src, half


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)] + [
        "| " + " | ".join(r) + " |" for r in rows
    ]


def write_report(directory: str | Path) -> Path:
    """Write ``report.md``, ``analysis.json`` and ``figures/`` into the study folder (module docstring)."""
    directory = Path(directory)
    analysis = analyse(directory)
    (directory / "analysis.json").write_text(json.dumps(analysis, indent=2))
    _write_unfinished(
        analysis["unfinished"], [p["name"] for p in analysis["study"]["parameters"]], directory / "unfinished.csv"
    )
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
        f"{analysis['assembles']} assembled; failures by reason: {analysis['failed'] or 'none'}.",
        "",
    ]
    if analysis["ends"]:
        counted = ", ".join(f"{n} {end}" for end, n in analysis["ends"].items() if n)
        share = analysis["unclassified"]
        lines += [
            f"How the prints' runs ended: {counted}; unclassified stops {100 * share['fraction']:.2g} % (95 % "
            f"interval {100 * share['fraction_low']:.2g} to {100 * share['fraction_high']:.2g} %).",
            "",
        ]
    if analysis["warnings"]:
        lines += ["## Warnings", ""] + [f"- {warning}" for warning in analysis["warnings"]] + [""]
    lines += [
        "## Percentiles",
        "",
        "Of the ok variants (the assembly's outputs: of every assembled variant); 95 % intervals distribution-free.",
        "",
    ]
    header = ["output", "unit", "n"] + [f"p{p}" for p in PERCENTILES] + ["p50, 95 % interval", "p95, 95 % interval"]
    rows = []
    for o, e in analysis["outputs"].items():
        label, unit, factor = display(o)
        scaled = _scaled(e["percentiles"], factor)
        rows.append(
            [label, unit, str(scaled.get("n", 0))]
            + [f"{scaled.get(f'p{p}', float('nan')):.4g}" for p in PERCENTILES]
            + [_interval(scaled, level) for level in (50, 95)]
        )
    lines += _table(header, rows) + [""]
    for output, limit in analysis.get("limits", {}).items():
        if limit["n"] == 0:
            continue
        label, unit, factor = display(output)
        lines.append(
            f"Limit {label} <= {factor * limit['above']:.4g} {unit}: {limit['exceeding']} of {limit['n']} ok prints "
            f"exceed it; yield {100 * limit['yield']:.4g} % (95 % interval {100 * limit['yield_low']:.4g} to "
            f"{100 * limit['yield_high']:.4g} %); failed prints are not counted."
        )
    lines += [""] + _print_shop(analysis, names)
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
        _convergence_figure(entry["convergence"], output, figures / f"{output}_convergence.png")
        _contributions_figure(entry, names, output, figures / f"{output}_contributions.png")
        top = _influence(entry, names)[:TOP_PARAMETERS]
        _scatter_figure({n: columns[n].astype(float) for n in top}, y, output, figures / f"{output}_scatter.png")
        lines += [
            f"![{output}](figures/{output}_{kind}.png)"
            for kind in ("distribution", "convergence", "contributions", "scatter")
        ]
        if study["method"] == "grid" and len(names) >= 2:
            x1, x2 = columns[names[0]].astype(float), columns[names[1]].astype(float)
            _contour_figure(x1, x2, y, (names[0], names[1], output), figures / f"{output}_contour.png")
            lines.append(f"![{output}](figures/{output}_contour.png)")
        lines.append("")
    path = directory / "report.md"
    path.write_text("\n".join(lines) + "\n")
    return path
