"""The front door: :func:`load` a model from what describes it, :meth:`Model.run` it, :meth:`Result.save` the run.

::

    import ffrf

    model = ffrf.load("linkage.toml")  # a scene or linkage file
    result = model.run()  # quasi-static or dynamic, as the scene says; the run checks itself
    result.save("out")  # results, metadata, assembly stresses, figures

``source`` is a scene file or a linkage file (TOML, told apart by its ``[linkage]`` table,
:mod:`ffrf.scenes.scene_file`), the same as a mapping (a parsed file), a single loop of :mod:`kinematics` (built with
:class:`~ffrf.scenes.linkage_description.LinkageOptions`), or a scene already built (:mod:`ffrf.scenes.builder`,
:mod:`ffrf.scenes.linkage_scene`). A linkage runs through :func:`ffrf.scenes.linkage_run.run_linkage` (assembly, the
drive's ramp and revolution, the coupler's sensors), any other scene through :func:`ffrf.scenes.scene_file.run_scene`;
both return the one :class:`~ffrf.output.result.Result`, which ``python -m ffrf`` saves too.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from threadpoolctl import threadpool_limits

from ffrf.errors import SceneError
from ffrf.output.result import Result
from ffrf.scenes.builder import Scene, build_scene
from ffrf.scenes.linkage_description import LinkageOptions
from ffrf.scenes.linkage_file import load_linkage
from ffrf.scenes.linkage_run import choose_mode, run_linkage
from ffrf.scenes.linkage_scene import LinkageScene, build_linkage
from ffrf.scenes.scene_file import load_scene, run_scene
from ffrf.solvers.stability import check_judged_at_equilibria
from kinematics.single_loop import SingleLoop

__all__ = ["Model", "load"]

#: The run settings a scene may hold and :meth:`Model.run` may override, by keyword.
RUN_SETTINGS = ("mode", "outputs", "step", "t_end", "rho_inf", "stability")


def load(
    source: str | Path | Mapping[str, Any] | SingleLoop | Scene,
    options: LinkageOptions | None = None,
    base: str | Path | None = None,
) -> Model:
    """The model ``source`` describes (module docstring). ``options``: how a :class:`~kinematics.single_loop.SingleLoop`
    is built into a linkage (default :class:`~ffrf.scenes.linkage_description.LinkageOptions`); ``base``: the folder
    a mapping's mesh files are relative to (default the working directory). Bad input is a
    :class:`ffrf.errors.FEInputError` naming what and where."""
    if options is not None and not isinstance(source, SingleLoop):
        raise SceneError("options build a kinematics SingleLoop into a linkage; this source describes its own")
    if isinstance(source, Scene):
        return Model(source)
    if isinstance(source, SingleLoop):
        return Model(build_linkage(source, options))
    if isinstance(source, Mapping):
        document, folder = dict(source), Path.cwd() if base is None else Path(base)
        return Model(load_linkage(document, folder) if "linkage" in document else build_scene(document, folder))
    if isinstance(source, str | Path):
        return Model(load_scene(source))
    raise SceneError(
        f"cannot load a {type(source).__name__}: give a scene or linkage file (path), its parsed mapping, "
        "a kinematics SingleLoop or a built scene"
    )


@dataclass(frozen=True)
class Model:
    """A built scene, ready to run: a linkage (:class:`~ffrf.scenes.linkage_scene.LinkageScene`) or any scene of
    bodies and joints (:class:`~ffrf.scenes.builder.Scene`)."""

    scene: Scene

    @property
    def name(self) -> str:
        return self.scene.name

    @property
    def kind(self) -> str:
        """``"linkage"`` or ``"scene"`` (:data:`ffrf.output.result.RESULT_KINDS`)."""
        return "linkage" if isinstance(self.scene, LinkageScene) else "scene"

    def settings(self, **overrides: Any) -> dict[str, Any]:
        """The run settings (:data:`RUN_SETTINGS`) the scene holds, with ``overrides`` that are not ``None``; a
        linkage's defaults: ``mode="auto"`` (:func:`ffrf.scenes.linkage_run.choose_mode`), 241 outputs, the drive's
        step rule, ``rho_inf = 0.9``, the whole ramp and revolution(s)."""
        unknown = set(overrides) - set(RUN_SETTINGS)
        if unknown:
            raise TypeError(f"unknown run settings {sorted(unknown)}: use {list(RUN_SETTINGS)}")
        if self.kind == "linkage":
            own = {"mode": "auto", "outputs": 241, "step": None, "t_end": None, "rho_inf": 0.9, "stability": False}
            own |= {
                key: self.scene.settings[key] for key in RUN_SETTINGS if key in self.scene.settings and key != "t_end"
            }
        else:
            own = {key: self.scene.settings[key] for key in RUN_SETTINGS if key in self.scene.settings}
        return own | {key: value for key, value in overrides.items() if value is not None}

    def choose_mode(self, mode: str | None = None, stability: bool | None = None) -> tuple[str, float]:
        """The mode a run takes, and for a linkage left to ``auto`` the vibration ratio it was chosen by (else NaN):
        with ``stability`` always quasi-static (:func:`ffrf.solvers.stability.check_judged_at_equilibria` refuses
        ``dynamic``); a linkage's ``auto`` by :func:`ffrf.scenes.linkage_run.choose_mode`; a scene's its own
        setting (default ``dynamic``)."""
        s = self.settings(mode=mode, stability=stability)
        requested, judged = s.get("mode", "dynamic"), s.get("stability", False)
        check_judged_at_equilibria(requested, judged, "run quasi-statically (mode='quasi_static')")
        chosen, ratio = requested, float("nan")
        if requested == "auto" and isinstance(self.scene, LinkageScene):
            chosen, ratio = choose_mode(self.scene)
        return ("quasi_static" if judged else chosen), ratio

    def run(
        self,
        mode: str | None = None,
        *,
        outputs: int | None = None,
        step: float | None = None,
        t_end: float | None = None,
        rho_inf: float | None = None,
        stability: bool | None = None,
        progress: Callable[[float, float], None] | None = None,
        sensors: str = "all",
        error_tolerance: float | None = None,
        blas_threads: int | None = 1,
        step_parts: list[list[int]] | None = None,
    ) -> Result:
        """Run the model; what is not given comes from the scene (:meth:`settings`). ``mode``: ``auto`` (linkages),
        ``quasi_static`` or ``dynamic``; ``outputs``: output rows; ``step``: the dynamic time step (s); ``t_end``
        (s); ``rho_inf``: generalized-alpha's spectral radius at infinity; ``stability``: Eq. (B1) at every
        equilibrium of a quasi-static run, which then goes on past folds; ``progress(t, t_end)``: called as the run
        goes, may raise :class:`ffrf.errors.Interrupted` to stop it; ``sensors`` (linkages): ``"all"`` or
        ``"path"`` (:data:`ffrf.scenes.linkage_run.SENSOR_SETS`); ``error_tolerance`` (linkages, m): the dynamic
        step's local error bound (Eq. (G8)); ``blas_threads``: the BLAS library's threads during the run (default 1,
        as ``python -m ffrf`` and a study's workers run: our dense matrices are small, and under some OpenBLAS
        kernels, Haswell's among them, a dense solve's last digits depend on the thread count; ``None`` keeps the
        process's setting); ``step_parts`` (dynamic linkages): another run's parts per step (its metadata's
        ``step_parts``), taken again instead of the step rules' (:func:`ffrf.scenes.linkage_run.run_linkage`).

        A run checks itself (the metadata's ``verification``). A run that stops raises the solver's error
        (:class:`ffrf.errors.StaticDivergence`, :class:`ffrf.errors.NewtonDivergence`,
        :class:`ffrf.errors.Interrupted`) with ``partial``, the :class:`Result` up to its last output, when there is
        one."""
        if blas_threads is not None:
            with threadpool_limits(limits=blas_threads, user_api="blas"):
                return self.run(
                    mode,
                    outputs=outputs,
                    step=step,
                    t_end=t_end,
                    rho_inf=rho_inf,
                    stability=stability,
                    progress=progress,
                    sensors=sensors,
                    error_tolerance=error_tolerance,
                    blas_threads=None,
                    step_parts=step_parts,
                )
        chosen, _ = self.choose_mode(mode, stability)  # refuses stability with a dynamic run
        s = self.settings(outputs=outputs, step=step, t_end=t_end, rho_inf=rho_inf, stability=stability)
        if isinstance(self.scene, LinkageScene):
            return run_linkage(
                self.scene,
                chosen,
                s["outputs"],
                s["step"],
                s["rho_inf"],
                progress,
                s["t_end"],
                s["stability"],
                sensors,
                error_tolerance,
                step_parts,
            )
        if sensors != "all" or error_tolerance is not None or step_parts is not None:
            raise SceneError(
                f"sensors={sensors!r}, error_tolerance and step_parts are of linkages; {self.name!r} is a scene"
            )
        given = {"mode": None if mode is None else chosen, "outputs": outputs, "step": step, "t_end": t_end}
        given |= {"rho_inf": rho_inf, "stability": stability}
        overrides = {key: value for key, value in given.items() if value is not None}
        # the scene's own settings object when nothing is overridden: its metadata then say what the file said
        scene = replace(self.scene, settings={**self.scene.settings, **overrides}) if overrides else self.scene
        return run_scene(scene, progress)
