r"""Study files (TOML): a base linkage, the parameters a study varies and how it samples them.

::

    [study]
    name = "bore tolerances"
    method = "saltelli"          # grid | monte_carlo | lhs | sobol | saltelli
    samples = 64                 # rows (monte_carlo, lhs, sobol: a power of 2); saltelli: N base rows -> N (d + 2)
    seed = 1                     # variants; grid: ignored (every combination of the values)
    # max_variants = 200000      # a design above 100000 variants is refused unless lifted here (ffrf.scenes.limits)

    [base]
    linkage = "my_linkage.toml"  # a linkage file (ffrf.scenes.linkage_file), relative to this file, or a
    # KEY = "NAME"               # named base of the application's catalogue (NamedBases, e.g. the paper's)
    h = 0.012                    # optional: element edge (m), order, modes, mode ("auto", "quasi_static",
    order = 1                    #   "dynamic"), outputs, revolutions, rpm
    modes = 2
    outputs = 25
    bore_error_model = "misfit"  # "misfit" (nominal meshes, the error in the joint frame) or "remesh"

    [[parameters]]
    name = "twist_3_0"
    target = "bore_twist_deg"    # see TARGETS
    joint = 3                    # bore targets: the joint and the link carrying the bore
    link = 0
    normal = {mean = 0.0, std = 0.5}   # or uniform = {low = ..., high = ...}, or values = [...] (grid; a
                                       # sampled study picks one of them with equal probability)

A parameter's value sets its target in the variant: a bore's twist about its link's common normal (deg, which
changes that link's DH twist alpha), its offset along it (mm, the DH length a) or its seat's shift along the
bore's own axis (mm, the joint's DH offset d), added to any error the base already has on that bore
(:class:`ffrf.scenes.linkage_description.BoreError`); every link's arm section, ``arm_width_mm`` and
``arm_thickness_mm`` (:class:`ffrf.geometry.link_geometry.LinkDesign`; the meshes change); the links' ``E``
(Pa) or ``rho`` (kg/m^3); the drive's ``rpm``; the element edge ``h`` (m) or the fixed-interface ``modes`` per
link (rounded to an integer); ``radial_clearance_mm``, the radial play of every passive joint (pins in bores,
:mod:`ffrf.system.clearance_joint`; the base's ``clearance`` table otherwise, or pins as long as the housings; 0:
ideal joints). :func:`load_study` checks a file before anything runs: a misspelt key, a wrong
type or an impossible value is one :class:`~ffrf.errors.SceneError` line naming the key, where it is and the fix.

**Named bases.** An application may offer built-in base linkages by name (:class:`NamedBases`, passed to
:func:`load_study`): its ``key`` in ``[base]`` names one of them, whose options and scene builder the application
gives (:mod:`ffrf.paper.bennett_scene` offers the paper's variants so).
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ffrf.errors import SceneError
from ffrf.scenes.limits import MAX_OUTPUTS, linkage_run_steps, steps_problem, variants_problem
from ffrf.scenes.linkage_description import BORE_ERROR_MODELS, LinkageOptions
from ffrf.scenes.linkage_scene import LinkageScene
from ffrf.scenes.scene_cache import SceneCache
from ffrf.scenes.schema_keys import Key, at_least, between, check_table, one_of, positive
from ffrf.solvers.stability import check_judged_at_equilibria
from ffrf.studies.outputs import output_names

__all__ = [
    "METHODS",
    "TARGETS",
    "Base",
    "NamedBases",
    "Parameter",
    "Study",
    "design_size",
    "load_study",
    "monitors_stability",
    "study_from_document",
]

#: Sampling methods (:mod:`ffrf.studies.sampling`).
METHODS = ("grid", "monte_carlo", "lhs", "sobol", "saltelli")
#: What a parameter may set, with its unit; the bore targets need ``joint`` and ``link``.
TARGETS = {
    "bore_twist_deg": "deg",
    "bore_offset_mm": "mm",
    "bore_axial_mm": "mm",
    "bore_tilt_deg": "deg",
    "bore_shift_mm": "mm",
    "arm_width_mm": "mm",
    "arm_thickness_mm": "mm",
    "E": "Pa",
    "rho": "kg/m^3",
    "rpm": "rev/min",
    "h": "m",
    "modes": "",
    "radial_clearance_mm": "mm",
}
BORE_TARGETS = ("bore_twist_deg", "bore_offset_mm", "bore_axial_mm", "bore_tilt_deg", "bore_shift_mm")
RUN_MODES = ("auto", "quasi_static", "dynamic")
#: Column names of a study's rows that a parameter may not take (:mod:`ffrf.studies.variant`).
RESERVED = ("id", "block", "sample", "status", "reason", "assembles", "wall_time_s", "worker")

_STUDY = {
    "name": Key("string"),
    "method": Key("string", True, one_of(METHODS)),
    "samples": Key("integer", False, at_least(1)),
    "seed": Key("integer"),
    "max_variants": Key("integer", False, at_least(1)),
}
_BASE = {
    "linkage": Key("string"),
    "h": Key("number", False, positive),
    "order": Key("integer", False, one_of((1, 2))),
    "modes": Key("integer", False, at_least(1)),
    "mode": Key("string", False, one_of(RUN_MODES)),
    "outputs": Key("integer", False, between(2, MAX_OUTPUTS, closed=True)),
    "revolutions": Key("number", False, positive),
    "rpm": Key("number", False, positive),
    "bore_error_model": Key("string", False, one_of(BORE_ERROR_MODELS)),
    "stability": Key("boolean"),
    "max_steps": Key("number", False, positive),
}
_UNIFORM = {"low": Key("number", True), "high": Key("number", True)}
#: A specification limit: a print whose ``output`` exceeds ``above`` (its SI unit) fails it.
_LIMIT = {"output": Key("string", True), "above": Key("number", True)}
_NORMAL = {"mean": Key("number", True), "std": Key("number", True, positive)}
_PARAMETER = {
    "name": Key("string", True),
    "target": Key("string", True, one_of(tuple(TARGETS))),
    "joint": Key("integer", False, at_least(0)),
    "link": Key("integer", False, at_least(0)),
    "uniform": Key("table", keys=_UNIFORM),
    "normal": Key("table", keys=_NORMAL),
    "values": Key("numbers"),
}


@dataclass(frozen=True)
class NamedBases:
    """Base linkages an application offers by name: ``[base]`` says ``key = "NAME"`` (one of ``names``, loops
    of ``n_joints`` joints) instead of a linkage file; ``options(NAME)`` gives its linkage options and
    ``build(options, NAME, cache)`` builds its scene with any options (a variant's), e.g. with its own ideal
    path. Module-level functions, so that a study pickles to the workers."""

    key: str
    names: tuple[str, ...]
    n_joints: int
    options: Callable[[str], LinkageOptions]
    build: Callable[[LinkageOptions, str, SceneCache | None], LinkageScene]


def _schema(bases: NamedBases | None) -> dict[str, Key]:
    """The study file's keys, with the named bases' key in ``[base]``."""
    named = {} if bases is None else {bases.key: Key("string", False, one_of(bases.names))}
    return {
        "study": Key("table", True, keys=_STUDY),
        "base": Key("table", True, keys=named | _BASE),
        "parameters": Key("tables", True, keys=_PARAMETER),
        "limits": Key("tables", keys=_LIMIT),
    }


@dataclass(frozen=True)
class Parameter:
    """One varied parameter: its ``name`` (a column of the results), ``target`` (:data:`TARGETS`), the bore it
    sets (``joint``, ``link``) and its ``distribution``: ``"uniform"`` (low, high), ``"normal"`` (mean, std) or
    ``"values"`` (the grid's values, or equally likely choices)."""

    name: str
    target: str
    distribution: str
    arguments: tuple[float, ...]
    joint: int | None = None
    link: int | None = None


@dataclass(frozen=True)
class Base:
    """The base linkage: a ``named`` base of ``bases`` or a linkage file's parsed ``document`` (with its path,
    for messages), and the run and discretisation settings that replace the base's own (``None``: keep);
    ``bases``: the named bases the study was read with."""

    named: str | None
    linkage: str | None
    document: dict | None
    overrides: dict[str, Any] = field(default_factory=dict)
    bore_error_model: str = "misfit"
    bases: NamedBases | None = None

    def description(self) -> dict[str, Any]:
        """What a study's results say of its base: the named base (under its key), the linkage file, overrides."""
        named = {} if self.bases is None else {self.bases.key: self.named}
        return named | {"linkage": self.linkage} | self.overrides


@dataclass(frozen=True)
class Study:
    """A checked study file (module docstring); ``fingerprint`` hashes the base, so that a variant's id
    (:func:`ffrf.studies.sampling.variant_id`) changes with the linkage it runs."""

    name: str
    method: str
    samples: int
    seed: int
    base: Base
    parameters: tuple[Parameter, ...]
    fingerprint: str
    n_links: int = 4
    limits: tuple[tuple[str, float], ...] = ()

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def stability(self) -> bool:
        """Whether variants run with stability monitoring (quasi-static, snaps followed: ``docs/stability.md``)."""
        return monitors_stability(self.base.overrides)


def _distribution(entry: dict, where: str, method: str) -> tuple[str, tuple[float, ...]]:
    """The one distribution a parameter gives, checked against the method."""
    given = [key for key in ("uniform", "normal", "values") if key in entry]
    if len(given) != 1:
        raise SceneError(
            f"{where}: give exactly one of uniform = {{low, high}}, normal = {{mean, std}} or values = [...], "
            f"got {given or 'none'}"
        )
    kind = given[0]
    if method == "grid" and kind != "values":
        raise SceneError(f"{where}: a grid study takes values = [...] for every parameter, got {kind}")
    if kind == "values":
        values = tuple(float(v) for v in entry["values"])
        if not values:
            raise SceneError(f"{where}: 'values' is empty; give at least one value")
        if not all(math.isfinite(v) for v in values):
            raise SceneError(f"{where}: 'values' must be finite numbers, got {list(values)}")
        return kind, values
    spec = entry[kind]
    numbers = (float(spec["low"]), float(spec["high"])) if kind == "uniform" else (spec["mean"], spec["std"])
    if not all(math.isfinite(v) for v in numbers):
        raise SceneError(f"{where}: {kind} must have finite numbers, got {spec}")
    if kind == "uniform" and not numbers[0] < numbers[1]:
        raise SceneError(f"{where}: uniform needs low < high, got low = {numbers[0]}, high = {numbers[1]}")
    return kind, tuple(float(v) for v in numbers)


def _parameter(entry: dict, where: str, method: str) -> Parameter:
    name, target = entry["name"], entry["target"]
    if name in RESERVED or name.startswith(("max_", "assembly_")):
        raise SceneError(f"{where}: name {name!r} is taken by a result column; choose another name")
    bore = target in BORE_TARGETS
    if bore and ("joint" not in entry or "link" not in entry):
        raise SceneError(f"{where}: target {target!r} sets a bore: give joint = J and link = L (the link carrying it)")
    if not bore and ("joint" in entry or "link" in entry):
        raise SceneError(f"{where}: target {target!r} sets no bore; drop joint and link")
    kind, arguments = _distribution(entry, where, method)
    return Parameter(name, target, kind, arguments, entry.get("joint"), entry.get("link"))


def _base(table: dict, directory: Path, where: str, bases: NamedBases | None) -> Base:
    sources = [key for key in ((bases.key,) if bases else ()) + ("linkage",) if key in table]
    if len(sources) != 1:
        choice = f'{bases.key} = "NAME" (one of {", ".join(bases.names)}) or ' if bases else ""
        raise SceneError(f'{where}: give exactly one base: {choice}linkage = "FILE.toml", got {sources or "none"}')
    document = None
    if "linkage" in table:
        path = directory / table["linkage"]
        try:
            document = tomllib.loads(path.read_text(encoding="utf-8-sig"))  # a BOM (Windows editors) is no TOML
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
            raise SceneError(f"{where}: cannot read the linkage file {path} ({error})") from error
        if "linkage" not in document:
            raise SceneError(f"{where}: {path} has no [linkage] table; a study's base is a linkage file")
    if "revolutions" in table or "rpm" in table:  # the base's drive: 1 rpm after a 1 s ramp
        steps = linkage_run_steps(
            2.0 * math.pi * table.get("rpm", 1.0) / 60.0, 1.0, table.get("revolutions", 1.0), table.get("mode", "auto")
        )
        problem = steps_problem(steps, table.get("max_steps"), "max_steps = N in [base]", " per variant")
        if problem is not None:
            raise SceneError(f"{where}: {problem}")
    keys = ("h", "order", "modes", "mode", "outputs", "revolutions", "rpm", "stability")
    overrides = {key: table[key] for key in keys if key in table}
    remedy = 'drop mode = "dynamic" or stability = true'
    check_judged_at_equilibria(overrides.get("mode", "auto"), overrides.get("stability", False), remedy, where)
    named = table.get(bases.key) if bases else None
    return Base(named, table.get("linkage"), document, overrides, table.get("bore_error_model", "misfit"), bases)


def monitors_stability(overrides: dict) -> bool:
    """A base's ``stability``: as given, by default on unless its mode is ``"dynamic"`` (a print that snaps is
    followed to where it lands instead of stopping there: issue #37; stability is judged at equilibria only)."""
    return bool(overrides.get("stability", overrides.get("mode", "auto") != "dynamic"))


def _check_bores(parameters: tuple[Parameter, ...], n: int, where: str) -> None:
    """Every bore target names a link and one of the two joints it carries (link k carries joints k-1 and k)."""
    for k, p in enumerate(parameters):
        if p.joint is None or p.link is None:
            continue
        carried = ((p.link - 1) % n, p.link)
        if p.link >= n or p.joint not in carried:
            raise SceneError(
                f"{where}, parameters[{k}] {p.name!r}: link {p.link} does not carry joint {p.joint}; link k carries "
                f"joints k-1 and k (link 0 the joints {n - 1} and 0) of this {n}-joint loop"
            )


def study_from_document(
    document: dict, directory: Path = Path("."), where: str = "study", bases: NamedBases | None = None
) -> Study:
    """Check a parsed study file and return its :class:`Study`; linkage files are read from ``directory``;
    ``bases``: the named bases its ``[base]`` may choose from (module docstring)."""
    check_table(document, _schema(bases), where)
    head = document["study"]
    method = head["method"]
    samples = int(head.get("samples", 0 if method == "grid" else 64))
    if method != "grid" and "samples" not in head:
        raise SceneError(f"{where}, study: method {method!r} needs samples = N (e.g. 64)")
    if method in ("sobol", "saltelli") and samples & (samples - 1):
        raise SceneError(
            f"{where}, study: a Sobol sequence keeps its balance with a power of 2 samples, got {samples}; "
            f"use {1 << max(samples.bit_length() - 1, 0)} or {1 << samples.bit_length()}"
        )
    entries = document["parameters"]
    if not entries:
        raise SceneError(f"{where}: list at least one [[parameters]] table")
    parameters = tuple(_parameter(e, f"{where}, parameters[{k}] {e['name']!r}", method) for k, e in enumerate(entries))
    names = [p.name for p in parameters]
    if len(set(names)) != len(names):
        raise SceneError(f"{where}: parameter names must be unique, got {names}")
    problem = variants_problem(design_size(method, samples, parameters), len(parameters), head.get("max_variants"))
    if problem is not None:
        raise SceneError(f"{where}, study: {problem}")
    base = _base(document["base"], directory, f"{where}, base", bases)
    if base.document is not None:
        n = _loop_size(base.document)
    else:
        assert bases is not None  # _base took a named base
        n = bases.n_joints
    _check_bores(parameters, n, where)
    fingerprint = hashlib.sha256(
        json.dumps({"base": document["base"], "document": base.document}, sort_keys=True, default=str).encode()
    ).hexdigest()[:16]
    name = head.get("name", "study")
    limits = _limits(document.get("limits", []), n, monitors_stability(base.overrides), where)
    return Study(name, method, samples, int(head.get("seed", 0)), base, parameters, fingerprint, n, limits)


def _limits(entries: list[dict], n_links: int, stability: bool, where: str) -> tuple[tuple[str, float], ...]:
    """The ``[[limits]]`` as (output, above) pairs, each output one of the study's (:func:`output_names`)."""
    outputs = output_names(n_links, stability)
    out = []
    for k, entry in enumerate(entries):
        if entry["output"] not in outputs:
            raise SceneError(
                f"{where}, limits[{k}]: output {entry['output']!r} is not one of this study's: {', '.join(outputs)}"
            )
        out.append((str(entry["output"]), float(entry["above"])))
    return tuple(out)


def design_size(method: str, samples: int, parameters: tuple[Parameter, ...]) -> int:
    """The number of variants of a design (:func:`ffrf.studies.sampling.study_design`), without building it: a grid
    every combination of the values, Saltelli ``samples (d + 2)``, the other methods ``samples``."""
    if method == "grid":
        return math.prod(len(p.arguments) for p in parameters)
    return samples * (len(parameters) + 2) if method == "saltelli" else samples


def _loop_size(document: dict) -> int:
    """The number of joints of a linkage file, from its source (the scene layer checks the rest)."""
    from ffrf.scenes.linkage_file import linkage_options

    loop, _, _ = linkage_options(document, "study base")
    return loop.n


def load_study(path: str | Path, bases: NamedBases | None = None) -> Study:
    """Read and check a study file (module docstring); ``bases``: the named bases it may choose from."""
    path = Path(path)
    try:
        document = tomllib.loads(path.read_text(encoding="utf-8-sig"))  # a BOM (Windows editors) is no TOML
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise SceneError(f"{path}: cannot read the study ({error})") from error
    return study_from_document(document, path.parent, path.name, bases)
