"""The generated tables of the docs: one function ``table_NAME`` per ``<!-- table NAME -->`` block.

Each reads the result files it needs from ``docs/results/`` and returns the Markdown table (with a source
line); ``scripts/update_docs.py`` writes the blocks and its ``--check`` compares them. The file is longer
than our modules usually are because it holds one short function per table of the docs (22), which are
read best side by side; ``format_like`` is the one rule for how a figure's digits are written.
"""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def format_like(written: str, value: float) -> str:
    """``value`` written with the digits of ``written`` (decimals, or mantissa decimals of a/e-b)."""
    if "e" in written:
        mantissa = written.split("e")[0]
        decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
        text = f"{value:.{decimals}e}"
        mantissa, exponent = text.split("e")
        return f"{mantissa}e{int(exponent)}"
    decimals = len(written.split(".")[1]) if "." in written else 0
    text = f"{value:.{decimals}f}"
    return text.lstrip("-") if float(text) == 0 else text


RESULTS = ROOT / "docs" / "results"


def _results(name: str) -> dict | None:
    path = RESULTS / f"{name}.json"
    return json.loads(path.read_text())["results"] if path.is_file() else None


def _source(*names: str) -> str:
    return "Source: " + ", ".join(f"[`{n}.json`](results/{n}.json)" for n in names if (RESULTS / f"{n}.json").is_file())


def _row(cells) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def _header(*cells: str) -> list[str]:
    return [_row(cells), _row(["---"] * len(cells))]


def _g2(x: float) -> str:
    """Two significant digits, without an exponent up to 1e5."""
    return f"{x:.0f}" if abs(x) >= 100 else f"{x:.2g}"


def _e(x: float, digits: int = 1) -> str:
    return format_like(f"1.{'0' * digits}e0" if digits else "1e0", x)


VARIANTS = ("rigid", "pla", "pla1", "pla2")
DISCRETISATIONS = (
    ("bennett_variants_default", "**default: P2, 6 mm, 4 modes**"),
    ("bennett_variants_p2_4mm", "**P2, 4 mm, 4 modes**"),
    ("bennett_variants_paper", "**paper's: P1, 2 mm, 32 modes**"),
    ("bennett_variants_joint_points", "**default, links centred on the joint points** (they pass through each other)"),
)


def table_bennett_variants() -> str:
    """The four variants at each recorded discretisation (``bench/bennett_variants.py``)."""
    lines = _header(
        "discretisation",
        "variant",
        "max deviation (mm)",
        "distance to path (mm)",
        "paper (mm)",
        "max abs torque (N mm)",
        "assembly max von Mises (MPa)",
        "strain energy (mJ)",
        "build (s)",
        "run (s)",
    )
    names = []
    for name, label in DISCRETISATIONS:
        data = _results(name)
        if data is None:
            continue
        names.append(name)
        for k, variant in enumerate(VARIANTS):
            r = data["variants"][variant]
            nodes = r["nodes_per_link"]
            first = f"{label} ({min(nodes)} to {max(nodes)} nodes per link, {r['n_coordinates']} coordinates)"
            paper = ("< " if variant == "rigid" else "") + f"{r['paper_max_deviation_mm']:g}"
            lines.append(
                _row(
                    [
                        first if k == 0 else "",
                        variant,
                        f"{r['max_coupler_deviation_mm']:.4g}",
                        f"{r['max_distance_to_path_mm']:.4g}",
                        paper,
                        f"{r['max_abs_driving_torque_Nmm']:.2f}",
                        f"{r['assembly_max_von_mises_MPa']:.3g}",
                        f"{r['assembly_strain_energy_mJ']:.3g}",
                        f"{r['wall_time_s']['build']:.1f}",
                        f"{r['wall_time_s']['run']:.1f}",
                    ]
                )
            )
    return "\n".join(lines + ["", _source(*names)])


