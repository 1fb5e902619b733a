"""Every benchmark, the result files of the docs it records, and the code each one measures.

A :class:`Benchmark` is a module of ``bench/`` run as ``python -m bench NAME [ARGS]``, or one of the library's own
command lines (``python -m ffrf ...``, ``python -m validation ...``, ``python -m kinematics ...``) whose output the docs
quote. Each :class:`Recording` is one result file ``docs/results/RESULT.json``: the arguments that measure it and how
the command's JSON becomes the file's ``results`` (``python -m bench record RESULT``, :mod:`bench.record`). A result
file is stale when a path its benchmark ``measures`` changed after the commit it was recorded at
(``python -m bench stale``, :mod:`bench.staleness`).

In ``args``, ``{out}`` is a fresh temporary folder of the recording; ``outputs`` are the JSON files the command writes
there.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BENCHMARKS", "Benchmark", "Recording", "benchmark", "recording", "recordings"]

#: The engine: any change to it can change a measured figure. ``ffrf`` imports ``kinematics``.
ENGINE = ("ffrf", "kinematics")
#: The engine and the Exudyn twins and validation reports.
WITH_VALIDATION = (*ENGINE, "validation", "identification")
#: The arguments of a command that writes its JSON to the file ``--json`` names.
JSON = ("--json", "{out}/report.json")
#: The built-in linkages beyond the paper's Bennett (whose four variants ``validation summary`` compares): each one's
#: linkage file in ``examples/`` and its recorded twin report, ``validation_<name>.json`` (issue #39).
TWIN_LINKAGES = ("goldberg_5r", "bennett_ark24", "collisions_free_6r", "plane_fold_6r", "interp_4poses_6r")


@dataclass(frozen=True)
class Recording:
    """One result file of the docs and how a benchmark's run makes it.

    Attributes
    ----------
    result : the file's stem: ``docs/results/{result}.json``.
    args : the command's arguments; ``{out}`` stands for the recording's temporary folder.
    outputs : the JSON files the command writes into ``{out}``; one: its content is the ``results``, several:
        ``{file stem: content}``.
    select : keep only these top-level keys of the results (all when empty).
    rows_by : key every list of dicts named ``rows`` by this field of its dicts, renamed ``rows_name``, so that a
        figure's JSON pointer names the row (``/variants/pla/...`` instead of ``/rows/1/...``).
    env : environment variables the command runs with (``NAME=value``), beyond the runner's own.
    recipe_missing : why the file cannot be recorded again by the runner (then ``args`` are what was run).
    """

    result: str
    args: tuple[str, ...] = JSON
    outputs: tuple[str, ...] = ("report.json",)
    select: tuple[str, ...] = ()
    rows_by: str | None = None
    rows_name: str = "rows"
    env: tuple[str, ...] = ()
    recipe_missing: str | None = None


@dataclass(frozen=True)
class Benchmark:
    """A measuring command, the result files it records and the code it measures.

    Attributes
    ----------
    name : ``python -m bench NAME``; for a module of ``bench/`` its module name there.
    summary : one line: what it measures.
    measures : repository paths (packages, modules) whose change makes its results stale; a module of ``bench/`` is
        added itself (:meth:`sources`).
    records : the result files it writes.
    module : the module run with ``python -m`` (``bench.{name}`` when empty), or the path of a script that writes its
        result files itself.
    helpers : other modules of ``bench/`` whose code takes part in the measurement.
    """

    name: str
    summary: str
    measures: tuple[str, ...] = ENGINE
    records: tuple[Recording, ...] = ()
    module: str = ""
    helpers: tuple[str, ...] = ()

    @property
    def runnable(self) -> str:
        """The module ``python -m`` runs."""
        return self.module or f"bench.{self.name}"

    @property
    def command(self) -> str:
        """How it is run, as typed at the repository's root."""
        if self.in_bench:
            return f"python -m bench {self.name}"
        return self.module if "/" in self.module else f"python -m {self.module}"

    @property
    def in_bench(self) -> bool:
        """Whether it is a module of ``bench/`` (else a command line of the library)."""
        return not self.module

    def sources(self) -> tuple[str, ...]:
        """Every repository path whose change since a recording makes its results stale."""
        own = (f"bench/{self.name}.py", *(f"bench/{helper}.py" for helper in self.helpers)) if self.in_bench else ()
        return (*self.measures, *own)


