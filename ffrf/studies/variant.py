r"""One variant of a study: its linkage options, its scene and its row of results (a pure function of the study
and the parameter values, so that any worker computes the same row).

The row holds the parameters, ``status`` (``"ok"`` or ``"failed"``), ``end`` (how its run ended, :func:`print_end`),
``reason`` (the error message of a failed variant), ``assembles`` (whether the static assembly found an equilibrium;
empty when the variant failed before), the outputs (SI, NaN where not computed; :func:`row_outputs` reads them from
the variant's :class:`~ffrf.output.result.Result`): ``max_coupler_deviation_m`` (same drive angle) and
``max_coupler_distance_to_path_m`` (closest point of the ideal curve), ``max_abs_driving_torque_Nm``,
``assembly_strain_energy_J`` (all links, assembled state) and ``max_assembly_stress_link{k}_Pa`` (von Mises,
:mod:`ffrf.output.assembly_stress`), the drive angles of the largest deviation and torque and of the path's end or
stop (:data:`~ffrf.studies.outputs.WHERE`), and ``wall_time_s`` (building and running the variant) and ``worker``.

**Cheap bore errors.** With ``bore_error_model = "misfit"`` (a study's default) a bore error is modelled on the
nominal meshes: the link keeps its nominal mesh and bore interface, and only that link's side of the joint takes
the erroneous axis and point, a joint-frame misfit that the static assembly closes elastically
(:class:`ffrf.scenes.linkage_description.LinkageOptions`). The rule: the bore's material is where the nominal
bore is, so the model is a small-error approximation of the remeshed part (``"remesh"``), good while the bore's
shift and the twist times the housing length are small against the housing's wall and the element size
(``docs/studies.md`` gives its error against remeshing). With the misfit model, variants that differ only in bore
errors have the same meshes, FE matrices, reductions and rigid start, which the worker's
:class:`~ffrf.scenes.scene_cache.SceneCache` keeps by content: such a variant pays only for its assembly and path.
"""

from __future__ import annotations

import logging
import math
import os
import socket
import time
from dataclasses import replace
from typing import Any

import numpy as np

from ffrf.errors import AssemblyDivergence, FEInputError, NewtonDivergence, StaticDivergence
from ffrf.output.result import Result
from ffrf.scenes.linkage_description import BoreError, LinkageOptions, with_radial_play
from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import LinkageScene, build_linkage
from ffrf.scenes.scene_cache import SceneCache
from ffrf.solvers.snap_through import NO_LANDING_WORDS
from ffrf.studies.outputs import OUTPUTS, WHERE, output_names
from ffrf.studies.sampling import Variant
from ffrf.studies.spec import NamedBases, Study
from ffrf.system.drives import rpm

__all__ = [
    "OUTPUTS",
    "output_names",
    "row_names",
    "print_end",
    "row_outputs",
    "variant_options",
    "build_variant",
    "run_variant",
]

log = logging.getLogger(__name__)


def row_names(study: Study) -> tuple[str, ...]:
    """Every column of a study's rows, in order."""
    head = ("id", "block", "sample", "status", "end", "reason", "assembles")
    outputs = output_names(study.n_links, study.stability)
    return head + study.parameter_names + outputs + WHERE + ("wall_time_s", "worker")


def _named(study: Study) -> NamedBases:
    """The named bases a study without a linkage file chose its base from."""
    if study.base.bases is None:
        raise ValueError(f"study {study.name!r} has neither a linkage file nor named bases to build its base from")
    return study.base.bases


def _base_options(study: Study) -> tuple[Any, LinkageOptions, dict]:
    """The base's loop (``None`` for a named base), its options and run settings, with the overrides."""
    base = study.base
    if base.document is not None:
        loop, options, run = linkage_options(base.document, str(base.linkage))
    else:
        loop, options, run = None, _named(study).options(str(base.named)), {}
    o = base.overrides
    options = replace(
        options,
        h=float(o.get("h", options.h)),
        order=int(o.get("order", options.order)),
        n_modes=int(o.get("modes", options.n_modes)),
        revolutions=float(o.get("revolutions", options.revolutions)),
        omega=rpm(float(o["rpm"])) if "rpm" in o else options.omega,
        bore_error_model=base.bore_error_model,
    )
    run = {"mode": o.get("mode", run.get("mode", "auto")), "outputs": int(o.get("outputs", run.get("outputs", 241)))}
    return loop, options, run