def table_clearance_variants() -> str:
    """The paper's variants with radial play in their passive joints (``bench/clearance_variants.py``)."""
    data = _results("clearance_variants")
    lines = _header(
        "variant",
        "radial play (mm)",
        "max deviation (mm)",
        "distance to path (mm)",
        "assembly max von Mises (MPa)",
        "strain energy (mJ)",
        "max abs torque (N mm)",
        "pins' max eccentricity (mm)",
        "identified alpha (deg)",
        "identified d (mm)",
        "run",
    )
    for r in (data or {}).get("runs", {}).values():
        if r["stopped"]:
            verdict = r["stopped"].split(":")[0]
        else:
            verdict = f"{'verified' if r['verified'] else 'not verified'}, {r['wall_time_s']['run']:.0f} s"
        lines.append(
            _row(
                [
                    r["variant"],
                    f"{r['radial_mm']:g}",
                    f"{r['max_coupler_deviation_mm']:.4g}",
                    f"{r['max_distance_to_path_mm']:.4g}",
                    f"{r['assembly_max_von_mises_MPa']:.3g}",
                    f"{r['assembly_strain_energy_mJ']:.3g}",
                    f"{r['max_abs_driving_torque_Nmm']:.2f}",
                    f"{r['max_pin_eccentricity_mm']:.4f}",
                    ", ".join(f"{a:.2f}" for a in r["identified_alpha_deg"] or []) or "-",
                    ", ".join(f"{d:.2f}" for d in r["identified_d_mm"] or []) or "-",
                    verdict,
                ]
            )
        )
    return "\n".join(lines + ["", _source("clearance_variants")])


def table_play_design() -> str:
    """Every play the PLA Bennett's play design ran (``bench/play_design.py``), in the order of the plays."""
    data = _results("play_design")
    lines = _header("radial play (mm)", "largest deviation (mm)", "assembly max von Mises (MPa)", "run", "bound")
    for r in sorted((data or {}).get("evaluated", []), key=lambda r: r["radial_mm"]):
        if r["stopped"]:
            run = "stopped: " + r["stopped"].split(":")[0]
        else:
            why = [reason.split()[0] for reason in r.get("not_verified_because", [])]
            verdict = "verified" if r["verified"] else "not verified" + (f" ({', '.join(why)})" if why else "")
            run = f"{verdict}, {r['seconds']:.0f} s"
        lines.append(
            _row(
                [
                    f"{r['radial_mm']:.4g}",
                    f"{r['max_deviation_mm']:.4g}",
                    f"{r['assembly_max_von_mises_mpa']:.3g}",
                    run,
                    "meets" if r["meets"] else "misses",
                ]
            )
        )
    return "\n".join(lines + ["", _source("play_design")])


def table_study_ends() -> str:
    """How each print of the 2000-print study ended (``python -m ffrf study``'s analysis, ``ends``)."""
    data = _results("study_pla_2000") or {}
    lines = _header("how the print's run ended", "prints")
    for end, count in data.get("ends", {}).items():
        lines.append(_row([end, count]))
    share = data.get("unclassified", {})
    if share.get("n"):
        lines += [
            "",
            f"Stopped for a reason the solver does not classify: {share['exceeding']} of {share['n']} "
            f"(95 % interval {100 * share['fraction_low']:.2g} to {100 * share['fraction_high']:.2g} %).",
        ]
    return "\n".join(lines + ["", _source("study_pla_2000")])


def table_study_worst() -> str:
    """The 2000-print study's five prints with the largest coupler deviation and where it occurs."""
    data = _results("study_pla_2000") or {}
    lines = _header("print", "largest coupler deviation (mm)", "at drive angle (deg)")
    for p in data.get("worst", {}).get("max_coupler_deviation_m", []):
        at = "-" if p["at_deg"] is None else f"{p['at_deg']:.1f}"
        lines.append(_row([p["id"], f"{p['value']:.4g}", at]))
    return "\n".join(lines + ["", _source("study_pla_2000")])


#: The linkage files of the recorded twin reports (``bench/registry.py``'s ``TWIN_LINKAGES``), in the table's order.
TWIN_LINKAGES = ("goldberg_5r", "bennett_ark24", "collisions_free_6r", "plane_fold_6r", "interp_4poses_6r")