BENCHMARKS: tuple[Benchmark, ...] = (
    # ---------------------------------------------------------------------------------------- modules of bench/
    Benchmark(
        "bennett_speed",
        "set-up, dynamic and quasi-static run times of the Bennett scene, fast options against the reference",
        records=(Recording("bennett_speed", ("--cold", *JSON)),),
    ),
    Benchmark(
        "bennett_variants",
        "the four variants of the paper's Bennett linkage at a discretisation (README's headline table)",
        records=(
            Recording("bennett_variants_default", rows_by="variant", rows_name="variants"),
            Recording(
                "bennett_variants_joint_points",
                ("--links-at-joint-points", *JSON),
                rows_by="variant",
                rows_name="variants",
            ),
            Recording("bennett_variants_p2_4mm", ("--h", "0.004", *JSON), rows_by="variant", rows_name="variants"),
            Recording(
                "bennett_variants_paper",
                ("--order", "1", "--h", "0.002", "--modes", "32", *JSON),
                rows_by="variant",
                rows_name="variants",
            ),
        ),
    ),
    Benchmark(
        "clearance_variants",
        "the paper's PLA Bennett and its misaligned variants with 0 to 0.3 mm of play in their passive joints",
        measures=(*ENGINE, "identification"),
        records=(Recording("clearance_variants", ("--workers", "2", *JSON), rows_by="run", rows_name="runs"),),
        helpers=("bennett_variants",),
    ),
    Benchmark(
        "blas_threads",
        "a second BLAS thread on the default scene, quiet and busy",
        records=(Recording("blas_threads"),),
    ),
    Benchmark(
        "compile_times",
        "numba's compile time of a cold run, per kernel",
        records=(Recording("compile_times"),),
    ),
    Benchmark(
        "collision_free_designs",
        "collision-free links of Rational Linkages' mechanisms: our stacking design against its own",
        records=(
            Recording(
                "collision_free_designs",
                ("--rl-check", "--rl-search", "bennett_ark24", *JSON),
            ),
        ),
    ),
    Benchmark(
        "conservation",
        "momentum and energy of the free flexible bar over 10^4 steps",
        measures=WITH_VALIDATION,
        records=(Recording("conservation", ("--out", "{out}"), ("conservation.json",)),),
    ),
    Benchmark(
        "dynamic_step_rule",
        "a dynamic revolution at each step against 2 ms steps",
        records=(Recording("dynamic_step_rule"),),
        helpers=("full_revolution",),
    ),
    Benchmark(
        "end_to_end",
        "from a cold start, set-up included: the default scene's revolutions, ours against Exudyn",
        measures=WITH_VALIDATION,
        records=(Recording("end_to_end"),),
        helpers=("speed_vs_error", "memory_probe"),
    ),
    Benchmark(
        "fe_beam_convergence",
        "P1 and P2 prisms' frequencies against beam theory",
        measures=(*ENGINE, "tests/test_fe_models/test_ffrf_beam_theory.py", "tests/test_fe_models/ffrf_reference.py"),
        records=(Recording("fe_beam_convergence"),),
    ),
    Benchmark(
        "fe_link",
        "mesh, assembly and modal-analysis cost of the coupler link",
        records=(
            Recording("fe_link_p1"),
            Recording("fe_link_p2", ("--order", "2", "--h", "0.004", "0.002", *JSON)),
        ),
    ),
    Benchmark(
        "full_revolution",
        "a whole ramp and revolution, ours against the Exudyn twin",
        measures=WITH_VALIDATION,
        records=(
            Recording("full_revolution", ("--step", "0.01", *JSON)),
            Recording(
                "full_revolution_paper", ("--order", "1", "--h", "0.004", "--modes", "32", "--step", "0.01", *JSON)
            ),
        ),
    ),
    Benchmark(
        "hard_cases",
        "seven families of hard cases of the flexible Bennett scene",
        measures=WITH_VALIDATION,
        records=(
            Recording(
                "hard_cases",
                ("--cases", "near_rigid,misalignment,speed,long_run,soft,singular", "--out", "{out}"),
                ("hard_cases.json",),
            ),
        ),
    ),
    Benchmark(
        "iteration_cost",
        "a Newton iteration's pieces against the modes per link",
        records=(Recording("iteration_cost", rows_by="modes_per_link"),),
    ),
    Benchmark(
        "memory",
        "peak resident memory of the main job, per stage and per mesh",
        records=(Recording("memory", ("--meshes", "1,0.002", "1,0.001", "2,0.003", *JSON)),),
        helpers=("memory_probe",),
    ),
    Benchmark(
        "misfit_vs_remesh",
        "a bore error as a joint-frame misfit against the remeshed link",
        records=(Recording("misfit_vs_remesh"),),
    ),
    Benchmark(
        "quasi_static_vs_dynamic",
        "the quasi-static path against the dynamic run at 1 rpm",
        records=(Recording("quasi_static_vs_dynamic"),),
    ),
    Benchmark(
        "compensation",
        "bore corrections that compensate the PLA Bennett's and a 6R's deviation, checked by forward runs of the print",
        records=(Recording("compensation", rows_by="variant", rows_name="variants"),),
    ),
    Benchmark(
        "section_design",
        "derivatives by the links' section against re-solved and remeshed linkages; the PLA Bennett's lightest arm",
        records=(Recording("section_design"),),
    ),
    Benchmark(
        "loop_sensitivity",
        "derivatives by the Bennett's own DH parameters against re-solved morphed and remeshed linkages",
        records=(Recording("loop_sensitivity"),),
    ),
    Benchmark(
        "stress_convergence",
        "each link's peak von Mises stress of the PLA Bennett against the element size: a singular stress or not",
        records=(Recording("stress_convergence"),),
    ),
    Benchmark(
        "play_design",
        "the largest play of the PLA Bennett's passive joints that keeps its coupler within 1 mm",
        records=(Recording("play_design"),),
    ),
    Benchmark(
        "study_stability",
        "stability monitoring in a study (its default): how the 2000-print study's first prints end, and the cost",
        records=(Recording("study_stability"),),
    ),
    Benchmark(
        "linear_tolerance",
        "the 2000-print tolerance study to first and second order against its full Monte Carlo, at four levels",
        records=(Recording("linear_tolerance", rows_by="level", rows_name="levels"),),
    ),
    Benchmark(
        "reach_isolated",
        "minimum-energy paths to collisions_free_6r's isolated assemblies",
        records=(Recording("reach_collisions_free_6r"),),
    ),
    Benchmark(
        "run_checks",
        "margins of the default runs' verification checks",
        records=(Recording("run_checks", rows_by="name", rows_name="runs"),),
    ),
    Benchmark(
        "setup_speed",
        "scene set-up time, cold and warm, with and without the disk cache",
        records=(Recording("setup_speed"),),
        helpers=("memory_probe",),
    ),
    Benchmark(
        "snap_plane_fold",
        "plane_fold_6r's fold: stability monitoring and the dynamic snap",
        records=(Recording("snap_plane_fold_6r"),),
    ),
    Benchmark(
        "snap_with_play",
        "plane_fold_6r's folds with ideal joints and with 0.1 mm of play in its passive joints",
        records=(Recording("snap_with_play"),),
    ),
    Benchmark(
        "speed_vs_error",
        "our solver and its Exudyn twin: speed against error over meshes, modes and steps",
        measures=WITH_VALIDATION,
        records=(
            Recording(
                "speed_vs_error_quasi_static",
                ("--qs-points", "1,0.006,2", "1,0.004,2", "2,0.006,4", "--dyn-points", "--dyn-qs-points")
                + ("--out", "{out}"),
                ("results.json", "reference.json"),
            ),
            Recording(
                "speed_vs_error_dynamic",
                ("--qs-points", "--dyn-points", "1,0.006,2,0.004,0.9", "1,0.006,8,0.004,0.9", "2,0.006,4,0.004,0.9")
                + ("1,0.006,2,0.002,0.9,ours", "1,0.006,2,0.001,0.9,ours", "1,0.006,2,0.004,0.5,ours")
                + ("1,0.006,2,0.004,1.0,ours", "--dyn-qs-points", "2,0.006,4", "--out", "{out}"),
                ("results.json", "reference.json"),
            ),
        ),
        helpers=("memory_probe",),
    ),
    Benchmark(
        "step_rules",
        "the step rules' stops, rate peaks and output solving",
        records=(Recording("step_rules"),),
    ),
    Benchmark(
        "study_speed",
        "a study's time per variant in process and through Dask",
        records=(Recording("study_speed", env=("OPENBLAS_NUM_THREADS=1",)),),
    ),
    Benchmark(
        "textbook_buckling",
        "von Mises truss and Euler column against their closed forms",
        measures=(*ENGINE, "validation/textbook_cases.py"),
        records=(Recording("textbook_buckling"),),
    ),
    Benchmark(
        "validation_refinement",
        "time-step refinement of both solvers on the coarse scene",
        measures=WITH_VALIDATION,
        records=(
            Recording("validation_refinement_pla", rows_by="step"),
            Recording("validation_refinement_pla1", ("--variant", "pla1", *JSON), rows_by="step"),
            Recording(
                "validation_refinement_pla1_exudyn_jacobian",
                ("--variant", "pla1", "--exudyn-jacobian", *JSON),
                rows_by="step",
            ),
        ),
    ),
    Benchmark(
        "warmup",
        "the main job cold, warm and after `python -m ffrf warmup`",
        records=(Recording("warmup"),),
    ),
    # --------------------------------------------------------------------- the library's own command lines
    Benchmark(
        "ffrf",
        "runs of `python -m ffrf` whose summaries the docs quote",
        module="ffrf",
        records=(
            *(
                Recording(
                    f"linkage_collisions_free_6r_{variant}",
                    ("linkage", "--model", "collisions_free_6r", "--variant", variant, "--outputs", "241")
                    + ("--out", "{out}"),
                    ("metadata.json",),
                    select=("summary", "assembly", "clearance", "n_coordinates"),
                )
                for variant in ("pla", "rigid")
            ),
            Recording(
                "linkage_collisions_free_6r_as_built",
                ("linkage", "--model", "collisions_free_6r", "--variant", "pla", "--bore-error", "5:0:1.0")
                + ("--outputs", "241", "--out", "{out}"),
                ("metadata.json",),
                select=("summary", "assembly", "clearance"),
            ),
            Recording(
                "linkage_plane_fold_6r_pla",
                ("linkage", "--model", "plane_fold_6r", "--variant", "pla", "--outputs", "241", "--out", "{out}"),
                ("metadata.json",),
                select=("summary", "stopped", "clearance", "verification", "near_dead_poses"),
            ),
            Recording(
                "linkage_plane_fold_6r_pla_dynamic",
                ("linkage", "--model", "plane_fold_6r", "--variant", "pla", "--dynamic", "--outputs", "241")
                + ("--out", "{out}"),
                ("metadata.json",),
                select=("summary", "clearance", "verification", "step_error_estimate", "near_dead_poses"),
            ),
            *(
                Recording(
                    f"stability_bennett_{variant}",
                    ("bennett", "--variant", variant, "--quasi-static", "--outputs", "241", "--stability")
                    + ("--out", "{out}"),
                    ("stability.json",),
                )
                for variant in ("pla", "pla1", "pla2")
            ),
            Recording(
                "stability_plane_fold_6r_pla",
                ("linkage", "--model", "plane_fold_6r", "--variant", "pla", "--outputs", "241", "--stability")
                + ("--out", "{out}"),
                ("stability.json",),
                select=("summary",),
            ),
            Recording(
                "study_pla_2000",
                ("study", "examples/study_bennett_pla_2000.toml", "--out", "{out}", "--workers", "2"),
                ("analysis.json",),
            ),
        ),
    ),
    Benchmark(
        "validation",
        "the comparisons with Exudyn of `python -m validation`",
        module="validation",
        measures=(*WITH_VALIDATION, *(f"examples/{name}.toml" for name in TWIN_LINKAGES)),
        records=(
            Recording("validation_summary", ("summary", "--out", "{out}"), ("summary.json",)),
            Recording("testmodels", ("testmodels", *JSON)),
            *(
                Recording(
                    f"validation_{name}",
                    ("report", "--scene", f"examples/{name}.toml", "--out", "{out}", "--max-minutes", "10"),
                    ("metrics.json",),
                )
                for name in TWIN_LINKAGES
            ),
        ),
    ),
    Benchmark(
        "kinematics",
        "nearby assemblies of the rigid linkages (`python -m kinematics nearby`)",
        module="kinematics",
        measures=("kinematics",),
        records=tuple(
            Recording(f"nearby_{model}", ("nearby", "--model", model, *JSON))
            for model in ("collisions_free_6r", "plane_fold_6r")
        ),
    ),
    Benchmark(
        "blas_matrix",
        "the default test suite under every OpenBLAS kernel and thread count",
        module="scripts/blas-matrix.sh",
        measures=(*WITH_VALIDATION, "tests", "scripts/blas-matrix.sh"),
        records=(
            Recording(
                "blas_matrix",
                (),
                (),
                recipe_missing="scripts/blas-matrix.sh writes it, with its own meta",
            ),
        ),
    ),
    Benchmark(
        "slow_tests",
        "the tests marked slow (long studies), which CI leaves out",
        module="scripts/run-slow-tests.sh",
        measures=(*WITH_VALIDATION, "tests", "scripts/record_tests.py"),
        records=(
            Recording("slow_tests", (), (), recipe_missing="scripts/run-slow-tests.sh writes it, with its own meta"),
        ),
    ),
    Benchmark(
        "coverage",
        "statement coverage of the packages by the tests, numba's JIT off",
        module="scripts/coverage.sh",
        measures=(*WITH_VALIDATION, "tests", "scripts/record_tests.py"),
        records=(Recording("coverage", (), (), recipe_missing="scripts/coverage.sh writes it, with its own meta"),),
    ),
)


def benchmark(name: str) -> Benchmark:
    """The benchmark called ``name``; KeyError listing the names."""
    for entry in BENCHMARKS:
        if entry.name == name:
            return entry
    raise KeyError(f"no benchmark {name!r} (known: {', '.join(b.name for b in BENCHMARKS)})")


def recordings() -> dict[str, tuple[Benchmark, Recording]]:
    """Every result file's stem -> its benchmark and recording."""
    return {record.result: (entry, record) for entry in BENCHMARKS for record in entry.records}


def recording(result: str) -> tuple[Benchmark, Recording]:
    """The benchmark and recording of ``docs/results/{result}.json``; KeyError naming the known ones."""
    found = recordings()
    if result not in found:
        raise KeyError(f"no recording of {result!r} in bench/registry.py (known: {', '.join(sorted(found))})")
    return found[result]