#: A bore target's field of :class:`BoreError` and its factor from the parameter's unit to SI.
BORE_FIELDS = {
    "bore_twist_deg": ("twist", math.radians(1.0)),
    "bore_offset_mm": ("offset", 1e-3),
    "bore_axial_mm": ("axial", 1e-3),
    "bore_tilt_deg": ("tilt", math.radians(1.0)),
    "bore_shift_mm": ("shift", 1e-3),
}
#: A section target's field of :class:`LinkDesign` (m from mm).
DESIGN_FIELDS = {"arm_width_mm": "arm_width", "arm_thickness_mm": "arm_thickness"}


def _with_bore_errors(
    errors: tuple[BoreError, ...], added: dict[tuple[int, int], dict[str, float]]
) -> tuple[BoreError, ...]:
    """The base's bore errors with the study's (SI, by bore and :class:`BoreError` field) added, bore by bore."""
    by_bore = {(e.joint, e.link): e for e in errors}
    for bore in sorted(added):
        old = by_bore.get(bore, BoreError(*bore))
        by_bore[bore] = replace(old, **{name: getattr(old, name) + x for name, x in added[bore].items()})
    return tuple(by_bore.values())


def variant_options(study: Study, values: dict[str, float]) -> tuple[Any, LinkageOptions, dict]:
    """The loop (``None``: a named base), the linkage options and run settings of one variant."""
    loop, options, run = _base_options(study)
    material, design, changes = options.material, options.design, dict[str, Any]()
    added: dict[tuple[int, int], dict[str, float]] = {}
    play: float | None = None
    for p in study.parameters:
        x = values[p.name]
        if p.target in BORE_FIELDS:
            name, factor = BORE_FIELDS[p.target]
            bore = added.setdefault((int(p.joint or 0), int(p.link or 0)), {})
            bore[name] = bore.get(name, 0.0) + factor * x
        elif p.target in DESIGN_FIELDS:
            design = replace(design, **{DESIGN_FIELDS[p.target]: 1e-3 * x})
        elif p.target == "E":
            material = replace(material, E=x)
        elif p.target == "rho":
            material = replace(material, rho=x)
        elif p.target == "rpm":
            changes["omega"] = rpm(x)
        elif p.target == "h":
            changes["h"] = x
        elif p.target == "modes":
            changes["n_modes"] = int(round(x))
        elif p.target == "radial_clearance_mm":
            play = x
    errors = _with_bore_errors(tuple(options.bore_errors), added)
    varied = replace(options, material=material, design=design, bore_errors=errors, **changes)
    return loop, varied if play is None else with_radial_play(varied, play), run  # pins as long as varied housings


def build_variant(study: Study, values: dict[str, float], cache: SceneCache | None = None) -> tuple[LinkageScene, dict]:
    """The scene of one variant and its run settings; ``cache``: what earlier builds computed, by content (default
    the process's :data:`~ffrf.scenes.scene_cache.PROCESS_CACHE`, which a Dask worker keeps between variants)."""
    loop, options, run = variant_options(study, values)
    if loop is None:
        return _named(study).build(options, str(study.base.named), cache), run
    return build_linkage(loop, options, where=f"{study.name}, variant", cache=cache), run