def _twin_row(name: str, run: str, m: dict, same: dict, wall: str) -> list:
    """One row of :func:`table_twins`; ``same``: the differences with Exudyn's marker Jacobian in both."""
    t_ours, t_exudyn = m["timing_s"]["inhouse"]["total"], m["timing_s"]["exudyn"]["total"]
    missed = sum(not c["passed"] for c in m["checks"])
    verdict = "met" if m["passed"] else f"{missed} of {len(m['checks'])} missed"
    if "stopped" in m:
        verdict = f"incomplete ({m['outputs_compared']} of {m['outputs']} outputs)"
    return [
        name,
        run,
        f"{1e3 * m['deviation']:.3g}",
        f"{m['worst']:.2g}",
        f"{same['worst']:.2g}",
        f"{m['torque']:.2g}",
        f"{same['torque']:.2g}",
        f"{t_ours:.0f} / {t_exudyn:.0f}",
        wall,
        verdict,
    ]


def table_twins() -> str:
    """The Exudyn twin of every built-in linkage: the paper's four Bennett variants (``validation summary``) and the
    linkage files of :data:`TWIN_LINKAGES` (``validation report --scene``)."""
    lines = _header(
        "linkage",
        "run",
        "coupler's elastic deviation (mm)",
        "max difference / elastic deviation",
        "with Exudyn's Jacobian",
        "driving torque difference / max",
        "with Exudyn's Jacobian",
        "time ours / Exudyn (s)",
        "report's wall time (s)",
        "targets",
    )
    summary = _results("validation_summary") or {}
    summary_wall = (
        json.loads((RESULTS / "validation_summary.json").read_text())["meta"]["wall_time_s"] if summary else 0
    )
    for variant, entry in summary.items():
        m = entry["metrics"]
        same = m["modelling_differences"]["with_exudyn_jacobian_vs_exudyn"]
        row = {
            **m,
            "deviation": m["coupler_deviation_from_ideal_m"]["exudyn"],
            "worst": max(v["relative_to_elastic_deviation"] for v in m["trajectories"].values()),
            "torque": m["torque"]["max_rel_diff"],
        }
        run = f"quasi-static, {m['settings']['outputs']} outputs; {m['settings']['dynamic_t_end']:g} s dynamic"
        wall = f"{summary_wall:.0f} (all four)"
        lines.append(
            _row(
                _twin_row(
                    f"Bennett {variant}",
                    run,
                    row,
                    {"worst": same["relative_to_elastic_deviation"], "torque": same["torque_max_rel_diff"]},
                    wall,
                )
            )
        )
    for name in TWIN_LINKAGES:
        m = _results(f"validation_{name}")
        if m is None or m.get("elastic_deviation_m") is None:
            continue
        sensors, torques = m["sensors"].values(), m["torques"].values()
        row = {
            **m,
            "deviation": m["elastic_deviation_m"],
            "worst": max(v["relative_to_elastic_deviation"] for v in sensors),
            "torque": max(v["max_rel_diff"] for v in torques),
        }
        same = {
            "worst": max(v["with_exudyn_jacobian_relative_to_elastic_deviation"] for v in sensors),
            "torque": max(v["with_exudyn_jacobian_max_rel_diff"] for v in torques),
        }
        step = "" if m["step_s"] is None else f", {1e3 * m['step_s']:g} ms steps"
        run = f"{m['mode'].replace('_', '-')}, {m['outputs']} outputs{step}"
        wall = json.loads((RESULTS / f"validation_{name}.json").read_text())["meta"]["wall_time_s"]
        lines.append(_row(_twin_row(m["scene"], run, row, same, f"{wall:.0f}")))
    sources = _source("validation_summary", *(f"validation_{name}" for name in TWIN_LINKAGES))
    return "\n".join(lines + ["", sources])


def table_assembly_stress_per_link() -> str:
    """Largest von Mises stress per link, default discretisation (paper's in brackets)."""
    default, paper = _results("bennett_variants_default"), _results("bennett_variants_paper")
    lines = _header("variant", "link 0 (base)", "link 1", "link 2 (coupler)", "link 3")
    for variant in VARIANTS:
        ours = default["variants"][variant]["assembly_von_mises_per_link_MPa"]
        theirs = paper["variants"][variant]["assembly_von_mises_per_link_MPa"] if paper else [None] * 4
        cells = [f"{a:.3f}" + (f" ({b:.3f})" if b is not None else "") for a, b in zip(ours, theirs, strict=True)]
        lines.append(_row([variant, *cells]))
    return "\n".join(lines + ["", _source("bennett_variants_default", "bennett_variants_paper")])


