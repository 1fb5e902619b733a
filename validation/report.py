"""Readable reports of Bennett cross-validations: ``report.md`` + PNGs + ``metrics.json`` per
variant, and a summary across variants in the layout of the paper's results.

The first screen of ``report.md`` states the verdict (the issue's targets, met or not, with
the measured values) and, when a target is missed, which modelling difference accounts for it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ffrf.paper.bennett_scene import paper_max_coupler_deviation

from . import figures
from .bennett_metrics import TARGETS
from .bennett_trajectory import tracked_nodes
from .bennett_validation import BennettValidation
from .markdown import checks_table, format_length, format_sci, markdown_table
from .twin_run import ComparedRun

__all__ = ["write_report", "write_summary", "identified_dh"]


def _verdict(m: dict) -> list[str]:
    failed = [c for c in m["checks"] if not c["passed"]]
    t, c = m["torque"], m["trajectories"]["coupler_point"]
    worst = max(m["trajectories"].values(), key=lambda v: v["max_abs_diff_m"])
    state = "all targets met" if not failed else f"{len(failed)} of {len(m['checks'])} targets missed"
    lines = [
        f"**Verdict: {state}.** "
        f"Same mesh, M, K, interfaces, joints, drive, gravity model and solver settings in both solvers; "
        f"Exudyn {m['versions']['exudyn']} reduces the links itself.",
        "",
        f"- Quasi-static revolution: coupler point differs by at most {format_length(c['max_abs_diff_m'])} "
        f"({format_sci(c['relative_to_elastic_deviation'])} of its "
        f"{format_length(m['coupler_deviation_from_ideal_m']['exudyn'])} "
        f"elastic deviation, at least 1 um; target {TARGETS['trajectory']:g}), tracked nodes by "
        f"{format_length(worst['max_abs_diff_m'])}, "
        f"driving torque by {format_sci(t['max_rel_diff'])} of its maximum (target {TARGETS['torque']:g}).",
    ]
    if "dynamic" in m:
        d = m["dynamic"]
        dw = max(d["trajectories"].values(), key=lambda v: v["max_abs_diff_m"])
        lines.append(
            f"- Dynamic window (0..{d['t_end']:g} s, generalized-alpha): nodes and coupler within "
            f"{format_length(dw['max_abs_diff_m'])} ({format_sci(dw['relative_to_elastic_deviation'])}), torque "
            f"{format_sci(d['torque']['max_rel_diff'])}."
        )
    freq = max(c["max_rel_freq_diff"] for c in m["modes"].values()) if m["modes"] else float("nan")
    mac = min(c["min_mac_diag"] for c in m["modes"].values()) if m["modes"] else float("nan")
    lines.append(
        f"- Modes: fixed-interface frequencies equal to {format_sci(freq)} (target {TARGETS['freq']:g}), "
        f"smallest diagonal MAC {mac:.12f}."
    )
    ti, te = m["timing_s"]["inhouse"], m["timing_s"]["exudyn"]
    lines.append(
        f"- Time: ours {ti['integration']:.1f} s, Exudyn {te['integration']:.1f} s for the quasi-static "
        f"revolution"
        + (
            f"; dynamic window ours {ti['dynamic_window']:.1f} s, Exudyn {te['dynamic_window']:.1f} s"
            if "dynamic_window" in ti
            else ""
        )
        + "."
    )
    if failed:
        lines += [
            "",
            "Missed: "
            + "; ".join(f"{c['name']} = {format_sci(c['value'])} (target {c['target']:g})" for c in failed)
            + ".",
            _attribution(m["modelling_differences"]["with_exudyn_jacobian_vs_exudyn"]),
        ]
    return lines


def _attribution(copied: dict) -> str:
    """Why targets were missed: the Jacobian explanation only if copying it closes the gap."""
    measured = (
        f"With Exudyn's marker rotation Jacobian replicated in our solver the difference to Exudyn is "
        f"{format_length(copied['max_abs_diff_m'])} ({format_sci(copied['relative_to_elastic_deviation'])}) "
        f"and {format_sci(copied['torque_max_rel_diff'])} in torque"
    )
    if (
        copied["relative_to_elastic_deviation"] > TARGETS["trajectory"]
        or copied["torque_max_rel_diff"] > TARGETS["torque"]
    ):
        return measured + ": that Jacobian does not explain the gap; it remains unexplained."
    return (
        measured + ", so the gap is that Jacobian: Exudyn's joint reactions use the marker angular velocity "
        "A(w + T theta_dot), not the derivative of its own constraint equations (A exp(theta~) T theta_dot); "
        "the error grows with the bores' elastic rotation theta, large where the links are forced into a "
        "misaligned assembly. Our exact Jacobian is the derivative of the constraint equations (checked against "
        "complex-step differentiation in tests/test_validation/test_bennett_vs_exudyn.py)."
    )


def _trajectory_table(trajectories: dict) -> str:
    """Per sensor: max and RMS difference, and the max relative to the coupler's elastic deviation."""
    return markdown_table(
        ["sensor", "max abs diff", "RMS", "max / coupler's elastic deviation"],
        [
            [
                name,
                format_length(t["max_abs_diff_m"]),
                format_length(t["rms_diff_m"]),
                format_sci(t["relative_to_elastic_deviation"]),
            ]
            for name, t in trajectories.items()
        ],
    )