def row_outputs(result: Result | None, n_links: int, path: bool, stability: bool = False) -> dict[str, float]:
    """The output columns of a row (:func:`output_names`), the one place they are read from the variant's run,
    its :class:`~ffrf.output.result.Result`: the path's maxima from :meth:`~ffrf.output.result.Result.summary` (with
    ``path``, a path run to its end), the assembly's from ``result.assembly``, the stability's from its metadata.
    NaN where not computed: no result, or a path that stopped; the snaps of a path that stopped count those before
    the stop. A row holds scalars only, so that a study's rows are one table."""
    out = dict.fromkeys(output_names(n_links, stability) + WHERE, math.nan)
    if result is None:
        return out
    angle = result.sensors.get("drive_angle")
    if angle is not None and len(angle):
        degrees = np.degrees(np.asarray(angle, dtype=float))
        out["last_drive_angle_deg"] = float(degrees[-1])
        if path:
            deviation = np.linalg.norm(result.sensors["coupler_deviation"], axis=1)
            out["max_coupler_deviation_at_deg"] = float(degrees[np.argmax(deviation)])
            out["max_abs_driving_torque_at_deg"] = float(degrees[np.argmax(np.abs(result.sensors["driving_torque"]))])
    monitored = result.metadata.get("stability")
    if stability and monitored:
        snaps = monitored.get("snaps", [])
        out["snaps"] = float(len(snaps))
        out["snap_energy_released_J"] = float(sum(snap.get("energy_released_J") or 0.0 for snap in snaps))
        lowest = monitored.get("min_frequency_hz")
        out["min_frequency_hz"] = math.nan if lowest is None else float(lowest)
    if result.assembly is not None:
        out["assembly_strain_energy_J"] = float(sum(link.strain_energy_j for link in result.assembly.links))
        for link in result.assembly.links:
            out[f"max_assembly_stress_link{link.link}_Pa"] = float(link.max_von_mises_pa)
    if path:
        summary = result.summary()
        for name in OUTPUTS[:3]:
            out[name] = summary[name]
    return out


def print_end(row: dict) -> str:
    """How the row's run ended, one of :data:`~ffrf.studies.outputs.ENDS`, from its status, reason and snaps."""
    reason = str(row.get("reason", ""))
    if row["status"] == "ok":
        snaps = row.get("snaps", math.nan)
        end = "completed through snaps" if snaps == snaps and snaps > 0 else "completed"
    elif reason.startswith("no assembly"):
        end = "no assembly"
    elif reason.startswith("the run stopped") and "near-dead point" in reason:
        end = "stopped at a near-dead pose"
    elif reason.startswith("the run stopped") and NO_LANDING_WORDS in reason:
        end = "stopped at a fold without landing"
    elif reason.startswith("the run stopped"):
        end = "stopped (unclassified)"
    else:
        end = "bad input" if reason.startswith("bad input") else "error"
    return end


def run_variant(study: Study, variant: Variant, cache: SceneCache | None = None) -> dict:
    """Build and run one variant; its row (module docstring). A variant that fails is a row with its reason, never
    an exception (bad input from the parameters, no assembly, a diverging path, or any other error)."""
    started = time.perf_counter()
    row: dict[str, Any] = {"id": variant.id, "block": variant.block, "sample": variant.sample}
    row |= {"status": "failed", "reason": "", "assembles": None} | dict(variant.values)
    result, path = None, False
    try:
        scene, run = build_variant(study, variant.values, cache)
        stability = study.stability
        mode = "quasi_static" if stability else run["mode"]
        result = run_linkage(scene, mode=mode, n_outputs=run["outputs"], sensors="path", stability=stability)
        row |= {"status": "ok", "assembles": True}
        path = True
    except AssemblyDivergence as error:
        row |= {"reason": f"no assembly: {error}", "assembles": False}
    except (StaticDivergence, NewtonDivergence) as error:
        result = error.partial  # the run up to where its path stopped, with the assembled state
        row |= {"reason": f"the run stopped: {error}", "assembles": True}
    except FEInputError as error:
        row["reason"] = f"bad input: {error}"
    except Exception as error:  # noqa: BLE001 -- one variant's failure is its row, never the study's end
        log.exception("variant %s failed", variant.id)
        row["reason"] = f"{type(error).__name__}: {error}"
    row |= row_outputs(result, study.n_links, path, study.stability)
    row["end"] = print_end(row)
    row["wall_time_s"] = time.perf_counter() - started
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    return row
