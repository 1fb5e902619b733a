"""The one result of a run (:func:`ffrf.load` ``(...).run()``): output times, sensors, coordinates, metadata, the
assembled state and, with stability, the critical pose; every run path returns it (a linkage's, a scene file's,
quasi-static or dynamic, and a study's row reads it).

:meth:`Result.save` writes what ``python -m ffrf run | bennett | linkage`` write: ``results.npz``, ``results.csv``,
``metadata.json`` and ``manifest.json`` (:func:`ffrf.output.tables.write_results`, read back by
:func:`~ffrf.output.tables.read_results`), the clearance of a linkage's links in the metadata, ``assembly.vtu``,
with stability ``stability.json`` and ``stability_critical.vtu``, for a linkage the figures over the drive angle,
and on request a ParaView series. The verification (:mod:`ffrf.output.verification`) is done by the run and
written in the metadata.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from ffrf.output.assembly_stress import AssemblyStress, scene_assembly_stress, write_assembly_vtu
from ffrf.output.energy_balance import energy_scale, relative_balance
from ffrf.output.paraview import write_time_series
from ffrf.output.tables import write_results
from ffrf.output.verification import Verification, clearance_check
from ffrf.solvers.stability import CriticalPose

__all__ = ["Result", "RESULT_KINDS"]

#: What ran: a single-loop linkage (coupler and drive sensors, figures over the drive angle) or any scene.
RESULT_KINDS = ("linkage", "scene")

#: The note of a linkage whose file says ``check_clearance = false``.
CLEARANCE_NOT_CHECKED = "clearance not checked: the linkage file says check_clearance = false"


@dataclass
class Result:
    """Output times, sensors (name -> array, rows = times), the coordinates ``q`` (rows = times), metadata, the
    stress state of the static assembly the run started from (``None`` for a scene that starts from its poses), the
    critical pose of a run with stability (the fold, or the least stable output), the run's checks of itself, the
    velocities (dynamic runs) and multipliers at the outputs, and the scene that ran (not saved)."""

    time: NDArray[np.float64]
    sensors: dict[str, NDArray[np.float64]]
    q: NDArray[np.float64]
    metadata: dict = field(default_factory=dict)
    assembly: AssemblyStress | None = None
    critical: CriticalPose | None = None
    verification: Verification | None = None
    qd: NDArray[np.float64] | None = None
    multipliers: NDArray[np.float64] | None = None
    kind: Literal["linkage", "scene"] = "linkage"
    scene: Any = field(default=None, repr=False, compare=False)

    def summary(self) -> dict[str, float]:
        """The largest values a reader looks at first, of the sensors the run evaluated: for a linkage the coupler's
        deviation (same drive angle), its distance to the ideal path and ``|driving torque|``; the constraint
        residual; and the energy balance's largest residual relative to the energy scale of Eq. (C2)
        (:func:`ffrf.output.energy_balance.energy_scale`, with the metadata's ``energy_floor_j``), never the 0/0 of
        a residual relative to a drive that does no work."""
        s = self.sensors
        out: dict[str, float] = {}
        if "coupler_deviation" in s:
            out["max_coupler_deviation_m"] = float(np.max(np.linalg.norm(s["coupler_deviation"], axis=1)))
            out["max_coupler_distance_to_path_m"] = float(np.max(s["coupler_distance_to_path"]))
            out["max_abs_driving_torque_Nm"] = float(np.max(np.abs(s["driving_torque"])))
        if "constraint_residual" in s:
            out["max_constraint_residual"] = float(np.max(s["constraint_residual"]))
        if "energy_balance_residual" in s:
            scale = energy_scale(s, float(self.metadata.get("energy_floor_j", 0.0)))
            out["energy_balance_relative"] = relative_balance(s["energy_balance_residual"], scale)
        return out

    def save(
        self,
        directory: str | Path,
        *,
        vtk_every: int = 0,
        label: str | None = None,
        colors: Mapping[str, str] | None = None,
        views: bool = True,
    ) -> Path:
        """Write everything of the module docstring into ``directory`` (created): for a linkage first its links'
        clearance along the rigid motion into the metadata (:meth:`add_clearance`), then :meth:`write_tables` and,
        with ``views``, :meth:`write_views`. Returns ``directory``."""
        if self.kind == "linkage":
            self.add_clearance()
        directory = self.write_tables(directory)
        if views:
            self.write_views(directory, vtk_every=vtk_every, label=label, colors=colors)
        return directory

    def add_clearance(self, margin: float | None = None) -> dict | None:
        """The signed clearance of a linkage's links along its rigid nominal motion against ``margin`` (m; default
        the scene's ``clearance_margin``, else 1 mm) (:meth:`ffrf.scenes.linkage_scene.LinkageScene.clearance`,
        ``docs/formulation.md`` Eqs. (CL1)-(CL4)) in the metadata, ``clearance``: its summary, per pair the smallest
        signed clearance (m, negative: overlap), the drive angle there and the clearance proven between the poses,
        the margin and whether every pair keeps it; and judged in the run's verification (its ``clearance`` check,
        :func:`ffrf.output.verification.clearance_check`), unless the scene says ``check_clearance = false`` (then a
        note says so and nothing is computed). Computed once; returns that entry (``None`` when not checked)."""
        settings = self.scene.settings
        if not settings.get("check_clearance", True):
            if self.verification is not None and CLEARANCE_NOT_CHECKED not in self.verification.notes:
                self._verified(self.verification.with_note(CLEARANCE_NOT_CHECKED))
            return None
        if "clearance" not in self.metadata:
            margin = settings.get("clearance_margin", 1e-3) if margin is None else margin
            clearance = self.scene.clearance(margin=margin)
            self.metadata["clearance"] = {
                "summary": clearance.summary(),
                "pairs": [
                    {
                        "links": [int(a), int(b)],
                        "clearance_m": float(gap),
                        "drive_angle_rad": float(angle),
                        "between_poses_m": float(bound),
                        "margin_met": bool(met),
                    }
                    for (a, b), gap, angle, bound, met in zip(
                        clearance.pairs,
                        clearance.distance,
                        clearance.drive_angle,
                        clearance.bound,
                        clearance.met,
                        strict=True,
                    )
                ],
                "margin_m": clearance.margin,
                "margin_met": clearance.margin_met,
            }
            if self.verification is not None:
                self._verified(self.verification.with_check(clearance_check(self.metadata["clearance"])))
        return self.metadata["clearance"]

    def _verified(self, verification: Verification) -> None:
        self.verification = verification
        self.metadata["verification"] = verification.as_dict()

    def write_tables(self, directory: str | Path) -> Path:
        """``results.npz`` (time, sensors, ``q``), ``results.csv``, ``metadata.json`` and ``manifest.json``; for a
        scene first what the manifest also lists: ``assembly.vtu`` and, with stability, ``stability.json`` and
        ``stability_critical.vtu``."""
        directory = Path(directory)
        if self.kind == "scene":
            self._write_assembly(directory)
            self._write_stability(directory)
        return write_results(directory, {"time": self.time, **self.sensors}, self.metadata, coordinates=self.q)

    def write_views(
        self,
        directory: str | Path,
        *,
        vtk_every: int = 0,
        label: str | None = None,
        colors: Mapping[str, str] | None = None,
    ) -> list[Path]:
        """What is drawn from the results, after them: every ``vtk_every``-th output's deformed bodies for ParaView
        (``linkage.pvd`` of a linkage, ``scene.pvd`` of a scene; 0: none); for a linkage ``assembly.vtu``, the
        figures ``coupler_deviation.png`` and ``driving_torque.png`` (one curve, ``label``, default the scene's
        name, in ``colors[label]`` if given) and, with stability, ``stability.json``, ``stability.png`` and
        ``stability_critical.vtu``. Returns the files written."""
        directory = Path(directory)
        written: list[Path] = []
        if vtk_every > 0:
            bodies = self.scene.bodies
            written.append(
                write_time_series(
                    directory,
                    [(body.mesh_model, body.reduction.basis) for body in bodies],
                    [self.scene.system.block(k) for k in range(len(bodies))],
                    self.time,
                    self.q,
                    every=vtk_every,
                    name=self.kind,
                )
            )
        if self.kind != "linkage":
            return written
        # matplotlib takes a second to import: only where a figure is drawn
        from ffrf.output.linkage_figures import plot_coupler_deviation, plot_driving_torque

        written += self._write_assembly(directory)
        runs = {self.scene.name if label is None else label: self}
        for name, plot in (("coupler_deviation", plot_coupler_deviation), ("driving_torque", plot_driving_torque)):
            plot(runs, directory / f"{name}.png", colors=colors)
            written.append(directory / f"{name}.png")
        return written + self._write_stability(directory)

    def _write_assembly(self, directory: Path) -> list[Path]:
        """``assembly.vtu``: the assembled state with its stresses (none for a scene that starts from its poses)."""
        if self.assembly is None:
            return []
        directory.mkdir(parents=True, exist_ok=True)
        path = write_assembly_vtu(directory / "assembly.vtu", self.scene, self.assembly)
        return [] if path is None else [path]

    def _write_stability(self, directory: Path) -> list[Path]:
        """``stability.json`` (per output: time, for a linkage the drive angle, the squared frequencies of Eq. (B1)),
        for a linkage ``stability.png``, and ``stability_critical.vtu`` (the critical pose with its mode)."""
        if "stability" not in self.metadata:
            return []
        directory.mkdir(parents=True, exist_ok=True)
        values = self.sensors["stability_squared_frequencies"]
        table: dict[str, Any] = {"summary": self.metadata["stability"], "time_s": self.time.tolist()}
        if self.kind == "linkage":
            table["drive_angle_rad"] = self.sensors["drive_angle"].tolist()
        table["squared_frequencies_rad2_per_s2"] = values.tolist()
        written = [directory / "stability.json"]
        written[0].write_text(json.dumps(table, indent=1))
        if self.kind == "linkage":
            from ffrf.output.linkage_figures import plot_stability  # matplotlib: only where a figure is drawn

            folds = [snap["drive_angle_deg"] for snap in self.metadata["stability"].get("snaps", [])]
            angle, torque = self.sensors["drive_angle"], self.sensors["driving_torque"]
            plot_stability(angle, values, torque, directory / "stability.png", folds)
            written.append(directory / "stability.png")
        if self.critical is not None:
            critical = self.critical
            stress = scene_assembly_stress(self.scene, critical.q, critical.multipliers)
            where = write_assembly_vtu(
                directory / "stability_critical.vtu", self.scene, stress, {"critical_mode": critical.mode}
            )
            written += [] if where is None else [where]
        return written