def table_validation_summary() -> str:
    """Ours against Exudyn per variant (``python -m validation summary``)."""
    data = _results("validation_summary")
    lines = _header(
        "variant",
        "coupler deviation ours / Exudyn (mm)",
        "paper (mm)",
        "nodes and coupler: max diff (relative to the elastic deviation)",
        "torque diff (quasi-static / dynamic window)",
        "with Exudyn's Jacobian copied",
        "targets",
    )
    for variant in VARIANTS:
        m = data[variant]["metrics"]
        dev = m["coupler_deviation_from_ideal_m"]
        worst = max(m["trajectories"].values(), key=lambda t: t["max_abs_diff_m"])
        copied = m["modelling_differences"]["with_exudyn_jacobian_vs_exudyn"]
        paper = {"rigid": "< 0.001", "pla": "0.211", "pla1": "1.215", "pla2": "2.305"}[variant]
        lines.append(
            _row(
                [
                    variant,
                    f"{1e3 * dev['inhouse']:.4g} / {1e3 * dev['exudyn']:.4g}",
                    paper,
                    f"{_e(worst['max_abs_diff_m'])} m ({_e(worst['relative_to_elastic_deviation'], 0)})",
                    f"{_e(m['torque']['max_rel_diff'])} / {_e(m['dynamic']['torque']['max_rel_diff'])}",
                    f"{_e(copied['max_abs_diff_m'])} m, {_e(copied['torque_max_rel_diff'])}",
                    "met" if m["passed"] else "missed",
                ]
            )
        )
    return "\n".join(lines + ["", _source("validation_summary")])


def table_validation_refinement() -> str:
    """Each solver against itself at half the step, and ours against Exudyn (``bench_validation_refinement``)."""
    lines = _header(
        "variant, our Jacobian", "step (s)", "ours: h vs h/2 (m)", "Exudyn: h vs h/2 (m)", "ours vs Exudyn (m)"
    )
    names = []
    for name, label in (
        ("validation_refinement_pla", "pla, exact"),
        ("validation_refinement_pla1", "pla1, exact"),
        ("validation_refinement_pla1_exudyn_jacobian", "pla1, Exudyn's"),
    ):
        data = _results(name)
        if data is None:
            continue
        names.append(name)
        for k, row in enumerate(data["rows"].values()):
            own = [_e(row[key], 2) if key in row else "" for key in ("ours_self_m", "exudyn_self_m")]
            lines.append(_row([label if k == 0 else "", f"{row['step']:g}", *own, _e(row["ours_vs_exudyn_m"])]))
    return "\n".join(lines + ["", _source(*names)])


def table_conservation() -> str:
    """Momentum and energy of the free flexible bar over 10^4 steps (``bench/conservation.py``)."""
    lines = _header(
        "integrator",
        "h (s)",
        "linear momentum",
        "angular momentum",
        "energy error",
        "energy drift",
        "Newton/step",
        "time (s)",
        "completed",
    )
    for p in _results("conservation"):
        if "linear_momentum_rel" not in p:  # Exudyn: completion only
            lines.append(
                _row(
                    [
                        p["integrator"],
                        f"{p['step_s']:g}",
                        "",
                        "",
                        "",
                        "",
                        "",
                        f"{p['wall_s']:.1f}",
                        "yes" if p["complete"] else "no",
                    ]
                )
            )
            continue
        lines.append(
            _row(
                [
                    p["integrator"],
                    f"{p['step_s']:g}",
                    _e(p["linear_momentum_rel"]),
                    _e(p["angular_momentum_rel"]),
                    _e(p["energy_error_rel"]),
                    _e(p["energy_drift_rel"]),
                    f"{p['newton_per_step']:.1f}",
                    f"{p['wall_s']:.1f}",
                    "yes" if p["complete"] else "no",
                ]
            )
        )
    return "\n".join(lines + ["", _source("conservation")])