def write_report(v: BennettValidation, directory: str | Path) -> Path:
    """Write ``report.md``, ``metrics.json`` and the figures into ``directory``; return the report path."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    m = v.metrics
    qs, variant = v.quasi_static, v.settings.variant
    figs = {
        "deviation": figures.coupler_deviation_figure(
            qs, v.ideal_coupler, out / "coupler_deviation.png", f"{variant}: coupler deviation from the ideal path"
        ),
        "difference": figures.difference_figure(
            qs["equivalent"],
            qs["exudyn"],
            out / "difference_quasi_static.png",
            f"{variant}: ours minus Exudyn, quasi-static revolution",
        ),
        "torque": figures.torque_figure(qs, out / "driving_torque.png", f"{variant}: driving torque"),
        "path": figures.coupler_path_figure(
            {k: qs[k] for k in ("production", "exudyn")}, v.ideal_coupler, out / "coupler_path.png"
        ),
    }
    if v.modes:
        figs["mac"] = figures.mac_figure(v.modes, out / "mac.png")
    if v.dynamic:
        figs["dynamic"] = figures.difference_figure(
            v.dynamic["equivalent"],
            v.dynamic["exudyn"],
            out / "difference_dynamic.png",
            f"{variant}: ours minus Exudyn, dynamic window",
        )
    (out / "metrics.json").write_text(json.dumps(m, indent=2, default=float))

    s = v.settings
    lines = [f"# Cross-validation against Exudyn: Bennett linkage, variant `{variant}`", ""]
    lines += _verdict(m)
    lines += [
        "",
        "## Checks against the targets",
        "",
        checks_table(m["checks"]),
    ]
    dev = m["coupler_deviation_from_ideal_m"]
    paper = paper_max_coupler_deviation(variant)
    lines += [
        "",
        "## Coupler deviation from the ideal path (motion polynomial)",
        "",
        markdown_table(
            ["run", "max deviation (mm)", "max driving torque (N mm)"],
            [
                [figures.STYLE[k]["label"], f"{1e3 * dev_k:.4f}", f"{1e3 * m['max_abs_driving_torque_Nm'][k]:.3f}"]
                for k, dev_k in (
                    ("production", dev["inhouse"]),
                    ("equivalent", dev["inhouse_equivalent"]),
                    ("exudyn", dev["exudyn"]),
                )
            ]
            + ([["paper (its STL links, 2 mm, 32 modes)", paper, ""]] if paper else []),
        ),
        "",
        "![coupler deviation](coupler_deviation.png) ![path](coupler_path.png)",
        "",
        "![driving torque](driving_torque.png)",
    ]
    lines += [
        "",
        "## Trajectories, quasi-static revolution (ours with Exudyn's gravity model vs Exudyn)",
        "",
        _trajectory_table(m["trajectories"]),
        "",
        f"Driving torque: max abs diff {1e3 * m['torque']['max_abs_diff_Nm']:.3e} N mm of "
        f"{1e3 * m['torque']['max_abs_Nm']:.4g} N mm ({format_sci(m['torque']['max_rel_diff'])}).",
        "",
        "![difference](difference_quasi_static.png)",
    ]
    if "dynamic" in m:
        d = m["dynamic"]
        lines += [
            "",
            f"## Dynamic window: 0..{d['t_end']:g} s, step {s.step:g} s, rho_inf {s.rho_inf:g}",
            "",
            _trajectory_table(d["trajectories"]),
            "",
            f"Driving torque: {format_sci(d['torque']['max_rel_diff'])} of its maximum. Constraint residuals "
            f"(our equations): ours {format_sci(d['constraint_residual']['inhouse'])}, Exudyn's run "
            f"{format_sci(d['constraint_residual']['exudyn'])}.",
            "",
            "![dynamic difference](difference_dynamic.png)",
        ]
    if v.modes:
        lines += ["", "## Modes (fixed-interface, ours vs Exudyn's own Craig-Bampton on the same matrices)", ""]
        rows = []
        for name, c in v.modes.items():
            for i, (fo, fe) in enumerate(zip(c.frequencies_hz, c.exudyn_frequencies_hz, strict=True)):
                rows.append(
                    [name, i, f"{fo:.6f}", f"{fe:.6f}", format_sci(abs(fo / fe - 1.0)), f"{c.diagonal_mac[i]:.12f}"]
                )
        lines += [
            markdown_table(["link", "mode", "ours (Hz)", "Exudyn (Hz)", "rel. diff", "MAC"], rows),
            "",
            "Static (constraint) mode spaces: largest principal angle "
            + ", ".join(f"{n} {format_sci(c.static_space_angle_rad)} rad" for n, c in v.modes.items())
            + ".",
            "",
            "![MAC](mac.png)",
        ]
    md = m["modelling_differences"]
    lines += [
        "",
        "## Where the remaining differences come from",
        "",
        "Each row compares two of our own runs (or ours with Exudyn's) on the quasi-static revolution:",
        "",
        markdown_table(
            ["comparison", "max abs diff (nodes, coupler)", "relative to elastic deviation", "torque"],
            [
                [
                    label,
                    format_length(md[key]["max_abs_diff_m"]),
                    format_sci(md[key]["relative_to_elastic_deviation"]),
                    format_sci(md[key]["torque_max_rel_diff"]),
                ]
                for key, label in (
                    ("exact_vs_exudyn_gravity", "exact gravity vs Exudyn's LoadMassProportional (modelling)"),
                    ("exact_vs_exudyn_marker_jacobian", "exact vs Exudyn's marker rotation Jacobian (ours both)"),
                    ("with_exudyn_jacobian_vs_exudyn", "ours with both Exudyn choices vs Exudyn (solver only)"),
                )
            ],
        ),
        "",
        "Energy balance over the revolution (drive work minus change of gravity and strain energy, "
        "relative to the work; Simpson over the rows, so limited by the output spacing): ours "
        f"{format_sci(m['energy_balance_relative']['inhouse'])}, ours with Exudyn's Jacobian "
        f"{format_sci(m['energy_balance_relative']['inhouse_exudyn_jacobian'])}, Exudyn's run "
        f"{format_sci(m['energy_balance_relative']['exudyn'])}. Constraint residuals in our equations: ours "
        f"{format_sci(m['constraint_residual']['inhouse'])}, Exudyn's run "
        f"{format_sci(m['constraint_residual']['exudyn'])}.",
    ]
    ti, te = m["timing_s"]["inhouse"], m["timing_s"]["exudyn"]
    lines += [
        "",
        "## Wall time (s, this machine, same run)",
        "",
        markdown_table(
            ["", "set-up", "quasi-static revolution", "dynamic window", "total"],
            [
                [label] + [f"{t.get(k, 0):.2f}" for k in ("setup", "integration", "dynamic_window", "total")]
                for label, t in (("ours", ti), ("Exudyn", te))
            ],
        ),
        "",
        "Ours: set-up = gmsh mesh, scikit-fem M and K, Craig-Bampton, system; revolution = static "
        "assembly + equilibria. Exudyn: set-up = its Craig-Bampton on our M and K + building the "
        "twin (it reuses our mesh and matrices); revolution = its static assembly + one SolveStatic sweep. "
        f"Our solver's kernels were compiled (or loaded from numba's cache) before the runs, in "
        f"{m['timing_s'].get('kernels_before_s', float('nan')):.1f} s, which no time above includes.",
        "",
        "## Settings and versions",
        "",
        "```json",
        json.dumps({"settings": m["settings"], "versions": m["versions"]}, indent=2, default=float),
        "```",
        "",
    ]
    path = out / "report.md"
    path.write_text("\n".join(lines))
    return path


def identified_dh(run: ComparedRun) -> dict:
    """DH parameters identified (paper's method, :mod:`identification`) from a run's tracked nodes."""
    from identification.loop import identify_dh

    tracked = tracked_nodes(run)
    loop = identify_dh({k: tracked[:, 3 * (k - 1) : 3 * k] for k in (1, 2, 3)})
    return {
        "a_mm": (1e3 * loop.dh.a).tolist(),
        "alpha_deg": np.degrees(loop.dh.alpha).tolist(),
        "d_mm": (1e3 * loop.dh.d).tolist(),
        "axis3_twist_deviation_deg": float(np.degrees(loop.axis3_twist_deviation)),
    }


def write_summary(validations: list[BennettValidation], directory: str | Path) -> Path:
    """``summary.md`` and ``summary.json`` across variants, in the layout of the paper's results."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    rows, dh_rows, data = [], [], {}
    for v in validations:
        m, variant = v.metrics, v.settings.variant
        dev = m["coupler_deviation_from_ideal_m"]
        worst = max(t["relative_to_elastic_deviation"] for t in m["trajectories"].values())
        rows.append(
            [
                variant,
                f"{1e3 * dev['inhouse']:.4f}",
                f"{1e3 * dev['exudyn']:.4f}",
                paper_max_coupler_deviation(variant),
                f"{1e3 * m['max_abs_driving_torque_Nm']['production']:.2f}",
                f"{1e3 * m['max_abs_driving_torque_Nm']['exudyn']:.2f}",
                format_sci(worst),
                format_sci(m["torque"]["max_rel_diff"]),
                "met" if m["passed"] else "missed (see report)",
            ]
        )
        ours, theirs = identified_dh(v.quasi_static["production"]), identified_dh(v.quasi_static["exudyn"])
        for label, dh in (("ours", ours), ("Exudyn", theirs)):
            dh_rows.append(
                [variant, label]
                + [f"{a:.3f}" for a in dh["a_mm"]]
                + [f"{a:.3f}" for a in dh["alpha_deg"]]
                + [f"{dh['axis3_twist_deviation_deg']:.3f}"]
            )
        data[variant] = {"metrics": m, "identified": {"inhouse": ours, "exudyn": theirs}}
    lines = [
        "# Bennett linkage: the four variants, ours against Exudyn",
        "",
        "Maximum coupler deviation from the ideal path and maximum driving torque over the revolution "
        "(quasi-static, 1 rpm), as in the paper's results; agreement of the two solvers on the same model "
        "(relative to the coupler's elastic deviation, and of the torque to its maximum).",
        "",
        markdown_table(
            [
                "variant",
                "ours (mm)",
                "Exudyn (mm)",
                "paper (mm)",
                "torque ours (N mm)",
                "torque Exudyn (N mm)",
                "trajectory diff",
                "torque diff",
                "targets",
            ],
            rows,
        ),
        "",
        "Our links are parametric (``ffrf.geometry.link_geometry``), not the paper's STL parts, so the deviations "
        "differ from the paper's; the trend with misalignment is the check.",
        "",
        "## DH parameters identified from the simulated link trajectories (paper's method)",
        "",
        markdown_table(
            [
                "variant",
                "solver",
                "a0",
                "a1",
                "a2",
                "a3",
                "alpha0",
                "alpha1",
                "alpha2",
                "alpha3",
                "axis-3 twist deviation (deg)",
            ],
            dh_rows,
        ),
        "",
        "Lengths in mm, angles in degrees. Per-variant reports: "
        + ", ".join(f"[{v.settings.variant}]({v.settings.variant}/report.md)" for v in validations)
        + ".",
        "",
    ]
    (out / "summary.json").write_text(json.dumps(data, indent=2, default=float))
    path = out / "summary.md"
    path.write_text("\n".join(lines))
    return path