def table_speed_vs_error_quasi_static() -> str:
    """Both solvers on the same quasi-static points (``bench/speed_vs_error.py --qs-points ...``)."""
    points = _results("speed_vs_error_quasi_static")["results"]
    lines = _header(
        "setting",
        "coupler error ours / Exudyn (m)",
        "set-up ours / Exudyn (s)",
        "run ours / Exudyn (s)",
        "run: Exudyn / ours",
        "peak memory ours / Exudyn (MiB)",
    )
    settings = {}
    for p in points:
        settings.setdefault((p["order"], p["h"], p["modes"]), {})[p["solver"]] = p
    for (order, h, modes), pair in settings.items():
        ours, theirs = pair["ffrf"], pair.get("exudyn")
        both = [ours] + ([theirs] if theirs else [])
        lines.append(
            _row(
                [
                    f"P{order}, {1e3 * h:g} mm, {modes} modes",
                    " / ".join(_e(q["coupler_error_m"], 2) for q in both),
                    " / ".join(f"{q['setup_s']:.1f}" for q in both),
                    " / ".join(f"{q['integration_s']:.2f}" for q in both),
                    f"{theirs['integration_s'] / ours['integration_s']:.0f}" if theirs else "",
                    " / ".join(f"{q['peak_mem_mb']:.0f}" for q in both),
                ]
            )
        )
    return "\n".join(lines + ["", _source("speed_vs_error_quasi_static")])


def table_hard_cases() -> str:
    """One row per run of the recorded hard cases (``bench/hard_cases.py --cases ...``)."""
    lines = _header(
        "case",
        "run",
        "mode",
        "converged",
        "steps",
        "Newton it.",
        "worst abs(g)",
        "energy balance",
        "time (s)",
        "vs Exudyn",
        "note",
    )
    for case in _results("hard_cases")["cases"]:
        for r in case["rows"]:
            residual, balance = r["max_constraint_residual"], r["energy_balance_relative"]
            lines.append(
                _row(
                    [
                        r["case"],
                        r["run"],
                        r["mode"],
                        "yes" if r["converged"] else "**no**",
                        r["steps"],
                        r["newton_iterations"],
                        _e(residual) if residual is not None else "-",
                        _e(balance) if balance is not None else "-",
                        f"{r['wall_s']:.1f}",
                        r["exudyn"] or "-",
                        r["error"][:200].replace("|", "/"),
                    ]
                )
            )
    return "\n".join(lines + ["", _source("hard_cases")])


def table_fe_beam_convergence() -> str:
    """Relative frequency errors of P1 and P2 prisms against beam theory (``bench/fe_beam_convergence.py``)."""
    lines = _header("order", "h (mm)", "boundary", "bending thin (z)", "bending wide (y)", "torsion")
    for r in _results("fe_beam_convergence"):
        errors = r["errors_percent"]
        lines.append(
            _row(
                [
                    f"P{r['order']}",
                    f"{1e3 * r['h_m']:g}",
                    r["bc"],
                    *(f"{errors[k]:+.3f}" for k in ("bend_z", "bend_y", "torsion")),
                ]
            )
        )
    return "\n".join(lines + ["", _source("fe_beam_convergence")])


def table_fe_link() -> str:
    """Mesh, assembly and modal-analysis cost of the coupler link (``bench/fe_link.py``)."""
    lines = _header(
        "order",
        "h (mm)",
        "tetrahedra",
        "DOFs",
        "min quality",
        "mesh (s)",
        "assembly (s)",
        "modal (s)",
        "peak RSS (MiB)",
        "first flexible mode (Hz)",
    )
    names = [n for n in ("fe_link_p1", "fe_link_p2") if _results(n) is not None]
    for name in names:
        for r in _results(name):
            lines.append(
                _row(
                    [
                        f"P{r['order']}",
                        f"{1e3 * r['h_m']:g}",
                        r["n_tets"],
                        r["n_dofs"],
                        f"{r['min_quality']:.3f}",
                        f"{r['mesh_s']:.1f}",
                        f"{r['assembly_s']:.1f}",
                        f"{r['modal_s']:.1f}",
                        f"{r['peak_after_modal_MiB']:.0f}",
                        f"{r['first_frequencies_hz'][0]:.1f}",
                    ]
                )
            )
    return "\n".join(lines + ["", _source(*names)])


def _hard_case(name: str) -> list[dict]:
    for case in _results("hard_cases")["cases"]:
        if case["case"] == name:
            return case["rows"]
    raise KeyError(f"hard_cases.json has no case {name!r}")


def _g(x, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def table_hard_cases_near_rigid() -> str:
    """Near-rigid links: conditioning and torque error against the finest step (``--cases near_rigid``)."""
    lines = _header(
        "step (s)",
        "iteration matrix condition",
        "Newton iterations per step (max)",
        "torque error vs the 1e-5 s run (of its peak)",
        "kinetic energy at the end (J)",
    )
    for r in _hard_case("near_rigid"):
        x = r["extra"]
        lines.append(
            _row(
                [
                    r["run"].split("step ")[-1].removesuffix(" s"),
                    _e(x.get("iteration_matrix_cond")) if "iteration_matrix_cond" in x else "-",
                    x.get("max_newton_per_step", "-"),
                    _e(x["torque_error_vs_finest_rel"]) if "torque_error_vs_finest_rel" in x else "(reference)",
                    _g(x.get("kinetic_energy_end_J"), ".4f"),
                ]
            )
        )
    return "\n".join(lines + ["", _source("hard_cases")])


def table_hard_cases_misalignment() -> str:
    """Misalignment sweep: torque, strain and bore rotation per twist (``--cases misalignment``)."""
    lines = _header(
        "alpha_3 (deg)",
        "max abs torque (N mm)",
        "largest equivalent strain (%)",
        "largest bore rotation (rad)",
        "small deformation",
    )
    for r in _hard_case("misalignment"):
        x = r["extra"]
        torque = x.get("max_abs_driving_torque_Nm")
        strain = x.get("max_equivalent_strain")
        lines.append(
            _row(
                [
                    r["run"].split("= ")[1].removesuffix(" deg"),
                    _g(None if torque is None else 1e3 * torque, ".1f"),
                    _g(None if strain is None else 100 * strain, ".2g"),
                    _g(x.get("max_bore_rotation_rad"), ".2g"),
                    "yes" if x.get("small_deformation_valid") else "**no**",
                ]
            )
        )
    return "\n".join(lines + ["", _source("hard_cases")])


def table_hard_cases_soft() -> str:
    """Very soft links: deformation against the small-deformation limits (``--cases soft``)."""
    lines = _header(
        "E (Pa)",
        "largest bore rotation (rad)",
        "largest equivalent strain (%)",
        "coupler deviation (mm)",
        "deviation x E (rel. to PLA)",
        "small deformation",
    )
    for r in _hard_case("soft"):
        x = r["extra"]
        strain, deviation = x.get("max_equivalent_strain"), x.get("max_coupler_deviation_m")
        valid = "yes" if x.get("small_deformation_valid") else "**no**"
        lines.append(
            _row(
                [
                    r["run"].split("= ")[1].removesuffix(" Pa"),
                    _g(x.get("max_bore_rotation_rad"), ".2g"),
                    _g(None if strain is None else 100 * strain, ".2g"),
                    _g(None if deviation is None else 1e3 * deviation, ".3g"),
                    _g(x.get("deviation_times_E_rel"), ".3g"),
                    valid + ("" if r["converged"] else " (fails)"),
                ]
            )
        )
    return "\n".join(lines + ["", _source("hard_cases")])


def table_hard_cases_speed() -> str:
    """Drive speed: dynamic against quasi-static per speed (``--cases speed``)."""
    lines = _header(
        "rpm",
        "vibration ratio",
        "inertia number",
        "auto mode",
        "torque: dynamic - quasi-static (of its peak)",
        "after the ramp",
        "coupler difference (m)",
        "of the elastic deviation",
    )
    for r in _hard_case("speed"):
        x = r["extra"]
        if "torque_diff_to_quasi_static_rel" not in x:
            continue
        lines.append(
            _row(
                [
                    r["run"].split(" rpm")[0],
                    f"{x['quasi_static_ratio']:.0f}",
                    f"{x['inertia_number']:.2g}",
                    x["auto_choice"],
                    f"{_g2(100 * x['torque_diff_to_quasi_static_rel'])} %",
                    f"{_g2(100 * x['torque_diff_after_ramp_rel'])} %",
                    _e(x["coupler_diff_to_quasi_static_m"]),
                    f"{_g2(100 * x['coupler_diff_rel_to_deviation'])} %",
                ]
            )
        )
    return "\n".join(lines + ["", _source("hard_cases")])


def table_hard_cases_long_run() -> str:
    """Ten revolutions at 60 rpm: first and last revolution (``--cases long_run``)."""
    lines = _header(
        "run",
        "worst abs(g) first / last revolution",
        "energy balance error per revolution, first / last",
        "drive work exchanged per revolution (J)",
        "net drive work per revolution (J)",
        "coupler / torque change from one revolution to the next (last three)",
    )
    for r in _hard_case("long_run"):
        x = r["extra"]
        if "constraint_residual_per_rev" not in x:
            continue
        g, e = x["constraint_residual_per_rev"], x["energy_balance_per_rev_rel"]
        lines.append(
            _row(
                [
                    r["run"],
                    f"{_e(g[0])} / {_e(g[-1])}",
                    f"{_e(e[0])} / {_e(e[-1])}",
                    f"{x['drive_work_peak_to_peak_per_rev_J'][-1]:.3g}",
                    _e(x["drive_work_per_rev_J"][-1]),
                    f"{_e(max(x['coupler_change_per_rev_m'][-3:]))} m / "
                    f"{_e(max(x['torque_change_per_rev_Nm'][-3:]))} N m",
                ]
            )
        )
    return "\n".join(lines + ["", _source("hard_cases")])


def table_speed_vs_error_dynamic() -> str:
    """Both solvers on the same points of the dynamic window (``bench/speed_vs_error.py --dyn-points ...``)."""
    points = _results("speed_vs_error_dynamic")["results"]
    lines = _header(
        "setting",
        "coupler error ours / Exudyn (m)",
        "torque error ours / Exudyn",
        "run ours / Exudyn (s)",
        "run: Exudyn / ours",
    )
    settings = {}
    for p in points:
        key = (p["order"], p["h"], p["modes"], p["mode"], p["step"], p["rho_inf"])
        settings.setdefault(key, {})[p["solver"]] = p
    for (order, h, modes, mode, step, rho), pair in settings.items():
        ours, theirs = pair["ffrf"], pair.get("exudyn")
        both = [ours] + ([theirs] if theirs else [])
        how = f"dt {1e3 * step:g} ms, rho_inf {rho:g}" if mode == "dynamic" else "quasi-static"
        lines.append(
            _row(
                [
                    f"P{order}, {1e3 * h:g} mm, {modes} modes, {how}",
                    " / ".join(_e(q["coupler_error_m"], 2) for q in both),
                    " / ".join(_e(q["torque_error_rel"]) for q in both),
                    " / ".join(f"{q['integration_s']:.2f}" for q in both),
                    f"{theirs['integration_s'] / ours['integration_s']:.0f}" if theirs else "",
                ]
            )
        )
    return "\n".join(lines + ["", _source("speed_vs_error_dynamic")])


PREDICTORS = {1: "line", 2: "parabola", 3: "cubic"}


def table_dynamic_step_rule() -> str:
    """A dynamic revolution at each step against 2 ms steps (``bench/dynamic_step_rule.py``)."""
    data = _results("dynamic_step_rule")
    lines = _header(
        "step (ms)",
        "Newton's start",
        "Newton tolerance",
        "coupler error (m)",
        "torque error",
        "iterations per step",
        "factorisations",
        "ms per step",
        "local estimate median / largest (m)",
    )
    for r in data["runs"]:
        lines.append(
            _row(
                [
                    f"{1e3 * r['step_s']:g}",
                    PREDICTORS[r["predictor_polynomial_order"]],
                    f"{r.get('newton_tolerance', 1e-10):.0e}",
                    _e(r["coupler_error_m"]),
                    _e(r["torque_error_rel"]),
                    f"{r['iterations_per_step']:.2f}",
                    r["factorisations"],
                    f"{r['ms_per_step']:.2f}",
                    f"{_e(r['estimate_median_m'])} / {_e(r['estimate_largest_m'])}",
                ]
            )
        )
    return "\n".join(lines + ["", _source("dynamic_step_rule")])


def table_iteration_cost() -> str:
    """A Newton iteration's pieces against the modes per link (``bench/iteration_cost.py``)."""
    rows = _results("iteration_cost")["rows"]
    lines = _header(
        "modes per link",
        "unknowns",
        "residual: bodies + constraints (us)",
        "back-substitution (us)",
        "iteration matrix (ms)",
        "LU (us)",
        "iterations per step",
        "per iteration (us)",
        "per step (ms)",
    )
    for r in rows.values():
        lines.append(
            _row(
                [
                    r["modes_per_link"],
                    r["unknowns"],
                    f"{r['residual_us']:.0f}: {r['body_terms_us']:.0f} + {r['constraint_terms_us']:.0f}",
                    f"{r['back_substitution_us']:.0f}",
                    f"{1e-3 * r['iteration_matrix_us']:.1f}",
                    f"{r['factorisation_us']:.0f}",
                    f"{r['iterations_per_step']:.2f}",
                    f"{r['us_per_iteration']:.0f}",
                    f"{r['ms_per_step']:.2f}",
                ]
            )
        )
    return "\n".join(lines + ["", _source("iteration_cost")])


def table_speed() -> str:
    """The speed table of docs/capabilities.md: ours, Exudyn where it does the same, and the target."""
    revolution, paper = _results("full_revolution"), _results("full_revolution_paper")
    quasi, setup, compiled = _results("bennett_speed"), _results("setup_speed"), _results("compile_times")
    quasi_static_s = quasi["quasi_static"]["fast"]["wall_s"]
    iteration = _results("iteration_cost")["rows"]["4"]
    memory, cold = _results("memory"), _results("end_to_end")
    lines = _header("default scene (P2, 6 mm, 4 modes) unless said", "ours", "Exudyn", "Exudyn / ours", "target")
    for label, run in (
        ("dynamic revolution, 6100 steps of 10 ms", revolution),
        ("the same at the paper's P1 4 mm, 32 modes", paper),
    ):
        lines.append(
            _row(
                [
                    label,
                    f"{run['ffrf']['solve_s']:.1f} s",
                    f"{run['exudyn']['solve_s']:.0f} s",
                    f"{run['ratio_integration']:.0f}x",
                    "3 s" if run is revolution else "10 s, 25x",
                ]
            )
        )
    lines += [
        _row(["quasi-static revolution, 361 poses", f"{quasi_static_s:.2f} s", "", "", "0.25 s"]),
        _row(
            [
                "Newton iteration: residual + back-substitution + Python",
                f"{iteration['us_per_iteration']:.0f} us",
                "",
                "",
                "about 57 us: 3x (arithmetic + back-substitution)",
            ]
        ),
        _row(
            [
                "set-up: first / from the disk cache",
                f"{setup['cold_no_cache_build_s']:.1f} s / {setup['warm_build_s']:.2f} s",
                f"{revolution['exudyn']['setup_s']:.1f} s (its reduction on our matrices)",
                "",
                "3 s",
            ]
        ),
        *(
            _row(
                [
                    f"{label} revolution from a cold start, set-up counted",
                    f"{cold[key]['ours']['total_s']:.1f} s",
                    f"{cold[key]['exudyn']['total_s']:.0f} s",
                    f"{cold[key]['ratio_total']:.1f}x",
                    target,
                ]
            )
            for label, key, target in (("quasi-static", "quasi_static", "8x"), ("dynamic", "dynamic", "25x"))
        ),
        _row(["first run: compiling (`python -m ffrf warmup`)", f"{compiled['command_s']:.0f} s", "", "", "60 s"]),
        _row(["peak memory of the main job", f"{memory['main_job']['peak_rss_mb']:.0f} MiB", "", "", ""]),
    ]
    names = ("full_revolution", "full_revolution_paper", "bennett_speed", "iteration_cost", "setup_speed")
    names += ("end_to_end", "compile_times", "memory")
    return "\n".join(lines + ["", "Source: " + ", ".join(f"[`{n}.json`](results/{n}.json)" for n in names)])


TABLES = {name[len("table_") :]: function for name, function in list(globals().items()) if name.startswith("table_")}
